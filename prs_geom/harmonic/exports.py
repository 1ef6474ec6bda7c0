"""Exports of the harmonic friction drive: ratio plot, CSV table, DXF axial section at
chosen positions, STL meshes of the cone-bored circular spline and the flexspline cup.

Meshes are solids of revolution of the undeformed parts (defined in
:mod:`prs_geom.harmonic.assembly` with the placed assembly, importable from here too; each in
its own frame, z along the axis, mm): the circular spline is a ring whose bore is the cone (radius b1 at z = 0 to
b2 at z = H); the flexspline is a cup (bottom at z = 0) of wall thickness t about the
neutral radius with, at its open end, the contact bulge: the arc of radius r_s centred at
radius r0 - c_s, height x_s = L - r_s, between the outer and the inner wall. Arcs are
sampled with half the chordal tolerance as chord sagitta and the revolution with the
other half; the revolution error is measured (:func:`revolve_deviation`) and reported with
the arc-chord bound.

:func:`place_harmonic` writes what the placed assembly adds and :func:`write_harmonic_html`
the page (the pipeline's harmonic stage calls them last):
the drive at one input position (:mod:`prs_geom.harmonic.assembly`) as per-part
STLs of the new parts (``flexspline_placed.stl``: the deformed flexspline in the assembly
frame; ``wave_generator.stl``: its own frame), ``assembly.glb`` (glTF 2.0, metres, +Y up, one
named node per part) and ``assembly.3mf`` (millimetres, one object and build item per part),
both through :mod:`prs_geom.exports.scene`, and ``report.html``
(:mod:`prs_geom.harmonic.report`).

Text goes through :mod:`prs_geom.exports.textsafe`: CSV text fields never begin a spreadsheet
formula, the design name is literal text in the DXF and in the plot title.
"""
from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import ezdxf
import numpy as np
import trimesh
from ezdxf import units

from prs_geom.exports.sheet import save_dxf
from prs_geom.exports.scene import Material, Scene, SceneMesh, SceneNode
from prs_geom.exports.textsafe import csv_field, dxf_text, mpl_text
from prs_geom.geometry.planar import point_segment_distance
# the parts' undeformed geometry lives with the assembly; these names stay importable from here
from prs_geom.harmonic.assembly import (circular_spline_mesh, circular_spline_profile,  # noqa: F401
                                        flexspline_mesh, flexspline_profile, revolution_sections)
from prs_geom.harmonic.assembly import circular_spline_placement, cone_start
from prs_geom.harmonic.model import HarmonicDesign, contact_point, contact_state, drive_contact, tilt_angle

__all__ = ["revolve_deviation", "ratio_table_csv", "plot_ratio", "plot_drive", "write_dxf", "ASSEMBLY_MATERIALS",
           "assembly_scene", "display_colours", "HarmonicPlacement", "place_harmonic",
           "write_harmonic_html"]


def revolve_deviation(mesh: trimesh.Trimesh, profile: np.ndarray) -> float:
    """Largest distance (mm) of sampled face points (centroid and edge midpoints) from the
    closed (r, z) profile polygon the mesh revolves: the error of the revolution."""
    tri = mesh.vertices[mesh.faces]
    pts = np.concatenate([tri.mean(axis=1), 0.5 * (tri[:, 0] + tri[:, 1]), 0.5 * (tri[:, 1] + tri[:, 2]),
                          0.5 * (tri[:, 2] + tri[:, 0])])
    q = np.column_stack([np.hypot(pts[:, 0], pts[:, 1]), pts[:, 2]])
    distance = point_segment_distance(q[:, None, :], profile[None], np.roll(profile, -1, axis=0)[None])
    return float(distance.min(axis=1).max())


def ratio_table_csv(table: list[dict[str, Any]]) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(table[0]), lineterminator="\n")
    w.writeheader()
    for row in table:
        w.writerow({k: repr(v) if isinstance(v, float) else csv_field(v) for k, v in row.items()})
    return buf.getvalue()


