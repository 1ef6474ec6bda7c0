"""Thread meshes against the analytic surfaces."""
import dataclasses
import math
import os

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from prs_geom.geometry.frames import part_warps, screw_thread_length, thread_length
from prs_geom.model.actuator import ActuatorSettings
from prs_geom.mesh.assembly import build_part
from prs_geom.analysis.contact import PartFlanks
from prs_geom.model.design import PRSDesign, Roller, Nut, Screw, Thread, default_design
from prs_geom.model.io import load_design
from prs_geom.model.errors import DesignError
from prs_geom.mesh.thread import (FACE_BODY, FACE_END_HI, FACE_END_LO, FACE_MARK, FACE_THREAD, analytic_thread_volume, axial_line_crossings,
                           edge_flags, manifold_status, measure_deviation, mesh_report, profile_distance)
from strategies import standard_designs

EXAMPLES = __import__("pathlib").Path(__file__).parent.parent / "examples"


def reference_volume(tm, n_theta=20000, n_u=200001):
    """Independent volume of a (possibly graded) threaded part, from the analytic profile.

    V = 1/2 int dtheta int rho(theta, z)^2 dz. At fixed theta the integrand is
    r_root^2 (r_root^2 -> body^2 for the nut, minus) plus one tooth bump per tooth, each
    tooth rigid at its warped mid-plane, so int rho^2 dz = r_root^2 Lz + sum_k
    [G(z_hi - c_k) - G(z_lo - c_k)], G the running integral of rho(u)^2 - r_root^2 over
    a tooth, tabulated here by the trapezoidal rule on a fine grid.
    """
    prof, warp = tm.profile, tm.warp
    p, L = prof.pitch, prof.lead
    rr = prof.root_radius
    u = np.linspace(-0.5 * p, 0.5 * p, n_u)
    f = prof.radius_at_offset(u) ** 2 - rr ** 2
    G = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(u))])

    def Gint(x):
        return np.interp(x, u, G, left=0.0, right=G[-1])

    theta = np.linspace(0, 2 * math.pi, n_theta, endpoint=False)
    k_lo = math.floor((tm.z_lo - tm.first_mid - L) / p) - 3
    k_hi = math.ceil((tm.z_hi - tm.first_mid) / p) + 3
    ks = np.arange(k_lo, k_hi + 1)
    mid = warp(tm.first_mid + ks[None, :] * p + L * theta[:, None] / (2 * math.pi))
    bumps = (Gint(tm.z_hi - mid) - Gint(tm.z_lo - mid)).sum(1)
    lz = tm.z_hi - tm.z_lo
    inner = 0.5 * np.mean(rr ** 2 * lz + bumps) * 2 * math.pi
    # the angular datum slot is a box wholly inside the solid: width x depth x radial length
    slot = 0.0 if tm.datum_mark is None else tm.datum_mark.width * tm.datum_mark.depth * (
        tm.datum_mark.r_outer - tm.datum_mark.r_inner)
    if prof.internal:
        return math.pi * tm.body_radius ** 2 * lz - inner - slot
    return inner - slot


def check_part(tm, tol):
    # the thread alone (built with run_outs=()): the actuator's run-outs are tested in
    # tests/test_thread_run_outs.py against their own closed form
    # a small part is meshed finer than asked (volume accuracy, part_chord_tolerance)
    assert tm.chord_tolerance <= tol
    tol = tm.chord_tolerance
    m = tm.to_trimesh()
    assert m.is_watertight and m.is_winding_consistent
    assert manifold_status(tm.vertices, tm.faces) == "NoError"
    assert m.volume > 0
    dev = measure_deviation(tm)
    for key in ("max_deviation_body_mm", "max_deviation_end_mm", "max_deviation_end_face_mm"):
        assert dev[key] <= tol, (tm.part, key, dev[key])
    # chordal error is real: the mesh is not exact, deviation reaches a good part of tol
    assert dev["max_deviation_body_mm"] > 0.2 * tol
    ref = reference_volume(tm)
    budget = m.area * dev["max_deviation_mm"]
    assert abs(m.volume - ref) <= budget, (tm.part, m.volume, ref, budget)
    return m, ref


