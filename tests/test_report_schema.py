"""The JSON Schema of report.json (prs_geom/schemas/report.schema.json): it is a valid draft
2020-12 schema, real reports of both kinds follow it, broken reports do not, and every key a
real report writes is described.

The default, graded and harmonic designs are the run's shared builds (tests/conftest.py); the
conftest fixture ``validate_every_build`` checks every other build of the suite."""
import copy
import json
import re
import sys
from pathlib import Path

import jsonschema
import pytest

from prs_geom import pipeline
from prs_geom.exports.report import REPORT_FORMAT_VERSION
from prs_geom.exports.report_schema import load_schema, validate_report

#: Open diagnostic objects whose keys the schema does not list.
OPEN_DIAGNOSTICS = ("$.loads.compliances.details",)


@pytest.fixture(scope="module")
def default_report(default_build):
    return {"returned": default_build.returned, "disk": default_build.report}


@pytest.fixture(scope="module")
def graded_report(graded_build):
    return {"returned": graded_build.returned, "disk": graded_build.report}


@pytest.fixture(scope="module")
def harmonic_report(harmonic_build):
    return {"returned": harmonic_build.returned, "disk": harmonic_build.report}


@pytest.fixture
def default(default_report):
    """A deep copy of the default report (as written to disk), free to break."""
    return copy.deepcopy(default_report["disk"])


def _fails(report: dict, path_part: str | None = None) -> jsonschema.ValidationError:
    with pytest.raises(jsonschema.ValidationError) as info:
        validate_report(report)
    if path_part is not None:
        assert path_part in str(info.value.message), info.value.message
    return info.value


# --------------------------------------------------------------------------- the schema
def test_schema_is_valid_draft_2020_12():
    schema = load_schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert schema["$id"].startswith("urn:prs-geom:report:")
    assert schema["title"] and schema["description"]
    assert schema["$defs"]["prs_report"]["properties"]["format_version"]["const"] == REPORT_FORMAT_VERSION


def test_load_schema_returns_a_private_copy():
    a = load_schema()
    a["title"] = "changed"
    assert load_schema()["title"] != "changed"


def test_every_build_in_the_suite_is_validated():
    """The conftest fixture wraps pipeline.build (the CLI imports it at call time) and the
    ``build`` of test modules that imported it by name."""
    assert hasattr(pipeline.build, "__wrapped__")
    tests_dir = Path(__file__).resolve().parent
    for mod in list(sys.modules.values()):
        fn = getattr(mod, "build", None)
        path = getattr(mod, "__file__", None)
        if path and tests_dir in Path(path).resolve().parents and callable(fn) \
                and getattr(fn, "__module__", None) == "prs_geom.pipeline" and fn.__name__ == "build":
            assert hasattr(fn, "__wrapped__"), mod.__name__


# --------------------------------------------------------------------------- real reports
@pytest.mark.parametrize("kind", ["default", "graded", "harmonic"])
def test_real_reports_validate(kind, request):
    rep = request.getfixturevalue(f"{kind}_report")
    validate_report(rep["returned"])
    validate_report(rep["disk"])


def test_tooth_gaps_null_for_constant_pitch_object_for_graded(default_report, graded_report):
    assert default_report["disk"]["contact"]["tooth_gaps"] is None
    gaps = graded_report["disk"]["contact"]["tooth_gaps"]
    assert set(gaps) == {"screw", "nut"}
    assert "pitch_list_mm" not in default_report["disk"]["design"]["roller"]
    assert "pitch_list_mm" in graded_report["disk"]["design"]["roller"]


def test_keys_being_added_elsewhere_are_allowed(default):
    """Optional keys other changes add: warnings on mesh rows and the FCL check, an FCL
    tolerance, per-roller coefficients and load shares."""
    for row in default["checks"]["meshes"]:
        row["warnings"] = []
    default["checks"]["meshes"][0]["warnings"] = ["measured deviation 0.02 mm exceeds the chord tolerance 0.01 mm"]
    default["checks"]["fcl"]["warnings"] = []
    default["checks"]["fcl"]["difference_tolerance_mm"] = 0.001
    n = default["design"]["thread"]["engaged_teeth"]
    z = default["design"]["roller"]["count"]
    default["loads"]["ldc_per_roller"] = {"nut_roller": [[1.0] * n] * z, "roller_screw": [[1.0] * n] * z}
    default["loads"]["roller_load_share"] = [1.0 / z] * z
    default["warnings"] = ["FCL check: something exceeded its tolerance"]
    validate_report(default)
    default["loads"]["ldc_per_roller"]["nut_roller"][0] = ["1.0"] * n
    _fails(default, "$.loads.ldc_per_roller.nut_roller[0][")


# --------------------------------------------------------------------------- broken reports
def test_missing_required_key_fails(default):
    del default["loads"]["max_ldc"]
    err = _fails(default, "$.loads")
    assert "max_ldc" in err.message


def test_missing_required_top_level_section_fails(default):
    del default["checks"]
    _fails(default, "'checks' is a required property")


def test_wrong_type_fails_with_its_path(default):
    default["loads"]["ldc_nut_roller"][3] = "1.02"
    _fails(default, "$.loads.ldc_nut_roller[3]")


def test_integer_count_must_be_integer(default):
    default["checks"]["meshes"][1]["triangles"] = 1.5
    _fails(default, "$.checks.meshes[1].triangles")


