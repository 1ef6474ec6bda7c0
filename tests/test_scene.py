"""CAD deliverables read back by independent readers (issue 15): STL, GLB, 3MF.

One default build (with ``--screw nominal``) is read back with trimesh (STL, GLB), the
Khronos glTF validator (npm ``gltf-validator``, where node is present) and lib3mf (3MF).
"""
import json
import math
import struct
from pathlib import Path

import numpy as np
import pytest

from prs_geom.geometry.actuator import actuator_layout
import trimesh

from readers import khronos_issues, read_3mf, solid, stl_merged
from prs_geom.exports.meshes import stl_bytes, write_stl_pieces
from prs_geom.exports.scene import split_normals
from prs_geom.geometry.actuator import actuator_layout
from prs_geom.geometry.datum import datum_mark
from prs_geom.geometry.frames import roller_transform
from prs_geom.geometry.mechanism import layout
from prs_geom.geometry.profiles import ThreadProfiles
from prs_geom.mesh.thread import axial_line_crossings
from prs_geom.model.design import default_design
from prs_geom.model.io import design_hash
from prs_geom.pipeline import BuildOptions, build


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("scene") / "out"
    d = default_design()
    report = build(d, out, options=BuildOptions(nominal_screw=True))
    return d, out, report


# --------------------------------------------------------------------------- STL
def test_exported_screw_is_the_theoretical_one(built):
    """screw.stl: its largest radius is the major radius, and its axial section at the
    theoretical pitch radius has tooth and groove each p/2 wide (the nominal screw's tooth
    is wider there); screw_nominal.stl is the nominal screw."""
    d, out, report = built
    r_th = 0.5 * report["contact"]["screw_roller"]["theoretical_pitch_diameter_mm"]
    for name, r_pitch in (("screw.stl", r_th), ("screw_nominal.stl", 0.5 * d.screw.pitch_diameter_mm)):
        m = stl_merged(out / name)
        r = np.hypot(m.vertices[:, 0], m.vertices[:, 1])
        assert r.max() == pytest.approx(0.5 * d.screw.major_diameter_mm, abs=1e-5)   # float32 in STL
        # the line (r_pitch, 0, z) pierces the flanks of the section at theta = 0
        xs = axial_line_crossings(np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces), r_pitch, 0.0)
        # on the full-depth thread (the run-outs fill the groove toward the screw's ends), and
        # whole widths only (the first and last crossing there cut a tooth or groove anywhere)
        full = actuator_layout(d).full_thread_z
        xs = xs[(xs > full[0]) & (xs < full[1])]
        assert len(xs) > 20
        widths = np.diff(np.sort(xs))[1:-1]
        # 5-start screw, pitch p: the section shows every pitch p/2 + p/2 (the chord error of
        # the 0.01 mm mesh moves a crossing by at most tol / tan(beta) = 0.01 mm)
        np.testing.assert_allclose(widths, 0.5 * d.thread.pitch_mm, atol=0.012)
    th = stl_merged(out / "screw.stl")
    nom = stl_merged(out / "screw_nominal.stl")
    # the theoretical screw is thinner at the same radius: less volume
    assert th.volume < nom.volume - 1.0


def test_stl_header_and_vectorised_writer_read_back(built):
    d, out, report = built
    head = (out / "roller.stl").read_bytes()[:80].decode("ascii")
    assert head.startswith("prs_geom roller; units mm; part frame; design sha256 " + design_hash(d))
    # the writer against trimesh's reader: same triangles (float32), normals of unit length
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    data = stl_bytes(V, F, "test tetrahedron")
    assert len(data) == 84 + 50 * 4 and struct.unpack("<I", data[80:84])[0] == 4
    m = trimesh.load(trimesh.util.wrap_as_stream(data), file_type="stl", process=False)
    np.testing.assert_array_equal(m.triangles, V[F].astype(np.float32))
    assert m.volume == pytest.approx(1 / 6, rel=1e-7) and m.is_winding_consistent
    with pytest.raises(ValueError, match="solid"):
        stl_bytes(V, F, "solid part")


def test_streamed_stl_is_the_one_piece_stl(tmp_path):
    """Issue 17: the assembly STL is written body by body (one body in memory at a time);
    the bytes are those of the concatenated mesh, count patched into the header."""
    rng = np.random.default_rng(7)
    pieces = [(rng.normal(size=(n, 3)), rng.integers(0, n, size=(2 * n, 3))) for n in (5, 40, 1)]
    n = write_stl_pieces(iter(pieces), tmp_path / "a.stl", "pieces")
    V = np.concatenate([p[0] for p in pieces])
    offsets = np.cumsum([0] + [len(p[0]) for p in pieces[:-1]])
    F = np.concatenate([p[1] + o for p, o in zip(pieces, offsets)])
    assert n == len(F) == 92
    assert (tmp_path / "a.stl").read_bytes() == stl_bytes(V, F, "pieces")


