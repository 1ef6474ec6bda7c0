"""The build pipeline: design -> analysis -> geometry -> checks -> exports.

``build`` runs every stage available on a design and writes all exports plus
``report.json`` into an output folder atomically (see :mod:`prs_geom.output`).
Each stage is a function ``stage(ctx)`` that fills its report section and may write files
into ``ctx.out``; stages run in the order of :data:`STAGES`.
"""
from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np
import trimesh

from . import __version__
from .assembly import carrier_angles, roller_spin
from .design import PRSDesign
from .designio import design_to_dict, dumps_toml
from .errors import EnvironmentFailure
from .output import AtomicOutputDir
from .progress import ProgressFn, silent

REPORT_NAME = "report.json"
#: Version of the report.json layout (``format_version``); the JSON Schema
#: ``prs_geom/schemas/report.schema.json`` describes it.
REPORT_FORMAT_VERSION = 1


@dataclass
class BuildContext:
    """What stages share: the design, the temporary output folder and the report."""

    design: PRSDesign
    out: Path
    report: dict[str, Any]
    progress: ProgressFn = silent

    def write_text(self, name: str, text: str) -> Path:
        path = self.out / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
        self.report["files"].append(name)
        return path

    def add_file(self, name: str) -> Path:
        """Register a file a stage writes itself; returns its path in the output folder."""
        path = self.out / name
        path.parent.mkdir(parents=True, exist_ok=True)
        self.report["files"].append(name)
        return path


def stage_design(ctx: BuildContext) -> None:
    """Write the resolved design back as ``design.toml``."""
    ctx.write_text("design.toml", dumps_toml(ctx.design, header=f"resolved design '{ctx.design.name}', "
                                                                f"written by prs_geom {__version__}"))


def stage_pitch(ctx: BuildContext) -> None:
    """Pitch lists of the three parts (tooth 1 at the loaded end)."""
    d = ctx.design
    ctx.report["pitch"] = {
        "screw_mm": list(d.pitch_list("screw")),
        "roller_mm": list(d.pitch_list("roller")),
        "nut_mm": list(d.pitch_list("nut")),
    }


def stage_loads(ctx: BuildContext) -> None:
    """Load distribution, equal-load pitch design, off-design and plots."""
    from .loads import build_model, design_pitches, forward, loads_report, off_design, with_pitch_lists
    from .plots import plot_loads

    d = ctx.design
    model = build_model(d)
    rep = loads_report(d, model, progress=ctx.progress)
    ctx.report["loads"] = rep
    equal = design_pitches(d, model=model)
    ctx.report["pitch"]["equal_load"] = {"roller_mm": list(equal.roller_mm), "nut_mm": list(equal.nut_mm)}
    if d.graded:
        shown = {"ldc_nut_roller": rep["ldc_nut_roller"], "ldc_roller_screw": rep["ldc_roller_screw"]}
        off, label = rep["off_design"], "design pitch lists"
        pr, pn = np.array(d.pitch_list("roller")), np.array(d.pitch_list("nut"))
    else:
        eq = with_pitch_lists(d, equal)
        r = forward(eq, model=model)
        shown = {"ldc_nut_roller": r.ldc_nr.tolist(), "ldc_roller_screw": r.ldc_rs.tolist()}
        off, label = off_design(eq, model=model), "equal-load pitch design"
        pr, pn = np.array(equal.roller_mm), np.array(equal.nut_mm)
    p = d.thread.pitch_mm
    for f in plot_loads(ctx.out, d.name, rep["constant_pitch"], shown, off, (pr - p) * 1e3, (pn - p) * 1e3, label):
        ctx.report["files"].append(f)


def stage_meshes(ctx: BuildContext) -> None:
    """Thread meshes, assembly, mesh checks (``checks.meshes``) and mesh exports."""
    from .assembly import SIMPLIFIED_PARTS, build_assembly, thread_length
    from .exports import export_meshes
    from .mesh import analytic_thread_volume, mesh_report

    d = ctx.design
    asm = build_assembly(d, progress=ctx.progress)
    rows = []
    lengths = {"screw": d.screw.length_mm, "roller": thread_length(d), "nut": thread_length(d)}
    for i, (name, tm) in enumerate(asm.parts.items()):
        graded = not tm.warp.is_identity
        vol = None if graded else analytic_thread_volume(
            tm.profile, lengths[name], tm.body_radius)
        rows.append(mesh_report(tm, vol))
        ctx.progress("mesh checks", i + 1, len(asm.parts))
    ctx.report["checks"]["meshes"] = rows
    ctx.report["assembly"] = {
        "parts": list(asm.placed),
        "roller_carrier_angles_deg": [float(np.degrees(a)) for a in carrier_angles(d)],
        "roller_spin_deg": [float(np.degrees(roller_spin(d, a)) % 360.0) for a in carrier_angles(d)],
        "simplified": SIMPLIFIED_PARTS,
        "triangles": int(sum(m.faces.shape[0] for m, _, _ in asm.placed.values())),
    }
    for name, text in export_meshes(asm, ctx.out).items():
        ctx.report["files"].append(name)


