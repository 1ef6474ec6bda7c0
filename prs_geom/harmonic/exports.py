"""Exports of the harmonic friction drive: ratio plot, CSV table, DXF axial section at
chosen positions, STL meshes of the cone-bored circular spline and the flexspline cup.

Meshes are solids of revolution of the undeformed parts (each in its own frame, z along
the axis, mm): the circular spline is a ring whose bore is the cone (radius b1 at z = 0 to
b2 at z = H); the flexspline is a cup (bottom at z = 0) of wall thickness t about the
neutral radius with, at its open end, the contact bulge: the arc of radius r_s centred at
radius r0 - c_s, height x_s = L - r_s, between the outer and the inner wall. Arcs are
sampled with half the chordal tolerance as chord sagitta and the revolution with the
other half; the revolution error is measured (:func:`revolve_deviation`) and reported with
the arc-chord bound.
"""
from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any

import ezdxf
import numpy as np
import trimesh
from ezdxf import units

from prs_geom.exports.dxf import save_dxf
from prs_geom.harmonic.model import HarmonicDesign, contact_point, contact_state, tilt_angle


def _sections(radius: float, tol: float) -> int:
    return max(24, int(math.ceil(math.pi / math.acos(1.0 - tol / radius))))


def circular_spline_mesh(d: HarmonicDesign) -> trimesh.Trimesh:
    prof = circular_spline_profile(d)
    closed = np.concatenate([prof, prof[:1]])
    return trimesh.creation.revolve(closed, sections=_sections(d.circular_spline.outer_radius_mm,
                                                              d.mesh.chord_tolerance_mm))


def flexspline_profile(d: HarmonicDesign) -> np.ndarray:
    """Closed (r, z) polygon of the cup's half section, counter-clockwise."""
    f = d.flexspline
    tol = d.mesh.chord_tolerance_mm
    r0, t, rs, cs = f.neutral_radius_mm, f.wall_thickness_mm, f.arc_radius_mm, f.arc_centre_offset_mm
    ro, ri = r0 + 0.5 * t, r0 - 0.5 * t
    cr, cz = r0 - cs, d.x_s
    if cr + rs <= ro:
        raise ValueError("the contact arc does not bulge beyond the outer wall")
    # arc from the outer wall (lower junction) over the bulge to the inner wall (upper junction)
    th0 = -math.acos((ro - cr) / rs)              # below the centre, on the outer wall
    th1 = math.acos((ri - cr) / rs) if abs(ri - cr) < rs else math.pi / 2
    dth = 2 * math.acos(1 - 0.5 * tol / rs)   # half the tolerance for the arc chords
    th = np.linspace(th0, th1, max(8, int(math.ceil((th1 - th0) / dth)) + 1))
    arc = np.column_stack([cr + rs * np.cos(th), cz + rs * np.sin(th)])
    pts = [[0.0, 0.0], [ro, 0.0], *arc.tolist(), [ri, t], [0.0, t]]
    return np.array(pts)


def circular_spline_profile(d: HarmonicDesign) -> np.ndarray:
    c = d.circular_spline
    return np.array([[c.bore_small_radius_mm, 0.0], [c.outer_radius_mm, 0.0],
                     [c.outer_radius_mm, c.bore_length_mm], [c.bore_large_radius_mm, c.bore_length_mm]])


def revolve_deviation(mesh: trimesh.Trimesh, profile: np.ndarray) -> float:
    """Largest distance (mm) of sampled face points (centroid and edge midpoints) from the
    closed (r, z) profile polygon the mesh revolves: the error of the revolution."""
    tri = mesh.vertices[mesh.faces]
    pts = np.concatenate([tri.mean(axis=1), 0.5 * (tri[:, 0] + tri[:, 1]), 0.5 * (tri[:, 1] + tri[:, 2]),
                          0.5 * (tri[:, 2] + tri[:, 0])])
    q = np.column_stack([np.hypot(pts[:, 0], pts[:, 1]), pts[:, 2]])
    a, b = profile, np.roll(profile, -1, axis=0)
    ab = b - a
    t = np.clip(np.einsum("nsd,sd->ns", q[:, None, :] - a[None], ab) / np.einsum("sd,sd->s", ab, ab), 0, 1)
    foot = a[None] + t[..., None] * ab[None]
    return float(np.linalg.norm(q[:, None, :] - foot, axis=2).min(axis=1).max())


def flexspline_mesh(d: HarmonicDesign) -> trimesh.Trimesh:
    prof = flexspline_profile(d)
    # trimesh.revolve wants a line that is closed or touches the axis; our polygon touches it
    return trimesh.creation.revolve(prof, sections=_sections(float(prof[:, 0].max()), 0.5 * d.mesh.chord_tolerance_mm))


def ratio_table_csv(table: list[dict[str, Any]]) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(table[0]), lineterminator="\n")
    w.writeheader()
    for row in table:
        w.writerow({k: repr(v) if isinstance(v, float) else v for k, v in row.items()})
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
    fig.suptitle(f"{d.name}: stepless harmonic friction drive")
    return save_figure(fig, out, "ratio")


def write_dxf(d: HarmonicDesign, path: Path) -> None:
    """Axial section (major axis) at each position of ``positions.drawing_mm``: the tilted
    flexspline generatrix (LINE, neutral layer) with its contact ARC, and the cone bore
    (LINE); one named block per position (``POSITION_<k>``), x from the flexspline bottom."""
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
        blk.add_line((-5.0, 0.0), (f.length_mm + 5.0, 0.0), dxfattribs={"layer": "CENTRE"})
        px, pr = contact_point(d, a)
        st = contact_state(d, a)
        blk.add_text(f"a = {a:g} mm, beta = {math.degrees(beta):.5f} deg, contact r = {float(st['contact_radius_mm']):.4f}, "
                     f"Delta = {float(st['radius_difference_mm']):.5f} mm, i = {float(st['ratio']):.1f}",
                     height=1.5, dxfattribs={"layer": "ANNOTATION"}).set_placement((0.0, c.outer_radius_mm + 2.0))
        blk.add_point((px, pr), dxfattribs={"layer": "ANNOTATION"})
        msp.add_blockref(blk.name, (0.0, k * (c.outer_radius_mm + 15.0)))
    msp.add_text(f"{d.name}: harmonic friction drive, axial sections at {list(d.positions.drawing_mm)} mm; units mm",
                 height=2.0, dxfattribs={"layer": "ANNOTATION"}).set_placement((0.0, -10.0))
    save_dxf(doc, path)
