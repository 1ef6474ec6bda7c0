"""prs_geom.exports.numbers: the one number formatter of the HTML reports (issue 28).

Expected strings are written by hand; G is the narrow no-break space between digit groups."""
import json
import math
import re
from decimal import Decimal
from importlib import resources

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from prs_geom.exports.numbers import (DASH, QUANTITIES, exact, format_cell, format_quantity, key_label, quantity,
                                      unit_label)

G = "\u202f"


@pytest.mark.parametrize("value, unit, expected", [
    # lengths in mm: 0.1 um, fixed decimals
    (23.867870054925227, "mm", "23.8679 mm"),
    (8.0, "mm", "8.0000 mm"),
    (-0.0666435, "mm", "-0.0666 mm"),
    (0.00006, "mm", "0.0001 mm"),
    (0.00004, "mm", "0.0000 mm"),
    (-1.75e-16, "mm", "0.0000 mm"),          # float noise: zero, no sign
    (-0.0, "mm", "0.0000 mm"),               # the old "gap -0"
    (1234567.123456, "mm", f"1{G}234{G}567.123 mm"),   # capped at 10 significant digits
    (123456789012.0, "mm", "1.234567890×10¹¹ mm"),
    # micrometres: 0.001 um, printed µm
    (-0.0, "um", "0.000 µm"),                # the old "-0.000 um"
    (-0.0004, "um", "0.000 µm"),
    (0.0123, "um", "0.012 µm"),
    (0.022316613069, "um", "0.022 µm"),      # a pitch correction per tooth stays visible
    (0.4, "um", "0.400 µm"),
    (-3.8158, "um", "-3.816 µm"),
    (8.340731911054888, "µm", "8.341 µm"),
    # forces: 4 significant digits, never coarser than 1 N
    (20000.0, "N", f"20{G}000 N"),
    (56766.103634581195, "N", f"56{G}766 N"),
    (7071.067811865475, "N", "7071 N"),
    (26431427.3, "N", f"26{G}431{G}427 N"),
    (12.3456, "N", "12.35 N"),
    (0.5, "N", "0.5000 N"),
    (-1e-14, "N", "0 N"),
    # speeds: 1 rpm, plain decimal with digit groups
    (1926122.43, "rpm", f"1{G}926{G}122 rpm"),
    (100.0, "rpm", "100 rpm"),
    (6250.0, "rpm", "6250 rpm"),
    # angles
    (7.596332569256962, "deg", "7.5963°"),
    (5.088887490341627e-14, "deg", "0.0000°"),
    (-171.05228, "deg", "-171.0523°"),
    # volumes: 1 mm³ or 4 significant digits; tiny overlaps in scientific notation
    (1.8947612150616425e-05, "mm3", "1.895×10⁻⁵ mm³"),
    (-1.7526805744585983e-16, "mm3", "0 mm³"),   # the old overlap -1.75e-16
    (21489.19179738787, "mm^3", f"21{G}489 mm³"),
    (0.004063200937563627, "mm3", "0.004063 mm³"),
    # dimensionless: ratios, LDC, factors to 4 significant digits
    (1.4292200000000001, None, "1.429"),
    (5.0, None, "5.000"),
    (0.7499999999999996, None, "0.7500"),
    (1.5735105557417666, "", "1.574"),
    (9.99996, None, "10.00"),                # rounding carries into the next decade
    (4155.133342053063, None, "4155"),
    (22865319.289317943, None, "2.287×10⁷"),
    (-3.2e-05, None, "-3.200×10⁻⁵"),
    (2.0e-13, None, "0.000"),                # below the noise floor
    # other units
    (2820.520545364365, "MPa", "2821 MPa"),
    (212000.0, "MPa", f"212{G}000 MPa"),
    (40.5062, "N m", "40.51 N m"),
    (978.64, "N/um", "978.6 N/µm"),
    (0.1686901556094948, "kg", "0.1687 kg"),
    (90.0, "%", "90.0 %"),
    (20.0, "degC", "20.0 °C"),
    (0.009425388257689432, "rad", "0.009425 rad"),
])
def test_format_quantity_by_unit(value, unit, expected):
    assert format_quantity(value, unit) == expected


@pytest.mark.parametrize("value, expected", [
    (None, DASH), (float("nan"), DASH), (np.nan, DASH), (np.float32("nan"), DASH),
    (float("inf"), "∞"), (-math.inf, "-∞"),
    (True, "yes"), (False, "no"), (np.bool_(True), "yes"), (np.bool_(False), "no"),
    (20, "20"), (1440, "1440"), (1085036, f"1{G}085{G}036"), (np.int64(-123456), f"-123{G}456"),
    ("tension-compression", "tension-compression"),
])
def test_no_value_booleans_integers_and_text(value, expected):
    assert format_cell(value, "mm") == expected
    assert DASH == "\u2014"


