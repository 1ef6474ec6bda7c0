"""Robust pitch design: pitch lists that keep the worst tooth low over a load spectrum and
the manufacturing errors, instead of sharing exactly equally at one load
(docs/theory/tolerances.md, "Robust pitch design").

Pure math, no I/O; :mod:`prs_geom.studies` runs the searches (in parallel when asked).

The family searched
-------------------
With equal loads the pitch corrections depend only on the body strains, which are linear
in the load (docs/theory/loads.md): the equal-load lists at load a F0 are the design-load
corrections times a. Each side has its own correction: roller-screw c_rs,j = p_r,j - p_s and
nut-roller c_nr,j = p_r,j - p_n,j. The family scales them independently,

    p_r,j = p + a_rs c_rs,j,    p_n,j = p_r,j - a_nr c_nr,j,

so (0, 0) is the constant pitch, (1, 1) the equal-load design at the design load and
(a, a) the equal-load design at a F0. A spectrum whose loads lie below the design load
pulls the optimum below 1; manufacturing errors add a spread that the corrections can only
shift, so the optimum trades the worst tooth at each load against the others.

The objective
-------------
The ``quantile`` (default 0.95) of the worst coefficient (both sides, every roller and
tooth) of the mixture over the spectrum: sample b of case l weighs w_l / B (w the case
weights of :class:`~prs_geom.model.spectrum.Spectrum`). All candidates are evaluated on the
same error samples (common random numbers), so the objective is a deterministic, piecewise
smooth function of (a_nr, a_rs).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from prs_geom.analysis.loads import PitchDesign
from prs_geom.model.design import PRSDesign

__all__ = ["PitchFamily", "weighted_quantile"]


@dataclass(frozen=True)
class PitchFamily:
    """The two-parameter family of pitch lists of the module docstring (mm)."""

    pitch_mm: float
    correction_rs: NDArray          # p_r,j - p_s of the equal-load design at the design load
    correction_nr: NDArray          # p_r,j - p_n,j

    @staticmethod
    def from_equal_load(design: PRSDesign, equal: PitchDesign) -> "PitchFamily":
        p = design.thread.pitch_mm
        r = np.asarray(equal.roller_mm) - p
        nut = np.asarray(equal.nut_mm) - p
        return PitchFamily(p, r, r - nut)

    def lists(self, a_nr: float, a_rs: float) -> tuple[NDArray, NDArray]:
        """Roller and nut pitch lists (n - 1,) of the member (a_nr, a_rs)."""
        roller = self.pitch_mm + a_rs * self.correction_rs
        nut = roller - a_nr * self.correction_nr
        return roller, nut

    def pitch_design(self, a_nr: float, a_rs: float, target: NDArray | None = None) -> PitchDesign:
        roller, nut = self.lists(a_nr, a_rs)
        t = np.ones(len(roller) + 1) if target is None else target
        return PitchDesign(tuple(map(float, roller)), tuple(map(float, nut)), self.pitch_mm, t, t)


def weighted_quantile(values: NDArray, weights: Sequence[float], q: float) -> float:
    """The q-quantile of the mixture of the rows of ``values`` (L, B): row l weighs
    ``weights[l]`` shared equally by its B samples (inverse of the weighted step CDF: the
    smallest value whose cumulative weight reaches q)."""
    v = np.asarray(values, dtype=np.float64)
    L, B = v.shape
    w = np.repeat(np.asarray(weights, dtype=np.float64) / B, B)
    order = np.argsort(v.ravel(), kind="stable")
    cum = np.cumsum(w[order])
    k = int(np.searchsorted(cum, q * cum[-1] * (1.0 - 1e-12), side="left"))
    return float(v.ravel()[order][min(k, v.size - 1)])