@pytest.mark.parametrize("tol", [0.01, 0.001])
@pytest.mark.parametrize("part", ["screw", "roller", "nut"])
def test_default_parts_closed_accurate_and_of_right_volume(part, tol):
    d = default_design()
    tm = build_part(d, part, tol, run_outs=())
    m, ref = check_part(tm, tol)
    # the tabulated reference agrees with the closed-form thread volume
    length = {"screw": screw_thread_length(d)}.get(part, thread_length(d))
    closed = analytic_thread_volume(tm.profile, length, tm.body_radius) - tm.datum_mark.volume
    assert ref == pytest.approx(closed, rel=1e-8)


@pytest.mark.parametrize("part", ["roller", "nut"])
def test_graded_parts_closed_accurate_and_of_right_volume(part):
    d = load_design(EXAMPLES / "graded-pitch.toml")
    tm = build_part(d, part, 0.01, run_outs=())
    assert not tm.warp.is_identity
    check_part(tm, 0.01)


@settings(max_examples=12, deadline=None)
@given(standard_designs(max_teeth=10, pitch_lists=True), st.sampled_from([0.02, 0.005]))
def test_sampled_designs_give_closed_accurate_meshes(d, tol):
    for part in ("screw", "roller", "nut"):
        check_part(build_part(d, part, tol, run_outs=()), tol)


def flank_positions(tm, theta, radius):
    """Flank z positions of the mesh along the axial line at (radius, theta)."""
    x, y = radius * math.cos(theta), radius * math.sin(theta)
    z = axial_line_crossings(tm.vertices, tm.faces, x, y)
    return z[(z > tm.z_lo + 1e-9) & (z < tm.z_hi - 1e-9)]


def analytic_flanks(tm, theta, radius):
    prof, warp = tm.profile, tm.warp
    t = float(prof.tooth_half_width(radius))
    ks = np.arange(-40, 80)
    mids = warp(tm.first_mid + ks * prof.pitch + prof.lead * theta / (2 * math.pi))
    z = np.sort(np.concatenate([mids - t, mids + t]))
    return z[(z > tm.z_lo + 1e-9) & (z < tm.z_hi - 1e-9)]


@pytest.mark.parametrize("theta", [0.0, 0.37, 1.9, -2.6])
def test_graded_roller_flanks_sit_at_listed_pitches(theta):
    pl = tuple(2.0 + 1e-3 * math.sin(0.9 * j) + 4e-4 * j / 19 for j in range(19))
    d = PRSDesign(roller=Roller(pitch_list_mm=pl))
    tm = build_part(d, "roller", 0.01, run_outs=())
    r = tm.profile.pitch_radius
    zm = flank_positions(tm, theta, r)
    za = analytic_flanks(tm, theta, r)
    assert len(zm) == len(za) >= 36
    # absolute position: within the chordal tolerance of the analytic flank
    assert np.abs(zm - za).max() <= 0.01
    # tooth-to-tooth distances: the listed pitches (through the warp) to 0.01 um
    np.testing.assert_allclose(np.diff(zm[0::2]), np.diff(za[0::2]), atol=1e-5, rtol=0)
    np.testing.assert_allclose(np.diff(zm[1::2]), np.diff(za[1::2]), atol=1e-5, rtol=0)
    if theta == 0.0:
        # at the reference angle both flanks of tooth j + 1 are p_j from those of tooth j
        lower, upper = zm[0::2], zm[1::2]
        assert len(lower) == 20
        np.testing.assert_allclose(np.diff(lower), pl, atol=1e-5, rtol=0)
        np.testing.assert_allclose(np.diff(upper), pl, atol=1e-5, rtol=0)