def test_exported_parts_do_not_interfere_and_the_nominal_screw_does(built):
    """The interference check run on the exported files themselves: each roller (roller.stl
    placed by its 3MF build-item transform) against screw.stl and nut.stl. The designed
    state touches along the contacts only: mean overlap thickness 2V/A within twice the
    chord tolerance. With screw_nominal.stl every roller overlaps the screw by far more."""
    d, out, report = built
    tol = d.mesh.chord_tolerance_mm
    screw, nut, roller = (stl_merged(out / f"{n}.stl") for n in ("screw", "nut", "roller"))
    nominal = stl_merged(out / "screw_nominal.stl")
    items = read_3mf(out / "assembly.3mf")["items"]
    S, N, R = (solid(m.vertices, m.faces) for m in (screw, nut, roller))
    SN = solid(nominal.vertices, nominal.faces)
    for k in range(d.roller.count):
        T = items[f"roller_{k}"]
        Rk = R.transform(np.ascontiguousarray(T[:3, :4]))
        for other, what in ((S, "screw"), (N, "nut")):
            inter = Rk ^ other
            vol = inter.volume()
            thick = 2 * vol / inter.surface_area() if vol > 0 else 0.0
            assert thick <= 2 * tol, (k, what, vol, thick)
        bad = Rk ^ SN
        assert bad.volume() > 0.1 and 2 * bad.volume() / bad.surface_area() > 2 * tol


# --------------------------------------------------------------------------- GLB
def _glb_json(path: Path) -> dict:
    data = path.read_bytes()
    magic, version, total = struct.unpack("<4sII", data[:12])
    assert magic == b"glTF" and version == 2 and total == len(data)
    n, kind = struct.unpack("<I4s", data[12:20])
    assert kind == b"JSON"
    return json.loads(data[20:20 + n])


def test_glb_is_metres_y_up_named_with_materials_and_normals(built):
    d, out, report = built
    doc = _glb_json(out / "assembly.glb")
    scene = trimesh.load(out / "assembly.glb")          # an independent reader applies the nodes
    lo, hi = scene.bounds
    ext = hi - lo
    # metres: the actuator's nut flange (the widest part) across x and z, the screw from end
    # face to end face along +Y (the axis): the actuator's parts reach beyond the nut's ends
    act = actuator_layout(d)
    assert act.nut_mount.flange_diameter_mm == 76.0 > d.nut.outer_diameter_mm
    assert ext[0] == pytest.approx(act.nut_mount.flange_diameter_mm * 1e-3, rel=1e-3)
    assert ext[2] == pytest.approx(act.nut_mount.flange_diameter_mm * 1e-3, rel=1e-3)
    assert act.screw_length_mm == pytest.approx(283.3)
    assert ext[1] == pytest.approx(act.screw_length_mm * 1e-3, rel=1e-3)
    names = {n["name"] for n in doc["nodes"]}
    assert {"screw", "nut"} | {f"roller_{k}" for k in range(d.roller.count)} <= names
    roller_meshes = {n["mesh"] for n in doc["nodes"] if n["name"] in {f"roller_{k}" for k in range(d.roller.count)}}
    assert len(roller_meshes) == 1                       # one roller mesh, placed z times
    assert len(doc["materials"]) >= 3
    for m in doc["materials"]:
        pbr = m["pbrMetallicRoughness"]
        assert len(pbr["baseColorFactor"]) == 4 and 0 <= pbr["metallicFactor"] <= 1
    for mesh in doc["meshes"]:
        prim = mesh["primitives"][0]
        assert "NORMAL" in prim["attributes"] and "material" in prim
    text = json.dumps(doc)
    assert "extras" not in text and "extensions" not in text
    # roller 3's node places it where the frames say (translation in metres)
    node = next(n for n in doc["nodes"] if n["name"] == "roller_3")
    np.testing.assert_allclose(node["translation"], roller_transform(d, 3)[:3, 3] * 1e-3, atol=1e-12)


