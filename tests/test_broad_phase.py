"""Broad phase of the interference check (prs_geom.checks.broad_phase): the bounds of a placed
mesh against closed forms and brute-force sampling, and the check with the broad phase and
the sliced BVHs against the check that asks FCL about every pair with whole BVHs."""
from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import trimesh

import prs_geom.checks.interference as itf
from prs_geom.analysis.contact import theoretical_screw
from prs_geom.checks.broad_phase import can_touch, face_boxes, longest_edge, near_faces, placed_bounds
from prs_geom.mesh.assembly import build_assembly
from prs_geom.model.design import default_design


def _placed(x: float = 0.0, angle: float = 0.0, z: float = 0.0) -> np.ndarray:
    T = trimesh.transformations.rotation_matrix(angle, [0, 0, 1])
    T[:3, 3] = [x, 0.0, z]
    return T


def _bounds(mesh: trimesh.Trimesh, T: np.ndarray):
    return placed_bounds(mesh.vertices, mesh.faces, T)


@pytest.mark.parametrize("sections", [12, 64])
def test_coaxial_tube_bounds_are_the_polygons_closed_forms(sections):
    """A tube on the axis: the nearest point of its bore is an edge midpoint of the inscribed
    polygon, at R_i cos(pi / n); the farthest a vertex on the outer circle, at R_o."""
    tube = trimesh.creation.annulus(r_min=4.0, r_max=6.0, height=3.0, sections=sections)
    b = _bounds(tube, _placed(angle=0.3))
    assert b.r_min == pytest.approx(4.0 * np.cos(np.pi / sections), abs=1e-12)
    assert b.r_max == pytest.approx(6.0, abs=1e-12)
    assert b.lo[2] == pytest.approx(-1.5) and b.hi[2] == pytest.approx(1.5)


def test_off_axis_cylinder_bounds_lie_between_the_circle_and_its_polygon():
    """A roller-like cylinder of radius R at distance a from the axis: its inscribed polygon
    lies between the circles R cos(pi / n) and R, so a - R <= r_min <= a - R cos(pi / n) and
    a + R cos(pi / n) <= r_max <= a + R."""
    n, R, a = 40, 5.0, 17.0
    cyl = trimesh.creation.cylinder(radius=R, height=10.0, sections=n)
    for angle in (0.0, 0.7, 2.0):
        b = _bounds(cyl, _placed(x=a, angle=angle))
        assert a - R - 1e-12 <= b.r_min <= a - R * np.cos(np.pi / n) + 1e-12
        assert a + R * np.cos(np.pi / n) - 1e-12 <= b.r_max <= a + R + 1e-12


def test_r_min_is_the_minimum_of_densely_sampled_surface_points():
    """Brute force: points sampled on every face (a barycentric grid of step 1/40) are never
    nearer the axis than r_min, and the nearest comes within the grid's resolution."""
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=3.0)
    T = _placed(x=4.2, angle=0.4, z=1.0)
    b = _bounds(sphere, T)
    k = 40
    u, v = np.meshgrid(np.arange(k + 1) / k, np.arange(k + 1) / k)
    keep = u + v <= 1.0
    bary = np.stack([1 - u[keep] - v[keep], u[keep], v[keep]], axis=1)
    W = sphere.vertices @ T[:3, :3].T + T[:3, 3]
    pts = np.einsum("sk,fkd->fsd", bary, W[sphere.faces]).reshape(-1, 3)
    r = np.hypot(pts[:, 0], pts[:, 1])
    assert r.min() >= b.r_min - 1e-12
    assert r.min() - b.r_min <= longest_edge(sphere.vertices, sphere.faces) / k
    # the analytic sphere's nearest distance is 4.2 - 3; the mesh is inscribed, so farther,
    # and no farther than its nearest vertex
    assert 1.2 - 1e-12 <= b.r_min <= np.hypot(W[:, 0], W[:, 1]).min()


def test_a_long_face_nearer_than_every_vertex_is_found():
    """A long thin face passes the axis at 1 mm while its vertices are 10 mm away; a small
    face has the nearest vertex (3 mm). The bound is the long face's interior."""
    V = np.array([[-10.0, 1.0, 0.0], [10.0, 1.0, 0.0], [10.0, 1.0, 1.0],
                  [3.0, 0.0, 0.0], [3.1, 0.0, 0.0], [3.0, 0.1, 0.0]])
    b = placed_bounds(V, np.array([[0, 1, 2], [3, 4, 5]]), np.eye(4))
    assert b.r_min == pytest.approx(1.0, abs=1e-12)


def test_a_face_over_the_axis_gives_zero():
    disk = trimesh.creation.cylinder(radius=1.0, height=1.0, sections=8)
    assert _bounds(disk, _placed(x=0.5)).r_min == 0.0


