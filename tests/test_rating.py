"""Issue 16: load ratings, life, limits, efficiency and stiffness (prs_geom.analysis.rating).

Every formula is checked against a published worked example, a published constant or a
closed form computed by hand here; the sources are named at each test. No build runs here
(the report schema of real builds is checked by tests/test_report_schema.py and by the
conftest fixture that validates every build); the ``rating`` section is validated against
its schema directly.
"""
from __future__ import annotations

import json
import math
import re
from pathlib import Path

import jsonschema
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cli_helpers import run
from prs_geom.analysis import rating as R
from prs_geom.analysis.contact import analyse_contact
from prs_geom.analysis.loads import build_model, design_pitches, gap_terms, pitch_gaps, solve_loads_batch
from prs_geom.exports.report import limit_check_dict, limit_warnings, rating_section
from prs_geom.exports.report_schema import load_schema
from prs_geom.model.design import Loading, PRSDesign, RatingSettings, Supports, Thread
from prs_geom.model.errors import DesignError
from prs_geom.model.io import dumps_toml, loads_toml
from prs_geom.model.spectrum import LoadCase, Spectrum
from prs_geom.pipeline import load_any_design
from strategies import standard_designs

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


@pytest.fixture(scope="module")
def default_rating():
    d = PRSDesign()
    c = analyse_contact(d)
    m = build_model(d, c)
    return d, c, m, R.analyse_rating(d, c, m)


# --------------------------------------------------------------------------- catalogue formulas
def test_reliability_factor_iso_3408_5_table():
    """ISO 3408-5:2006 (and ISO 281:1990, table 1): a_1 = 1, 0.62, 0.53, 0.44, 0.33, 0.21 for
    90, 95 ... 99 %; between the points 4.48 (ln(100/R))^(2/3), which rounds to the table."""
    for r, a1 in R.A1_TABLE.items():
        assert R.reliability_factor(r) == a1
        assert round(4.48 * math.log(100.0 / r) ** (2.0 / 3.0), 2) == pytest.approx(a1, abs=0.011)
    assert R.A1_TABLE == {90.0: 1.0, 95.0: 0.62, 96.0: 0.53, 97.0: 0.44, 98.0: 0.33, 99.0: 0.21}
    mid = R.reliability_factor(92.5)
    assert mid == pytest.approx(4.48 * math.log(100 / 92.5) ** (2 / 3))
    assert 0.62 < mid < 1.0
    for bad in (89.9, 99.5, float("nan")):
        with pytest.raises(DesignError):
            R.reliability_factor(bad)


def test_spectrum_cubic_mean_hand_computed():
    """Two cases by hand: 10 kN at 100 rpm and 20 kN at 50 rpm, half the time each:
    n_m = 0.5 x 100 + 0.5 x 50 = 75 rpm; F_m^3 = (10^12 x 50 + 8 x 10^12 x 25) / 75
    = 3.3333 x 10^12 N^3, F_m = 14938.0 N."""
    s = Spectrum((LoadCase(10_000.0, 0.5, 100.0), LoadCase(20_000.0, 0.5, 50.0)))
    Fm, nm = R.equivalent_load(s)
    assert nm == pytest.approx(75.0, rel=1e-15)
    assert Fm == pytest.approx((2.5e14 / 75.0) ** (1.0 / 3.0), rel=1e-13)
    assert Fm == pytest.approx(14938.0, abs=0.1)


def test_spectrum_mean_speed_rollvis_worked_example():
    """Rollvis, 'Vis à rouleaux satellites' catalogue (French), calculation example RV 20 x 5,
    p. 16: q = 5/40/50/5 %, n = 15/110/70/1700 rpm gives n_m = (75 + 4400 + 3500 + 8500) / 100
    = 164.75 rpm, printed there as 165 rpm. The cubic mean of its loads 8300/4500/4200/1150 N,
    by hand: (4.28840e11 + 4.00950e12 + 2.59308e12 + 1.29274e11) / 164.75 = 4.34640e10,
    cube root 3515.95 N."""
    s = Spectrum(tuple(LoadCase(F, q, n) for F, q, n in
                       ((8300.0, 0.05, 15.0), (4500.0, 0.40, 110.0), (4200.0, 0.50, 70.0), (1150.0, 0.05, 1700.0))))
    Fm, nm = R.equivalent_load(s)
    assert nm == pytest.approx(164.75, rel=1e-12)
    assert round(nm) == 165
    assert Fm == pytest.approx(3515.95, abs=0.01)


def test_spectrum_without_speeds_is_refused():
    with pytest.raises(DesignError, match="speed_rpm"):
        R.equivalent_load(Spectrum((LoadCase(1000.0, 1.0),)))


