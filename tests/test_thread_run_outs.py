"""Thread run-outs (:func:`prs_geom.mesh.thread.apply_run_outs`) on the default design's parts.

The screw gets a grinding-wheel exit of one lead (starts x pitch = 10 mm) at both ends, the
roller and the nut a 45 degree chamfer from the crest down to the pitch radius at both ends.
Every value is checked against a closed form computed here from the profile alone
(:meth:`~prs_geom.geometry.profiles.ThreadProfile.radius_at_offset`), not from the meshing code.

Volumes: at a height z the thread surface is r = rho(u), u = z - m0 - L theta / 2 pi, and
theta over one turn sweeps whole periods p of rho, so the volume a run-out adds or removes is

    V = (pi / p) * integral over the depth d from the end plane and over one period u of
        max(a^2 - b^2, 0)

with (a, b) = (r_cone(d), rho(u)) for the wheel exit (material added below the cone),
(rho(u), r_e + d) for the roller chamfer and (r_e - d, rho(u)) for the nut's countersink
(material removed beyond the cone). The double integral is taken by the midpoint rule.

Bound of the mesh's volume change: outside the run-outs the two meshes are the same triangles
(manifold3d keeps untouched faces bit for bit, and the part of a face it splits lies in that
face), and planar faces (end faces, the frustum's base, the datum slot) are exact, so only
the changed curved surfaces count: the run-out faces off the end planes and the thread
surface the run-outs took away. Every point of them lies within its region's measured
deviation (within the chord tolerance, ``test_deviation_within_the_chord_tolerance``) of its
analytic surface, so the volume change differs from the analytic one by at most the sum of
deviation x area over these surfaces (to first order in the curvature), plus the midpoint
rule's error.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import trimesh

from prs_geom.mesh.assembly import build_part, part_z_range
from prs_geom.mesh.thread import (FACE_RUN_OUT, FACE_THREAD, RUN_OUT_CREST_GAP_MM, RUN_OUT_ROOT_MARGIN_MM,
                                  RunOut, ThreadMesh, apply_run_outs, cut_datum_mark, manifold_status,
                                  measure_deviation, thread_mesh)
from prs_geom.geometry.profiles import ThreadProfiles
from prs_geom.model.design import PRSDesign, Thread, default_design

DESIGN = default_design()
PARTS = ("screw", "roller", "nut")
#: Euler characteristic 2 - 2 genus: screw and roller are solid (genus 0), the nut a ring (genus 1).
EULER = {"screw": 2, "roller": 2, "nut": 0}


def _run_outs(part: str, profile) -> list[RunOut]:
    """The run-outs of the brief: a wheel exit of one lead on the screw, chamfers to the
    pitch radius on roller and nut, at both ends."""
    if part == "screw":
        return [RunOut(end, "wheel-exit", profile.starts * profile.pitch) for end in ("lo", "hi")]
    return [RunOut(end, "chamfer", abs(profile.crest_radius - profile.pitch_radius)) for end in ("lo", "hi")]


@pytest.fixture(scope="module")
def built() -> dict[str, tuple[ThreadMesh, ThreadMesh]]:
    """Per part: (the part as today, the part with its run-outs)."""
    out = {}
    for part in PARTS:
        base = build_part(DESIGN, part, run_outs=())
        out[part] = (base, build_part(DESIGN, part, run_outs=_run_outs(part, base.profile)))
    return out


# --------------------------------------------------------------------------- closed forms
def _cone(profile, length: float, d):
    """The wheel exit's cone radius (mm) at depth d (mm) from the end plane."""
    r_end = profile.crest_radius - RUN_OUT_CREST_GAP_MM
    r_in = profile.root_radius - RUN_OUT_ROOT_MARGIN_MM
    return r_end + (r_in - r_end) * np.asarray(d) / length


def _revolved_volume(profile, depth: float, squares, n_u: int, n_d: int) -> float:
    """(pi / p) * the midpoint-rule integral of max(a^2 - b^2, 0) over d in [0, depth] and one
    period u in [0, p), ``squares(rho, d)`` -> (a, b) on the grid (module docstring)."""
    p = profile.pitch
    u = (np.arange(n_u) + 0.5) * p / n_u
    rho = profile.radius_at_offset(u)[None, :]
    total = 0.0
    for d in np.array_split((np.arange(n_d) + 0.5) * depth / n_d, 16):
        a, b = squares(rho, d[:, None])
        total += float(np.maximum(a * a - b * b, 0.0).sum())
    return math.pi / p * total * (p / n_u) * (depth / n_d)