def test_split_normals_keep_sharp_edges_and_smooth_surfaces():
    box = trimesh.creation.box([1, 2, 3])
    V, N, F = split_normals(box.vertices, box.faces)
    assert len(V) == 24                                   # every corner of a cube is sharp
    np.testing.assert_allclose(np.abs(N).max(axis=1), 1.0, atol=1e-12)
    cyl = trimesh.creation.cylinder(radius=1.0, height=2.0, sections=64)
    V, N, F = split_normals(cyl.vertices, cyl.faces)
    side = np.abs(N[:, 2]) < 1e-9
    # side normals are radial (smooth across the 5.6 deg facets), caps axial
    np.testing.assert_allclose(N[side][:, :2], V[side][:, :2] / np.hypot(V[side][:, 0], V[side][:, 1])[:, None],
                               atol=1e-12)
    assert np.all(np.abs(np.abs(N[~side][:, 2]) - 1) < 1e-12)
    # same triangles as before, only the vertices split
    np.testing.assert_allclose(V[F], cyl.vertices[cyl.faces], atol=0)


def test_glb_passes_the_khronos_validator(built, tmp_path):
    d, out, report = built
    issues = khronos_issues(out / "assembly.glb", tmp_path)
    assert issues["numErrors"] == 0, issues["messages"][:10]
    assert issues["numWarnings"] == 0, issues["messages"][:10]


# --------------------------------------------------------------------------- 3MF
def test_3mf_reads_back_with_one_object_per_part_in_millimetres(built):
    d, out, report = built
    m = read_3mf(out / "assembly.3mf")
    assert m["unit"] == m["mm"]
    assert {"screw", "nut", "roller"} <= set(m["objects"])
    rollers = [f"roller_{k}" for k in range(d.roller.count)]
    assert {m["item_object"][r] for r in rollers} == {"roller"}     # one mesh, z build items
    parts = {row["name"]: row for row in report["assembly"]["complete_parts"]}
    # one object per complete part, one build item per copy
    assert set(m["objects"]) == set(parts)
    assert set(m["items"]) == {body for row in parts.values() for body in row["instances"]}
    for k in (0, 3):
        # lib3mf keeps transforms as float32 and writes them with 6 decimals: ~5 nm here
        np.testing.assert_allclose(m["items"][f"roller_{k}"], roller_transform(d, k), atol=1e-5)
    # volumes equal the per-part STLs' (both float32 coordinates)
    for name in ("screw", "roller", "nut"):
        V, F = m["objects"][name]
        vol = trimesh.Trimesh(V, F, process=False).volume
        # lib3mf writes float32 coordinates rounded to about 8 significant digits: each vertex
        # may move by up to one float32 step (4e-6 mm at these radii) from the STL's, so the
        # volumes agree within surface area x 4e-6 mm
        stl = trimesh.load(out / f"{name}.stl", file_type="stl", process=False)
        assert abs(vol - stl.volume) <= stl.area * 4e-6, (name, vol, stl.volume)
        assert vol == pytest.approx(parts[name]["volume_mm3"], rel=1e-6)


def test_writing_3mf_leaves_the_process_locale_as_it_was(tmp_path):
    """lib3mf sets the C locale and leaves it; the writer restores it (else every later text
    file of the process would be written as ASCII)."""
    import locale

    from prs_geom.exports.scene import Scene, SceneMesh, SceneNode, MATERIALS, write_3mf

    before = locale.setlocale(locale.LC_ALL, None)
    box = trimesh.creation.box([1, 1, 1])
    scene = Scene({"box": SceneMesh("box", box.vertices, box.faces, "screw")}, {"screw": MATERIALS["screw"]},
                  (SceneNode("box", "box"),), "locale test")
    write_3mf(scene, tmp_path / "box.3mf")
    assert locale.setlocale(locale.LC_ALL, None) == before
    assert read_3mf(tmp_path / "box.3mf")["objects"]["box"][0].shape == (8, 3)


