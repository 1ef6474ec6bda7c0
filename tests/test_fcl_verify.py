"""FCL mesh distances against the analytic contact distances (issue 4)."""
import numpy as np
import pytest

from prs_geom.design import default_design
from prs_geom.designio import load_design
from prs_geom.fcl_verify import flank_patch, verify_contacts
from prs_geom.contact import part_flanks

EXAMPLES = __import__("pathlib").Path(__file__).parent.parent / "examples"


@pytest.mark.parametrize("design", [default_design(), load_design(EXAMPLES / "graded-pitch.toml")],
                         ids=["default", "graded"])
def test_fcl_distances_agree_with_analytic_within_patch_tolerance(design):
    tol = 0.001
    rep = verify_contacts(design, tol)
    comps = rep["comparisons"]
    assert {c["side"] for c in comps} == {"screw", "nut"}
    assert len({c["roller"] for c in comps}) >= 3 and len({c["tooth"] for c in comps}) >= 3
    for c in comps:
        assert c["analytic_distance_mm"] > 0.003      # every checked contact has a clearance
        assert abs(c["difference_mm"]) <= tol, c
    assert rep["max_abs_difference_mm"] <= tol
    for side in ("screw", "nut"):
        assert rep["patches"][side]["patch_error_mm"] <= tol
        assert rep["patches"][side]["transform_error_bound_mm"] < 1e-5
    # nearest points: on near-parallel surfaces a distance error e moves the nearest point
    # by about sqrt(2 e / kappa_rel); kappa_rel >= 0.1/mm here, so 0.2 mm bounds it
    assert rep["max_point_difference_mm"] < 0.2


def test_distances_differ_between_teeth_of_a_graded_design():
    rep = verify_contacts(load_design(EXAMPLES / "graded-pitch.toml"), 0.001)
    screw = [c for c in rep["comparisons"] if c["side"] == "screw"]
    d = [c["analytic_distance_mm"] for c in screw]
    assert max(d) - min(d) > 1e-3          # micrometre pitch corrections show up
    f = [c["fcl_distance_mm"] for c in screw]
    np.testing.assert_allclose(np.diff(f), np.diff(d), atol=1e-4)


def test_patch_error_is_measured_not_assumed():
    fl = part_flanks(default_design())
    V, F, err = flank_patch(fl["roller"], 4.0, np.pi, 0.5, 1.0, 1e-3)
    assert 0 < err <= 1e-3
    V2, F2, err2 = flank_patch(fl["roller"], 4.0, np.pi, 0.5, 1.0, 1e-4)
    assert err2 < err and len(F2) > len(F)