def _closed_form_volume(part: str, profile, run_out: RunOut) -> tuple[float, float]:
    """The volume (mm^3) one run-out adds (> 0) or removes (< 0), and the midpoint rule's
    error estimate (the change from halving the grid, mm^3)."""
    L = run_out.length_mm
    if part == "screw":
        squares, sign = (lambda rho, d: (_cone(profile, L, d), rho)), 1.0
    elif profile.internal:
        squares, sign = (lambda rho, d: (profile.crest_radius + L - d, rho)), -1.0
    else:
        squares, sign = (lambda rho, d: (rho, profile.crest_radius - L + d)), -1.0
    fine = _revolved_volume(profile, L, squares, 4000, 2000)
    coarse = _revolved_volume(profile, L, squares, 2000, 1000)
    return sign * fine, abs(fine - coarse)


def _area(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    tri = V[F]
    return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)


def _row_keys(*arrays: np.ndarray) -> list[np.ndarray]:
    """An integer id per float64 row (x, y, z), the same id for bit-identical rows across
    ``arrays``."""
    rows = np.concatenate(arrays)
    _, ids = np.unique(np.ascontiguousarray(rows).view(np.dtype((np.void, rows.itemsize * 3))).ravel(),
                       return_inverse=True)
    return np.split(ids.ravel(), np.cumsum([len(a) for a in arrays])[:-1])


def _faces_absent(base: ThreadMesh, tm: ThreadMesh) -> np.ndarray:
    """Mask of the faces of ``base`` that ``tm`` does not have (by their vertices' coordinates)."""
    vb, vt = _row_keys(base.vertices, tm.vertices)
    fb, ft = np.sort(vb[base.faces], axis=1), np.sort(vt[tm.faces], axis=1)
    keys = _row_keys(fb.astype(np.float64), ft.astype(np.float64))
    return ~np.isin(keys[0], keys[1])


def _section_radii(tm: ThreadMesh, z: float) -> tuple[float, float]:
    """Smallest and largest distance (mm) from the axis of the outer contour of the mesh's
    section by the plane z: the exact minimum over its segments, the maximum over their end
    points. The outer contour is the segments beyond 0.9 root radius (the datum slot in face
    A reaches 0.8 root radius, :mod:`prs_geom.geometry.datum`)."""
    seg = trimesh.intersections.mesh_plane(tm.to_trimesh(), [0.0, 0.0, 1.0], [0.0, 0.0, z])[:, :, :2]
    seg = seg[(np.linalg.norm(seg, axis=2) > 0.9 * tm.profile.root_radius).all(axis=1)]
    a, ab = seg[:, 0], seg[:, 1] - seg[:, 0]
    t = np.clip(-np.sum(a * ab, 1) / np.maximum(np.sum(ab * ab, 1), 1e-300), 0.0, 1.0)
    return float(np.linalg.norm(a + t[:, None] * ab, axis=1).min()), float(np.linalg.norm(seg, axis=2).max())


# --------------------------------------------------------------------------- tests
@pytest.mark.parametrize("part", PARTS)
def test_result_is_one_closed_manifold(built, part):
    base, tm = built[part]
    m = tm.to_trimesh()
    assert manifold_status(tm.vertices, tm.faces) == "NoError"
    assert m.is_watertight and m.is_winding_consistent
    assert m.euler_number == EULER[part] == base.to_trimesh().euler_number
    assert len(m.split(only_watertight=False)) == 1
    assert tm.run_outs == tuple(_run_outs(part, base.profile))
    assert np.count_nonzero(tm.face_kind == FACE_RUN_OUT) > 0
    assert tm.datum_mark == base.datum_mark      # the mark is cut after the run-outs, as before


@pytest.mark.parametrize("part", PARTS)
def test_deviation_within_the_chord_tolerance(built, part):
    _, tm = built[part]
    dev = measure_deviation(tm)
    regions = {k: v for k, v in dev.items() if k.startswith("max_deviation_")}
    assert "max_deviation_run_out_mm" in regions
    assert all(v <= tm.chord_tolerance for v in regions.values()), (regions, tm.chord_tolerance)
    # the run-out faces are the sampled tool surfaces: their error is the tools' sagitta,
    # within the tolerance but not zero (a check that measured nothing would read 0)
    assert 0.1 * tm.chord_tolerance < regions["max_deviation_run_out_mm"]