def plot_ratio(d: HarmonicDesign, out: Path) -> list[str]:
    from prs_geom.exports.plots import plt, save_figure

    a = np.linspace(d.positions.min_mm, d.positions.max_mm, 400)
    st = contact_state(d, a)
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    ax[0].semilogy(a, st["ratio"])
    ax[0].set_xlabel("position a of the cone's small end (mm)")
    ax[0].set_ylabel("ratio i = r0 / Delta")
    ax[0].grid(alpha=0.3, which="both")
    ax[1].plot(a, st["radius_difference_mm"] * 1e3)
    ax[1].set_xlabel("position a (mm)")
    ax[1].set_ylabel("radius difference Delta (um)")
    ax[1].grid(alpha=0.3)
    fig.suptitle(f"{mpl_text(d.name)}: stepless harmonic friction drive")
    return save_figure(fig, out, "ratio")


def plot_drive(d: HarmonicDesign, out: Path) -> list[str]:
    """``drive.png/.svg``: the arrangement sketch (the axial half-section at the last drawing
    position, drawn from the model: the tilted flexspline generatrix with its contact arc, the
    conical bore, the wave generator, which member is fixed and which is the output), the
    flexspline's wall bending stress against each reference material's allowed stress, and the
    torque capacity and Hertz pressure over the travel."""
    from prs_geom.exports.plots import plt, save_figure
    from prs_geom.harmonic.drive import FLEXSPLINE_MATERIALS
    from prs_geom.harmonic.model import drive_load, flexspline_stress

    fig, ax = plt.subplots(1, 3, figsize=(15, 4.6))
    _sketch(d, ax[0])
    a = np.linspace(d.positions.min_mm, d.positions.max_mm, 200)
    f = d.flexspline
    for k, (key, mat) in enumerate(FLEXSPLINE_MATERIALS.items()):
        sigma = flexspline_stress(d, a, mat)
        ax[1].semilogy(a, sigma, color=f"C{k}", label=f"{key}: wall stress")
        ax[1].axhline(mat.allowed_bending_stress_mpa, color=f"C{k}", ls="--", label=f"{key}: allowed")
    ax[1].set_xlabel("position a (mm)")
    ax[1].set_ylabel("flexspline bending stress (MPa)")
    rule = "2 E t W / (r0 + L)^2, W = L sin(beta)" if d.arrangement.is_disc else "3 E t Delta / (2 r0^2)"
    ax[1].set_title(f"wall {f.wall_thickness_mm:g} mm, sigma = {rule}", fontsize=9)
    ax[1].grid(alpha=0.3, which="both")
    ax[1].legend(fontsize=7)
    st = contact_state(d, a)
    load = drive_load(d, st)
    ax[2].plot(a, load.output_torque_nm, color="C0", label="output torque (N m)")
    ax[2].set_xlabel("position a (mm)")
    ax[2].set_ylabel("output torque (N m)")
    ax[2].set_ylim(0.0, 1.2 * float(load.output_torque_nm.max()))
    p = ax[2].twinx()
    p.plot(a, load.max_pressure_mpa, color="C3", label="Hertz pressure (MPa)")
    p.plot(a[~load.hertz_valid], load.max_pressure_mpa[~load.hertz_valid], color="C3", lw=3, alpha=0.4,
           label="Hertz not valid (upper estimate)")
    p.set_ylabel("Hertz pressure (MPa)")
    ax[2].set_title(f"pressing {d.drive.pressing_force_n:g} N, mu {d.drive.friction_coefficient:g}, "
                    f"S {d.drive.slip_safety_factor:g}", fontsize=9)
    ax[2].grid(alpha=0.3)
    h1, l1 = ax[2].get_legend_handles_labels()
    h2, l2 = p.get_legend_handles_labels()
    ax[2].legend(h1 + h2, l1 + l2, fontsize=7, loc="center left")
    fig.suptitle(f"{mpl_text(d.name)}: arrangement, strength and torque")
    fig.tight_layout()
    return save_figure(fig, out, "drive")


