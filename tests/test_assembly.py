"""Assembly placement and phases; part volumes of the rigid bodies."""
import math

import numpy as np
import pytest

from prs_geom.geometry.actuator import actuator_layout
from prs_geom.geometry.frames import FIRST_MID_PITCHES, carrier_angles, roller_transform
from prs_geom.mesh.assembly import build_assembly
from prs_geom.mesh.volumes import part_volumes
from prs_geom.model.design import PRSDesign, Roller, Thread, default_design
from prs_geom.mesh.thread import axial_line_crossings


def mod_p(x, p):
    """x reduced to [-p/2, p/2)."""
    return (np.asarray(x) + 0.5 * p) % p - 0.5 * p


def tooth_mid_phase(design, part_first_mid, lead, hand, theta):
    """Helix coordinate of a tooth mid-plane of the part at angle theta, mod p."""
    return mod_p(part_first_mid + hand * lead * theta / (2 * math.pi), design.thread.pitch_mm)


@pytest.mark.parametrize("hand", ["right", "left"])
@pytest.mark.parametrize("count", [10, 7])
def test_every_roller_sits_in_screw_and_nut_grooves(hand, count):
    d = PRSDesign(thread=Thread(hand=hand), roller=Roller(count=count))
    h = d.thread.hand_sign
    p = d.thread.pitch_mm
    a = d.centre_distance_mm
    rs, rr = 0.5 * d.screw.pitch_diameter_mm, 0.5 * d.roller.pitch_diameter_mm
    for k, psi in enumerate(carrier_angles(d)):
        T = roller_transform(d, k)
        assert np.allclose(T[:3, 3], [a * math.cos(psi), a * math.sin(psi), 0.0], atol=1e-12)
        Tinv = np.linalg.inv(T)
        for radius, part, groove_offset in ((rs, "screw", 0.5 * p), (a + rr, "nut", 0.5 * p)):
            P = np.array([radius * math.cos(psi), radius * math.sin(psi), 0.0, 1.0])
            local = Tinv @ P
            th_r = math.atan2(local[1], local[0])
            roller_mid = tooth_mid_phase(d, FIRST_MID_PITCHES["roller"] * p, p, h, th_r)
            lead = (d.screw.starts if part == "screw" else d.nut.starts) * p
            groove_mid = tooth_mid_phase(d, FIRST_MID_PITCHES[part] * p + groove_offset, lead, h, psi)
            assert abs(mod_p(roller_mid - groove_mid, p)) < 1e-12, (k, part)


def test_nut_groove_is_half_pitch_from_screw_groove_at_psi_0():
    d = default_design()
    p = d.thread.pitch_mm
    screw_groove = FIRST_MID_PITCHES["screw"] * p + 0.5 * p
    nut_groove = FIRST_MID_PITCHES["nut"] * p + 0.5 * p
    assert abs(abs(mod_p(nut_groove - screw_groove, p)) - 0.5 * p) < 1e-15


def test_meshed_rollers_interleave_with_screw_on_line_of_centres():
    """Read flanks off the placed meshes where roller k faces the screw: every roller tooth
    lies in a screw groove, mid-plane to mid-plane within the chordal tolerance."""
    d = default_design()
    tol = 0.01
    asm = build_assembly(d, tol=tol, gears=False)
    p = d.thread.pitch_mm
    rs = 0.5 * d.screw.pitch_diameter_mm
    screw = asm.placed_mesh("screw")
    for k, psi in enumerate(carrier_angles(d)):
        x, y = rs * math.cos(psi), rs * math.sin(psi)
        roller = asm.placed_mesh(f"roller_{k}")
        roller_mids = tooth_mids(roller, x, y)
        screw_grooves = tooth_mids(screw, x, y) + 0.5 * p
        assert len(roller_mids) >= 19
        offs = mod_p(roller_mids[:, None] - screw_grooves[None, :], p)
        assert np.abs(offs).min(axis=1).max() < tol, k


def tooth_mids(mesh, x, y):
    """Mid-planes of the whole teeth crossed by the axial line at (x, y): pairs of an
    entering (-1) and the next leaving (+1) crossing, end faces excluded."""
    z, sgn = axial_line_crossings(mesh.vertices, mesh.faces, x, y, with_direction=True)
    zmin, zmax = mesh.vertices[:, 2].min(), mesh.vertices[:, 2].max()
    inner = (z > zmin + 1e-9) & (z < zmax - 1e-9)
    z, sgn = z[inner], sgn[inner]
    start = np.nonzero((sgn[:-1] < 0) & (sgn[1:] > 0))[0]
    return 0.5 * (z[start] + z[start + 1])