def test_catalogue_life_and_required_rating_hand_computed():
    """L10 = (C/F)^3 10^6: C = 56 kN, F = 20 kN gives 2.8^3 = 21.952 x 10^6 revolutions,
    21.952e6 / (60 x 100) = 3658.67 h at 100 rpm; the required rating for that life is C."""
    L = R.life_revolutions(56_000.0, 20_000.0)
    assert L == pytest.approx(21.952e6, rel=1e-12)
    assert R.life_hours(L, 100.0) == pytest.approx(3658.6667, rel=1e-6)
    assert R.required_dynamic_load(20_000.0, 100.0, 3658.6667) == pytest.approx(56_000.0, rel=1e-6)
    # reliability and operating factor: a_1 (C / (f_w F))^3
    assert R.life_revolutions(56_000.0, 20_000.0, 0.21, 1.2) == pytest.approx(0.21 * (56 / 24) ** 3 * 1e6)
    assert R.required_dynamic_load(20_000.0, 100.0, 3658.6667 * 0.21, 0.21) == pytest.approx(56_000.0, rel=1e-6)


# --------------------------------------------------------------------------- Lundberg-Palmgren
def test_stress_functions_line_contact_limit():
    """Orthogonal shear stress of line contact: amplitude 0.25 p_0 at depth 0.5 b (Johnson,
    Contact Mechanics, sec. 4.2; the limit b/a -> 0 of Lundberg-Palmgren's T and zeta)."""
    T, zeta = R.lp_stress_functions(np.array([1e-6]))
    assert T[0] == pytest.approx(0.25, abs=1e-6)
    assert zeta[0] == pytest.approx(0.5, abs=1e-6)
    T, zeta = R.lp_stress_functions(np.array([0.2, 1.0, 3.0]))
    assert np.all(np.diff(T) < 0) and np.all(np.diff(zeta) < 0)       # rounder contacts: lower and shallower


def test_general_form_reproduces_the_closed_form_ball_capacity():
    """The general Lundberg-Palmgren form of this module against the published closed form
    Q_c = 98.1 (2f/(2f-1))^0.41 (1 -+ gamma)^1.39 / (1 +- gamma)^(1/3) gamma^0.3 D^1.8 Z^(-1/3)
    (N, mm; Harris & Kotzalas, Rolling Bearing Analysis; the basis of ISO 281 / ISO 3408-5):
    within -3 % / +5 % over the calibration range, and the same D^1.8 Z^(-1/3) scaling exactly."""
    lo, hi = R.calibration_spread()
    assert 0.97 <= lo <= 1.0 <= hi <= 1.05
    for D, Z in ((5.0, 9), (12.7, 16)):
        gen = R.general_ball_raceway_capacity(D, 0.2, 0.52, Z)
        cf = R.lp_ball_raceway_capacity(D, 0.2, 0.52, Z)
        assert gen == pytest.approx(cf, rel=0.05)
    # exact exponents of the general form: D^1.8 and Z^(-1/3)
    a, b = R.general_ball_raceway_capacity(5.0, 0.2, 0.52, 9), R.general_ball_raceway_capacity(10.0, 0.2, 0.52, 9)
    assert b / a == pytest.approx(2 ** 1.8, rel=1e-9)
    a, b = R.general_ball_raceway_capacity(5.0, 0.2, 0.52, 8), R.general_ball_raceway_capacity(5.0, 0.2, 0.52, 27)
    assert b / a == pytest.approx((27 / 8) ** (-1 / 3), rel=1e-9)


def test_ratings_of_the_default_design(default_rating):
    d, c, m, res = default_rating
    s = rating_section(res)
    rings = R.contact_rings(d, c, m)
    # cycles per screw turn from the carrier speed w_c = w_s r_s / (r_s + r_n) = 0.375 w_s (DOMAIN 9)
    assert rings.cycles == pytest.approx((10 * 0.625, 0.375 * 5, 0.375 * 5, 10 * 0.375))
    assert s["dynamic_load_rating_n"] == pytest.approx(R.dynamic_load_rating(rings), rel=1e-12)
    # magnitudes of a 24 x 10 roller screw, 10 rollers, 20 teeth (docs/theory/ratings.md)
    assert 40_000 < s["dynamic_load_rating_n"] < 90_000
    assert 1.2 < s["static_load_rating_n"] / s["dynamic_load_rating_n"] < 2.5
    for key in ("equivalent_load_n", "equivalent_speed_rpm", "l10_revolutions", "l10_hours", "reliability_factor",
                "required_dynamic_load_n", "dynamic_load_rating_n", "static_load_rating_n", "static_safety"):
        assert math.isfinite(s[key]) and s[key] > 0


