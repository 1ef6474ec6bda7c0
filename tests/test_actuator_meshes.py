"""Meshes of the actuator parts (prs_geom.mesh.actuator): the screw ends against closed forms,
the purchased parts' envelopes against the catalogue tables, the nut flange, the scene
integration, and the nut assembly at both stroke ends clear of the screw."""
from __future__ import annotations

import math
from pathlib import Path

import manifold3d
import numpy as np
import pytest
from scipy.integrate import quad

from prs_geom.checks.interference import body_pairs
from prs_geom.exports.scene import moving_group
from prs_geom.geometry.actuator import actuator_layout
from prs_geom.geometry.mechanism import layout
from prs_geom.mesh.actuator import RUN_OUT_INSET_MM, actuator_meshes
from prs_geom.mesh.assembly import Assembly, build_assembly, build_part, mechanism_parts, scene_names
from prs_geom.mesh.mechanism import MECHANISM_CHORD_MM
from prs_geom.mesh.thread import to_manifold
from prs_geom.model.actuator import ActuatorSettings, DriveEnd
from prs_geom.model.design import PRSDesign, default_design
from prs_geom.model.io import load_design

#: Thread meshes at the design's 0.01 mm (the screw is meshed finer anyway, 0.08 % of its
#: radius); the actuator parts are meshed at MECHANISM_CHORD_MM whatever the tolerance.
TOL = 0.01
#: manifold3d's cross-sections (Clipper2) round coordinates to about 1e-8 mm: a vertex "on"
#: its circle or plane is there to this.
ROUND = 1e-8
#: The actuator's scene parts of the default design, in their stated order.
ACTUATOR_PARTS = ["screw_end_lo", "screw_end_hi", "nut_flange", "bearing_fixed_0", "bearing_fixed_1",
                  "bearing_floating_0", "locknut", "shaft_ring", *(f"flange_bolt_{k}" for k in range(6)), "drive_key"]
PURCHASED = ACTUATOR_PARTS[3:]
#: The purchased parts modelled as rings about the screw axis.
RINGS = ACTUATOR_PARTS[3:8]


FOUR_START = Path(__file__).resolve().parents[1] / "examples" / "four-start-seven-rollers.toml"


def _assembled(d):
    """A design, its actuator layout and its assembly with the theoretical screw (the state
    the interference check certifies)."""
    from prs_geom.analysis.contact import theoretical_screw

    return d, actuator_layout(d), build_assembly(d, tol=TOL, screw_profile=theoretical_screw(d).profile)


@pytest.fixture(scope="module")
def default():
    return _assembled(default_design())


@pytest.fixture(scope="module")
def four_start():
    """The shared 4-start, 7-roller example (examples/four-start-seven-rollers.toml)."""
    return _assembled(load_design(FOUR_START))


def _solid(mesh, T=None):
    s = to_manifold(mesh.vertices, mesh.faces)
    return s if T is None else s.transform(np.ascontiguousarray(np.asarray(T)[:3, :4]))


def _keyway_volume(r: float, b: float, t1: float, length: float) -> float:
    """A DIN 6885-1 form A keyway cut in a journal of radius r (mm^3): the straight part
    (length - b) times the section {x^2 + y^2 <= r^2, x >= r - t1, |y| <= b / 2} (closed form),
    plus the two rounded ends, a disc of radius b / 2 under the cylinder (quadrature)."""
    a = 0.5 * b
    section = a * math.sqrt(r * r - a * a) + r * r * math.asin(a / r) - b * (r - t1)
    ends, _ = quad(lambda y: 2.0 * math.sqrt(a * a - y * y) * (math.sqrt(r * r - y * y) - (r - t1)), -a, a)
    return section * (length - b) + ends


def _end_volume(end, r_run_out: float) -> float:
    """Closed form of a screw end without its drive feature: the steps and the run-out
    cylinder, each pi r^2 l."""
    steps = sum(math.pi * (0.5 * st.diameter_mm) ** 2 * (st.z[1] - st.z[0]) for st in end.steps)
    return steps + math.pi * r_run_out ** 2 * (end.run_out[1] - end.run_out[0])