def _sketch(d: HarmonicDesign, ax: Any) -> None:
    """The arrangement sketch on ``ax``: the drive's half-section, z along the axis, rho the
    distance from it (mm); the working section drawn through the arrangement's map
    (:mod:`prs_geom.harmonic.arrangement`)."""
    f, c = d.flexspline, d.circular_spline
    arr = d.arrangement
    a = d.positions.drawing_mm[-1]
    if arr.kind == "sealed":
        _sealed_sketch(d, ax, a)
        return
    beta = float(tilt_angle(d, a))
    L, r0 = f.length_mm, f.neutral_radius_mm

    def draw(x: Any, r: Any) -> tuple[Any, Any]:
        rho, z = arr.to_drive(x, r)
        return z, rho

    # flexspline: the bottom diaphragm to the axis (the disc's clamp), the generatrix tilted
    # by beta about A = (0, r0)
    end = (L * math.cos(beta), r0 + L * math.sin(beta))
    if arr.is_disc:
        ax.plot(*draw([0.0, 0.0], [r0 - 3.0, r0 + 3.0]), color="k", lw=3)
    else:
        ax.plot([0.0, 0.0], [0.0, r0], color="C0", lw=2)
    ax.plot(*draw([0.0, end[0]], [r0, end[1]]), color="C0", lw=2, label="flexspline")
    cx, cr = contact_point(d, a)
    centre = (d.x_s * math.cos(beta) + f.arc_centre_offset_mm * math.sin(beta),
              r0 + d.x_s * math.sin(beta) - f.arc_centre_offset_mm * math.cos(beta))
    # the contact arc around its contact point, which lies at 90 deg + alpha from the centre
    psi = 0.5 * math.pi + d.alpha + np.radians(np.linspace(-60.0, 60.0, 41))
    ax.plot(*draw(centre[0] + f.arc_radius_mm * np.cos(psi), centre[1] + f.arc_radius_mm * np.sin(psi)),
            color="C0", lw=2)
    # circular spline: the ring with its conical wall (the end face's ring keeps its radial
    # place and moves along the axis: the same face line)
    x0 = cone_start(d, a)
    shift = circular_spline_placement(d, a) if arr.is_disc else 0.0
    ring = np.array([[x0, c.bore_small_radius_mm], [x0, c.outer_radius_mm],
                     [x0 + c.bore_length_mm, c.outer_radius_mm], [x0 + c.bore_length_mm, c.bore_large_radius_mm],
                     [x0, c.bore_small_radius_mm]])
    fixed = d.drive.fixed_member
    rz, rr = draw(ring[:, 0], ring[:, 1])
    ax.fill(rz + shift, rr, facecolor="0.85" if fixed == "circular_spline" else "none",
            edgecolor="C1", hatch="///" if fixed == "circular_spline" else None, lw=1.5, label="circular spline")
    # wave generator under the working section's open end
    gx = end[0] - 0.5 * f.arc_radius_mm
    ax.fill(*draw([gx - 6.0, gx + 6.0, gx + 6.0, gx - 6.0], [0.0, 0.0, r0 - 2.0, r0 - 2.0]), facecolor="C2",
            alpha=0.25, edgecolor="C2", label="wave generator (input)")
    ax.plot(*draw([cx], [cr]), "o", color="C3", ms=5, label=f"contact, a = {a:g} mm")
    ax.autoscale()
    _finish_sketch(d, ax, f"{arr.kind.replace('_', ' ')}: ", "cone")