def test_unit_goes_with_the_value_only_when_there_is_one():
    assert format_quantity(None, "mm") == DASH                  # no "— mm"
    assert format_quantity(True, "mm") == "yes"
    assert format_quantity(float("inf"), "rpm") == "∞ rpm"
    assert format_quantity(20, "N") == "20 N"
    assert format_quantity(1.0) == "1.000"                      # dimensionless: no unit
    assert format_cell(23.867870054925227, "mm") == "23.8679"   # a cell: the column title has the unit


def test_numpy_scalars_and_lists():
    assert format_quantity(np.float64(23.867870054925227), "mm") == "23.8679 mm"
    assert format_quantity(np.float32(1.5), "mm") == "1.5000 mm"
    assert format_cell([2.0004240156, 2.0, None], "mm", precision=1e-6) == "2.000424, 2.000000, —"
    assert format_cell(np.array([0.25, -0.0]), "um") == "0.250, 0.000"


@pytest.mark.parametrize("key, value, expected", [
    # unit from the key's suffix (the schema annotates none of these)
    ("pitch_diameter_mm", 23.867870054925227, "23.8679 mm"),
    ("measurement_correction_um", 8.340731911054888, "8.341 µm"),
    ("design_load_N", 20000.0, f"20{G}000 N"),
    ("axial_stiffness_N_per_um", 978.64, "978.6 N/µm"),
    ("temperature_coefficient_um_per_k", 0.30202162240216524, "0.302 µm/K"),
    ("thermal_growth_of_engaged_length_um_per_K", 0.437, "0.437 µm/K"),
    ("reference_temperature_degC", 20.0, "20.0 °C"),
    ("reliability_pct", 90.0, "90.0 %"),
    ("l10_hours", 3810.886548219657, "3811 h"),
    ("l10_revolutions", 22865319.289317943, "2.287×10⁷ rev"),
    ("max_hertz_pressure_mpa", 2820.520545364365, "2821 MPa"),
    ("critical_speed_rpm", 1926122.43, f"1{G}926{G}122 rpm"),
    ("lead_angle_deg", 7.596332569256962, "7.5963°"),
    ("volume_mm3", 1.8947612150616425e-05, "1.895×10⁻⁵ mm³"),
    ("density_kg_m3", 7850.0, "7850 kg/m³"),
    ("mass_kg", 0.019654485688837812, "0.01965 kg"),
    ("thermal_expansion_per_k", 1.15e-05, "1.150×10⁻⁵ 1/K"),
    ("temperature_k", 2.0, "2.000 K"),
    ("time_s", 0.00123, "0.001230 s"),
    ("design.materials.nut.youngs_modulus_mpa", 212000.0, f"212{G}000 MPa"),
    ("max_ldc", 1.42922, "1.429"),
    ("contact_ratio", 1.5735105557417666, "1.574"),
    # schema annotations (x-precision, x-unit) take precedence over the suffix
    ("machining.nut.rows.designed_pitch_mm", 2.000424015648311, "2.000424 mm"),
    ("designed_pitch_mm", 2.000424015648311, "2.000424 mm"),         # bare name: one annotation everywhere
    ("pitch.equal_load.roller_mm", 2.000424015648311, "2.000424 mm"),
    ("design.roller.pitch_list_mm", [2.000424015648311, 2.000401699035242], "2.000424, 2.000402 mm"),
    ("machining.roller.starts.nominal_lead_mm", 10.0, "10.000000 mm"),
    ("checks.fcl.comparisons.fcl_distance_mm", 0.0035101317266371273, "0.003510 mm"),
    ("design.contact.precision_mm", 1e-10, "1.000×10⁻¹⁰ mm"),          # a solver tolerance, not a length
    ("rating.efficiency.drive_torque_nm", 40.50623, "40.51 N m"),      # N m, not nanometres
    # tooth_thickness_mm is annotated on the machining rows only: elsewhere the mm rule holds
    ("machining.nut.rows.tooth_thickness_mm", 1.0000000000000009, "1.000000 mm"),
    ("gears.roller_gear.tooth_thickness_mm", 0.6083185307179586, "0.6083 mm"),
    ("tooth_thickness_mm", 0.6083185307179586, "0.6083 mm"),
])
def test_quantity_from_schema_annotation_or_key_suffix(key, value, expected):
    assert format_quantity(value, key=key) == expected


