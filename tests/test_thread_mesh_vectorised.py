"""The vectorised thread mesher against a straightforward reference construction.

``thread_mesh`` writes the regular middle of every band arithmetically, tabulates cos, sin
and the helix advance per column, and merges only the pieces next to the end planes. The
reference below is kept as plain as possible: every vertex computed on its own, every
band's two chains built in a loop and merged in theta with a lexsort, the end faces from
those. The mesher must give the same arrays bit for bit.
"""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from prs_geom.geometry.frames import FIRST_MID_PITCHES, part_warps, screw_z_range, thread_length
from prs_geom.geometry.helix import identity_warp
from prs_geom.geometry.profiles import ThreadProfiles
from prs_geom.mesh.thread import (FACE_BODY, FACE_END_HI, FACE_END_LO, FACE_THREAD, _open_columns,
                                  _ring_angles, choose_tessellation, merge_strips, part_chord_tolerance,
                                  profile_strands, thread_mesh)
from prs_geom.model.design import PRSDesign, Roller, Thread, default_design
from prs_geom.model.io import load_design
from strategies import standard_designs

EXAMPLES = __import__("pathlib").Path(__file__).parent.parent / "examples"


def lexsort_merge(a_ids, a_th, b_ids, b_th):
    """Chains merged in (strip, theta, A before B, chain order), counting the events seen."""
    tris = []
    for A, ta, B, tb in zip(a_ids, a_th, b_ids, b_th):
        ev = [(ta[k], 0, k) for k in range(1, len(A))] + [(tb[k], 1, k) for k in range(1, len(B))]
        ev.sort(key=lambda e: (e[0], e[1]))          # stable: chain order at equal keys
        seen = [0, 0]                                # A and B events so far
        for _, is_b, k in ev:
            if is_b:                                 # (current A, B[k], B[k - 1])
                tris.append((A[seen[0]], B[k], B[k - 1]))
            else:                                    # (A[k - 1], A[k], current B)
                tris.append((A[k - 1], A[k], B[seen[1]]))
            seen[is_b] += 1
    return np.array(tris, np.int64).reshape(-1, 3)