def test_can_touch_settles_coaxial_fits_by_radius_and_separated_boxes():
    shaft = trimesh.creation.cylinder(radius=10.0, height=20.0, sections=256)
    n = 256
    # a bore whose inscribed polygon clears the shaft by 1 um: the boxes overlap, the
    # radial intervals do not
    clear = trimesh.creation.annulus(r_min=(10.0 + 1e-3) / np.cos(np.pi / n), r_max=14.0, height=5.0, sections=n)
    tight = trimesh.creation.annulus(r_min=9.99, r_max=14.0, height=5.0, sections=n)
    s = _bounds(shaft, _placed())
    assert not can_touch(s, _bounds(clear, _placed()))
    assert can_touch(s, _bounds(tight, _placed()))
    # axially apart
    assert not can_touch(s, _bounds(tight, _placed(z=12.6)))
    assert can_touch(s, _bounds(tight, _placed(z=12.4)))


def test_near_faces_keeps_every_face_with_a_point_in_the_box():
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=5.0)
    T = _placed(x=2.0, angle=1.0)
    lo, hi = np.array([3.0, -1.0, -2.0]), np.array([9.0, 2.0, 1.0])
    near = near_faces(face_boxes(sphere.vertices, sphere.faces, T), lo, hi)
    W = sphere.vertices @ T[:3, :3].T + T[:3, 3]
    bary = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1 / 3, 1 / 3, 1 / 3], [0.5, 0.5, 0], [0, 0.5, 0.5], [0.5, 0, 0.5]])
    pts = np.einsum("sk,fkd->fsd", bary, W[sphere.faces])
    inside = np.any(np.all((pts >= lo) & (pts <= hi), axis=2), axis=1)
    assert set(np.flatnonzero(inside)) <= set(near)
    assert 0 < len(near) < len(sphere.faces) / 2


# --------------------------------------------------------------------------- the check
#: Coarse meshes keep the test quick; the screw still has more than SPLIT_FACES faces.
TOL = 0.01


def _outcomes(asm, brute: bool, mp: pytest.MonkeyPatch) -> tuple[dict, list[int]]:
    faces: list[int] = []
    bvh_model = itf.bvh_model

    def counting(V, F):
        faces.append(len(F))
        return bvh_model(V, F)

    with mp.context() as m:
        m.setattr(itf, "bvh_model", counting)
        if brute:
            m.setattr(itf, "can_touch", lambda a, b: True)
            m.setattr(itf, "SPLIT_FACES", 10 ** 12)
        return itf.pair_overlaps(asm), faces


#: FCL's contact cap of the check, as the package sets it
CAP = itf.MAX_CONTACTS


@pytest.mark.parametrize("cap", [CAP, 50])
def test_broad_phase_and_slices_give_what_every_pair_on_whole_meshes_gives(monkeypatch, cap):
    """The reference is the check without a broad phase: every pair of different rigid
    bodies asked of FCL with whole-mesh BVHs. With the broad phase and the sliced screw the
    same pairs collide with the same contacts (count and heights) and the same overlap
    volumes and areas; the nominal screw is used so that the screw's pairs collide. With
    FCL's contact cap at 50 the screw's pairs are capped: which 50 contacts FCL gives
    depends on the BVH, so a capped sliced query is asked again of the whole meshes and
    gives the reference's 50."""
    monkeypatch.setattr(itf, "MAX_CONTACTS", cap)
    design = default_design()
    asm = build_assembly(design, tol=TOL, screw_profile=None)
    ref, ref_faces = _outcomes(asm, True, monkeypatch)
    got, got_faces = _outcomes(asm, False, monkeypatch)
    assert list(got) == list(ref)
    colliding = [pair for pair, hit in ref.items() if hit is not None]
    assert any("screw" in pair for pair in colliding) and len(colliding) >= 2 * design.roller.count
    for pair in ref:
        a, b = ref[pair], got[pair]
        assert (a is None) == (b is None), pair
        if a is not None:
            assert np.array_equal(np.sort(a.contact_z), np.sort(b.contact_z)), pair
            assert (a.volume, a.area) == (b.volume, b.area), pair
    screw_faces = len(asm.placed["screw"][0].faces)
    assert screw_faces in ref_faces
    if cap == CAP:
        assert screw_faces not in got_faces
        # the slices of the screw together are less than the screw
        assert sum(got_faces) < sum(ref_faces)
    else:
        assert any(len(ref[p].contact_z) == cap for p in colliding if "screw" in p)
        assert screw_faces in got_faces


def test_theoretical_screw_check_is_unchanged_by_the_broad_phase(monkeypatch):
    design = default_design()
    asm = build_assembly(design, tol=TOL, screw_profile=theoretical_screw(design).profile)
    ref, _ = _outcomes(asm, True, monkeypatch)
    got, _ = _outcomes(asm, False, monkeypatch)
    strip: Any = lambda d: {k: (None if v is None else (len(v.contact_z), v.volume, v.area)) for k, v in d.items()}
    assert strip(got) == strip(ref)