def test_unknown_top_level_key_fails(default):
    default["extra"] = 1
    _fails(default, "'extra' was unexpected")


def test_unknown_key_in_a_fixed_section_fails(default):
    default["loads"]["max_ldc_typo"] = 1.4
    _fails(default, "$.loads")


def test_negative_triangle_count_fails(default):
    default["assembly"]["triangles"] = -1
    _fails(default, "$.assembly.triangles")
    default["assembly"]["triangles"] = 10
    default["checks"]["meshes"][0]["triangles"] = -5
    _fails(default, "$.checks.meshes[0].triangles")


def test_wrong_format_version_fails(default):
    default["format_version"] = 2
    _fails(default, "$.format_version")


def test_non_positive_tolerance_and_ldc_fail(default):
    broken = copy.deepcopy(default)
    broken["checks"]["fcl"]["patch_chord_tolerance_mm"] = 0.0
    _fails(broken, "$.checks.fcl.patch_chord_tolerance_mm")
    default["loads"]["max_ldc"] = 0.0
    _fails(default, "$.loads.max_ldc")


def test_tooth_gaps_of_wrong_shape_fail(default, graded_report):
    default["contact"]["tooth_gaps"] = {"screw": {}}
    _fails(default, "$.contact.tooth_gaps")
    graded = copy.deepcopy(graded_report["disk"])
    graded["contact"]["tooth_gaps"]["nut"]["upper"]["gap_mm"] = [1.0, 2.0]
    _fails(graded)


def test_harmonic_report_with_a_prs_section_fails(harmonic_report, default):
    rep = copy.deepcopy(harmonic_report["disk"])
    rep["loads"] = default["loads"]
    _fails(rep, "'loads' was unexpected")


def test_prs_report_with_the_harmonic_kind_fails(default):
    default["kind"] = "harmonic"
    _fails(default)


def test_harmonic_report_without_its_section_fails(harmonic_report):
    rep = copy.deepcopy(harmonic_report["disk"])
    del rep["harmonic"]
    _fails(rep, "'harmonic' is a required property")


# --------------------------------------------------------------------------- descriptions
def _applicable(validator, schema: dict, instance) -> list[dict]:
    """The schema objects that apply to ``instance``: ``schema`` with its ``$ref`` targets,
    the taken branch of if/then/else and the oneOf/anyOf branches the instance satisfies."""
    root = validator.schema
    out, todo = [], [schema]
    while todo:
        s = todo.pop()
        if not isinstance(s, dict):
            continue
        out.append(s)
        if "$ref" in s:
            assert s["$ref"].startswith("#/"), s["$ref"]
            target = root
            for part in s["$ref"][2:].split("/"):
                target = target[part]
            todo.append(target)
        todo += s.get("allOf", [])
        if "if" in s:
            taken = "then" if validator.evolve(schema=s["if"]).is_valid(instance) else "else"
            if taken in s:
                todo.append(s[taken])
        for key in ("oneOf", "anyOf"):
            todo += [b for b in s.get(key, []) if validator.evolve(schema=b).is_valid(instance)]
    return out


def _walk(validator, schema: dict, instance, path: str, missing: list[str], open_keys: list[str]) -> None:
    nodes = _applicable(validator, schema, instance)
    if isinstance(instance, dict):
        for key, value in instance.items():
            sub_path = f"{path}.{key}"
            prop = None
            for node in nodes:
                if key in node.get("properties", {}):
                    prop = node["properties"][key]
                    break
                matches = [v for pat, v in node.get("patternProperties", {}).items() if re.search(pat, key)]
                if matches:
                    prop = matches[0]
                    break
                if isinstance(node.get("additionalProperties"), dict):
                    prop = node["additionalProperties"]
                    break
            if prop is None:
                open_keys.append(sub_path)
                continue
            if not str(prop.get("description", "")).strip():
                missing.append(sub_path)
            _walk(validator, prop, value, sub_path, missing, open_keys)
    elif isinstance(instance, list):
        for node in nodes:
            if isinstance(node.get("items"), dict):
                for i, value in enumerate(instance):
                    _walk(validator, node["items"], value, f"{path}[{i}]", missing, open_keys)
                break


@pytest.mark.parametrize("kind", ["default", "graded", "harmonic"])
def test_every_key_of_the_real_reports_is_described(kind, request):
    report = request.getfixturevalue(f"{kind}_report")["disk"]
    schema = load_schema()
    validator = jsonschema.Draft202012Validator(schema)
    missing, open_keys = [], []
    _walk(validator, schema, report, "$", missing, open_keys)
    assert not missing, f"keys whose schema has no description: {missing}"
    undeclared = [k for k in open_keys if not k.startswith(OPEN_DIAGNOSTICS)]
    assert not undeclared, f"keys the schema does not list: {undeclared}"


def test_every_property_in_the_schema_is_described():
    """Also the keys no real report happens to write (optional ones)."""
    missing = []

    def visit(node, path):
        if isinstance(node, dict):
            for key, sub in node.get("properties", {}).items():
                if not str(sub.get("description", "")).strip():
                    missing.append(f"{path}/properties/{key}")
            for key, sub in node.items():
                visit(sub, f"{path}/{key}")
        elif isinstance(node, list):
            for i, sub in enumerate(node):
                visit(sub, f"{path}/{i}")

    visit(load_schema(), "#")
    assert not missing, missing