def _radii(mesh):
    return np.hypot(mesh.vertices[:, 0], mesh.vertices[:, 1])


# --------------------------------------------------------------------------- scene
def test_scene_order_rigid_bodies_and_the_design_without_actuator():
    d = default_design()
    names = scene_names(d, gears=True, mechanism=True)
    # after the retaining rings, in the stated order
    assert names[-2 - len(ACTUATOR_PARTS):] == ["retaining_ring_lo", "retaining_ring_hi", *ACTUATOR_PARTS]
    bodies = {n: Assembly.rigid_body(n) for n in ACTUATOR_PARTS}
    assert bodies == {"screw_end_lo": "screw", "screw_end_hi": "screw", "nut_flange": "nut",
                      **{n: n for n in PURCHASED}}
    pairs = set(body_pairs(names))
    assert ("screw", "screw_end_lo") not in pairs and ("nut", "nut_flange") not in pairs
    assert ("bearing_fixed_0", "bearing_fixed_1") in pairs and ("screw", "bearing_fixed_0") in pairs
    # without the actuator: the scene of a mechanism only, as before
    bare = PRSDesign(actuator=ActuatorSettings(enabled=False))
    plain = scene_names(bare, gears=True, mechanism=True)
    assert plain == names[:-len(ACTUATOR_PARTS)]
    assert set(mechanism_parts(bare, TOL)) == {f"{p}_{s}" for p in ("journal", "carrier", "retaining_ring", "nut_end")
                                               for s in ("lo", "hi")}


def test_default_assembly_places_the_actuator_parts_without_interference(default):
    """Every made actuator part placed with the identity, every purchased one by a rigid
    transform of its own mesh; the parts that touch by design (a bearing on its shoulder, the
    bearing pair, the locknut on the pair, the shaft ring on its bearing, each bolt head on
    the flange, the key on its keyway's floor) touch without volume: the check passes with
    them as contacts."""
    from prs_geom.checks.interference import check_assembly

    d, lay, asm = default
    for name in ACTUATOR_PARTS:
        mesh, T, kind = asm.placed[name]
        assert kind == "actuator" and mesh.is_watertight, name
        if name in PURCHASED and name not in RINGS:
            # a bolt or the key: meshed once in its own frame, placed by a translation
            assert np.array_equal(T[:3, :3], np.eye(3)) and np.array_equal(T[3], [0.0, 0.0, 0.0, 1.0]), name
        elif name in PURCHASED:
            # meshed once per size in its own frame: a turn about the axis and a shift along it
            assert np.array_equal(T[2], [0.0, 0.0, 1.0, T[2, 3]]) and np.array_equal(T[:2, 2:], np.zeros((2, 2)))
            assert T[:2, :2] @ T[:2, :2].T == pytest.approx(np.eye(2), abs=1e-15), name
        else:
            assert np.array_equal(T, np.eye(4)), name
    rep = check_assembly(asm, TOL)
    assert rep["found"] is False
    touching = {tuple(r["pair"]) for r in rep["contact_within_tolerance"]}
    assert {("bearing_fixed_0", "bearing_fixed_1"), ("bearing_fixed_1", "locknut"),
            ("screw_end_lo", "bearing_fixed_0"), ("bearing_floating_0", "shaft_ring"),
            ("screw_end_lo", "drive_key"), *(("nut_flange", f"flange_bolt_{k}") for k in range(6))} <= touching
    for row in rep["contact_within_tolerance"]:
        if set(row["pair"]) & set(ACTUATOR_PARTS):
            assert row["volume_mm3"] < 1e-9, row


