"""The report serialiser (prs_geom.exports.report): typed results in, report.json sections out."""
import dataclasses
import json

import pytest

from prs_geom.analysis.contact import analyse_contact
from prs_geom.analysis.load_details import LoadModelDetails
from prs_geom.analysis.loads import build_model, load_distribution
from prs_geom.exports.report import (BuildResults, contact_section, load_details_dict, loads_section,
                                     model_risk_section, report_dict)
from prs_geom.model.design import default_design


@pytest.fixture(scope="module")
def analytic():
    d = default_design()
    contact = analyse_contact(d)
    return d, contact, build_model(d, contact)


def test_details_serialise_in_the_documented_order(analytic):
    _, _, model = analytic
    out = load_details_dict(model.details)
    assert list(out) == ["tooth_width", "hertz_rs", "hertz_nr", "tooth_screw", "tooth_roller_screw_side",
                         "tooth_roller_nut_side", "tooth_nut", "section_areas_mm2"]
    assert list(out["hertz_rs"])[-2:] == ["normal_axial_component", "C_normal"]
    assert list(out["tooth_nut"]) == ["a_mm", "b_mm", "c_mm", "width_mm", "bending", "shear", "root_tilt",
                                      "root_shear", "radial"]
    assert load_details_dict(None) == {}
    json.dumps(out)


def test_details_are_frozen_and_fe_goes_with_its_summary(analytic):
    _, _, model = analytic
    with pytest.raises(dataclasses.FrozenInstanceError):
        model.details.tooth_width = "unit"
    with pytest.raises(ValueError):
        dataclasses.replace(model.details, compliance="fe")
    assert isinstance(model.details, LoadModelDetails) and model.details.compliance is None


def test_loads_section_from_the_distribution(analytic):
    d, _, model = analytic
    dist = load_distribution(d, model)
    sec = loads_section(dist)
    assert sec["max_ldc"] == dist.max_ldc == max(sec["ldc_nut_roller"] + sec["ldc_roller_screw"])
    assert sec["compliances"]["model"] == "analytic"
    assert model_risk_section(None)["computed"] is False


def test_report_of_a_run_without_stages_is_the_skeleton(analytic):
    d, contact, _ = analytic
    results = BuildResults(d, warnings=d.sizing_warnings())
    rep = report_dict(results)
    assert list(rep) == ["format_version", "prs_geom_version", "design", "warnings", "contact", "loads", "pitch",
                         "checks", "machining", "timings_s", "files"]
    assert rep["contact"] is None and rep["checks"] == {}
    results.contact = contact
    assert report_dict(results)["contact"] == contact_section(contact)