def reference_mesh(profile, z_lo, z_hi, tol, first_mid=0.0, warp=None, body_radius=None):
    """(vertices, faces, face kinds) by the per-band construction."""
    warp = warp or identity_warp(profile.pitch)
    tess = choose_tessellation(profile, tol)
    dth, ncol = tess.dtheta, tess.columns_per_turn
    L, p = profile.lead, profile.pitch
    u_s, r_s = profile_strands(profile, tess)
    M = len(u_s)
    G = profile.starts * M
    u_g = np.array([u_s[g % M] for g in range(G)])
    r_g = np.array([r_s[g % M] for g in range(G)])
    base_g = np.array([first_mid + (g // M) * p for g in range(G)])
    th_lo = 2.0 * math.pi * (warp.inverse(z_lo - u_g) - base_g) / L
    th_hi = 2.0 * math.pi * (warp.inverse(z_hi - u_g) - base_g) / L
    c0, c1 = _open_columns(th_lo, th_hi, dth)

    def point(r, th, z):
        return [r * np.cos(th), r * np.sin(th), z]

    verts, ids, cols = [], [], []
    for g in range(G):                               # strand columns
        cols.append(np.arange(c0[g], c1[g] + 1))
        th = cols[g] * dth
        z = warp(base_g[g] + L * th / (2 * math.pi)) + u_g[g]
        ids.append(list(range(len(verts), len(verts) + len(th))))
        verts += [point(r_g[g], th[k], z[k]) for k in range(len(th))]
    e_lo = [len(verts) + g for g in range(G)]
    verts += [point(r_g[g], th_lo[g], z_lo) for g in range(G)]
    e_hi = [len(verts) + g for g in range(G)]
    verts += [point(r_g[g], th_hi[g], z_hi) for g in range(G)]
    ends = {}                                        # band -> (ids, theta) of its end curve
    for name, z_e, th_e in (("lo", z_lo, th_lo), ("hi", z_hi, th_hi)):
        for g in range(G):
            h, wrap = (g + 1) % G, (-2.0 * math.pi if g == G - 1 else 0.0)
            b0, b1 = _open_columns(np.array([th_e[h] + wrap]), np.array([th_e[g]]), dth)
            cc = np.arange(b0[0], b1[0] + 1)
            eth = cc * dth
            u_star = z_e - warp(base_g[g] + L * eth / (2 * math.pi))
            rho = profile.radius_at_offset(u_star)
            ends[name, g] = (list(range(len(verts), len(verts) + len(cc))), eth)
            verts += [point(rho[k], eth[k], z_e) for k in range(len(cc))]
    A_ids, A_th, B_ids, B_th = [], [], [], []
    for g in range(G):
        h, wrap, shift = (g + 1) % G, (-2.0 * math.pi if g == G - 1 else 0.0), (-ncol if g == G - 1 else 0)
        lo_ids, lo_th = ends["lo", g]
        hi_ids, hi_th = ends["hi", g]
        A_ids.append([e_lo[h], *lo_ids, e_lo[g], *ids[g], e_hi[g]])
        A_th.append(np.concatenate([[th_lo[h] + wrap], lo_th, [th_lo[g]], cols[g] * dth, [th_hi[g]]]))
        B_ids.append([*ids[h], e_hi[h], *hi_ids])
        B_th.append(np.concatenate([(cols[h] + shift) * dth, [th_hi[h] + wrap], hi_th]))
    faces = [lexsort_merge(A_ids, A_th, B_ids, B_th)]
    polys = {}
    for name, e, th_e in (("lo", e_lo, th_lo), ("hi", e_hi, th_hi)):
        P, T = [], []
        for g in range(G - 1, -1, -1):
            h, wrap = (g + 1) % G, (-2.0 * math.pi if g == G - 1 else 0.0)
            P += [e[h], *ends[name, g][0]]
            T += [th_e[h] + wrap, *ends[name, g][1]]
        polys[name] = (np.array(P), np.array(T))
    V = np.array(verts, dtype=np.float64)
    kinds = [FACE_THREAD]
    if not profile.internal:
        for name, centre, kind in (("lo", len(V), FACE_END_LO), ("hi", len(V) + 1, FACE_END_HI)):
            P = polys[name][0]
            fan = np.column_stack([np.full(len(P), centre), P, np.roll(P, -1)])
            faces.append(fan[:, [0, 2, 1]] if name == "lo" else fan)
            kinds.append(kind)
        V = np.concatenate([V, [[0.0, 0.0, z_lo], [0.0, 0.0, z_hi]]])
    else:
        faces[0] = faces[0][:, [0, 2, 1]]
        step_max = 2.0 * math.acos(1.0 - tol / body_radius)
        rings = {}
        for name, z_e, kind in (("lo", z_lo, FACE_END_LO), ("hi", z_hi, FACE_END_HI)):
            P, th = polys[name]
            ang = _ring_angles(th, np.hypot(V[P, 0], V[P, 1]), step_max)
            rids = len(V) + np.arange(len(ang))
            V = np.concatenate([V, np.column_stack([body_radius * np.cos(ang), body_radius * np.sin(ang),
                                                    np.full(len(ang), z_e)])])
            rings[name] = (rids, ang)
            rel = (ang - th[0]) % (2 * math.pi)
            order = np.argsort(rel, kind="stable")
            b_th = th[0] + rel[order]
            f = lexsort_merge([np.append(P, P[0])], [np.append(th, th[0] + 2 * math.pi)],
                              [np.append(rids[order], rids[order[0]])], [np.append(b_th, b_th[0] + 2 * math.pi)])
            faces.append(f[:, [0, 2, 1]] if name == "hi" else f)
            kinds.append(kind)
        (lo_ids, lo_ang), (hi_ids, hi_ang) = rings["lo"], rings["hi"]
        faces.append(lexsort_merge([np.append(lo_ids, lo_ids[0])], [np.append(lo_ang, lo_ang[0] + 2 * math.pi)],
                                   [np.append(hi_ids, hi_ids[0])], [np.append(hi_ang, hi_ang[0] + 2 * math.pi)]))
        kinds.append(FACE_BODY)
    kind = np.concatenate([np.full(len(f), k, np.int8) for f, k in zip(faces, kinds)])
    F = np.concatenate(faces)
    if profile.hand_sign < 0:
        V = V * np.array([1.0, -1.0, 1.0])
        F = F[:, [0, 2, 1]]
    return V, F, kind


def assert_same(args, kwargs):
    tm = thread_mesh(*args, **kwargs)
    V, F, kind = reference_mesh(*args, **kwargs)
    assert tm.vertices.dtype == np.float64 and tm.faces.dtype == np.int64 and tm.face_kind.dtype == np.int8
    assert np.array_equal(tm.vertices, V)
    assert np.array_equal(np.signbit(tm.vertices), np.signbit(V))      # the signs of zeros too
    assert np.array_equal(tm.faces, F)
    assert np.array_equal(tm.face_kind, kind)


def part_args(d, part, tol):
    prof = ThreadProfiles.from_design(d)
    p = d.thread.pitch_mm
    warps = part_warps(d)
    profile = getattr(prof, part)
    lo, hi = screw_z_range(d) if part == "screw" else (0.0, thread_length(d))
    kwargs = {"body_radius": 0.5 * d.nut.outer_diameter_mm} if part == "nut" else {}
    return (profile, lo, hi, part_chord_tolerance(profile, tol), FIRST_MID_PITCHES[part] * p, warps[part]), kwargs


@pytest.mark.parametrize("part", ["screw", "roller", "nut"])
@pytest.mark.parametrize("design", ["default", "graded", "left"])
def test_parts_are_the_reference_construction(design, part):
    d = {"default": default_design, "graded": lambda: load_design(EXAMPLES / "graded-pitch.toml"),
         "left": lambda: PRSDesign(thread=Thread(hand="left", flank_half_angle_deg=20.0, engaged_teeth=4),
                                   roller=Roller(count=3))}[design]()
    assert_same(*part_args(d, part, 0.02))


@pytest.mark.parametrize("part", ["screw", "roller", "nut"])
@pytest.mark.parametrize("z_lo, dz, first_mid", [
    (0.0, 1e-3, 0.0),           # shorter than a column: strands without columns, no middles
    (-0.5, 0.25, 0.3),          # a fraction of a pitch
    (0.0, 2.0, 0.0),            # end planes through strand crossings at theta = 0
    (0.37, 7.3, -1.1),
])
def test_short_and_odd_parts_are_the_reference_construction(part, z_lo, dz, first_mid):
    d = default_design()
    (profile, _, _, tol, _, warp), kwargs = part_args(d, part, 0.05)
    assert_same((profile, z_lo, z_lo + dz, tol, first_mid, warp), kwargs)


@settings(max_examples=6, deadline=None)
@given(standard_designs(max_teeth=8, pitch_lists=True), st.sampled_from([0.05, 0.02]),
       st.floats(-2.0, 2.0), st.floats(0.05, 1.0))
def test_sampled_designs_are_the_reference_construction(d, tol, shift, frac):
    for part in ("screw", "roller", "nut"):
        (profile, lo, hi, t, first_mid, warp), kwargs = part_args(d, part, tol)
        assert_same((profile, lo, hi, t, first_mid, warp), kwargs)
        assert_same((profile, lo + shift, lo + shift + frac * (hi - lo), t, first_mid + shift, warp), kwargs)


def test_merge_strips_is_the_lexsort_merge():
    rng = np.random.default_rng(17)
    for _ in range(300):
        n = rng.integers(1, 5)
        na, nb = rng.integers(1, 7, n), rng.integers(1, 7, n)
        sort = rng.random() < 0.5          # sorted chains, or any order (ties everywhere)
        a_th = [np.sort(x) if sort else x for x in (rng.integers(0, 4, k).astype(float) for k in na)]
        b_th = [np.sort(x) if sort else x for x in (rng.integers(0, 4, k).astype(float) for k in nb)]
        a_ids = [rng.integers(0, 50, k) for k in na]
        b_ids = [rng.integers(50, 99, k) for k in nb]
        assert np.array_equal(merge_strips(a_ids, a_th, b_ids, b_th), lexsort_merge(a_ids, a_th, b_ids, b_th))