# --------------------------------------------------------------------------- screw ends
def test_screw_ends_against_the_closed_form(default):
    """Volume of each end = sum of pi r^2 l over its steps and the run-out cylinder, less the
    keyway (straight section closed form, rounded ends by quadrature). Every mesh vertex lies
    on the true surface and every facet within the chord tolerance of it, so the volumes
    differ by at most tol x the mesh's surface area."""
    d, lay, asm = default
    r_run_out = 0.5 * d.screw.minor_diameter_mm - max(RUN_OUT_INSET_MM, TOL)
    fixed, floating = lay.ends
    assert (fixed.role, floating.role) == ("fixed", "floating")
    key = fixed.key
    journal = fixed.steps[-1]
    assert journal.name == "drive journal" and (key.width_mm, key.shaft_depth_mm) == (5.0, 3.0)
    keyway = _keyway_volume(0.5 * journal.diameter_mm, key.width_mm, key.shaft_depth_mm,
                            fixed.key_z[1] - fixed.key_z[0])
    # the default 22 mm key in the 16 mm journal: 243.9 mm^3 straight + 56.9 mm^3 at the ends
    assert keyway == pytest.approx(300.8, abs=0.1)
    for name, end, cut in (("screw_end_lo", fixed, keyway), ("screw_end_hi", floating, 0.0)):
        mesh = asm.placed[name][0]
        assert mesh.is_watertight and mesh.body_count == 1
        exact = _end_volume(end, r_run_out) - cut
        assert abs(mesh.volume - exact) <= MECHANISM_CHORD_MM * mesh.area, (name, mesh.volume, exact)
        # the run-out piece stays inside the thread's root radius by the inset
        zs = mesh.vertices[:, 2]
        r_top = _radii(mesh)[(zs >= end.run_out[0] - 1e-9) & (zs <= end.run_out[1] + 1e-9)].max()
        assert r_top == pytest.approx(r_run_out, abs=ROUND)
        assert r_top <= 0.5 * d.screw.minor_diameter_mm - RUN_OUT_INSET_MM + ROUND
    # without its keyway the lower end would be larger by the keyway's volume
    lo = asm.placed["screw_end_lo"][0]
    assert _end_volume(fixed, r_run_out) - lo.volume == pytest.approx(keyway, abs=MECHANISM_CHORD_MM * lo.area)


def test_keyway_sits_on_plus_x_at_depth_t1(default):
    """The section through the key's middle: the journal circle less the slot on +x, whose
    floor is t1 below the journal's top and whose walls are b apart."""
    d, lay, asm = default
    end = lay.ends[0]
    r = 0.5 * end.steps[-1].diameter_mm
    b, t1 = end.key.width_mm, end.key.shaft_depth_mm
    z = 0.5 * sum(end.key_z)
    cs = _solid(asm.placed["screw_end_lo"][0]).slice(z)
    P = np.vstack(cs.to_polygons())
    assert P[:, 0].min() == pytest.approx(-r, abs=ROUND)                 # the -x side untouched
    assert P[:, 0].max() == pytest.approx(math.sqrt(r * r - 0.25 * b * b), abs=MECHANISM_CHORD_MM)
    floor = P[np.abs(P[:, 1]) < 0.5 * b - 1e-6]
    assert floor[:, 0].max() == pytest.approx(r - t1, abs=ROUND)
    section = 0.5 * b * math.sqrt(r * r - 0.25 * b * b) + r * r * math.asin(0.5 * b / r) - b * (r - t1)
    assert cs.area() == pytest.approx(math.pi * r * r - section, abs=2 * math.pi * r * MECHANISM_CHORD_MM)


def test_flat_drive_cuts_a_circular_segment():
    """drive.kind = "flat": a plane flat_depth below the journal's top over the key span; the
    end loses the circular segment's area times that length (closed form)."""
    d = PRSDesign(actuator=ActuatorSettings(drive=DriveEnd(kind="flat")))
    lay = actuator_layout(d)
    end = lay.ends[0]
    assert end.key is None and end.flat_depth_mm == pytest.approx(1.6)
    mesh = actuator_meshes(d, lay, TOL)["screw_end_lo"][0]
    r, h = 0.5 * end.steps[-1].diameter_mm, end.flat_depth_mm
    segment = r * r * math.acos((r - h) / r) - (r - h) * math.sqrt(2 * r * h - h * h)
    exact = _end_volume(end, 0.5 * d.screw.minor_diameter_mm - max(RUN_OUT_INSET_MM, TOL)) \
        - segment * (end.key_z[1] - end.key_z[0])
    assert mesh.is_watertight
    assert abs(mesh.volume - exact) <= MECHANISM_CHORD_MM * mesh.area
    P = np.vstack(_solid(mesh).slice(0.5 * sum(end.key_z)).to_polygons())
    assert P[:, 0].max() == pytest.approx(r - h, abs=ROUND)


