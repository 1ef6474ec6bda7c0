"""End to end: build on non-default designs (left hand, compression-compression, 4 starts)."""
import json

import pytest

from prs_geom.model.design import Loading, Nut, PRSDesign, Roller, Screw, Thread
from prs_geom.pipeline import STAGES, build
from prs_geom.pipeline import load_any_design as load_design

DESIGNS = {
    "left-hand-cc": lambda: PRSDesign(name="lh", thread=Thread(hand="left"),
                                      loading=Loading(installation="compression-compression", axial_load_n=8000.0),
                                      roller=Roller(count=7)),
    "four-starts": lambda: PRSDesign(name="s4", thread=Thread(pitch_mm=1.0, engaged_teeth=8, flank_half_angle_deg=40.0),
                                     screw=Screw(pitch_diameter_mm=12.0, starts=4),
                                     roller=Roller(pitch_diameter_mm=6.0, count=5),
                                     nut=Nut(pitch_diameter_mm=24.0, starts=4, outer_diameter_mm=32.0)),
}


@pytest.mark.parametrize("key", sorted(DESIGNS))
def test_build_every_stage_on_other_designs(key, tmp_path):
    d = DESIGNS[key]()
    out = tmp_path / "out"
    rep = build(d, out)
    assert set(rep["timings_s"]) == {name for name, _ in STAGES}
    on_disk = json.loads((out / "report.json").read_text())
    assert load_design(out / "design.toml") == d
    assert on_disk["design"]["thread"]["hand"] == d.thread.hand
    for row in rep["checks"]["meshes"]:
        assert row["watertight"] and row["manifold"] and row["max_deviation_mm"] <= row["chord_tolerance_mm"]
    assert rep["checks"]["fcl"]["max_abs_difference_mm"] <= rep["checks"]["fcl"]["patch_chord_tolerance_mm"]
    assert rep["checks"]["interference"]["found"] is False
    assert rep["checks"]["interference"]["nominal_screw"]["found"] is True
    assert rep["loads"]["max_ldc"] > 1.0 and rep["loads"]["installation"] == d.loading.installation
    assert len(rep["machining"]["roller"]["rows"]) == 2 * d.thread.engaged_teeth
    for f in rep["files"]:
        assert (out / f).is_file()
