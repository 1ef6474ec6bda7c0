"""Checks of the mechanism parts (``mechanism`` in report.json).

* **Journal fits**, analytically: the ISO 286 limits of the journal (and, when guided,
  the carrier) fit give the diametral clearance range; a running fit needs it positive at
  both limits.
* **Journal clearances**, on the meshes: the FCL distance between every placed roller
  journal and its carrier, which must lie in the fit's radial range [c_min / 2, c_max / 2]
  (the meshes are at the middle of the zones, coaxial; the journal polygon's vertices are
  on its circle and the bore's edges tangent to its circle, so the distance exceeds the
  modelled radial clearance by at most the journal's chordal deviation).
* **Axial stack-up** of carriers, rollers and rings (:class:`~prs_geom.geometry.mechanism.StackUp`).

The interference of every pair of parts, mechanism parts included, is the interference
check (:mod:`prs_geom.checks.interference`).
"""
from __future__ import annotations

from typing import Any

import fcl
import numpy as np

from prs_geom.checks.fcl import bvh_model
from prs_geom.geometry.mechanism import MechanismLayout

__all__ = ["journal_clearances", "mechanism_section"]


def journal_clearances(asm: Any, lay: MechanismLayout) -> list[dict[str, Any]]:
    """FCL distance (mm) between each roller journal and its carrier, with the fit's radial
    range; one row per roller and end."""
    objs: dict[int, Any] = {}

    def obj(name: str) -> fcl.CollisionObject:
        mesh, T, _ = asm.placed[name]
        if id(mesh) not in objs:
            objs[id(mesh)] = bvh_model(np.asarray(mesh.vertices), np.asarray(mesh.faces))
        return fcl.CollisionObject(objs[id(mesh)], fcl.Transform(T[:3, :3], T[:3, 3]))

    lo = 0.5 * lay.journal_fit.min_clearance_mm
    hi = 0.5 * lay.journal_fit.max_clearance_mm
    rows = []
    for k in range(lay.roller_count):
        for side in ("lo", "hi"):
            res = fcl.DistanceResult()
            dist = fcl.distance(obj(f"roller_{k}_journal_{side}"), obj(f"carrier_{side}"),
                                fcl.DistanceRequest(enable_nearest_points=True), res)
            rows.append({"roller": k, "end": side, "fcl_clearance_mm": float(dist),
                         "fit_radial_range_mm": [lo, hi],
                         "modelled_radial_clearance_mm": 0.5 * lay.journal_fit.modelled_clearance_mm,
                         "passed": bool(lo <= dist <= hi)})
    return rows


def mechanism_section(asm: Any, lay: MechanismLayout, ring_designation: str) -> dict[str, Any]:
    """The ``mechanism`` section of report.json: sizes, fits, journal clearances, stack-up,
    and a pass/fail list of the checks."""
    journals = journal_clearances(asm, lay)
    fits = [lay.journal_fit.report()] + ([lay.carrier_fit.report()] if lay.carrier_fit else [])
    checks = [{"name": f"fit: {f['feature']}", "passed": f["passed"]} for f in fits]
    checks.append({"name": "journal clearances (FCL) within the fit", "passed": all(r["passed"] for r in journals)})
    checks.append({"name": "axial stack-up: play positive at worst case", "passed": lay.stack.passed})
    ring = lay.ring
    return {
        "journal_diameter_mm": lay.journal_diameter_mm,
        "carrier": {"inner_diameter_mm": 2 * lay.carrier_inner_radius_mm,
                    "outer_diameter_mm": 2 * lay.carrier_outer_radius_mm,
                    "thickness_mm": lay.carrier_thickness_mm},
        "retaining_ring": {"designation": ring_designation, "bore_mm": ring.bore_mm,
                           "thickness_mm": ring.thickness_mm, "groove_diameter_mm": ring.groove_diameter_mm,
                           "groove_width_mm": ring.groove_width_mm, "edge_distance_mm": ring.edge_distance_mm,
                           "section_width_mm": ring.section_width_mm},
        "nut_end": {"bore_diameter_mm": 2 * lay.nut_bore_radius_mm, "length_mm": lay.ends[0].nut_end[1]
                    - lay.ends[0].nut_end[0]},
        "axial_layout_mm": [{"end": side, "gear": list(e.gear_zone), "journal": list(e.journal),
                             "carrier": list(e.carrier), "retaining_ring": list(e.ring),
                             "groove": list(e.groove), "nut_end": list(e.nut_end)}
                            for side, e in zip(("lo", "hi"), lay.ends)],
        "fits": fits,
        "journal_clearances": journals,
        "stack_up": lay.stack.report(),
        "checks": checks,
        "passed": all(c["passed"] for c in checks),
    }