def test_graded_nut_flanks_sit_at_listed_pitches():
    pl = tuple(2.0 + 5e-4 * (19 - j) / 19 + 2e-4 * math.cos(j) for j in range(19))
    d = PRSDesign(nut=Nut(pitch_list_mm=pl))
    tm = build_part(d, "nut", 0.01, run_outs=())
    r = tm.profile.pitch_radius
    z = flank_positions(tm, 0.0, r)
    za = analytic_flanks(tm, 0.0, r)
    assert len(z) == len(za)
    np.testing.assert_allclose(np.diff(z), np.diff(za), atol=1e-5, rtol=0)
    # nut tooth j (mid-plane at (j - 1) p at theta = 0): its upper flank sits at +p/4
    knots = part_warps(d)["nut"].knots
    t = float(tm.profile.tooth_half_width(r))
    idx = [int(np.argmin(np.abs(za - (k + t)))) for k in knots]
    upper = z[idx]
    np.testing.assert_allclose(np.diff(upper), pl, atol=1e-5, rtol=0)


def test_left_hand_thread_winds_the_other_way():
    right = build_part(default_design(), "screw", 0.01, run_outs=())
    left = build_part(PRSDesign(thread=Thread(hand="left")), "screw", 0.01, run_outs=())
    r = right.profile.pitch_radius
    dtheta = 0.3
    shift = right.profile.lead * dtheta / (2 * math.pi)
    zr0, zr1 = flank_positions(right, 0.0, r), flank_positions(right, dtheta, r)
    zl1 = flank_positions(left, dtheta, r)
    # right hand: flanks rise with theta; left hand: they fall
    assert np.abs(zr1[2:10] - (zr0[2:10] + shift)).max() < 0.01
    assert np.abs(zl1[2:10] - (zr0[3:11] - shift)).max() < 0.01 or \
        np.abs(zl1[2:10] - (zr0[2:10] - shift)).max() < 0.01
    assert left.to_trimesh().is_watertight and left.to_trimesh().volume == pytest.approx(
        right.to_trimesh().volume, rel=1e-12)


def test_tessellation_follows_tolerance():
    d = default_design()
    # the nut: the roller is meshed finer than 0.01 mm anyway (part_chord_tolerance)
    coarse = build_part(d, "nut", 0.01, run_outs=())
    fine = build_part(d, "nut", 0.001, run_outs=())
    assert fine.meta["columns_per_turn"] > 2.5 * coarse.meta["columns_per_turn"]
    assert measure_deviation(fine)["max_deviation_mm"] < measure_deviation(coarse)["max_deviation_mm"] / 5


@pytest.mark.parametrize("part", ["screw", "roller", "nut"])
def test_end_faces_are_planar_and_contain_corner_points(part):
    tm = build_part(default_design(), part, 0.01, run_outs=())
    prof = tm.profile
    cap = np.isin(tm.face_kind, [FACE_END_LO, FACE_END_HI, FACE_BODY])
    z = tm.vertices[tm.faces[cap]][:, :, 2]
    assert set(np.unique(z)) == {tm.z_lo, tm.z_hi}
    # the datum slot's faces lie in face A or inside the slot box
    mark = tm.datum_mark
    zm = tm.vertices[tm.faces[tm.face_kind == FACE_MARK]][:, :, 2]
    assert set(np.unique(zm)) == {tm.z_lo, tm.z_lo + mark.depth}
    lo_verts = tm.vertices[np.unique(tm.faces[tm.face_kind == 1])]
    # every profile corner helix crosses the end plane exactly at a vertex of the end face
    corners_u = prof.corner_offsets()
    radii = [prof.root_radius, prof.crest_radius, prof.crest_radius, prof.root_radius]
    for u, r in zip(corners_u, radii):
        for k in range(prof.starts):
            # z_lo = first_mid + k p + L theta / 2 pi + u (constant pitch)
            theta = 2 * math.pi * (tm.z_lo - u - tm.first_mid - k * prof.pitch) / prof.lead
            expect = np.array([r * math.cos(theta), r * math.sin(theta), tm.z_lo])
            assert np.min(np.linalg.norm(lo_verts - expect, axis=1)) < 1e-12


