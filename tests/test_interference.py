"""Interference check: nominal screw interferes, corrected screw does not."""
import json


from cli_helpers import run




def test_check_default_design_corrected_screw_is_clean():
    code, out, _ = run(["check", "--json", "--quiet"])
    rep = json.loads(out)
    assert code == 0
    assert rep["found"] is False and rep["pairs"] == []
    assert rep["screw"] == "corrected"
    assert rep["screw_pitch_diameter_mm"] < 24.0
    # touching roller-nut flanks (zero design gap) overlap by no more than the mesh tolerance
    for row in rep["contact_within_tolerance"]:
        assert row["mean_thickness_mm"] <= 2 * rep["chord_tolerance_mm"]


def test_check_default_design_nominal_screw_interferes_at_screw_roller_pairs():
    code, out, _ = run(["check", "--screw", "nominal", "--json", "--quiet"])
    rep = json.loads(out)
    assert code == 1
    assert rep["found"] is True
    pairs = {tuple(r["pair"]) for r in rep["pairs"]}
    # the roller threads and the roller gears (their teeth carry the thread) hit the screw
    assert pairs == {("screw", f"roller_{k}{g}") for k in range(10) for g in ("", "_gear_lo", "_gear_hi")}
    for r in rep["pairs"]:
        thread = "gear" not in r["pair"][1]
        assert r["volume_mm3"] > (0.1 if thread else 0.005)
        if thread:
            assert r["teeth"] == list(range(1, 21))
        # the overlap is as thick as the analytic interference (0.047 mm along the normal)
        assert 0.015 < r["mean_thickness_mm"] < 0.047


def test_check_text_output_names_pairs():
    code, out, _ = run(["check", "--screw", "nominal", "--quiet"])
    assert code == 1
    assert "INTERFERENCE screw / roller_0" in out and "interference found" in out