def test_assembly_stl_is_closed_and_holds_every_part(built):
    """assembly.stl read back by trimesh: closed (every edge used by exactly two faces after
    merging coincident vertices, although a roller and its gears, the nut and its ring gears,
    touch face to face), and its volume is the sum of the 3MF build items' (an independent
    reader of the other file), within the float32 rounding. Each 3MF object (a complete part)
    is the union of its pieces: their volumes less the overlaps, which are checked against
    their closed forms, plus the datum slot the union fills."""
    from prs_geom.analysis.contact import theoretical_screw
    from prs_geom.mesh.assembly import build_assembly

    d, out, report = built
    stl = trimesh.load(out / "assembly.stl", file_type="stl")
    assert stl.is_watertight and stl.is_winding_consistent
    m = read_3mf(out / "assembly.3mf")
    vols = {name: trimesh.Trimesh(V, F, process=False).volume for name, (V, F) in m["objects"].items()}
    total = sum(vols[m["item_object"][item]] for item in m["items"])
    assert abs(stl.volume - total) <= stl.area * 4e-6, (stl.volume, total)
    # the pieces overlap where each nut end sleeve grips its ring gear's body (an annulus,
    # docs/theory/mechanism.md), where the nut flange grips the lower nut end (an annulus 0.5
    # mm thick) and where each screw end's run-out cylinder lies in the thread; the complete
    # part counts each once (the closed forms of the true circles agree to 0.1 %)
    lay, act = layout(d), actuator_layout(d)
    # the pieces as the build placed them (its screw is the theoretical one)
    asm = build_assembly(d, screw_profile=theoretical_screw(d).profile)

    def overlap_of(one: str, other: str) -> float:
        a, b = asm.placed_mesh(one), asm.placed_mesh(other)
        return (solid(a.vertices, a.faces) ^ solid(b.vertices, b.faces)).volume()

    gear = sum(overlap_of(f"nut_end_{side}", f"nut_ring_gear_{side}") for side in ("lo", "hi"))
    exact = math.pi * (lay.ring_gear_outer_radius_mm ** 2 - lay.nut_end_sleeve_inner_radius_mm ** 2) \
        * lay.gear_face_width_mm
    assert gear == pytest.approx(2 * exact, rel=1e-3)
    flange = overlap_of("nut_end_lo", "nut_flange")
    R, t = lay.nut_end_outer_radius_mm, act.nut_mount.z[1] - act.nut_mount.z[0]
    # a thin annulus: its two polygons (1 um chords) each move its area by up to 1 um x perimeter
    assert flange == pytest.approx(math.pi * (R ** 2 - (R - 0.5) ** 2) * t, abs=2 * math.pi * (2 * R - 0.5) * t * 1e-3)
    ends = overlap_of("screw", "screw_end_lo") + overlap_of("screw", "screw_end_hi")
    # the run-out cylinders (root radius less the chord tolerance), less the datum slot of
    # the thread's face A that the lower one fills
    r_ro = 0.5 * d.screw.minor_diameter_mm - max(0.01, d.mesh.chord_tolerance_mm)
    slot = datum_mark(ThreadProfiles.from_design(d).screw, act.thread_z[0]).volume
    run_outs = sum(math.pi * r_ro ** 2 * (e.run_out[1] - e.run_out[0]) for e in act.ends)
    assert ends == pytest.approx(run_outs - slot, rel=1e-3)
    parts = {row["name"]: row for row in report["assembly"]["complete_parts"]}
    for name, overlap in (("nut", gear + flange), ("screw", ends)):
        pieces = sum(float(asm.placed[p][0].volume) for p in parts[name]["pieces"])
        expected = pieces - overlap + parts[name]["filled_voids_mm3"]
        assert abs(vols[name] - expected) <= 1e-3 * overlap + stl.area * 4e-6, (name, vols[name], expected)


def _box_scene():
    from prs_geom.exports.scene import MATERIALS, Scene, SceneMesh, SceneNode

    box = trimesh.creation.box([1, 1, 1])
    return Scene({"box": SceneMesh("box", box.vertices, box.faces, "screw")}, {"screw": MATERIALS["screw"]},
                 (SceneNode("box", "box"),), "atomic test")


def test_a_scene_write_that_fails_midway_leaves_no_file(tmp_path, monkeypatch):
    """write_glb and write_3mf write through a temporary sibling: a writer that dies after
    writing part of the file leaves neither the target nor a temporary file."""
    import prs_geom.exports.scene as scene_module

    def half_then_fail(scene, sharp_deg):     # the header written, then the disk is full
        yield b"glTF" + bytes(8)
        raise OSError("disk full")

    def model_half_then_fail(model, path):
        Path(path).write_bytes(b"PK\x03\x04")
        raise RuntimeError("lib3mf failed")

    scene = _box_scene()
    with monkeypatch.context() as m:
        m.setattr(scene_module, "_glb_file", half_then_fail)
        with pytest.raises(OSError, match="disk full"):
            scene_module.write_glb(scene, tmp_path / "assembly.glb")
    assert list(tmp_path.iterdir()) == []
    with monkeypatch.context() as m:
        m.setattr(scene_module, "_write_model", model_half_then_fail)
        with pytest.raises(RuntimeError, match="lib3mf failed"):
            scene_module.write_3mf(scene, tmp_path / "assembly.3mf")
    assert list(tmp_path.iterdir()) == []
    # and when nothing fails, the files and only they are there
    scene_module.write_glb(scene, tmp_path / "assembly.glb")
    scene_module.write_3mf(scene, tmp_path / "assembly.3mf")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["assembly.3mf", "assembly.glb"]
    assert read_3mf(tmp_path / "assembly.3mf")["objects"]["box"][0].shape == (8, 3)