def test_screw_and_its_ends_are_one_body(default):
    d, lay, asm = default
    screw = sum((_solid(asm.placed[n][0]) for n in ("screw_end_lo", "screw_end_hi")),
                _solid(asm.placed["screw"][0]))
    assert len(screw.decompose()) == 1
    lo, hi = lay.screw_z
    bb = screw.bounding_box()
    assert (bb[2], bb[5]) == pytest.approx((lo, hi), abs=ROUND)
    assert lay.screw_length_mm == pytest.approx(283.3)


# --------------------------------------------------------------------------- purchased parts
#: Catalogue rows (ISO 15 series 02 bore 20: d x D x B; KM 4: M20x1, outside 32, width 6;
#: DIN 471 for a 20 mm shaft: groove 19, ring 1.2) as printed, the reference of the envelopes.
CATALOGUE = {"bearing_fixed_0": (10.0, 23.5, 14.0), "bearing_fixed_1": (10.0, 23.5, 14.0),
             "bearing_floating_0": (10.0, 23.5, 14.0), "locknut": (10.0, 16.0, 6.0),
             "shaft_ring": (9.5, 10.0 + 1.5, 1.2)}


@pytest.mark.parametrize("name", RINGS)
def test_purchased_envelopes_have_the_catalogue_sizes(default, name):
    """Outside vertices on the outside circle, the bore's edges tangent to the bore circle
    (its vertices at most one chord tolerance beyond), the axial span as placed."""
    d, lay, asm = default
    mesh = asm.placed_mesh(name)
    r_in, r_out, width = CATALOGUE[name]
    r = _radii(mesh)
    assert r.max() == pytest.approx(r_out, abs=ROUND)
    assert r_in - ROUND <= r.min() <= r_in + MECHANISM_CHORD_MM
    z0, z1 = mesh.bounds[:, 2]
    assert z1 - z0 == pytest.approx(width, abs=ROUND)
    placed = {f"bearing_{e.role}_{k}": b.z for e in lay.ends for k, b in enumerate(e.bearings)}
    placed.update(locknut=lay.ends[0].locknut_z, shaft_ring=lay.ends[1].ring_z)
    assert (z0, z1) == pytest.approx(placed[name], abs=ROUND)
    exact = math.pi * (r_out ** 2 - r_in ** 2) * width
    assert abs(mesh.volume - exact) <= MECHANISM_CHORD_MM * mesh.area


def test_flange_bolts_stand_in_their_holes_with_heads_on_the_flange(default):
    """ISO 4762 M5 x 16 (d_k 8.5, k = d = 5) as head and shank cylinders: the mesh's volume
    against pi (r_s^2 l + r_h^2 k) within the chord tolerance times its area; each bolt's
    axis through its hole's centre (bolt circle 65.5 mm, at 30, 90, ... deg), the shank clear
    of the ISO 273 hole (5.5 mm), the head's underside on the flange's upper face, the tip l
    below it."""
    from prs_geom.mesh.actuator import flange_bolts

    d, lay, asm = default
    m = lay.nut_mount
    bolts = flange_bolts(lay)
    assert [b.designation for b in bolts] == ["ISO 4762 M5 x 16 - 8.8"] * 6
    meshes = {id(asm.placed[b.name][0]) for b in bolts}
    assert len(meshes) == 1                                   # one mesh, six placements
    mesh = asm.placed["flange_bolt_0"][0]
    exact = math.pi * (2.5 ** 2 * 16.0 + 4.25 ** 2 * 5.0)
    assert bolts[0].volume_mm3 == pytest.approx(exact, rel=1e-15)
    assert mesh.is_watertight and abs(mesh.volume - exact) <= MECHANISM_CHORD_MM * mesh.area
    for k, b in enumerate(bolts):
        V = asm.placed_mesh(b.name).vertices
        a = math.radians(30.0 + 60.0 * k)
        centre = 32.75 * np.array([math.cos(a), math.sin(a)])
        r = np.hypot(*(V[:, :2] - centre).T)
        shank = V[:, 2] < m.z[1] - 1e-9
        assert r[shank].max() == pytest.approx(2.5, abs=ROUND) and r[shank].max() < 0.5 * 5.5
        assert r.max() == pytest.approx(4.25, abs=ROUND)
        head = V[~shank, 2]
        assert (head.min(), head.max()) == pytest.approx((m.z[1], m.z[1] + 5.0), abs=ROUND)
        assert V[:, 2].min() == pytest.approx(m.z[1] - 16.0, abs=ROUND)