@pytest.mark.heavy
def test_fine_tolerance_assembly_meshes(heavy_scale):
    """The default design's parts at the finest benchmark tolerance (0.5 um; CI: 2 um):
    closed, accepted by manifold3d, within tolerance everywhere."""
    from prs_geom.mesh.assembly import build_assembly
    tol = 0.0005 if heavy_scale == "full" else 0.002
    asm = build_assembly(default_design(), tol=tol, gears=False)
    for part, tm in asm.parts.items():
        m = tm.to_trimesh()
        assert m.is_watertight and m.is_winding_consistent, part
        assert manifold_status(tm.vertices, tm.faces) == "NoError"
        dev = measure_deviation(tm)
        assert dev["max_deviation_mm"] <= tol, (part, dev)
    V, F = asm.combined_arrays()
    assert len(F) > (1_500_000 if heavy_scale == "full" else 400_000)


# --------------------------------------------------------------------------- flank angles
# Issue: near the top of the allowed flank half-angle range (70-80 deg) the measured
# deviation exceeded the chord tolerance (1.4x on screw and roller, 2.4x on the nut at
# 80 deg) without any warning. Those thread surfaces were within tolerance; the measure was
# wrong: the flank term of profile_distance only applied to samples whose radius lay inside
# the flank's radius band, so a sample a few micrometres below the root radius next to a
# steep (nearly axial) flank fell back to the distance to the root corner, about tan(beta)
# times too large; and on the convex roller arc the tangent-line estimate under-reported by
# up to 18 %. With the exact measure, the search over the whole range found one real excess,
# at the other end of it: the nut's end annulus covered part of the thread groove where a
# near-radial flank (10-20 deg) makes a deep notch in the end curve (1.5x on a thin nut,
# 10x with a wall of 0.1 % of the diameter).

HEAVY_FULL = os.environ.get("PRS_HEAVY") == "full"


@st.composite
def flank_angle_designs(draw, max_teeth: int = 6, pitch_lists: bool = True) -> PRSDesign:
    """Standard-sizing designs (like tests/strategies.py) over the whole allowed flank
    half-angle range 10..80 deg, both hands, optionally graded; short parts."""
    starts = draw(st.integers(4, 7))
    roller_d = draw(st.floats(4.0, 16.0))
    pitch = draw(st.floats(0.12, 0.3)) * roller_d
    beta = draw(st.one_of(st.floats(10.0, 80.0), st.sampled_from([10.0, 70.0, 75.0, 80.0])))
    teeth = draw(st.integers(3, max_teeth))
    # nut wall: from a thin skin over the groove root to a thick body
    root_d = starts * roller_d + 2 * 0.8 * pitch / (4 * math.tan(math.radians(beta)))
    outer_d = root_d * (1.0 + draw(st.sampled_from([0.001, 0.01, 0.05, 0.2, 0.5])))
    rl = nl = None
    if pitch_lists and draw(st.booleans()):
        rl = tuple(pitch + draw(st.floats(-1e-3, 1e-3)) for _ in range(teeth - 1))
        nl = tuple(pitch + draw(st.floats(-1e-3, 1e-3)) for _ in range(teeth - 1))
    try:
        return PRSDesign(
            name="flank-angle",
            thread=Thread(pitch_mm=pitch, flank_half_angle_deg=beta, engaged_teeth=teeth,
                          hand=draw(st.sampled_from(["right", "left"]))),
            screw=Screw(pitch_diameter_mm=(starts - 2) * roller_d, starts=starts),
            roller=Roller(pitch_diameter_mm=roller_d, count=1, pitch_list_mm=rl),
            nut=Nut(pitch_diameter_mm=starts * roller_d, starts=starts, outer_diameter_mm=outer_d,
                    pitch_list_mm=nl),
            actuator=ActuatorSettings(enabled=False),      # the threads alone (see strategies.py)
        )
    except DesignError:
        assume(False)


def assert_within_tolerance(d: PRSDesign, tol: float | None = None) -> None:
    tol = tol or d.mesh.chord_tolerance_mm
    for part in ("screw", "roller", "nut"):
        dev = measure_deviation(build_part(d, part, tol, run_outs=()))
        assert dev["max_deviation_mm"] <= tol, (part, d.thread, dev)