def test_equal_sharing_gives_back_the_catalogue_life(default_rating):
    """With every tooth at F / (n z) the life from the tooth loads is (C_a / F)^3 10^6."""
    d, c, m, res = default_rating
    rings = R.contact_rings(d, c, m)
    Ca = R.dynamic_load_rating(rings)
    for F in (5_000.0, 20_000.0, 35_000.0):
        f = np.full(d.thread.engaged_teeth, F / (d.thread.engaged_teeth * d.roller.count))
        assert float(R.system_life(rings, f, f)) == pytest.approx((Ca / F) ** 3, rel=1e-12)
    eq = rating_section(res)["distribution_life"]["equal_load"]
    assert eq["life_ratio_to_equal_sharing"] == pytest.approx(1.0, abs=1e-9)


def test_static_rating_puts_the_limit_pressure_on_the_contacts(default_rating):
    d, c, m, res = default_rating
    rings = R.contact_rings(d, c, m)
    C0a = rating_section(res)["static_load_rating_n"]
    f = np.full(d.thread.engaged_teeth, C0a / (d.thread.engaged_teeth * d.roller.count))
    p = max(R.hertz_pressure(rings, 0, f).max(), R.hertz_pressure(rings, 1, f).max())
    assert p == pytest.approx(4200.0, rel=1e-12)


# --------------------------------------------------------------------------- graded against constant
@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(0.05, 5.0), min_size=2, max_size=30), st.lists(st.floats(0.05, 5.0), min_size=2, max_size=30))
def test_any_unequal_sharing_lives_shorter(default_rating, nr, rs):
    """Jensen: with the same total load per side, equal sharing minimises sum Q^(10/3)."""
    d, c, m, _ = default_rating
    rings = R.contact_rings(d, c, m)
    n = min(len(nr), len(rs))
    f_nr, f_rs = np.array(nr[:n]), np.array(rs[:n])
    f_rs *= f_nr.sum() / f_rs.sum()
    eq = np.full(n, f_nr.mean())
    assert float(R.system_life(rings, f_rs, f_nr)) <= float(R.system_life(rings, eq, eq)) * (1 + 1e-12)


def _life_constant_and_equal(design: PRSDesign) -> tuple[float, float]:
    c = analyse_contact(design)
    m = build_model(design, c)
    rings = R.contact_rings(design, c, m)
    pd = design_pitches(design, model=m)
    F = design.loading.axial_load_n
    g0 = gap_terms(design, (design.thread.pitch_mm,) * (design.thread.engaged_teeth - 1),
                   (design.thread.pitch_mm,) * (design.thread.engaged_teeth - 1))
    g1 = pitch_gaps(design.thread.pitch_mm, pd.roller_mm, pd.nut_mm)
    b = solve_loads_batch(m, F, np.stack([g0[0], g1[0]]), np.stack([g0[1], g1[1]]))
    life = R.system_life(rings, b.f_rs, b.f_nr)
    return float(life[0]), float(life[1])


def test_equal_sharing_never_shorter_than_constant_pitch_at_the_design_load():
    """The default and the graded example, both installations: the equal-load pitch lives at
    least as long as constant pitch at the design load (and the example gains)."""
    for d in (PRSDesign(), load_any_design(EXAMPLES / "graded-pitch.toml"),
              PRSDesign(loading=Loading(installation="compression-compression"))):
        const, equal = _life_constant_and_equal(d)
        assert equal >= const * (1 - 1e-12)
        assert equal / const > 1.01


@settings(max_examples=12, deadline=None)
@given(standard_designs(max_teeth=25))
def test_equal_sharing_never_shorter_on_sampled_designs(d):
    const, equal = _life_constant_and_equal(d)
    assert equal >= const * (1 - 1e-9)


def test_graded_example_reports_its_life_gain():
    res = rating_section(R.analyse_rating(load_any_design(EXAMPLES / "graded-pitch.toml")))
    dl = res["distribution_life"]
    assert set(dl) == {"constant_pitch", "equal_load"}      # its lists are the equal-load design
    assert dl["equal_load"]["gain_over_constant_pitch_hours"] > 0
    assert dl["equal_load"]["gain_factor_over_constant_pitch"] > 1.05
    assert dl["equal_load"]["max_hertz_pressure_mpa"] < dl["constant_pitch"]["max_hertz_pressure_mpa"]
    assert dl["equal_load"]["static_safety"] > dl["constant_pitch"]["static_safety"]