def stage_contact(ctx: BuildContext) -> None:
    """Analytic contact points and the theoretical screw pitch diameter."""
    from .contact import contact_report

    ctx.report["contact"] = contact_report(ctx.design)


def stage_checks(ctx: BuildContext) -> None:
    """FCL verification of the contacts and the interference check (both screws)."""
    from .fcl_verify import verify_contacts
    from .interference import interference

    ctx.report["checks"]["fcl"] = verify_contacts(ctx.design)
    ctx.progress("fcl verification", 1, 1)
    corrected = interference(ctx.design, "corrected", progress=ctx.progress)
    corrected["nominal_screw"] = interference(ctx.design, "nominal", progress=ctx.progress)
    ctx.report["checks"]["interference"] = corrected
    ctx.report["warnings"] += check_warnings(ctx.report)


def stage_manufacturing(ctx: BuildContext) -> None:
    """Machining sheets (CSV per part, one XLSX) and the DXF profile drawing."""
    from .dxf import write_dxf
    from .machining import machining_sheets
    from .sheets import sheet_csv, write_xlsx

    sheets = machining_sheets(ctx.design)
    ctx.report["machining"] = {part: sh.as_dict() for part, sh in sheets.items()}
    for part, sh in sheets.items():
        ctx.write_text(f"machining_{part}.csv", sheet_csv(sh))
    write_xlsx(sheets, ctx.add_file("machining.xlsx"))
    extra = {}
    if ctx.report.get("contact"):
        sr = ctx.report["contact"]["screw_roller"]
        extra["theoretical screw pitch dia. (grind to)"] = f"{sr['theoretical_pitch_diameter_mm']:.6f} mm"
    write_dxf(ctx.design, ctx.add_file("profiles.dxf"), extra)


def stage_html(ctx: BuildContext) -> None:
    """The self-contained HTML report (needs every earlier section)."""
    from .html_report import write_html

    write_html(ctx.design, ctx.report, ctx.out, ctx.add_file("report.html"))


#: Stages in run order: (report name, function).
STAGES: list[tuple[str, Callable[[BuildContext], None]]] = [
    ("design", stage_design),
    ("pitch", stage_pitch),
    ("contact", stage_contact),
    ("loads", stage_loads),
    ("meshes", stage_meshes),
    ("checks", stage_checks),
    ("manufacturing", stage_manufacturing),
    ("html", stage_html),
]


def new_report(design) -> dict[str, Any]:
    """The report skeleton; see README "report.json" for the schema."""
    from .harmonic import HarmonicDesign

    if isinstance(design, HarmonicDesign):
        return {"format_version": REPORT_FORMAT_VERSION, "prs_geom_version": __version__, "kind": "harmonic",
                "design": design_to_dict(design), "warnings": [], "harmonic": None, "checks": {},
                "timings_s": {}, "files": []}
    return {
        "format_version": REPORT_FORMAT_VERSION,
        "prs_geom_version": __version__,
        "design": design_to_dict(design),
        "warnings": design.sizing_warnings(),
        "contact": None,
        "loads": None,
        "pitch": None,
        "checks": {},
        "machining": None,
        "timings_s": {},
        "files": [],
    }


def check_warnings(report: dict[str, Any]) -> list[str]:
    """Every check whose measured difference exceeds its documented tolerance, as one line
    each: the ``warnings`` lists of the mesh checks and of the FCL verification."""
    out = []
    checks = report.get("checks") or {}
    for row in checks.get("meshes") or []:
        out += [f"mesh check ({row['part']}): {w}" for w in row.get("warnings", [])]
    fcl_check = checks.get("fcl") or {}
    out += [f"FCL check: {w}" for w in fcl_check.get("warnings", [])]
    return out