def test_drive_key_fills_its_keyway(default):
    """DIN 6885 A 5 x 5 x 22 on the +x side: its mesh volume against ((l - b) b + pi b^2 / 4)
    h; its bottom on the keyway floor (x = r_j - t1), its top h above, its span the key's;
    the part below the journal surface is the keyway (the closed form of
    test_screw_ends_against_the_closed_form). The key's outline lies inside the keyway's
    polygon (staggered, prs_geom.mesh.actuator._stadium_prism), at most 2 chord tolerances
    inside the true stadium: the bounds hold to that inset and the volumes to it times the
    key's area;
    key and screw end share no volume."""
    from prs_geom.mesh.actuator import drive_key

    d, lay, asm = default
    end = lay.ends[0]
    key = drive_key(lay)
    assert key.designation == "DIN 6885 A 5 x 5 x 22" and key.designation == lay.sizes["actuator.drive.key"].value
    mesh = asm.placed_mesh("drive_key")
    exact = (17.0 * 5.0 + math.pi * 6.25) * 5.0
    assert key.volume_mm3 == pytest.approx(exact, rel=1e-15)
    assert mesh.is_watertight and abs(mesh.volume - exact) <= 2 * MECHANISM_CHORD_MM * mesh.area
    r_j = 0.5 * end.steps[-1].diameter_mm
    floor = r_j - end.key.shaft_depth_mm
    lo, hi = mesh.bounds
    assert (lo[0], hi[0]) == pytest.approx((floor, floor + 5.0), abs=ROUND)
    # the outline staggered against the keyway's: within 2 chord tolerances inside the stadium
    inset = 2 * MECHANISM_CHORD_MM
    assert end.key_z[0] <= lo[2] <= end.key_z[0] + inset and end.key_z[1] - inset <= hi[2] <= end.key_z[1]
    assert 2.5 - inset <= hi[1] <= 2.5 and -2.5 <= lo[1] <= -2.5 + inset
    journal = manifold3d.Manifold.cylinder(end.key_z[1] - end.key_z[0] + 2.0, r_j, r_j,
                                           4 * math.ceil(math.pi / math.acos(1 - 1e-5 / r_j) / 4)
                                           ).translate((0.0, 0.0, end.key_z[0] - 1.0))
    inside = (_solid(mesh) ^ journal).volume()
    keyway = _keyway_volume(r_j, 5.0, end.key.shaft_depth_mm, 22.0)
    assert abs(inside - keyway) <= 2 * MECHANISM_CHORD_MM * mesh.area, (inside, keyway)
    assert (_solid(mesh) ^ _solid(asm.placed["screw_end_lo"][0])).volume() < 1e-9