def _finish_sketch(d: HarmonicDesign, ax: Any, lead: str, cone: str) -> None:
    """The sketch's title (fixed member, output, cone angle), axis labels, scale and legend."""
    fixed = d.drive.fixed_member
    out = "flexspline" if fixed == "circular_spline" else "circular spline"
    ax.set_title(f"{lead}{fixed.replace('_', ' ')} fixed (hatched), {out} output; {cone} "
                 f"{math.degrees(d.alpha):.3f} deg", fontsize=9)
    ax.set_xlabel("z along the axis (mm)")
    ax.set_ylabel("distance from the axis (mm)")
    ax.set_aspect("equal")
    ax.set_ylim(bottom=0.0)
    ax.legend(fontsize=7, loc="lower left")


def _dxf_position_note(d: HarmonicDesign, blk: Any, a: float, beta: float) -> None:
    """The axis line, the contact point and the position's numbers in a DXF block."""
    f, c = d.flexspline, d.circular_spline
    blk.add_line((-5.0, 0.0), (f.length_mm + 5.0, 0.0), dxfattribs={"layer": "CENTRE"})
    st = contact_state(d, a)
    # the contact in the drive frame (the section's own for the published and sealed drives)
    hit = drive_contact(d, a)
    px, pr = float(hit.contact_z_mm), float(hit.contact_rho_mm)
    top = max(c.outer_radius_mm, f.neutral_radius_mm + f.length_mm) if d.arrangement.is_disc else c.outer_radius_mm
    blk.add_text(f"a = {a:g} mm, beta = {math.degrees(beta):.5f} deg, contact r = {float(st['contact_radius_mm']):.4f}, "
                 f"Delta = {float(st['radius_difference_mm']):.5f} mm, i = {float(st['ratio']):.1f}",
                 height=1.5, dxfattribs={"layer": "ANNOTATION"}).set_placement((0.0, top + 2.0))
    blk.add_point((px, pr), dxfattribs={"layer": "ANNOTATION"})


def _mapped_section(d: HarmonicDesign, blk: Any, a: float, beta: float) -> None:
    """The outer-wave and end-face drives' section in the drive frame (x along the axis, y
    the distance from it): the tilted generatrix (LINE), the contact arc +-30 deg about the
    contact (LWPOLYLINE of its mapped points) and the circular spline's cone wall (LINE; the
    end face's ring at its radial place, :func:`~prs_geom.harmonic.assembly.face_reference_position`)."""
    f, c, arr = d.flexspline, d.circular_spline, d.arrangement
    r0 = f.neutral_radius_mm

    def to_dxf(x: Any, r: Any) -> list[tuple[float, float]]:
        rho, z = arr.to_drive(np.atleast_1d(x), np.atleast_1d(r))
        return [(float(zz), float(rr)) for zz, rr in zip(z, rho)]

    g = np.array([math.cos(beta), math.sin(beta)])
    nrm = np.array([-math.sin(beta), math.cos(beta)])
    A = np.array([0.0, r0])
    C = A + d.x_s * g - f.arc_centre_offset_mm * nrm
    end = A + d.x_s * g
    blk.add_line(*to_dxf([A[0], end[0]], [A[1], end[1]]), dxfattribs={"layer": "PROFILE"})
    psi = math.pi / 2 + d.alpha + np.radians(np.linspace(-30.0, 30.0, 61))
    blk.add_lwpolyline(to_dxf(C[0] + f.arc_radius_mm * np.cos(psi), C[1] + f.arc_radius_mm * np.sin(psi)),
                       dxfattribs={"layer": "PROFILE"})
    x0 = cone_start(d, a)
    xs = np.array([x0, x0 + c.bore_length_mm])
    blk.add_line(*to_dxf(xs, c.bore_small_radius_mm + (xs - a) * math.tan(d.alpha)), dxfattribs={"layer": "PROFILE"})