# --------------------------------------------------------------------------- efficiency, limits
def test_efficiency_of_a_24_x_10_roller_screw():
    """DOMAIN 7: mu = 0.025 on 45 deg flanks reproduces the catalogue efficiency 0.79 of a
    24 x 10 roller screw: lambda = atan(10 / 24 pi) = 7.555 deg, rho' = atan(0.025 / cos 45)
    = 2.025 deg, tan(7.555) / tan(9.580) = 0.786."""
    e = R.efficiency(10.0, 24.0, 0.025, math.radians(45.0))
    assert e["lead_angle_deg"] == pytest.approx(7.555, abs=1e-3)
    assert e["friction_angle_deg"] == pytest.approx(2.0249, abs=1e-3)
    assert round(e["forward"], 2) == 0.79
    lam, rho = math.radians(e["lead_angle_deg"]), math.radians(e["friction_angle_deg"])
    assert e["back_driving"] == pytest.approx(math.tan(lam - rho) / math.tan(lam), rel=1e-12)
    assert not e["self_locking"]
    locked = R.efficiency(2.0, 24.0, 0.3, math.radians(45.0))
    assert locked["self_locking"] and locked["back_driving"] == 0.0
    # torque to drive 20 kN on a 10 mm lead at efficiency 0.786: 20000 x 10 / (2 pi 0.786) N mm
    assert R.drive_torque(20_000.0, 10.0, 0.786) == pytest.approx(20_000 * 10 / (2 * math.pi * 0.786) / 1e3)


def test_critical_speed_matches_the_catalogue_constants():
    """Eichenberger Gewinde AG, 'Bases de calculs' (Carry ball screws, V 12 01 30), p. 35:
    n = K_D 10^6 d_2 / l_a^2 (rpm, mm) with K_D = 276, 190, 122, 43 for fixed-fixed,
    fixed-supported, supported-supported, fixed-free; the beam formula with steel
    (E = 210 GPa, 7850 kg/m^3) gives the same constants to 1 %."""
    for ends, K in (("fixed-fixed", 276e6), ("fixed-supported", 190e6), ("supported-supported", 122e6),
                    ("fixed-free", 43e6)):
        n = R.critical_speed(20.0, 1000.0, ends, 210_000.0)
        assert n * 1000.0 ** 2 / 20.0 == pytest.approx(K, rel=0.011)


def test_euler_buckling_hand_computed():
    """d = 20 mm, L = 1000 mm, pinned-pinned, E = 210 GPa: I = pi 20^4 / 64 = 7853.98 mm^4,
    F = pi^2 E I / L^2 = 16278.3 N; effective lengths 0.5 L, 0.699 L, 2 L (Euler)."""
    F = R.buckling_load(20.0, 1000.0, "supported-supported", 210_000.0)
    assert F == pytest.approx(16278.3, abs=0.1)
    assert R.buckling_load(20.0, 1000.0, "fixed-fixed", 210_000.0) == pytest.approx(4 * F)
    assert R.buckling_load(20.0, 1000.0, "fixed-free", 210_000.0) == pytest.approx(F / 4)
    assert R.buckling_load(20.0, 1000.0, "fixed-supported", 210_000.0) == pytest.approx(F / 0.699 ** 2)


def test_double_nut_loses_a_hertzian_preload_at_2_83_times_the_preload():
    """Rollvis catalogue, calculation example p. 16: a preloaded nut half is unloaded when
    F >= 2.83 F_v, i.e. 2^(3/2) F_v for a Hertzian curve delta = c F^(2/3); below it the
    double nut is twice as stiff as one half at the preload."""
    F = np.linspace(0.0, 40_000.0, 4001)
    delta = 1e-4 * F ** (2.0 / 3.0)
    out = R.double_nut(F, delta, 5_000.0, np.array([0.0, 100.0, 20_000.0]))
    assert out["lift_off_n"] == pytest.approx(2 ** 1.5 * 5_000.0, rel=2e-4)
    x0, x1 = out["displacement_mm"][:2]
    single_tangent = 1.0 / (1e-4 * (2 / 3) * 5_000.0 ** (-1 / 3))
    assert 100.0 / (x1 - x0) == pytest.approx(2 * single_tangent, rel=0.01)
    assert out["loaded_half_n"][2] == 20_000.0 and out["other_half_n"][2] == 0.0   # beyond lift-off


def test_double_nut_and_stiffness_of_the_default_design(default_rating):
    d, *_, res = default_rating
    st_, dn = rating_section(res)["stiffness"], rating_section(res)["double_nut"]
    assert np.all(np.diff(st_["axial_deflection_um"]) > 0)
    assert np.all(np.diff(st_["secant_n_per_um"]) > 0)              # Hertz stiffens with load
    assert dn["preload_n"] == pytest.approx(d.loading.axial_load_n / 2 ** 1.5)
    # linear tooth and body terms make the curve less than Hertzian: preload lost earlier than 2.83
    assert dn["preload_n"] < dn["lift_off_load_n"] < 2 ** 1.5 * dn["preload_n"]
    assert dn["stiffness_n_per_um"][0] > st_["secant_n_per_um"][0]