def test_nut_flange_holes_and_volume(default):
    """Annulus from the nut end's outside less 0.5 mm to the flange diameter, 6 ISO 273 holes
    (M5: 5.5 mm) on the 65.5 mm circle, none on +x."""
    d, lay, asm = default
    m = lay.nut_mount
    mech = layout(d)
    assert (m.bolt.name, m.bolt_count, m.bolt_circle_diameter_mm, m.flange_diameter_mm) == ("M5", 6, 65.5, 76.0)
    mesh = asm.placed["nut_flange"][0]
    t = m.z[1] - m.z[0]
    r_in = mech.nut_end_outer_radius_mm - 0.5
    exact = (math.pi * (38.0 ** 2 - r_in ** 2) - 6 * math.pi * 2.75 ** 2) * t
    assert mesh.is_watertight and abs(mesh.volume - exact) <= MECHANISM_CHORD_MM * mesh.area
    solid = _solid(mesh)
    probe = manifold3d.Manifold.cube((0.2, 0.2, 0.2), True)
    zc = 0.5 * sum(m.z)
    r_bc = 0.5 * m.bolt_circle_diameter_mm
    for k in range(12):          # material on the bolt circle at 0, 60, ... deg; holes at 30, 90, ...
        a = math.pi * k / 6
        inside = (solid ^ probe.translate((r_bc * math.cos(a), r_bc * math.sin(a), zc))).volume()
        assert inside == pytest.approx(0.0 if k % 2 else 0.008, abs=1e-9), k


# --------------------------------------------------------------------------- stroke ends
@pytest.mark.parametrize("which", ["default", "four_start"])
@pytest.mark.parametrize("stroke_end", [0, 1])
def test_nut_assembly_at_the_stroke_ends_clears_the_screw(request, which, stroke_end):
    """The nut assembly (nut, its ends and flange, the flange bolts, ring gears, carriers,
    retaining rings, rollers with gears and journals) moved by the stroke end's shift: no
    volume shared with the screw (thread and ends; the screw-roller thread contact is a
    designed line contact, checked elsewhere) nor with the bearings, locknut, shaft ring and
    drive key; and the screw runs
    through both carriers (its section at their mid-planes reaches the root radius and stays
    inside the carrier bore)."""
    d, lay, asm = request.getfixturevalue(which)
    mech = layout(d)
    s = lay.shifts[stroke_end]
    assert s == (-50.0, 50.0)[stroke_end]                     # both: the default 100 mm stroke
    screw_parts = {"screw": build_part(d, "screw", TOL).to_trimesh(),
                   **{n: asm.placed[n][0] for n in ("screw_end_lo", "screw_end_hi")}}
    screw = {n: _solid(m) for n, m in screw_parts.items()}
    # what stays with the screw (moving_group "screw"): its ends and the bearings, locknut,
    # shaft ring and drive key; the flange bolts travel with the nut
    fixed = {n: _solid(*asm.placed[n][:2]) for n in PURCHASED if moving_group(n) == "screw"}
    moving = [n for n in asm.placed if moving_group(Assembly.rigid_body(n)) != "screw"]
    assert set(fixed) == set(PURCHASED) - {f"flange_bolt_{k}" for k in range(6)}
    last = d.roller.count - 1
    assert {"nut", "nut_flange", "nut_end_lo", "nut_ring_gear_hi", "carrier_lo", "retaining_ring_hi",
            f"roller_{last}", f"roller_{last}_gear_lo", f"roller_{last}_journal_hi"} <= set(moving)
    for name in moving:
        part = _solid(*asm.placed[name][:2]).translate((0.0, 0.0, s))
        if not name.startswith("roller_"):
            # the parts around the screw stay over it at the stroke end: the check is not empty
            bb = part.bounding_box()
            assert lay.screw_z[0] < bb[2] and bb[5] < lay.screw_z[1], name
        thread_contact = name.startswith("roller_") and "_journal_" not in name
        for other, solid in [*([] if thread_contact else screw.items()), *fixed.items()]:
            assert (part ^ solid).volume() < 1e-6, (name, other, s)
    whole = screw["screw"] + screw["screw_end_lo"] + screw["screw_end_hi"]
    for end in mech.ends:
        P = np.vstack(whole.slice(0.5 * sum(end.carrier) + s).to_polygons())
        r = np.hypot(P[:, 0], P[:, 1]).max()
        assert 0.5 * d.screw.minor_diameter_mm <= r < mech.carrier_inner_radius_mm