def _sealed_profiles(d: HarmonicDesign, a: float) -> tuple[np.ndarray, np.ndarray]:
    """The sealed drive's half-section at position a (mm) in the drive frame, as (rho, z)
    polygons: the flexspline's (the conical cup turned by beta about A, the major axis's
    meridian) and the circular spline's (the ridged ring placed with its arc's centre at a)."""
    from prs_geom.harmonic.assembly import tilt_meridian

    prof = flexspline_profile(d)
    rho, z = tilt_meridian(d, prof[:, 0], prof[:, 1], float(tilt_angle(d, a)))
    flex = np.column_stack([rho, z])
    flex[[0, -1], 0] = 0.0                     # the bottom's axis points stay on the axis
    ring = circular_spline_profile(d) + np.array([0.0, circular_spline_placement(d, a)])
    return flex, ring


def _sealed_sketch(d: HarmonicDesign, ax: Any, a: float) -> None:
    """The sealed drive's sketch: the tilted conical flexspline, the ridged circular spline
    (the output, hatched when fixed), the generator under the contact, z along the axis."""
    flex, ring = _sealed_profiles(d, a)
    fixed = d.drive.fixed_member
    ax.fill(flex[:, 1], flex[:, 0], facecolor="0.85" if fixed == "flexspline" else "none", edgecolor="C0",
            hatch="///" if fixed == "flexspline" else None, lw=1.5, label="flexspline (cone, on the bellows)")
    ax.fill(ring[:, 1], ring[:, 0], facecolor="0.85" if fixed == "circular_spline" else "none", edgecolor="C1",
            hatch="///" if fixed == "circular_spline" else None, lw=1.5, label="circular spline (working arc)")
    cx, cr = contact_point(d, a)
    ax.fill([cx - 6.0, cx + 6.0, cx + 6.0, cx - 6.0], [0.0, 0.0, d.flexspline.neutral_radius_mm - 3.0,
                                                     d.flexspline.neutral_radius_mm - 3.0],
            facecolor="C2", alpha=0.25, edgecolor="C2", label="wave generator (input)")
    ax.plot([cx], [cr], "o", color="C3", ms=5, label=f"contact, a = {a:g} mm")
    _finish_sketch(d, ax, "sealed: ", "flexspline cone")