def test_limits_use_the_supports_section():
    d = PRSDesign(supports=Supports(unsupported_length_mm=800.0, critical_speed_ends="supported-supported",
                                    buckling_ends="fixed-free", buckling_safety=3.0))
    lim = rating_section(R.analyse_rating(d))["limits"]
    droot = d.screw.minor_diameter_mm
    assert lim["critical_speed_rpm"] == pytest.approx(
        R.critical_speed(droot, 800.0, "supported-supported", d.materials.screw.youngs_modulus_mpa))
    assert lim["permissible_buckling_load_n"] == pytest.approx(
        R.buckling_load(droot, 800.0, "fixed-free", d.materials.screw.youngs_modulus_mpa) / 3.0)
    assert lim["dn_speed_limit_rpm"] == pytest.approx(150_000.0 / 24.0)


# --------------------------------------------------------------------------- catalogue cross-check
#: Published ratings of real planetary roller screws, 5-start 10 mm lead, C_a and C_0a in kN:
#: Helix Linear Technologies, SRS roller screws, as published in the maker's public
#: configurator source (github.com/vdimichele-helix/email-roller-screw-configuration,
#: src/components/builder/srsCTechnicalData.jsx at commit beed04e3ab5f, rows "21_10", "24_10",
#: "30_10"; the same C_a stand in the repository's second table, loadCapacityData.jsx). The
#: source gives neither roller count nor nut length: the designs are rebuilt with this
#: tool's standard sizing (rollers d/3, nut 5d/3, 2 mm pitch, 45 deg flanks, as many rollers
#: as fit) at two engaged lengths, the default 20 teeth and 40 teeth (80 mm).
CATALOGUE_POINTS = {"SRS 21x10": (21.0, 78.0, 127.0), "SRS 24x10": (24.0, 112.0, 210.0),
                    "SRS 30x10": (30.0, 145.0, 281.0)}


def catalogue_design(screw_d: float, teeth: int) -> PRSDesign:
    """A standard-sized 5-start, 2 mm pitch screw of pitch diameter ``screw_d`` (mm)."""
    roller_d = screw_d / 3.0
    a = 0.5 * (screw_d + roller_d)
    roller_major = roller_d + 1.2 * 2.0 / 4.0  # flank half-depth p / (4 tan 45 deg)
    count = int(math.pi / math.asin(roller_major / (2.0 * a))) - 1
    from prs_geom.model.design import Nut, Roller, Screw
    return PRSDesign(name=f"catalogue-{screw_d:g}x10",
                     thread=Thread(pitch_mm=2.0, flank_half_angle_deg=45.0, engaged_teeth=teeth),
                     screw=Screw(pitch_diameter_mm=screw_d, starts=5),
                     roller=Roller(pitch_diameter_mm=roller_d, count=count),
                     nut=Nut(pitch_diameter_mm=5 * roller_d, starts=5, outer_diameter_mm=7 * roller_d))


def _docs_rows() -> dict[tuple[str, int], tuple[float, float]]:
    """The cross-check table of docs/theory/ratings.md: (designation, teeth) -> % differences."""
    text = (Path(__file__).resolve().parent.parent / "docs" / "theory" / "ratings.md").read_text(encoding="utf-8")
    rows = {}
    for m in re.finditer(r"^\| (SRS \d+x10) \| (\d+) \|.*\| ([+-]\d+) % \|.*\| ([+-]\d+) % \|$", text, re.M):
        rows[(m[1], int(m[2]))] = (float(m[3]), float(m[4]))
    return rows


@pytest.mark.parametrize("name", sorted(CATALOGUE_POINTS))
def test_catalogue_cross_check(name):
    """The computed ratings against the catalogue, as docs/theory/ratings.md states them:
    at the default 20 teeth the method gives 51-59 % of the catalogue C_a (a short nut); at
    40 teeth (80 mm, an assumed nut length) within -18 ... -5 % of C_a and -10 ... +14 %
    of C_0a. The docs table must carry the percentages computed here."""
    screw_d, ca_kn, c0a_kn = CATALOGUE_POINTS[name]
    docs = _docs_rows()
    for teeth, ca_band, c0a_band in ((20, (0.50, 0.60), (0.44, 0.58)), (40, (0.80, 0.97), (0.88, 1.16))):
        d = catalogue_design(screw_d, teeth)
        assert d.roller.count == 10
        res = rating_section(R.analyse_rating(d))
        ca = res["dynamic_load_rating_n"] / 1e3 / ca_kn
        c0a = res["static_load_rating_n"] / 1e3 / c0a_kn
        assert ca_band[0] <= ca <= ca_band[1], (teeth, ca)
        assert c0a_band[0] <= c0a <= c0a_band[1], (teeth, c0a)
        assert docs[(name, teeth)] == (round(100 * (ca - 1)), round(100 * (c0a - 1)))


