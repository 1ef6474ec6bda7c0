"""Hypothesis strategies shared by the tests: valid PRS designs of standard sizing."""
from __future__ import annotations

import math

from hypothesis import assume
from hypothesis import strategies as st

from prs_geom.model.actuator import ActuatorSettings
from prs_geom.model.design import Loading, Nut, PRSDesign, Roller, Screw, Thread
from prs_geom.model.errors import DesignError


@st.composite
def standard_designs(draw, max_teeth: int = 30, pitch_lists: bool = False) -> PRSDesign:
    """Designs obeying r_s = (n - 2) r_r, r_n = n r_r with n starts on screw and nut."""
    starts = draw(st.integers(4, 7))
    roller_d = draw(st.floats(4.0, 16.0))
    pitch = draw(st.floats(0.12, 0.3)) * roller_d
    beta = draw(st.floats(35.0, 55.0))
    teeth = draw(st.integers(3, max_teeth))
    a = 0.5 * (starts - 1) * roller_d
    half_depth = pitch / (4 * math.tan(math.radians(beta)))
    roller_major = roller_d + 1.2 * half_depth
    z_max = max(1, int(math.pi / math.asin(min(1.0, roller_major / (2 * a)))) - 1)
    count = draw(st.integers(1, min(z_max, 12)))
    n = teeth
    rl = nl = None
    if pitch_lists:
        # micrometre-size graded corrections, as an equal-load design produces
        rl = tuple(pitch + draw(st.floats(-1e-3, 1e-3)) for _ in range(n - 1))
        nl = tuple(pitch + draw(st.floats(-1e-3, 1e-3)) for _ in range(n - 1))
    try:
        d = PRSDesign(
            name="hyp",
            thread=Thread(pitch_mm=pitch, flank_half_angle_deg=beta, engaged_teeth=teeth,
                          hand=draw(st.sampled_from(["right", "left"]))),
            screw=Screw(pitch_diameter_mm=(starts - 2) * roller_d, starts=starts),
            roller=Roller(pitch_diameter_mm=roller_d, count=count, pitch_list_mm=rl),
            nut=Nut(pitch_diameter_mm=starts * roller_d, starts=starts,
                    outer_diameter_mm=starts * roller_d * draw(st.floats(1.2, 1.6)), pitch_list_mm=nl),
            loading=Loading(axial_load_n=draw(st.floats(1e3, 1e5)),
                            installation=draw(st.sampled_from(["tension-compression",
                                                               "compression-compression"]))),
            # the thread-level properties drawn for do not depend on the actuator, whose
            # tables (bearings from 10 mm bore) need not cover every drawn size
            actuator=ActuatorSettings(enabled=False),
        )
    except DesignError:
        assume(False)
    return d