def write_dxf(d: HarmonicDesign, path: Path) -> None:
    """Axial section (major axis) at each position of ``positions.drawing_mm``: the tilted
    flexspline generatrix (LINE, neutral layer) with its contact ARC, and the cone bore
    (LINE); one named block per position (``POSITION_<k>``), x from the flexspline bottom
    along the axis, y the distance from it, in the drive frame of the arrangement (the
    outer-wave and end-face sections mapped, :func:`_mapped_section`; the sealed drive's
    outlines, :func:`_sealed_profiles`)."""
    doc = ezdxf.new("R2010", setup=True)
    doc.units = units.MM
    doc.header["$INSUNITS"] = 4
    for name, color, lt in (("PROFILE", 7, "Continuous"), ("CENTRE", 1, "CENTER"), ("ANNOTATION", 2, "Continuous")):
        doc.layers.add(name, color=color, linetype=lt)
    msp = doc.modelspace()
    f, c = d.flexspline, d.circular_spline
    for k, a in enumerate(d.positions.drawing_mm):
        beta = float(tilt_angle(d, a))
        blk = doc.blocks.new(f"POSITION_{k}")
        r0 = f.neutral_radius_mm
        if d.drive.arrangement == "sealed":
            # the half-section's outlines, x along the axis, r up (LWPOLYLINE each)
            for poly in _sealed_profiles(d, a):
                blk.add_lwpolyline([(float(q[1]), float(q[0])) for q in poly], close=True,
                                   dxfattribs={"layer": "PROFILE"})
            _dxf_position_note(d, blk, a, beta)
            msp.add_blockref(blk.name, (0.0, k * (c.outer_radius_mm + 15.0)))
            continue
        if d.drive.arrangement != "radial_inner":
            _mapped_section(d, blk, a, beta)
            _dxf_position_note(d, blk, a, beta)
            msp.add_blockref(blk.name, (0.0, k * (c.outer_radius_mm + 15.0)))
            continue
        g = np.array([math.cos(beta), math.sin(beta)])
        nrm = np.array([-math.sin(beta), math.cos(beta)])
        A = np.array([0.0, r0])
        C = A + d.x_s * g - f.arc_centre_offset_mm * nrm
        blk.add_line(tuple(A), tuple(A + d.x_s * g), dxfattribs={"layer": "PROFILE"})
        # contact arc: +-30 deg about the contact direction (normal of the cone wall)
        ang = math.degrees(math.pi / 2 + d.alpha)
        blk.add_arc(tuple(C), f.arc_radius_mm, ang - 30.0, ang + 30.0, dxfattribs={"layer": "PROFILE"})
        blk.add_line((a, c.bore_small_radius_mm), (a + c.bore_length_mm, c.bore_large_radius_mm),
                     dxfattribs={"layer": "PROFILE"})
        _dxf_position_note(d, blk, a, beta)
        msp.add_blockref(blk.name, (0.0, k * (c.outer_radius_mm + 15.0)))
    msp.add_text(f"{dxf_text(d.name)}: harmonic friction drive, axial sections at {list(d.positions.drawing_mm)} mm; "
                 "units mm",
                 height=2.0, dxfattribs={"layer": "ANNOTATION"}).set_placement((0.0, -10.0))
    # $EXTMIN/$EXTMAX: the real model-space extents (block references included), which CAD
    # "zoom extents" and viewers read; ezdxf leaves them at their empty-drawing sentinels
    from ezdxf import bbox

    ext = bbox.extents(msp)
    msp.dxf.extmin, msp.dxf.extmax = tuple(ext.extmin), tuple(ext.extmax)
    doc.header["$EXTMIN"], doc.header["$EXTMAX"] = msp.dxf.extmin, msp.dxf.extmax
    save_dxf(doc, path)


# --------------------------------------------------------------------------- placed assembly
#: Part materials of the placed assembly (linear RGB, PBR): ring steel, a blued spring-steel
#: flexspline, a bronze-coloured wave generator; the viewer uses their sRGB colours.
ASSEMBLY_MATERIALS: dict[str, Material] = {
    "circular_spline": Material("circular spline steel", (0.40, 0.43, 0.48, 1.0), 0.85, 0.35),
    "flexspline": Material("flexspline spring steel", (0.16, 0.30, 0.55, 1.0), 0.80, 0.30),
    "wave_generator": Material("wave generator bronze", (0.62, 0.36, 0.12, 1.0), 0.75, 0.40),
}


def assembly_scene(asm: Any) -> Scene:
    """The :class:`~prs_geom.exports.scene.Scene` of a placed
    :class:`~prs_geom.harmonic.assembly.HarmonicAssembly`: one mesh, one material and one
    top-level node per part (named as the part), placed by its rigid transform (mm)."""
    meshes, nodes = {}, []
    for name, (mesh, T) in asm.parts.items():
        meshes[name] = SceneMesh(name, np.asarray(mesh.vertices, dtype=np.float64),
                                 np.asarray(mesh.faces, dtype=np.int64), name)
        nodes.append(SceneNode(name, name, np.asarray(T, dtype=np.float64)))
    return Scene(meshes, {k: ASSEMBLY_MATERIALS[k] for k in meshes}, tuple(nodes),
                 f"{asm.design.name} at a = {asm.position_mm:g} mm")


def display_colours() -> dict[str, str]:
    """Part -> ``#rrggbb`` (sRGB) of :data:`ASSEMBLY_MATERIALS`, for the report's viewer."""
    return {k: m.srgb_hex[:7].lower() for k, m in ASSEMBLY_MATERIALS.items()}