def test_scene_names_and_gear_parts():
    d = PRSDesign(roller=Roller(count=4))
    asm = build_assembly(d, tol=0.02)
    names = set(asm.placed)
    assert {"screw", "nut", "roller_0", "roller_3", "roller_3_gear_lo", "nut_ring_gear_hi"} <= names
    kinds = {n: kind for n, (_, _, kind) in asm.placed.items()}
    assert kinds["roller_0_gear_lo"] == "gear" and kinds["roller_0"] == "thread"
    for n, (mesh, _, _) in asm.placed.items():
        assert mesh.is_watertight, n
    assert asm.rigid_body("roller_2_gear_hi") == "roller_2"
    assert asm.rigid_body("nut_ring_gear_lo") == "nut"
    V, F = asm.combined_arrays()
    assert len(F) == sum(len(m.faces) for m, _, _ in asm.placed.values())
    # combined arrays equal the per-part transformed meshes
    m3 = asm.placed_mesh("roller_3")
    assert V.shape[1] == 3 and np.isfinite(V).all()
    start = int(np.argmin(np.linalg.norm(V - m3.vertices[0], axis=1)))
    np.testing.assert_allclose(V[start:start + len(m3.vertices)], m3.vertices, atol=1e-12, rtol=0)
    # one volume per rigid body: a roller with its gears (they meet in end faces: no overlap)
    vol = part_volumes(asm)
    assert set(vol) == {asm.rigid_body(n) for n in asm.placed}
    # the screw with its actuator ends: each end's run-out cylinder (root radius - 0.02 mm, the
    # tolerance, over the run-out) lies in the thread and counts once; at the lower end it
    # fills the thread's datum slot, which the union therefore does not lose
    lay = actuator_layout(d)
    assert asm.rigid_body("screw_end_lo") == asm.rigid_body("screw_end_hi") == "screw"
    screw = [m for n, (m, _, _) in asm.placed.items() if asm.rigid_body(n) == "screw"]
    assert len(screw) == 3
    r_ro = 0.5 * d.screw.minor_diameter_mm - 0.02
    run_outs = sum(math.pi * r_ro ** 2 * (e.run_out[1] - e.run_out[0]) for e in lay.ends)
    slot = asm.parts["screw"].datum_mark.volume
    assert vol["screw"] == pytest.approx(sum(float(m.volume) for m in screw) - run_outs + slot, rel=1e-5)
    assert len({vol[f"roller_{k}"] for k in range(4)}) == 1
    roller = [m for n, (m, _, _) in asm.placed.items() if asm.rigid_body(n) == "roller_0"]
    # the pieces meet in end faces (no overlap); the union fills the datum slot a gear covers
    filled = asm.complete_parts()["roller"].filled_voids_mm3
    assert filled == pytest.approx(asm.parts["roller"].datum_mark.volume, rel=1e-6)
    assert vol["roller_0"] == pytest.approx(sum(float(m.volume) for m in roller) + filled, rel=1e-12)
    nut = [m for n, (m, _, _) in asm.placed.items() if asm.rigid_body(n) == "nut"]
    assert 0.0 < vol["nut"] <= sum(float(m.volume) for m in nut) * (1 + 1e-12)


def test_end_gears_mesh_with_the_ring_gear_by_the_backlash_and_carry_the_thread():
    """Every placed roller gear stands off the ring gear by half the normal backlash (FCL
    distance of the meshes, at both ends): the phasing is right for every roller. The
    roller gear's tips carry the thread (largest radius = the thread's major radius) and
    its flanks lie inside the involute outline."""
    import fcl

    from prs_geom.analysis.gears import analyse_gears
    from prs_geom.checks.fcl import bvh_model

    d = PRSDesign()
    g = analyse_gears(d)
    asm = build_assembly(d, tol=0.01)
    jn = g.checks.backlash_normal_mm
    objs = {}
    for name, (mesh, T, kind) in asm.placed.items():
        if kind == "gear":
            objs[name] = fcl.CollisionObject(bvh_model(np.asarray(mesh.vertices), np.asarray(mesh.faces)),
                                             fcl.Transform(T[:3, :3], T[:3, 3]))
    for end in ("lo", "hi"):
        ring = objs[f"nut_ring_gear_{end}"]
        for k in range(d.roller.count):
            res = fcl.DistanceResult()
            dist = fcl.distance(objs[f"roller_{k}_gear_{end}"], ring, fcl.DistanceRequest(), res)
            # 1 um gear outlines: the distance is j_n / 2 within the two chord errors
            assert dist == pytest.approx(0.5 * jn, abs=2.5e-3), (end, k, dist)
    mesh = asm.placed["roller_0_gear_lo"][0]
    r = np.hypot(mesh.vertices[:, 0], mesh.vertices[:, 1])
    # gear tip (capped at the thread major diameter) and thread crest, both within the chord
    assert 0.5 * d.roller.major_diameter_mm - 0.01 <= r.max() <= 0.5 * d.roller.major_diameter_mm + 1e-9
    off_axis = r > 1e-9                                  # the end caps' fan centres lie on the axis
    assert r[off_axis].min() >= g.roller_gear.root_radius_mm - 1e-9
    # same mesh on every roller (identical parts), one face width long
    assert asm.placed["roller_7_gear_lo"][0] is mesh
    z = mesh.vertices[:, 2]
    assert z.min() == pytest.approx(-g.face_width_mm) and z.max() == pytest.approx(0.0, abs=1e-12)