@settings(max_examples=25, deadline=None)
@given(flank_angle_designs())
def test_deviation_within_tolerance_over_the_flank_angle_range(d):
    assert_within_tolerance(d)


@pytest.mark.heavy
@settings(max_examples=60 if HEAVY_FULL else 10, deadline=None)
@given(flank_angle_designs(max_teeth=20 if HEAVY_FULL else 8), st.sampled_from([0.01, 0.001]))
def test_deviation_within_tolerance_over_the_flank_angle_range_heavy(d, tol):
    assert_within_tolerance(d, tol)


@pytest.mark.parametrize("hand", ["right", "left"])
@pytest.mark.parametrize("beta", [10.0, 45.0, 70.0, 75.0, 80.0])
def test_default_sizes_within_tolerance_at_flank_angle(beta, hand):
    # the thread alone: at 75 and 80 deg no gear pair fits, so no mechanism and no actuator
    d = PRSDesign(thread=Thread(flank_half_angle_deg=beta, engaged_teeth=4, hand=hand),
                  roller=Roller(count=3), actuator=ActuatorSettings(enabled=False))
    tol = d.mesh.chord_tolerance_mm
    for part in ("screw", "roller", "nut"):
        row = mesh_report(build_part(d, part, run_outs=()))
        assert row["max_deviation_mm"] <= tol, (part, row["deviation_mm"])
        assert row["warnings"] == []
        assert row["watertight"] and row["manifold"]


@pytest.mark.parametrize("beta", [45.0, 75.0, 80.0])
@pytest.mark.parametrize("part", ["screw", "roller", "nut"])
def test_profile_distance_is_the_distance_on_steep_flanks(part, beta):
    """Points offset by d along the 3D surface normal of a flank are d from the surface;
    the axial-section measure must not under-report (it claims an upper bound of the 3D
    distance) and must not over-report by more than the 1/cos of the normal's tilt out
    of the axial half-plane (< 1 %)."""
    d = PRSDesign(thread=Thread(flank_half_angle_deg=beta, engaged_teeth=4), actuator=ActuatorSettings(enabled=False))
    tm = build_part(d, part, run_outs=())
    prof = tm.profile
    assert prof.hand_sign == 1  # right hand: part frame = the frame of profile_distance
    fl = PartFlanks(prof, tm.warp)
    lo, hi = prof.inner_radius, prof.outer_radius
    r = np.linspace(lo + 0.25 * (hi - lo), hi - 0.25 * (hi - lo), 41)   # away from the corners
    th = np.full_like(r, 0.4)
    for xi in (1.0, -1.0):
        m = np.full_like(r, tm.first_mid + 2 * prof.pitch)
        Z, Zr, Zt, _, _ = fl.z_derivatives(r, th, m, np.full_like(r, xi))
        P = np.column_stack([r * np.cos(th), r * np.sin(th), Z])
        e_r = np.column_stack([np.cos(th), np.sin(th), 0 * th])
        e_t = np.column_stack([-np.sin(th), np.cos(th), 0 * th])
        n = np.column_stack([0 * th, 0 * th, 1 + 0 * th]) - Zr[:, None] * e_r - (Zt / r)[:, None] * e_t
        n /= np.linalg.norm(n, axis=1)[:, None]
        for off in (0.005, -0.005):
            Q = P + off * n
            dist = profile_distance(tm, np.arctan2(Q[:, 1], Q[:, 0]), np.hypot(Q[:, 0], Q[:, 1]), Q[:, 2])
            ratio = dist / abs(off)
            assert ratio.min() >= 1.0 - 1e-6, (xi, off, ratio.min())
            assert ratio.max() <= 1.01, (xi, off, ratio.max())