@dataclass(frozen=True)
class HarmonicPlacement:
    """What :func:`place_harmonic` placed, checked and wrote.

    ``assembly``: report.json's ``assembly`` section (placement, wave generator, mesh checks
    of the placed parts); ``checks``: its ``checks.assembly`` section (contact gap,
    clearances, interference); ``warnings``: one line per check past its tolerance;
    ``files``: the files written, relative to the output folder; ``assembly_model``: the
    placed :class:`~prs_geom.harmonic.assembly.HarmonicAssembly`.
    """

    assembly: dict[str, Any]
    checks: dict[str, Any]
    warnings: tuple[str, ...]
    files: tuple[str, ...]
    assembly_model: Any


def place_harmonic(design: HarmonicDesign, out_dir: Path, *, position_mm: float | None = None) -> HarmonicPlacement:
    """Place the drive at ``position_mm`` (mm; default the middle of the control range,
    :func:`prs_geom.harmonic.assembly.default_position`), check it and write
    ``flexspline_placed.stl``, ``wave_generator.stl``, ``assembly.glb`` and ``assembly.3mf``
    into ``out_dir`` (which exists)."""
    from prs_geom.exports.meshes import stl_header, write_stl
    from prs_geom.exports.scene import write_3mf, write_glb
    from prs_geom.harmonic.assembly import assembly_checks, assembly_summary, build_assembly
    from prs_geom.model.io import design_hash

    out = Path(out_dir)
    asm = build_assembly(design, position_mm)
    summary = assembly_summary(asm)
    checks = assembly_checks(asm)
    warnings = [f"mesh check ({row['part']}, placed): {w}" for row in summary["meshes"] for w in row["warnings"]]
    warnings += [f"assembly check: {w}" for w in checks["warnings"]]
    h = design_hash(design)
    files = []
    for name, file, frame in (("flexspline", "flexspline_placed.stl", "assembly frame"),
                              ("wave_generator", "wave_generator.stl", "part frame")):
        label = "flexspline placed" if name == "flexspline" else "wave generator"
        write_stl(asm.parts[name][0], out / file, stl_header(label, h, frame))
        files.append(file)
    scene = assembly_scene(asm)
    write_glb(scene, out / "assembly.glb")
    write_3mf(scene, out / "assembly.3mf")
    files += ["assembly.glb", "assembly.3mf"]
    return HarmonicPlacement(assembly=summary, checks=checks, warnings=tuple(warnings), files=tuple(files),
                             assembly_model=asm)


def write_harmonic_html(design: HarmonicDesign, out_dir: Path, report: dict[str, Any], placement: HarmonicPlacement,
                        date: str, version: str) -> str:
    """Write ``report.html`` of a harmonic build from its ``report`` (report.json's content)
    and the placed drive; returns the file name. ``ratio.svg`` is read from ``out_dir``
    when the harmonic stage wrote it (else the plot is rendered again, to a temporary
    folder). ``date``, ``version``: build date (ISO) and prs_geom version, for provenance."""
    import tempfile

    from prs_geom.harmonic.assembly import build_assembly
    from prs_geom.harmonic.report import DISPLAY_TOLERANCE_MM, write_report_html

    out = Path(out_dir)
    texts = []
    for stem, plot in (("ratio", plot_ratio), ("drive", plot_drive)):
        svg = out / f"{stem}.svg"
        if svg.is_file():
            texts.append(svg.read_text(encoding="utf-8"))
        else:
            with tempfile.TemporaryDirectory() as tmp:
                plot(design, Path(tmp))
                texts.append((Path(tmp) / f"{stem}.svg").read_text(encoding="utf-8"))
    svg_text = texts[0]
    asm = placement.assembly_model
    view = build_assembly(design, asm.position_mm, max(DISPLAY_TOLERANCE_MM, asm.tolerance_mm))
    write_report_html(out / "report.html", design, report, view, display_colours(), svg_text, date, version,
                      drive_svg=texts[1])
    return "report.html"
