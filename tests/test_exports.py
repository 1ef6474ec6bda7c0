"""Mesh exports read back (issue 3)."""
import json

import numpy as np
import pytest
import trimesh

from prs_geom.model.design import PRSDesign, Roller, MeshSettings
from prs_geom.pipeline import build


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("b") / "out"
    d = PRSDesign(name="exp", roller=Roller(count=5), mesh=MeshSettings(chord_tolerance_mm=0.02))
    report = build(d, out)
    return d, out, report


def test_stl_files_read_back_to_the_reported_meshes(built):
    d, out, report = built
    rows = {r["part"]: r for r in report["checks"]["meshes"]}
    parts = {r["name"]: r for r in report["assembly"]["complete_parts"]}
    for part in ("screw", "roller", "nut"):
        # the file is the complete part (thread and the rest of its body)
        m = trimesh.load(out / f"{part}.stl")
        assert len(m.faces) == parts[part]["triangles"]
        assert m.is_watertight and parts[part]["closed"] and parts[part]["shells"] == 1
        assert m.volume == pytest.approx(parts[part]["volume_mm3"], rel=1e-6)
        assert m.volume > rows[part]["volume_mm3"]        # more than the thread alone
        assert rows[part]["float32_rounding_mm"] < 5e-6
    asm = trimesh.load(out / "assembly.stl")
    # one closed shell per rigid body: screw, nut (with its ring gears), 5 rollers (with gears)
    assert asm.is_watertight and asm.is_winding_consistent


def test_glb_scene_has_named_parts(built):
    d, out, report = built
    scene = trimesh.load(out / "assembly.glb")
    assert isinstance(scene, trimesh.Scene)
    names = set(scene.graph.nodes_geometry)
    assert set(report["assembly"]["parts"]) == names
    # roller 3 placed at its carrier angle: its axis at the centre distance (metres, +Y up:
    # the screw axis is glTF's y, so the radial plane is x-z)
    T, geom = scene.graph["roller_3"]
    assert np.hypot(T[0, 3], T[2, 3]) == pytest.approx(d.centre_distance_mm * 1e-3, abs=1e-8)


def test_report_mesh_section(built):
    d, out, report = built
    on_disk = json.loads((out / "report.json").read_text())
    assert on_disk["checks"]["meshes"] == report["checks"]["meshes"]
    for row in report["checks"]["meshes"]:
        assert set(row) >= {"part", "triangles", "watertight", "manifold", "chord_tolerance_mm",
                            "max_deviation_mm"}
        assert row["watertight"] and row["manifold"]
        # the design's 0.02 mm, or 0.08 % of the outer thread radius for a small part (so the
        # mesh volume stays within 0.1 % of the solid's): the rollers here
        r_out = 0.5 * getattr(d, row["part"]).major_diameter_mm
        assert row["chord_tolerance_mm"] == pytest.approx(min(0.02, 8e-4 * r_out), rel=1e-12)
        assert 0 < row["max_deviation_mm"] <= row["chord_tolerance_mm"]
        assert abs(row["volume_rel_error"]) < 1e-3
    assert report["gears"]["passed"] and report["gears"]["roller_gear"]["teeth"] * report["gears"]["roller_gear"][
        "module_mm"] == pytest.approx(8.0)
    assert report["assembly"]["roller_carrier_angles_deg"] == pytest.approx([0, 72, 144, 216, 288])
    assert set(report["files"]) >= {"screw.stl", "roller.stl", "nut.stl", "assembly.stl", "assembly.glb",
                                    "report.json", "design.toml"}
    for f in report["files"]:
        assert (out / f).is_file()


def test_load_plots_and_sections(built):
    d, out, report = built
    for stem in ("loads_ldc", "pitch_corrections", "off_design"):
        png = (out / f"{stem}.png").read_bytes()
        assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10000
        assert b"<svg" in (out / f"{stem}.svg").read_bytes()[:500]
    L = report["loads"]
    assert len(L["ldc_nut_roller"]) == d.thread.engaged_teeth
    assert L["max_ldc"] > 1.1 and L["axial_stiffness_N_per_um"] > 0
    assert len(report["pitch"]["equal_load"]["roller_mm"]) == d.thread.engaged_teeth - 1