@pytest.mark.parametrize("part", PARTS)
def test_volume_change_is_the_closed_form(built, part):
    base, tm = built[part]
    expected, numerics = np.sum([_closed_form_volume(part, base.profile, ro) for ro in tm.run_outs], axis=0)
    change = tm.to_trimesh().volume - base.to_trimesh().volume
    # the changed curved surfaces (module docstring): the run-out faces off the end planes
    # (the frustum's base is exactly planar) and the thread surface the run-outs took away
    # (a thread face the boolean split keeps its kept part exactly); each at its region's
    # measured deviation from the analytic surface
    area_base, area = _area(base.vertices, base.faces), _area(tm.vertices, tm.faces)
    z = tm.vertices[tm.faces][:, :, 2]
    off_plane = (tm.face_kind == FACE_RUN_OUT) & ~(z == z[:, :1]).all(axis=1)
    thread_removed = area_base[base.face_kind == FACE_THREAD].sum() - area[tm.face_kind == FACE_THREAD].sum()
    dev_base, dev = measure_deviation(base), measure_deviation(tm)
    bound = (dev["max_deviation_run_out_mm"] * area[off_plane].sum()
             + max(dev_base["max_deviation_body_mm"], dev_base["max_deviation_end_mm"]) * thread_removed
             + numerics)
    assert numerics < 1e-5 * abs(expected)
    assert abs(change - expected) <= bound, (change, expected, bound)
    # the bound is 4-10 % of the change; measured (default design): screw +167.10 vs
    # +166.98 mm^3 (0.07 %), roller -0.6773 vs -0.6793 (0.3 %), nut -3.350 vs -3.355 (0.13 %):
    # both meshes are chords at the same column angles and their errors mostly cancel.
    # A regression margin on that:
    assert bound < 0.15 * abs(expected)
    assert abs(change - expected) <= 0.01 * abs(expected), (change, expected)


def test_wheel_exit_fills_the_groove_at_the_end_plane(built):
    base, tm = built["screw"]
    prof, tol, L = tm.profile, tm.chord_tolerance, tm.run_outs[0].length_mm
    for z_end, s in ((tm.z_lo, -1.0), (tm.z_hi, 1.0)):
        # next to the end plane the groove is filled up to the crest less the gap (the
        # cone's polygon lies within tol inside the cone)
        r_min, r_max = _section_radii(tm, z_end - s * 0.01)
        assert r_min >= prof.crest_radius - RUN_OUT_CREST_GAP_MM - tol
        # 0.1 mm inside: filled up to the cone, which has dropped by 0.1 / L of its rise
        # there (0.007 mm, so crest - gap - tol would fail by 0.002 mm: measured 12.2830)
        r_min, r_max = _section_radii(tm, z_end - s * 0.1)
        assert prof.crest_radius - tol <= r_max <= prof.crest_radius + 1e-9
        assert r_min >= float(_cone(prof, L, 0.1)) - tol
        # the inner end of the run-out: the full groove depth
        r_min, _ = _section_radii(tm, z_end - s * L)
        assert abs(r_min - prof.root_radius) <= tol
        # and without the run-out the same section 0.1 mm inside reaches the root
        assert abs(_section_radii(base, z_end - s * 0.1)[0] - prof.root_radius) <= tol


@pytest.mark.parametrize("part", ["roller", "nut"])
def test_chamfers_keep_every_contact_point(built, part):
    """The chamfers reach no flank contact: no vertex of the thread surface farther from the
    end plane than |crest - pitch radius| is removed or moved."""
    base, tm = built[part]
    prof = base.profile
    far = np.minimum(base.vertices[:, 2] - base.z_lo, base.z_hi - base.vertices[:, 2]) > abs(
        prof.crest_radius - prof.pitch_radius)
    on_thread = np.zeros(len(base.vertices), bool)
    on_thread[base.faces[base.face_kind == FACE_THREAD].ravel()] = True
    keys_base, keys_tm = _row_keys(base.vertices, tm.vertices)
    kept = np.isin(keys_base, keys_tm)
    assert np.count_nonzero(far & on_thread) > 0.5 * np.count_nonzero(on_thread)
    assert kept[far & on_thread].all()
    # the chamfer did remove the crest corners at the end planes
    assert not kept[~far & on_thread].all()