# --------------------------------------------------------------------------- design sections
def test_design_sections_round_trip_and_name_their_fields():
    d = PRSDesign(supports=Supports(unsupported_length_mm=600.0, buckling_ends="fixed-fixed"),
                  rating=RatingSettings(friction_coefficient=0.03, preload_n=4000.0, reliability_pct=95.0))
    assert loads_toml(dumps_toml(d)) == d
    assert "supports" not in dumps_toml(PRSDesign()) and "[rating]" not in dumps_toml(PRSDesign())
    for text, field in (("[rating]\nfriction_coefficient = -0.1\n", "rating.friction_coefficient"),
                        ("[rating]\nreliability_pct = 99.5\n", "rating.reliability_pct"),
                        ("[supports]\nbuckling_ends = \"clamped\"\n", "supports.buckling_ends"),
                        ("[supports]\ncritical_speed_factor = 1.5\n", "supports.critical_speed_factor"),
                        ("[rating]\npreload_n = 0\n", "rating.preload_n")):
        with pytest.raises(DesignError) as info:
            loads_toml(text)
        assert info.value.field == field


# --------------------------------------------------------------------------- command line
REQUIRED_KEYS = ("equivalent_load_n", "equivalent_speed_rpm", "l10_revolutions", "l10_hours", "reliability_factor",
                 "required_dynamic_load_n", "dynamic_load_rating_n", "static_load_rating_n", "static_safety")


def test_cli_json_keys_and_flags():
    code, out, err = run(["rating", "--json", "--mean-load", "15000", "--speed-rpm", "300", "--life-hours", "10000",
                          "--fw", "1.2", "--reliability", "95"])
    assert code == 0, err
    rep = json.loads(out)
    for key in REQUIRED_KEYS:
        assert isinstance(rep[key], float)
    assert rep["equivalent_load_n"] == 15000.0 and rep["equivalent_speed_rpm"] == 300.0
    assert rep["reliability_factor"] == 0.62 and rep["operating_factor"] == 1.2
    assert rep["l10_revolutions"] == pytest.approx(0.62 * (rep["dynamic_load_rating_n"] / 18000.0) ** 3 * 1e6)
    code, out, err = run(["rating"])
    assert code == 0 and "C_a" in out and "equal_load" in out


def test_cli_spectrum_adds_the_robust_pitch(tmp_path):
    spec = tmp_path / "duty.toml"
    spec.write_text("[[case]]\nload_n = 8000.0\ntime_share = 0.5\nspeed_rpm = 300.0\n"
                    "[[case]]\nload_n = 20000.0\ntime_share = 0.5\nspeed_rpm = 100.0\n", encoding="utf-8")
    code, out, err = run(["rating", str(EXAMPLES / "graded-pitch.toml"), "--spectrum", str(spec), "--json"])
    assert code == 0, err
    rep = json.loads(out)
    assert rep["equivalent_speed_rpm"] == pytest.approx(200.0)
    assert rep["equivalent_load_n"] == pytest.approx(((8000.0 ** 3 * 150 + 20000.0 ** 3 * 50) / 200) ** (1 / 3))
    assert rep["robust"] is None and "robust" in rep["distribution_life"]
    dl = rep["distribution_life"]
    assert dl["robust"]["l10_hours"] >= dl["constant_pitch"]["l10_hours"]


@pytest.mark.parametrize("argv, flag", [
    (["--reliability", "80"], "--reliability"),
    (["--fw", "0.5"], "--fw"),
    (["--mean-load", "-1"], "--mean-load"),
    (["--speed-rpm", "0"], "--speed-rpm"),
    (["--life-hours", "0"], "--life-hours"),
])
def test_cli_bad_flags_exit_2_naming_the_flag(argv, flag):
    code, out, err = run(["rating", *argv])
    assert code == 2
    assert err.startswith(f"error: {flag} = ") and "Traceback" not in err


def test_cli_bad_spectrum_and_design_exit_2(tmp_path):
    nospeed = tmp_path / "s.toml"
    nospeed.write_text("[[case]]\nload_n = 8000.0\ntime_share = 1.0\n", encoding="utf-8")
    code, _, err = run(["rating", "--spectrum", str(nospeed)])
    assert code == 2 and "speed_rpm" in err
    ok = tmp_path / "ok.toml"
    ok.write_text("[[case]]\nload_n = 8000.0\ntime_share = 1.0\nspeed_rpm = 10.0\n", encoding="utf-8")
    code, _, err = run(["rating", "--spectrum", str(ok), "--mean-load", "5000"])
    assert code == 2 and "--spectrum" in err
    bad = tmp_path / "d.toml"
    bad.write_text("[rating]\nfriction_coefficient = 0.9\n", encoding="utf-8")
    code, _, err = run(["rating", str(bad)])
    assert code == 2 and "rating.friction_coefficient = 0.9: must be in [0, 0.5]" in err