def test_caller_precision_and_unit_win():
    assert format_quantity(2.000424015648311, "mm", precision=1e-6) == "2.000424 mm"
    assert format_quantity(2.000424015648311, "mm", precision="3 significant digits") == "2.00 mm"
    assert format_quantity(2.000424015648311, "mm", precision=1) == "2 mm"
    assert format_quantity(0.0123, "um", key="pitch_diameter_mm") == "0.012 µm"
    with pytest.raises(ValueError):
        format_quantity(1.0, "mm", precision="fine")
    with pytest.raises(ValueError):
        format_quantity(1.0, "mm", precision=0)


def test_exact_is_the_full_float64_text():
    assert exact(23.867870054925227) == "23.867870054925227"
    assert exact(np.float64(-1.7526805744585983e-16)) == "-1.7526805744585983e-16"
    assert float(exact(0.1 + 0.2)) == 0.1 + 0.2
    assert exact(20) is None and exact(True) is None and exact(None) is None and exact("x") is None


def test_labels():
    assert unit_label("um") == "µm" and unit_label("mm^3") == "mm³" and unit_label("deg") == "°"
    assert unit_label("kg/m^3") == "kg/m³" and unit_label("") == "" and unit_label(None) == ""
    assert key_label("measurement_correction_um") == "measurement correction (µm)"
    assert key_label("temperature_coefficient_um_per_k") == "temperature coefficient (µm/K)"
    assert key_label("thermal_growth_of_engaged_length_um_per_K") == "thermal growth of engaged length (µm/K)"
    assert key_label("constant_pitch") == "constant pitch"


def test_schema_annotations_are_well_formed():
    """Every x-unit of the report schema is a unit the formatter knows, every x-precision a
    power-of-ten resolution or 'N significant digits', and each annotation reaches the
    quantity of its path."""
    text = resources.files("prs_geom.exports.schemas").joinpath("report.schema.json").read_text(encoding="utf-8")
    found = []

    def visit(node, where):
        if isinstance(node, dict):
            if "x-unit" in node:
                assert unit_label(node["x-unit"]) in QUANTITIES, where
            if "x-precision" in node:
                p = node["x-precision"]
                if isinstance(p, str):
                    assert re.fullmatch(r"\d+ significant digits", p), where
                else:
                    assert p > 0 and math.log10(p) == round(math.log10(p)), where
                found.append(where)
            for k, v in node.items():
                visit(v, f"{where}/{k}")
        elif isinstance(node, list):
            for i, v in enumerate(node):
                visit(v, f"{where}/{i}")

    visit(json.loads(text), "#")
    assert len(found) >= 20
    assert quantity(key="machining.roller.rows.base_position_mm").decimals == 6
    assert quantity(key="design.contact.precision_mm").sig == 4
    assert quantity(key="rating.efficiency.holding_torque_nm").unit == "N m"


_DIGITS = re.compile(r"-?\d[\d\u202f]*(?:\.\d+)?")


def _significant(text: str) -> int:
    mantissa = text.split("×")[0].lstrip("-").replace("\u202f", "")
    return len(mantissa.replace(".", "").lstrip("0")) or 1


@given(st.floats(allow_nan=True, allow_infinity=True, width=64),
       st.sampled_from(["mm", "um", "N", "MPa", "deg", "rpm", "mm3", "", "rev", "h", "s", "kg", "%"]))
def test_any_float_prints_clean(x, unit):
    """Whatever the value: no Python words, no signed zero, at most 10 significant digits,
    and a plain-decimal result reads back within half its last digit."""
    text = format_cell(x, unit)
    assert not re.search(r"\b(None|True|False|nan|inf|e[+-]\d)", text), text
    assert not re.fullmatch(r"-0(\.0+)?", text), text
    if not math.isfinite(x):
        assert text in (DASH, "∞", "-∞")
        return
    assert _significant(text) <= 10, text
    if "×" not in text:
        assert _DIGITS.fullmatch(text), text
        back = float(text.replace("\u202f", ""))
        decimals = len(text.partition(".")[2])
        q = quantity(unit)
        floor = q.zero if q.sig is not None else 0.0
        assert abs(back - x) <= 0.5 * 10.0 ** -decimals * (1 + 1e-9) + floor + abs(x) * 1e-15, (x, text)
    else:
        mantissa, _, exponent = text.partition("×10")
        power = int(exponent.translate(str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")))
        digits = len(mantissa.lstrip("-").replace(".", ""))
        assert 1 <= abs(float(mantissa)) < 10, text
        back = Decimal(mantissa).scaleb(power)
        assert abs(back - Decimal(x)) <= Decimal(5).scaleb(power - digits) * Decimal("1.000001"), (x, text)