def test_window_pieces_take_the_run_outs_of_the_ends_they_reach():
    lo, hi = part_z_range(DESIGN, "screw")
    prof = ThreadProfiles.from_design(DESIGN).screw
    run_outs = _run_outs("screw", prof)
    inner = build_part(DESIGN, "screw", z_window=(lo + 1.0, hi + 1.0), run_outs=run_outs)
    assert inner.run_outs == (run_outs[1],)
    # a piece shorter than the wheel exit: the frustum is clipped to it (and its datum mark cut)
    short = build_part(DESIGN, "screw", z_window=(lo - 1.0, lo + 4.0), run_outs=run_outs)
    assert short.run_outs == (run_outs[0],)
    for tm in (inner, short):
        assert manifold_status(tm.vertices, tm.faces) == "NoError" and tm.to_trimesh().euler_number == 2
        dev = measure_deviation(tm)
        assert dev["max_deviation_mm"] <= tm.chord_tolerance, dev
    r_min, _ = _section_radii(short, lo + 3.9)
    assert r_min >= float(_cone(prof, run_outs[0].length_mm, 3.9)) - short.chord_tolerance


def test_left_hand_run_outs_mirror_the_right_hand_ones(built):
    _, right = built["screw"]
    left = build_part(PRSDesign(thread=Thread(hand="left")), "screw", run_outs=right.run_outs)
    assert left.profile.hand_sign == -1
    assert manifold_status(left.vertices, left.faces) == "NoError"
    assert left.to_trimesh().volume == pytest.approx(right.to_trimesh().volume, rel=1e-12)
    assert measure_deviation(left)["max_deviation_mm"] <= left.chord_tolerance


def test_one_pass_with_the_datum_mark_is_the_two_passes(built):
    """build_part cuts the run-outs and the datum mark in one boolean pass: the same solid and
    face kinds as the run-outs first, then :func:`cut_datum_mark`."""
    base, tm = built["roller"]
    prof = base.profile
    bare = thread_mesh(prof, base.z_lo, base.z_hi, base.chord_tolerance, base.first_mid, base.warp)
    two = cut_datum_mark(apply_run_outs(bare, tm.run_outs), base.datum_mark)
    assert (tm.run_outs, tm.datum_mark) == (two.run_outs, two.datum_mark)
    assert tm.to_trimesh().volume == pytest.approx(two.to_trimesh().volume, rel=1e-12)
    area_one, area_two = _area(tm.vertices, tm.faces), _area(two.vertices, two.faces)
    for kind in range(FACE_RUN_OUT + 1):
        assert area_one[tm.face_kind == kind].sum() == pytest.approx(area_two[two.face_kind == kind].sum(),
                                                                     rel=1e-9, abs=1e-12)


def test_no_run_outs_leave_the_part_as_it_was(built):
    base, _ = built["roller"]
    assert apply_run_outs(base, []) is base
    again = build_part(DESIGN, "roller", run_outs=())
    assert np.array_equal(again.vertices, base.vertices) and np.array_equal(again.faces, base.faces)
    assert "max_deviation_run_out_mm" not in measure_deviation(base)


@pytest.mark.parametrize("part, run_outs, match", [
    ("nut", [RunOut("lo", "wheel-exit", 2.0)], "wheel-exit"),
    ("screw", [RunOut("hi", "wheel-exit", 110.0)], "half"),     # the actuator screw thread: 201.5 mm
    ("roller", [RunOut("lo", "chamfer", 0.31)], "pitch radius"),
    ("roller", [RunOut("lo", "chamfer", 0.1), RunOut("lo", "chamfer", 0.2)], "twice"),
])
def test_invalid_run_outs_are_refused(built, part, run_outs, match):
    base, _ = built[part]
    with pytest.raises(ValueError, match=match):
        apply_run_outs(base, run_outs)


@pytest.mark.parametrize("field, value", [("end", "top"), ("kind", "undercut"), ("length_mm", 0.0),
                                          ("length_mm", float("nan"))])
def test_run_out_fields_are_checked(field, value):
    good = dict(end="lo", kind="chamfer", length_mm=0.3)
    with pytest.raises(ValueError, match=f"RunOut.{field}"):
        RunOut(**{**good, field: value})
    assert dataclasses.asdict(RunOut(**good)) == good