def run_stages(design: PRSDesign, out: Path, progress: ProgressFn = silent,
               stages: list[tuple[str, Callable[[BuildContext], None]]] | None = None) -> BuildContext:
    ctx = BuildContext(design=design, out=out, report=new_report(design), progress=progress)
    for name, fn in (STAGES if stages is None else stages):
        t0 = time.perf_counter()
        fn(ctx)
        ctx.report["timings_s"][name] = time.perf_counter() - t0
        progress(name, 1, 1)
    return ctx


def harmonic_stage(ctx: BuildContext) -> None:
    """Ratio table and plot, DXF at the drawing positions, STL meshes (harmonic designs)."""
    from .harmonic import harmonic_report
    from .harmonic_exports import (circular_spline_mesh, circular_spline_profile, flexspline_mesh,
                                   flexspline_profile, plot_ratio, ratio_table_csv, revolve_deviation,
                                   write_dxf)

    d = ctx.design
    rep = harmonic_report(d)
    ctx.report["harmonic"] = rep
    ctx.write_text("ratio_table.csv", ratio_table_csv(rep["table"]))
    ctx.report["files"] += plot_ratio(d, ctx.out)
    write_dxf(d, ctx.add_file("axial_sections.dxf"))
    rows = []
    tol = d.mesh.chord_tolerance_mm
    for name, mesh, prof, arc_bound in (
            ("circular_spline", circular_spline_mesh(d), circular_spline_profile(d), 0.0),
            ("flexspline", flexspline_mesh(d), flexspline_profile(d), 0.5 * tol)):
        ctx.add_file(f"{name}.stl").write_bytes(trimesh.exchange.stl.export_stl(mesh))
        rev = revolve_deviation(mesh, prof)
        dev = rev + arc_bound
        rows.append({"part": name, "triangles": int(len(mesh.faces)), "watertight": bool(mesh.is_watertight),
                     "volume_mm3": float(mesh.volume), "chord_tolerance_mm": tol,
                     "revolution_deviation_mm": rev, "arc_chord_bound_mm": arc_bound,
                     "max_deviation_mm": dev,
                     "warnings": [f"measured deviation {dev:.3g} mm exceeds the chord tolerance {tol:g} mm"]
                     if dev > tol else []})
    ctx.report["checks"]["meshes"] = rows
    ctx.report["warnings"] += check_warnings(ctx.report)


HARMONIC_STAGES: list[tuple[str, Callable[[BuildContext], None]]] = [
    ("design", stage_design),
    ("harmonic", harmonic_stage),
]


def _environment_failure(exc: OSError, atomic: AtomicOutputDir) -> EnvironmentFailure:
    """One line naming the path (as the user will know it, not the temporary folder) and
    the operating system's reason."""
    path = str(exc.filename) if exc.filename is not None else str(atomic.target)
    if atomic.tmp is not None:
        path = path.replace(str(atomic.tmp), str(atomic.target))
    return EnvironmentFailure(f"cannot write {path}: {exc.strerror or exc} (nothing was written; "
                              f"{atomic.given} is as it was)")


def build(design, out_dir: str | Path, progress: ProgressFn = silent,
          memory_budget: int | None = None) -> dict[str, Any]:
    """Run every stage and write the exports and ``report.json`` to ``out_dir``.

    ``out_dir`` must be a new path, an empty folder or an earlier prs-geom output folder
    (:mod:`prs_geom.output`; anything else raises :class:`~prs_geom.output.OutputRefused`
    before any work). The job is refused up front when its estimated memory exceeds
    ``memory_budget`` (bytes; default a share of the available memory,
    :mod:`prs_geom.resources`). Written atomically: if any stage fails, ``out_dir`` keeps
    its previous content. Returns the report dict.
    """
    from .harmonic import HarmonicDesign
    from .resources import guard

    harmonic = isinstance(design, HarmonicDesign)
    atomic = AtomicOutputDir(out_dir, {"design": design.name})
    if not harmonic:
        guard(design, memory_budget)
    try:
        with atomic as tmp:
            ctx = run_stages(design, tmp, progress, HARMONIC_STAGES if harmonic else None)
            ctx.report["files"].append(REPORT_NAME)
            (tmp / REPORT_NAME).write_text(json.dumps(ctx.report, indent=2) + "\n", encoding="utf-8")
    except OSError as exc:
        raise _environment_failure(exc, atomic) from exc
    return ctx.report