@pytest.mark.parametrize("beta, pitch, roller_d, starts, outer_d, tol", [
    (10.0, 1.1875, 4.0, 4, 19.25, 0.1),     # near-radial flank, coarse tolerance
    (12.4, 1.0, 4.9, 6, None, 0.001),       # wall 0.1 % of the root diameter
])
def test_thin_nut_end_faces_stay_within_tolerance(beta, pitch, roller_d, starts, outer_d, tol):
    """The nut's end annulus must not cover the thread groove: with a near-radial flank the
    end curve has a deep notch at the root corner, which an edge from a coarse outer ring
    to the polygon could cut across."""
    root_d = starts * roller_d + 2 * 0.8 * pitch / (4 * math.tan(math.radians(beta)))
    d = PRSDesign(thread=Thread(pitch_mm=pitch, flank_half_angle_deg=beta, engaged_teeth=3),
                  screw=Screw(pitch_diameter_mm=(starts - 2) * roller_d, starts=starts),
                  roller=Roller(pitch_diameter_mm=roller_d, count=1),
                  nut=Nut(pitch_diameter_mm=starts * roller_d, starts=starts,
                          outer_diameter_mm=outer_d or 1.001 * root_d))
    tm = build_part(d, "nut", tol, run_outs=())
    dev = measure_deviation(tm)
    assert dev["max_deviation_end_face_mm"] <= tol, dev
    assert dev["max_deviation_mm"] <= tol, dev
    m = tm.to_trimesh()
    assert m.is_watertight and m.is_winding_consistent and m.volume > 0
    assert manifold_status(tm.vertices, tm.faces) == "NoError"


def test_mesh_report_warns_when_the_deviation_exceeds_the_tolerance():
    d = PRSDesign(thread=Thread(engaged_teeth=4))
    tm = build_part(d, "roller", 0.01, run_outs=())
    row = mesh_report(tm)
    assert row["warnings"] == []
    dev = row["deviation_mm"]["body"]
    assert 0.002 < dev <= 0.01
    # the same mesh judged against a tighter tolerance than it was built for
    tight = dataclasses.replace(tm, chord_tolerance=0.002)
    row = mesh_report(tight)
    assert row["max_deviation_mm"] > 0.002
    assert row["warnings"], row
    body = [w for w in row["warnings"] if "on the thread surface exceeds" in w]
    assert len(body) == 1
    assert "measured deviation" in body[0] and f"{dev:.4g} mm" in body[0]
    assert "chord tolerance 0.002 mm" in body[0]
    # every region over the tolerance is named, nothing under it
    over = {k for k, v in row["deviation_mm"].items() if v > 0.002}
    assert len(row["warnings"]) == len(over)


def test_deviation_in_chunks_equals_deviation_at_once(monkeypatch):
    """measure_deviation samples large meshes in chunks to bound memory; the result is the
    same to the bit (every distance is per point)."""
    import prs_geom.mesh.thread as thread

    tm = build_part(default_design(), "nut", 0.01, run_outs=())
    whole = thread.measure_deviation(tm)
    monkeypatch.setattr(thread, "DEVIATION_CHUNK_FACES", 997)
    assert len(tm.faces) > 10 * 997
    assert thread.measure_deviation(tm) == whole


def test_edge_flags_agree_with_trimesh():
    """mesh_report's watertight and winding flags (edge_flags, one sort of edge keys) give
    trimesh's is_watertight and is_winding_consistent, the independent reference: on the
    default roller (closed), with a face removed (open: not watertight), with a face flipped
    (watertight, winding not consistent), both (neither) and with a face doubled (edges of
    three faces); a mesh without faces is neither."""
    import trimesh

    tm = build_part(default_design(), "roller")
    V, F = np.asarray(tm.vertices), np.asarray(tm.faces)
    flipped = F.copy()
    flipped[10] = flipped[10, ::-1]
    cases = {"closed": F, "open": F[1:], "flipped": flipped, "open and flipped": flipped[1:],
             "doubled": np.vstack([F, F[:1]])}
    seen = set()
    for name, faces in cases.items():
        ref = trimesh.Trimesh(V, faces, process=False, validate=False)
        expected = (bool(ref.is_watertight), bool(ref.is_winding_consistent))
        assert edge_flags(faces) == expected, name
        seen.add(expected)
    assert {(True, True), (False, True), (True, False), (False, False)} <= seen
    assert edge_flags(F[:0]) == (False, False)