# --------------------------------------------------------------------------- report schema
def _validator_for(path: str):
    schema = load_schema()
    sub = schema
    for part in path.split("/"):
        sub = sub[part]
    return jsonschema.Draft202012Validator({**sub, "$defs": schema["$defs"]})


def test_rating_section_follows_the_report_schema(default_rating):
    *_, res = default_rating
    v = _validator_for("$defs/prs_report/properties/rating")
    section = json.loads(json.dumps(rating_section(res)))
    v.validate(section)
    broken = json.loads(json.dumps(section))
    broken["dynamic_load_rating_n"] = "57 kN"
    assert not v.is_valid(broken)
    broken = json.loads(json.dumps(section))
    broken["unexpected"] = 1
    assert not v.is_valid(broken)


def test_design_sections_follow_the_report_schema():
    from prs_geom.model.io import design_to_dict

    v = _validator_for("$defs/prs_design")
    d = PRSDesign(supports=Supports(unsupported_length_mm=600.0), rating=RatingSettings(preload_n=4000.0))
    v.validate(json.loads(json.dumps(design_to_dict(d))))
    v.validate(json.loads(json.dumps(design_to_dict(PRSDesign(thread=Thread(engaged_teeth=10))))))


def test_rating_figure_files(default_rating, tmp_path):
    """rating.png and rating.svg (the light renderer of prs_geom.exports.plots): a valid SVG
    handed on for report.html, a PNG of the stated size, the same bytes on a second run."""
    import xml.dom.minidom

    from PIL import Image

    from prs_geom.exports.plots import plot_rating

    *_, res = default_rating
    svgs: dict[str, str] = {}
    assert plot_rating(tmp_path, "default", res, svgs) == ["rating.png", "rating.svg"]
    doc = xml.dom.minidom.parseString(svgs["rating"])
    assert doc.documentElement.tagName == "svg"
    assert (tmp_path / "rating.svg").read_text(encoding="utf-8") == svgs["rating"]
    assert "equal-load pitch" in svgs["rating"] and "constant pitch" in svgs["rating"]
    with Image.open(tmp_path / "rating.png") as im:
        assert im.size == (1500, 470)
    first = (tmp_path / "rating.png").read_bytes()
    plot_rating(tmp_path, "default", res)
    assert (tmp_path / "rating.png").read_bytes() == first


def test_readme_rating_example_is_what_the_command_prints():
    """README's ``prs-geom rating`` console block is the real output on the default design
    (every line after the shortened first one, verbatim)."""
    text = (Path(__file__).resolve().parent.parent / "README.md").read_text(encoding="utf-8")
    block = text.split("$ .venv/bin/prs-geom rating\n", 1)[1].split("```", 1)[0]
    shown = [line for line in block.splitlines() if line.strip()]
    code, out, err = run(["rating"])
    assert code == 0, err
    printed = out.splitlines()
    assert len(shown) >= 8
    for line in shown:
        assert line in printed, line
    assert "constant_pitch                  3370.2" in block


# --------------------------------------------------------------------------- limit checks (issue 28)
def _by_hand_limits():
    """The default design's limits from the formulas of docs/theory/ratings.md (DOMAIN 7), by
    hand: root d = 24 - 1.6 x 0.5 = 23.2 mm, fixed-supported (lambda 3.926602312, k 0.699),
    E 212000 MPa, rho 7.85e-9 t/mm^3; the actuator's spans (docs/theory/actuator.md): whirl
    between the 7204 B pair's middle z = -94.75 and the 6204's middle z = 127.75, L = 222.5 mm;
    buckling from -94.75 to the nut thread's far end at the upper stroke end, 40 + 50 = 90 mm,
    L = 184.75 mm."""
    d, E = 23.2, 212_000.0
    L_cr, L_b = 127.75 + 94.75, 90.0 + 94.75
    n_cr = 60.0 / (2 * math.pi) * (3.926602312 / L_cr) ** 2 * math.sqrt(E * (math.pi * d ** 4 / 64)
                                                                        / (7.85e-9 * math.pi * d ** 2 / 4))
    F_k = math.pi ** 2 * E * (math.pi * d ** 4 / 64) / (0.699 * L_b) ** 2
    return {"speed": 150_000.0 / 24.0, "dn": 150_000.0, "critical_speed": 0.8 * n_cr, "buckling": F_k / 2.0,
            "static_safety": 2.0}


