"""Studies at the pipeline layer: backends give identical numbers; robust pitch design.

The robust design is checked against its own objective evaluated independently (a direct
tolerance study of the written design on the same seed and spectrum) and against the two
designs it must not lose to (constant pitch and equal sharing at the design load).
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from prs_geom import studies
from prs_geom.analysis.contact import analyse_contact
from prs_geom.analysis.loads import build_model, design_pitches, with_pitch_lists
from prs_geom.analysis.robust import weighted_quantile
from prs_geom.exports.report import tolerance_section
from prs_geom.model.design import Tolerances, default_design
from prs_geom.model.io import load_design
from prs_geom.model.spectrum import LoadCase, Spectrum

from cli_helpers import run


@pytest.fixture(scope="module")
def setup():
    d = default_design()
    c = analyse_contact(d)
    return d, c, build_model(d, c)


def test_dask_local_cluster_equals_joblib_bit_for_bit(setup):
    """Done-when: a Dask LocalCluster run gives bit-identical results to the joblib run (and to
    the serial run); 3 chunks of CHUNK_SAMPLES, so the chunking is exercised."""
    pytest.importorskip("distributed")
    d, c, m = setup
    tol = Tolerances(flank_um=0.5, roller_diameter_um=1.0, nut_eccentricity_um=1.0, lead_um=1.0,
                     samples=2 * studies.CHUNK_SAMPLES + 17, seed=42, load_fractions=(0.5, 1.0))
    runs = {}
    for name, ex in (("serial", studies.Execution(workers=1)), ("joblib", studies.Execution(workers=2)),
                     ("dask", studies.Execution(dask_workers=2))):
        runs[name] = studies.tolerance_study(d, tol, contact=c, model=m, execution=ex)
    for name in ("joblib", "dask"):
        for key in ("worst_nr", "worst_rs", "share_max", "share_min", "open_teeth"):
            assert np.array_equal(getattr(runs[name].stats, key), getattr(runs["serial"].stats, key)), (name, key)
        section = json.dumps(tolerance_section(runs[name]), sort_keys=True)
        assert section == json.dumps(tolerance_section(runs["serial"]), sort_keys=True)
    assert runs["serial"].stats.worst.shape == (2, tol.samples)


def test_weighted_quantile_matches_repeated_samples():
    v = np.array([[3.0, 1.0, 2.0, 4.0], [10.0, 12.0, 11.0, 13.0]])
    # weights 0.75 / 0.25 = the first row counted three times
    expanded = np.concatenate([v[0], v[0], v[0], v[1]])
    for q in (0.1, 0.5, 0.7, 0.75, 0.76, 0.95):
        ref = np.sort(expanded)[int(np.ceil(q * expanded.size)) - 1]
        assert weighted_quantile(v, [0.75, 0.25], q) == ref


def test_robust_design_beats_equal_at_design_load(setup, tmp_path):
    """Done-when: the robust design beats equal-at-design-load on its own objective over the
    spectrum; the written design re-evaluated by an independent tolerance study agrees."""
    d, c, m = setup
    F0 = d.loading.axial_load_n
    spectrum = Spectrum((LoadCase(0.25 * F0, 0.5), LoadCase(0.5 * F0, 0.3), LoadCase(F0, 0.2)))
    tol = Tolerances(flank_um=0.5)
    res = studies.robust_pitch(d, spectrum, tol, samples=40, seed=7, contact=c, model=m,
                               grid=(0.0, 0.5, 1.0))
    cmp = res.comparison
    robust, equal, const = (cmp[k]["objective"] for k in ("robust", "equal_at_design_load", "constant_pitch"))
    assert robust < equal - 0.02
    assert robust <= const
    # independent evaluation of the written lists: a tolerance study on the same draws
    st = studies.tolerance_study(res.design, Tolerances(flank_um=0.5, samples=40, seed=7), contact=c, model=m,
                                 loads_n=spectrum.loads_n, importance=False)
    assert abs(weighted_quantile(st.stats.worst, spectrum.weights, 0.95) - robust) < 1e-12
    # with the model rebuilt from the graded design (its contact point moves with the grading)
    st = studies.tolerance_study(res.design, Tolerances(flank_um=0.5, samples=40, seed=7),
                                 loads_n=spectrum.loads_n, importance=False)
    assert abs(weighted_quantile(st.stats.worst, spectrum.weights, 0.95) - robust) < 1e-3
    # (1, 1) of the family is the equal-load design
    eq = with_pitch_lists(d, design_pitches(d, model=m))
    st_eq = studies.tolerance_study(eq, Tolerances(flank_um=0.5, samples=40, seed=7), contact=c, model=m,
                                    loads_n=spectrum.loads_n, importance=False)
    assert abs(weighted_quantile(st_eq.stats.worst, spectrum.weights, 0.95) - equal) < 1e-12


def test_cli_robust_writes_design(tmp_path):
    spec = tmp_path / "spectrum.toml"
    spec.write_text("[[case]]\nload_n = 5000.0\ntime_share = 0.7\nspeed_rpm = 1000.0\n\n"
                    "[[case]]\nload_n = 20000.0\ntime_share = 0.3\nspeed_rpm = 200.0\n", encoding="utf-8")
    out = tmp_path / "robust.toml"
    code, stdout, stderr = run(["design-pitch", "--robust", "--spectrum", str(spec), "--flank-um", "0.3",
                                "--samples", "20", "--out", str(out), "--json"])
    assert code == 0, stderr
    rep = json.loads(stdout)
    assert rep["spectrum"]["weighting"] == "revolutions"
    assert abs(rep["spectrum"]["cases"][0]["weight"] - 0.7 * 1000 / (0.7 * 1000 + 0.3 * 200)) < 1e-12
    assert rep["robust"]["objective"] <= rep["equal_at_design_load"]["objective"]
    new = load_design(out)
    assert new.name == "default-robust" and new.graded
    code, _, stderr = run(["design-pitch", "--spectrum", str(spec)])
    assert code == 2 and "--spectrum goes with --robust" in stderr
