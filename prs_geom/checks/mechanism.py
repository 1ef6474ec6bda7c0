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

from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np

from prs_geom.checks.fcl import bvh_model
from prs_geom.geometry.mechanism import MechanismLayout

__all__ = ["journal_clearances", "MechanismCheck", "check_mechanism"]


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


@dataclass(frozen=True)
class MechanismCheck:
    """The checks of the mechanism parts of a placed assembly.

    ``layout``: the mechanism's sizes, fits and stack-up; ``ring_designation``: the
    retaining ring's standard designation; ``journal_clearances``: the rows of
    :func:`journal_clearances`. report.json prints it as ``mechanism``
    (:func:`prs_geom.exports.report.mechanism_section`).
    """

    layout: MechanismLayout
    ring_designation: str
    journal_clearances: tuple[dict[str, Any], ...]

    @property
    def fits(self) -> list[Any]:
        """The journal fit, and the carrier fit when the carriers are guided by the nut."""
        lay = self.layout
        return [lay.journal_fit] + ([lay.carrier_fit] if lay.carrier_fit else [])

    @property
    def checks(self) -> list[tuple[str, bool]]:
        """(name, passed) of every check: each fit, the journal clearances, the stack-up."""
        out = [(f"fit: {f.feature}", bool(f.passed)) for f in self.fits]
        out.append(("journal clearances (FCL) within the fit", all(r["passed"] for r in self.journal_clearances)))
        out.append(("axial stack-up: play positive at worst case", bool(self.layout.stack.passed)))
        return out

    @property
    def passed(self) -> bool:
        """Whether every check passed."""
        return all(ok for _, ok in self.checks)


def check_mechanism(asm: Any, lay: MechanismLayout, ring_designation: str) -> MechanismCheck:
    """The fits, the journal clearances on the meshes (FCL) and the stack-up of ``lay`` on
    the placed assembly ``asm``."""
    return MechanismCheck(layout=lay, ring_designation=ring_designation,
                          journal_clearances=tuple(journal_clearances(asm, lay)))