def test_limit_checks_of_the_default_design(default_rating):
    d, *_, res = default_rating
    lim = rating_section(res)["limits"]
    checks = {c["name"]: c for c in lim["checks"]}
    assert [c["name"] for c in lim["checks"]] == ["speed", "dn", "critical_speed", "buckling", "static_safety"]
    hand = _by_hand_limits()
    for name, limit in hand.items():
        assert checks[name]["limit"] == pytest.approx(limit, rel=1e-9), name
    assert checks["speed"]["limit"] == 6250.0 and lim["permissible_speed_rpm"] == 6250.0   # d n governs
    # the duty: the design load 20 kN at rating.speed_rpm 100 rpm, nominal diameter 24 mm
    values = {"speed": 100.0, "dn": 2400.0, "critical_speed": 100.0, "buckling": 20_000.0,
              "static_safety": rating_section(res)["static_load_rating_n"] / 20_000.0}
    units = {"speed": "rpm", "dn": "mm/min", "critical_speed": "rpm", "buckling": "N", "static_safety": "-"}
    for name, c in checks.items():
        assert c["value"] == pytest.approx(values[name], rel=1e-12) and c["unit"] == units[name]
        # upper limits: margin = limit / value - 1; the lower limit s0: value / limit - 1
        want = values[name] / hand[name] - 1 if name == "static_safety" else hand[name] / values[name] - 1
        assert c["margin"] == pytest.approx(want, rel=1e-9) and c["passed"] is True
        assert c["kind"] == ("lower" if name == "static_safety" else "upper")
    assert checks["speed"]["margin"] == pytest.approx(61.5)          # 6250 / 100 - 1
    assert checks["static_safety"]["value"] == pytest.approx(94382 / 20_000, rel=1e-4)   # C_0a 94.4 kN (docs)
    assert lim["required_static_safety"] == 2.0 and lim["all_passed"] is True


def test_speed_check_flips_at_the_permissible_speed():
    d = PRSDesign()
    c = analyse_contact(d)
    m = build_model(d, c)

    def speed_check(n):
        res = R.analyse_rating(d, c, m, R.rating_case(d, speed_rpm=n))
        return {k.name: k for k in res.checks}

    at, above = speed_check(6250.0), speed_check(6250.0 * (1 + 1e-9))
    assert at["speed"].passed and at["speed"].margin == 0.0 and at["dn"].passed
    assert not above["speed"].passed and above["speed"].margin < 0 and not above["dn"].passed
    assert above["critical_speed"].passed             # the whirling limit is 1.5e6 rpm here
    assert limit_warnings(list(above.values())) == [
        "speed 6250 rpm exceeds the permissible 6250 rpm (the smaller of the d n limit and the critical speed "
        "limit)",
        "d n = nominal diameter x speed = 150000 mm/min exceeds the nut speed limit rating.dn_limit_mm_rpm = "
        "150000 mm/min"]


def test_static_safety_and_buckling_fail_under_an_absurd_load(default_rating):
    d, c, m, res0 = default_rating
    res = R.analyse_rating(d, c, m, R.rating_case(d, mean_load_n=2e9))
    checks = {k["name"]: k for k in rating_section(res)["limits"]["checks"]}
    C0a = rating_section(res0)["static_load_rating_n"]
    assert checks["static_safety"]["value"] == pytest.approx(C0a / 2e9, rel=1e-12)
    assert checks["static_safety"]["value"] == pytest.approx(4.7e-5, rel=0.01)
    assert not checks["static_safety"]["passed"] and not checks["buckling"]["passed"]
    assert checks["buckling"]["margin"] == pytest.approx(_by_hand_limits()["buckling"] / 2e9 - 1, rel=1e-9)
    assert checks["speed"]["passed"] and rating_section(res)["limits"]["all_passed"] is False


def test_required_static_safety_moves_the_verdict(default_rating):
    """s0 = C_0a / 20 kN = 4.72: passes the default 2 and fails a required 5 (the catalogue
    value with vibration or impact)."""
    d, c, m, _ = default_rating
    strict = PRSDesign(rating=RatingSettings(required_static_safety=5.0))
    ch = {k["name"]: k for k in rating_section(R.analyse_rating(strict, c, m))["limits"]["checks"]}["static_safety"]
    assert ch["limit"] == 5.0 and not ch["passed"] and ch["margin"] == pytest.approx(ch["value"] / 5.0 - 1)


def test_limit_check_margins_and_equality():
    up = limit_check_dict(R.limit_check("speed", 100.0, 6250.0))
    assert up == {"name": "speed", "kind": "upper", "value": 100.0, "limit": 6250.0, "unit": "rpm",
                  "margin": 61.5, "passed": True}
    assert R.limit_check("buckling", 4.0, 2.0).margin == -0.5            # twice the limit
    lo = R.limit_check("static_safety", 1.0, 2.0)
    assert lo.margin == -0.5 and lo.passed is False and lo.kind == "lower"
    assert R.limit_check("static_safety", 2.0, 2.0).passed and R.limit_check("dn", 5.0, 5.0).passed
