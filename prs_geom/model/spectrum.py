"""Load spectra: the duty cycle of an actuator as load cases with time shares.

A spectrum file is a small TOML file (read by :func:`prs_geom.model.io.load_spectrum`)::

    # time_share: fraction of the operating time; the shares sum to 1
    [[case]]
    load_n = 5000.0
    time_share = 0.6
    speed_rpm = 1500.0      # optional here; required by ratings

    [[case]]
    load_n = 20000.0
    time_share = 0.4
    speed_rpm = 300.0

Used by the robust pitch design (``prs-geom design-pitch --robust --spectrum``), the
tolerance study (``prs-geom tolerance --spectrum``) and the ratings. With speeds on every
case, a case weighs by its share of the revolutions (time share x speed), else by its time
share (docs/theory/tolerances.md).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from prs_geom.model.errors import DesignError
from prs_geom.model.validation import positive, real

__all__ = ["SHARE_SUM_TOL", "LoadCase", "Spectrum", "spectrum_from_dict"]

#: The shares must sum to 1 within this (they are typed with a few digits).
SHARE_SUM_TOL = 1e-9


@dataclass(frozen=True)
class LoadCase:
    """One case: axial load (N), fraction of the operating time, speed (rpm, optional)."""

    load_n: float
    time_share: float
    speed_rpm: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "load_n", positive("load_n", self.load_n))
        t = real("time_share", self.time_share)
        if not 0.0 < t <= 1.0:
            raise DesignError("time_share", self.time_share, "must be in (0, 1]")
        object.__setattr__(self, "time_share", t)
        if self.speed_rpm is not None:
            object.__setattr__(self, "speed_rpm", positive("speed_rpm", self.speed_rpm))


@dataclass(frozen=True)
class Spectrum:
    """Load cases whose time shares sum to 1 (within :data:`SHARE_SUM_TOL`)."""

    cases: tuple[LoadCase, ...]

    def __post_init__(self) -> None:
        if len(self.cases) == 0:
            raise DesignError("case", [], "a spectrum needs at least one [[case]]")
        total = sum(c.time_share for c in self.cases)
        if abs(total - 1.0) > SHARE_SUM_TOL:
            raise DesignError("case[].time_share", [c.time_share for c in self.cases],
                              f"must sum to 1 (they sum to {total!r})")
        speeds = [c.speed_rpm is not None for c in self.cases]
        if any(speeds) and not all(speeds):
            k = speeds.index(False)
            raise DesignError(f"case[{k}].speed_rpm", None,
                              "give speed_rpm on every case or on none (weights are by revolutions "
                              "when speeds are given)")

    @property
    def has_speeds(self) -> bool:
        """True when the cases give speeds (then every case does)."""
        return self.cases[0].speed_rpm is not None

    @property
    def weights(self) -> np.ndarray:
        """Weight of each case: share of the revolutions with speeds, else of the time."""
        t = np.array([c.time_share for c in self.cases])
        if self.has_speeds:
            t = t * np.array([c.speed_rpm for c in self.cases])
        return t / t.sum()

    @property
    def weighting(self) -> str:
        """What the weights share: ``"revolutions"`` with speeds, else ``"time"``."""
        return "revolutions" if self.has_speeds else "time"

    @property
    def loads_n(self) -> tuple[float, ...]:
        """The axial load of each case (N)."""
        return tuple(c.load_n for c in self.cases)

    @staticmethod
    def single(load_n: float) -> "Spectrum":
        """The one-case spectrum of a constant load."""
        return Spectrum((LoadCase(load_n, 1.0),))

    @staticmethod
    def from_fractions(design_load_n: float, fractions: tuple[float, ...]) -> "Spectrum":
        """Equal time shares at fractions of the design load."""
        k = len(fractions)
        return Spectrum(tuple(LoadCase(f * design_load_n, 1.0 / k) for f in fractions))

    def as_dict(self) -> dict[str, Any]:
        """The spectrum as the report writes it: weighting and per case load (N), time share,
        speed (rpm or None) and weight."""
        return {"weighting": self.weighting,
                "cases": [{"load_n": c.load_n, "time_share": c.time_share, "speed_rpm": c.speed_rpm,
                           "weight": float(w)} for c, w in zip(self.cases, self.weights)]}


def spectrum_from_dict(data: Any) -> Spectrum:
    """A :class:`Spectrum` from the parsed TOML ``{"case": [{...}, ...]}``; errors name the
    case index and key."""
    if not isinstance(data, dict):
        raise DesignError("spectrum", data, "must be a table with [[case]] entries")
    unknown = set(data) - {"case"}
    if unknown:
        raise DesignError(sorted(unknown)[0], data[sorted(unknown)[0]], "unknown key; allowed: case")
    cases = data.get("case")
    if not isinstance(cases, list) or not cases:
        raise DesignError("case", cases, "a spectrum needs at least one [[case]] table")
    out = []
    allowed = {"load_n", "time_share", "speed_rpm"}
    for k, c in enumerate(cases):
        if not isinstance(c, dict):
            raise DesignError(f"case[{k}]", c, "must be a table")
        for key in c:
            if key not in allowed:
                raise DesignError(f"case[{k}].{key}", c[key], "unknown key; allowed: " + ", ".join(sorted(allowed)))
        for key in ("load_n", "time_share"):
            if key not in c:
                raise DesignError(f"case[{k}].{key}", None, "is required")
        try:
            out.append(LoadCase(c["load_n"], c["time_share"], c.get("speed_rpm")))
        except DesignError as exc:
            raise exc.prefixed(f"case[{k}]") from None
    return Spectrum(tuple(out))
