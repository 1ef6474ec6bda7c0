"""The harmonic drive's arrangements (issue 35): radial inner wave (published), radial outer
wave and end face, each the working section placed in the drive by a rigid map
(docs/theory/harmonic.md, "Arrangements")."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

import prs_geom as pg
from prs_geom.harmonic.arrangement import Arrangement
from prs_geom.harmonic.assembly import assembly_checks, build_assembly, measured_ratio, mesh_rows
from prs_geom.harmonic.drive import disc_wave_stress
from prs_geom.harmonic.model import contact_state, drive_contact, ratio_table, strength_section, tilt_angle
from prs_geom.model.errors import DesignError

POSITIONS = (42.0, 58.0, 74.0)


EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def arranged(kind: str, **changes) -> pg.HarmonicDesign:
    """The published section in arrangement ``kind``; the sealed drive from its example."""
    if kind == "sealed":
        from prs_geom.pipeline import load_any_design

        return load_any_design(EXAMPLES / "harmonic-sealed.toml")
    d = pg.HarmonicDesign()
    return dataclasses.replace(d, drive=dataclasses.replace(d.drive, arrangement=kind, **changes))


def _turn(point, pivot, angle):
    """An independent 2-D rotation (a rotation matrix) of ``point`` about ``pivot``."""
    c, s = math.cos(angle), math.sin(angle)
    v = np.asarray(point, float) - pivot
    return pivot + np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def test_the_published_arrangement_is_the_closed_form():
    """The arrangement's contact (generic: arc centre turned about A, then mapped) for the
    radial inner-wave drive equals the closed-form section model bit for bit, and the
    published numbers stand (545.0, 963.6, 4155.1; 53.773 / 0.0519, 53.772 / 0.0120)."""
    d = pg.HarmonicDesign()
    a = np.linspace(42.0, 74.0, 33)
    f = d.flexspline
    beta = tilt_angle(d, a)
    phi = d.alpha - beta
    r_c = f.neutral_radius_mm - f.arc_centre_offset_mm + f.arc_radius_mm * np.cos(phi)
    R_c = (f.neutral_radius_mm + d.x_s * np.sin(beta) - f.arc_centre_offset_mm * np.cos(beta)
           + f.arc_radius_mm * math.cos(d.alpha))
    st = contact_state(d, a)
    assert np.array_equal(st["radius_difference_mm"], R_c - r_c)
    assert np.array_equal(st["ratio"], f.neutral_radius_mm / (R_c - r_c))
    got = contact_state(d, [73.0, 73.5, 74.0])
    assert np.round(got["ratio"], 1).tolist() == [545.0, 963.6, 4155.1]
    assert np.round(got["contact_radius_mm"][1:], 3).tolist() == [53.773, 53.772]
    assert np.round(got["radius_difference_mm"][1:], 4).tolist() == [0.0519, 0.0120]


def test_outer_wave_is_the_mirror_image_with_the_opposite_sense():
    """Mirrored about the neutral layer: the same |ratio| at every position, Delta negative
    (the flexspline's circle is the longer one), so with the circular spline fixed the
    flexspline turns with the generator (+r0/|Delta|) and with the flexspline fixed the
    circular spline turns against it, one less in magnitude (Willis, written out here)."""
    inner, outer = pg.HarmonicDesign(), arranged("radial_outer")
    a = np.linspace(42.0, 74.0, 17)
    si, so = contact_state(inner, a), contact_state(outer, a)
    assert np.allclose(so["ratio"], si["ratio"], rtol=1e-12)
    assert np.allclose(so["radius_difference_mm"], -si["radius_difference_mm"], rtol=1e-12)
    r0 = outer.flexspline.neutral_radius_mm
    # the contact radius of the mirrored section: 2 r0 - R_c
    assert np.allclose(so["cone_radius_mm"], 2 * r0 - si["cone_radius_mm"], atol=1e-12)
    rows = ratio_table(outer, a)
    delta = np.abs(si["radius_difference_mm"])
    # Willis with r_f = r0, r_c = r0 - |Delta|: w_g / w_f = r_f / (r_f - r_c) and w_g / w_c = r_c / (r_c - r_f)
    assert np.allclose([r["ratio_circular_spline_fixed"] for r in rows], r0 / delta, rtol=1e-12)
    assert np.allclose([r["ratio_flexspline_fixed"] for r in rows], -(r0 - delta) / delta, rtol=1e-12)
    assert all(r["ratio_circular_spline_fixed"] > 0 > r["ratio_flexspline_fixed"] for r in rows)


def test_end_face_contact_by_an_independent_construction():
    """The end face built directly in the drive frame: the disc (clamp A = (rho r0, z 0)),
    its rim arc centre turned about A by the tilt, the conical face (half-angle 90 deg -
    alpha) moved along the axis by the face travel. The arc touches the face there (distance
    of the centre from the face line = r_s to 1e-9 mm), and Delta is the radial shift of the
    contact's material point under that turn."""
    d = arranged("end_face")
    f = d.flexspline
    r0, rs = f.neutral_radius_mm, f.arc_radius_mm
    c = d.circular_spline
    a_ref = 58.0
    for a in POSITIONS:
        beta = float(tilt_angle(d, a))
        A = np.array([r0, 0.0])
        # the disc's arc centre (rho, z) before the turn, and the turn that lifts the rim to +z
        centre = _turn([r0 + d.x_s, -f.arc_centre_offset_mm], A, beta)
        # the face line through its inner corner, at the reference place moved by the travel
        travel = -(a - a_ref) * math.tan(d.alpha)
        p0 = np.array([r0 + a_ref, c.bore_small_radius_mm - r0 + travel])
        u = np.array([math.cos(d.alpha), math.sin(d.alpha)])
        v = centre - p0
        dist = abs(v[0] * u[1] - v[1] * u[0])
        assert dist == pytest.approx(rs, abs=1e-9)
        # the contact point: from the centre along the face's normal, toward the face
        n = np.array([-u[1], u[0]])
        n = n if np.dot(p0 - centre, n) > 0 else -n
        contact = centre + rs * n
        material = _turn(contact, A, -beta)
        got = drive_contact(d, a)
        assert float(got.contact_rho_mm) == pytest.approx(contact[0], abs=1e-9)
        assert float(got.contact_z_mm) == pytest.approx(contact[1], abs=1e-9)
        assert float(got.radius_difference_mm) == pytest.approx(contact[0] - material[0], abs=1e-9)
        assert float(got.ratio) == pytest.approx(material[0] / abs(contact[0] - material[0]), rel=1e-9)
    # the disc's circle is the longer one: the flexspline turns with the generator
    rows = ratio_table(d, POSITIONS)
    assert all(r["radius_difference_mm"] < 0 < r["ratio_circular_spline_fixed"] for r in rows)
    # the adjusting mechanism moves the face along the axis: tan(alpha) per mm of a
    assert rows[-1]["circular_spline_travel_mm"] == pytest.approx(-32.0 * math.tan(d.alpha), rel=1e-12)
    assert rows[-1]["adjusting_turns"] == pytest.approx(32.0 * math.tan(d.alpha) / d.drive.adjusting_travel_per_turn_mm)


def test_arrangement_maps_are_rigid_and_invertible():
    rng = np.random.default_rng(5)
    x, r = rng.uniform(0, 100, 50), rng.uniform(30, 70, 50)
    for kind in ("radial_inner", "radial_outer", "end_face"):
        m = Arrangement(kind, 50.0)
        rho, z = m.to_drive(x, r)
        back = m.to_section(rho, z)
        assert np.allclose(back[0], x, atol=1e-12) and np.allclose(back[1], r, atol=1e-12)
        # distances kept
        dd = np.hypot(np.diff(rho), np.diff(z))
        assert np.allclose(dd, np.hypot(np.diff(x), np.diff(r)), rtol=1e-12)


def test_disc_wave_stress_is_the_ring_curvature_change():
    """2 E t W / r^2 against the numerical curvature change w'' / r^2 of w = W cos(2 theta)
    on a ring of radius r (second difference), times E t / 2."""
    E, t, W, r = 206e3, 1.0, 0.7, 120.0
    h = 1e-4
    w = lambda th: W * math.cos(2 * th)  # noqa: E731
    curvature = abs(w(h) - 2 * w(0.0) + w(-h)) / h ** 2 / r ** 2
    assert float(disc_wave_stress(W, r, t, E)) == pytest.approx(E * 0.5 * t * curvature, rel=1e-6)


def test_strength_per_arrangement():
    """Outer wave: the thin-ring limit of the published drive (steel smallest ratio 20.6,
    PA66 3.6, as the source's 'about 20' and 'below 10'). End face: the rim's out-of-plane
    bending at the largest allowed tilt, whose ratio is the section's at that tilt."""
    outer = {r["material"]: r for r in strength_section(arranged("radial_outer"))}
    assert 15 < outer["steel"]["min_ratio"] < 30 and outer["pa66"]["min_ratio"] < 10
    d = arranged("end_face")
    f = d.flexspline
    face = {r["material"]: r for r in strength_section(d)}
    rim = f.neutral_radius_mm + f.length_mm
    beta = math.asin(300.0 * rim ** 2 / (2 * 206e3 * f.wall_thickness_mm) / f.length_mm)
    # the contact at that tilt, built with rotation matrices in the drive frame (rho, z):
    # the rim arc's centre turned about the clamp, the contact r_s from it along the face's
    # normal (the face leans alpha from the radial plane), its material point turned back
    A = np.array([f.neutral_radius_mm, 0.0])
    centre = _turn([f.neutral_radius_mm + d.x_s, -f.arc_centre_offset_mm], A, beta)
    contact = centre + f.arc_radius_mm * np.array([-math.sin(d.alpha), math.cos(d.alpha)])
    material = _turn(contact, A, -beta)
    expect = material[0] / abs(contact[0] - material[0])
    assert face["steel"]["min_ratio"] == pytest.approx(expect, rel=1e-9)
    assert face["steel"]["stress_at_min_position_mpa"] == pytest.approx(
        2 * 206e3 * f.wall_thickness_mm * f.length_mm * math.sin(float(tilt_angle(d, 42.0))) / rim ** 2, rel=1e-12)


@pytest.mark.parametrize("kind", ["radial_inner", "radial_outer", "end_face", "sealed"])
def test_placed_parts_never_overlap_at_three_positions(kind):
    """Each arrangement's placed meshes at the ends and the middle of the range: closed,
    within their chord tolerance, the parts clear or touching (never interfering), the
    flexspline's mesh on the model's contact point."""
    d = arranged(kind)
    for a in (d.positions.min_mm, 0.5 * (d.positions.min_mm + d.positions.max_mm), d.positions.max_mm):
        asm = build_assembly(d, a)
        checks = assembly_checks(asm)
        assert not checks["interference"]["found"], (kind, a, checks["interference"])
        assert {p["status"] for p in checks["interference"]["pairs"]} <= {"clear", "touching"}
        assert -1e-9 <= checks["contact_gap_mm"] <= asm.tolerance_mm
        assert checks["contact_offset_mm"] <= asm.tolerance_mm
        assert checks["wave_generator_clearance_min_mm"] >= -1e-9
        for row in mesh_rows(asm):
            assert row["watertight"] and row["max_deviation_mm"] <= asm.tolerance_mm, row


@pytest.mark.parametrize("kind,tol,positions", [
    ("radial_inner", 0.01, (42.0, 50.0, 58.0)),
    ("radial_outer", 0.01, (42.0, 50.0, 58.0)),
    ("end_face", 0.0015, (42.0,)),
    ("sealed", 0.01, (47.0, 55.0, 62.0)),
])
def test_ratio_measured_on_the_meshes_is_the_model_ratio(kind, tol, positions):
    """Where Delta is at least 100 chord tolerances, the ratio measured on the placed meshes
    (circumference difference at the contact from the circular spline's placed mesh and the
    undeformed flexspline's mesh) equals the model's within 1 %."""
    d = arranged(kind)
    for a in positions:
        m = measured_ratio(build_assembly(d, a, tol))
        assert m["resolved"], (kind, a, m)
        assert abs(m["relative_difference"]) < 0.01, (kind, a, m)
        assert np.sign(m["radius_difference_mm"]) == np.sign(m["model_radius_difference_mm"])


def test_unknown_arrangement_is_refused_with_the_rule():
    with pytest.raises(DesignError, match="must be one of radial_inner, radial_outer, end_face, sealed"):
        arranged("conical_both")


def test_sealed_contact_by_an_independent_construction():
    """The sealed drive built with rotation matrices: the conical flexspline's neutral line
    from A = (z 0, rho r0) at alpha_f, turned by the tilt about A; its outer wall t / 2 off it
    touches the working arc (centre at (a, rho_C)): the centre's distance from the turned
    outer line is r_s (1e-9 mm). Delta is the radial shift of the contact's material point
    under the turn; Delta = 0 exactly at the infinite-ratio position (beta = 0 there); with
    the flexspline fixed (the bellows) the circular spline turns with the generator."""
    from prs_geom.harmonic.model import infinite_ratio_position

    d = arranged("sealed")
    f, c = d.flexspline, d.circular_spline
    A = np.array([0.0, f.neutral_radius_mm])           # (z, rho)
    for a in (47.0, 60.0, 75.0, 80.0):
        beta = float(tilt_angle(d, a))
        u = _turn(A + [math.cos(d.alpha), math.sin(d.alpha)], A, beta) - A     # the turned generatrix
        n = np.array([-u[1], u[0]])
        outer_point = A + 0.5 * f.wall_thickness_mm * n
        centre = np.array([a, c.arc_centre_radius_mm])
        assert float(np.dot(centre - outer_point, n)) == pytest.approx(c.arc_radius_mm, abs=1e-9)
        contact = centre - c.arc_radius_mm * n
        material = _turn(contact, A, -beta)
        got = drive_contact(d, a)
        assert float(got.contact_z_mm) == pytest.approx(contact[0], abs=1e-9)
        assert float(got.radius_difference_mm) == pytest.approx(contact[1] - material[1], abs=1e-9)
        assert float(got.radius_difference_mm) > 0
    a_inf = infinite_ratio_position(d)
    assert float(tilt_angle(d, a_inf)) == pytest.approx(0.0, abs=1e-12)
    assert float(drive_contact(d, a_inf).radius_difference_mm) == pytest.approx(0.0, abs=1e-12)
    rows = ratio_table(d, (47.0, 80.0))
    assert all(r["ratio_flexspline_fixed"] > 0 > r["ratio_circular_spline_fixed"] for r in rows)
    # a flexspline without a cone is refused for the sealed drive, naming the field
    with pytest.raises(DesignError, match="cone_half_angle_deg"):
        dataclasses.replace(d, flexspline=dataclasses.replace(f, cone_half_angle_deg=0.0))


def _willis(r_f: float, r_c: float, fixed: str) -> float:
    """Generator over output speed from the rolling condition at the travelling contact,
    r_f (w_f - w_g) = r_c (w_c - w_g), solved as a 2x2 linear system with w_g = 1 and the
    fixed member's speed 0 (unknowns: the two members' speeds)."""
    A = np.array([[r_f, -r_c], [1.0, 0.0] if fixed == "flexspline" else [0.0, 1.0]])
    w_f, w_c = np.linalg.solve(A, [r_f - r_c, 0.0])
    return 1.0 / (w_c if fixed == "flexspline" else w_f)


@pytest.mark.parametrize("kind", ["radial_inner", "radial_outer", "end_face", "sealed"])
def test_signed_ratios_are_willis_for_every_arrangement(kind):
    """The table's signed ratios against Willis' equation solved as a linear system, with
    the flexspline rolling on r_f and the circular spline on r_f + Delta (the arrangement's
    Delta in the drive frame)."""
    d = arranged(kind)
    for row in ratio_table(d, (d.positions.min_mm, d.positions.max_mm)):
        c = drive_contact(d, row["a_mm"])
        r_f = float(c.flexspline_rolling_radius_mm)
        r_c = r_f + float(c.radius_difference_mm)
        for fixed in ("circular_spline", "flexspline"):
            assert row[f"ratio_{fixed}_fixed"] == pytest.approx(_willis(r_f, r_c, fixed), rel=1e-9)


@pytest.mark.parametrize("kind", ["radial_inner", "radial_outer", "end_face", "sealed"])
def test_pressing_force_and_torque_per_arrangement(kind):
    """The normal force is the axial pressing force over the sine of the working cone's
    half-angle about the axis: alpha for the radial drives, the flexspline's cone for the
    sealed one, 90 deg - alpha for the end face's face (no wedge); the torque mu N r / S."""
    d = arranged(kind)
    drive = d.drive
    alpha = math.radians(d.flexspline.cone_half_angle_deg) if kind == "sealed" else d.alpha
    half = 0.5 * math.pi - alpha if kind == "end_face" else alpha
    from prs_geom.harmonic.model import drive_section

    rows = ratio_table(d)
    sec = drive_section(d, rows)
    assert sec["normal_force_n"] == pytest.approx(drive.pressing_force_n / math.sin(half), rel=1e-12)
    assert sec["arrangement"] == kind
    for row in rows[::16]:
        expect = drive.friction_coefficient * sec["normal_force_n"] * row["contact_radius_mm"] / drive.slip_safety_factor
        assert row["output_torque_nm"] == pytest.approx(expect * 1e-3, rel=1e-12)


def test_sealed_contact_load_takes_the_ridge_arc():
    """In the sealed drive the meridian curvature is the circular spline's working arc: its
    radius moves the Hertz pressure, the flexspline's unused arc radius does not."""
    d = arranged("sealed")
    base = ratio_table(d, [60.0])[0]["contact_pressure_mpa"]
    flex = dataclasses.replace(d, flexspline=dataclasses.replace(d.flexspline, arc_radius_mm=5.0))
    assert ratio_table(flex, [60.0])[0]["contact_pressure_mpa"] == pytest.approx(base, rel=1e-12)
    ridge = dataclasses.replace(d, circular_spline=dataclasses.replace(d.circular_spline, arc_radius_mm=14.0,
                                                                       arc_centre_radius_mm=71.0))
    assert ratio_table(ridge, [60.0])[0]["contact_pressure_mpa"] > 1.01 * base


def test_sealed_strength_bends_the_cone_at_its_contact_radius():
    """The thin ring that bends is the cone at the contact: 3 E t Delta / (2 r^2) with r the
    rolling radius there (not r0), so the smallest ratio is r / Delta_max."""
    d = arranged("sealed")
    f = d.flexspline
    rows = {r["material"]: r for r in strength_section(d)}
    c = drive_contact(d, d.positions.min_mm)
    r = float(c.flexspline_rolling_radius_mm)
    assert r > f.neutral_radius_mm + 3.0
    stress = 3 * 206e3 * f.wall_thickness_mm * abs(float(c.radius_difference_mm)) / (2 * r ** 2)
    assert rows["steel"]["stress_at_min_position_mpa"] == pytest.approx(stress, rel=1e-12)
    assert rows["steel"]["min_ratio"] == pytest.approx(r / (300.0 * 2 * r ** 2 / (3 * 206e3 * f.wall_thickness_mm)),
                                                       rel=1e-12)


@pytest.mark.parametrize("kind", ["radial_outer", "end_face", "sealed"])
def test_tolerance_rule_uses_the_arrangements_radii(kind):
    """At the largest ratio the radius difference of the tolerance rule is the table's Delta
    at positions.max_mm, on the contact diameter there."""
    from prs_geom.harmonic.model import tolerance_for_ratio

    d = arranged(kind)
    last = ratio_table(d, [d.positions.max_mm])[0]
    tol = tolerance_for_ratio(d, last["ratio"])
    assert tol["radius_difference_mm"] == pytest.approx(abs(last["radius_difference_mm"]), rel=1e-9)
    assert tol["bore_diameter_mm"] == pytest.approx(2.0 * last["cone_radius_mm"], rel=1e-12)


@pytest.mark.parametrize("kind", ["radial_outer", "end_face", "sealed"])
def test_axial_sections_dxf_is_drawn_in_the_drive_frame(kind, tmp_path):
    """axial_sections.dxf read back with ezdxf: in each position's block the contact POINT is
    the drive-frame contact (x along the axis, y from it), and the circular spline's working
    outline passes through it (the cone LINE, or the sealed ring's outline)."""
    import ezdxf

    from prs_geom.geometry.planar import point_segment_distance
    from prs_geom.harmonic.exports import write_dxf

    d = arranged(kind)
    write_dxf(d, tmp_path / "s.dxf")
    doc = ezdxf.readfile(tmp_path / "s.dxf")
    for k, a in enumerate(d.positions.drawing_mm):
        blk = doc.blocks.get(f"POSITION_{k}")
        c = drive_contact(d, a)
        p = np.array([float(c.contact_z_mm), float(c.contact_rho_mm)])
        pt = [e for e in blk if e.dxftype() == "POINT"][0].dxf.location
        assert np.allclose([pt.x, pt.y], p, atol=1e-9)
        segs = []
        for e in blk:
            if e.dxftype() == "LINE":
                segs.append((np.array(e.dxf.start)[:2], np.array(e.dxf.end)[:2]))
            elif e.dxftype() == "LWPOLYLINE":
                q = np.array([v[:2] for v in e.get_points()])
                if e.closed:
                    q = np.concatenate([q, q[:1]])
                segs += list(zip(q[:-1], q[1:]))
        start = np.array([s[0] for s in segs])
        end = np.array([s[1] for s in segs])
        # the flexspline's outline and the circular spline's both touch the contact
        near = np.sort(point_segment_distance(p, start, end))
        assert near[1] <= 2e-3, (kind, a, near[:3])
