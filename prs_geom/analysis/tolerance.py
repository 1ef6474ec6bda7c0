"""Manufacturing errors and the load sharing they leave: the error model of a design, its
Monte Carlo evaluation on all z rollers side by side, the linear (closed-form) propagation,
the importance of each error term and the tolerance synthesis (docs/theory/tolerances.md).

Pure math, no I/O. Sampling takes a :class:`numpy.random.SeedSequence` and draws every
number of a chunk from it, so that a study cut into the same chunks gives the same numbers
whatever runs the chunks (:mod:`prs_geom.runtime.scaleout`); the studies themselves are run by
:mod:`prs_geom.studies`.

How an error enters the load model
----------------------------------
Every error is a change of the cumulative initial gaps g_nr[r, j], g_rs[r, j] of
:func:`prs_geom.analysis.loads.gap_terms` (roller r, tooth j, mm; positive = the contact
opens), linear in the errors: dg = A x with x the vector of all error values (mm, K) and A
the (2 z n, m) map of :meth:`ErrorModel.gap_map`. The pitch-list gaps count positions from
tooth 1 along +z: an axial flank position error e of tooth j (positive = the flank moved
towards the free end, like a longer pitch before it) shifts the gap of that tooth as the
pitch list would: roller flank +e on the nut side, -e on the screw side, nut -e, screw +e.

* ``screw_flank``, ``nut_flank`` (n each): per tooth, one value for the whole tooth ring (the
  tooth position an inspection measures), so every roller sees it;
* ``roller_screw_flank``, ``roller_nut_flank`` (z n each): per roller and tooth;
* ``roller_diameter`` (z): a roller pitch diameter larger by dd closes both of its contacts
  radially by dd / 2, an axial closure k dd / 2 with k = |n . e_r| / |n_z| from the contact
  normal n and the radial direction e_r of the roller at the contact;
* ``screw_eccentricity``, ``nut_eccentricity`` (2 each, the offset vector (e_x, e_y) in the
  screw frame): at roller r the contact point lies at azimuth theta_r + psi (theta_r =
  2 pi r / z, psi the contact's angle from the contact solver); a screw offset closes that
  contact radially by e . e_r, a nut offset opens it by e . e_r (only the radial part: the
  tangential part moves a helical contact by about tan(lead angle) of it, which shifts the
  pattern's phase by a few degrees and its amplitude by under 1 %);
* ``lead`` (screw, z rollers, nut): a base pitch longer by dp per pitch adds (j - 1) dp at
  tooth j, as a pitch list would;
* ``temperature`` (screw, rollers, nut; K): the part's pitch grows by p alpha dT.
  A uniform radial growth is the same for every roller and tooth: it only moves the
  approach, not the sharing, and is left out.

Distributions: "uniform" within +-T (an eccentricity: uniform over the disc of radius T),
"normal" with standard deviation T / 3 (an eccentricity: each component).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, Sequence

import numpy as np
from numpy.typing import NDArray

from prs_geom.analysis.contact import ContactResult
from prs_geom.analysis.load_solver import LoadModel, RollerLoadResult, solve_loads_rollers
from prs_geom.analysis.loads import check_load_scale, gap_terms_rollers
from prs_geom.model.design import FLANK_FIELDS, PRSDesign, Tolerances
from prs_geom.model.errors import DesignError

__all__ = ["TERMS", "GROUPS", "QUANTILES", "ErrorModel", "error_model", "StudyProblem", "study_problem",
           "SampleStats", "solve_samples", "evaluate", "ChunkTask", "run_chunk", "summary",
           "clopper_pearson_lower", "quantile_upper_bound", "variance_shares", "linear_influence",
           "linear_moments", "flank_influence", "allocation_weights"]

#: The error terms, in the order of the columns of :meth:`ErrorModel.gap_map`.
TERMS = ("screw_flank", "roller_screw_flank", "roller_nut_flank", "nut_flank", "roller_diameter",
         "screw_eccentricity", "nut_eccentricity", "lead", "temperature")
#: Terms grouped as the designer names them (the importance ranking, the CLI flags).
GROUPS = {"flank": ("screw_flank", "roller_screw_flank", "roller_nut_flank", "nut_flank"),
          "roller_diameter": ("roller_diameter",), "screw_eccentricity": ("screw_eccentricity",),
          "nut_eccentricity": ("nut_eccentricity",), "lead": ("lead",), "temperature": ("temperature",)}
#: Quantiles reported for every distribution.
QUANTILES = {"median": 0.5, "p95": 0.95, "p99": 0.99}


# --------------------------------------------------------------------------- the model
@dataclass(frozen=True)
class ErrorModel:
    """The error terms of one design as tolerances (half-widths) in mm or K, and the
    geometry that turns them into gap changes (module docstring).

    ``tolerance`` maps each term of :data:`TERMS` to its half-widths, one per column of
    the term (e.g. (n,) for ``screw_flank``, (z n,) for ``roller_nut_flank``, roller-major).
    """

    n: int
    z: int
    pitch_mm: float
    distribution: str
    tolerance: dict[str, NDArray]
    closure_rs: tuple[float, float]          # axial per radial closure at roller-screw: (screw, roller)
    closure_nr: tuple[float, float]          # at nut-roller: (nut, roller)
    contact_angle_rs: float                  # psi of the contact point (rad), screw frame
    contact_angle_nr: float
    expansion: tuple[float, float, float]    # alpha of screw, roller, nut (1/K)
    _map: NDArray = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        tol = {}
        for term in TERMS:
            v = np.array(self.tolerance[term], dtype=np.float64).ravel()
            if v.shape != (self.width(term),):
                raise ValueError(f"tolerance of {term} must have {self.width(term)} entries, has {v.size}")
            if not (np.all(np.isfinite(v)) and np.all(v >= 0)):
                raise ValueError(f"tolerance of {term} must be finite and >= 0")
            v.setflags(write=False)
            tol[term] = v
        object.__setattr__(self, "tolerance", tol)
        object.__setattr__(self, "_map", self._build_map())

    def width(self, term: str) -> int:
        """Number of error values (columns) of ``term``."""
        n, z = self.n, self.z
        return {"screw_flank": n, "roller_screw_flank": z * n, "roller_nut_flank": z * n, "nut_flank": n,
                "roller_diameter": z, "screw_eccentricity": 2, "nut_eccentricity": 2, "lead": z + 2,
                "temperature": 3}[term]

    def columns(self, term: str) -> slice:
        """The columns of ``term`` in x and in :meth:`gap_map`."""
        start = 0
        for t in TERMS:
            if t == term:
                return slice(start, start + self.width(t))
            start += self.width(t)
        raise KeyError(term)

    @property
    def size(self) -> int:
        return sum(self.width(t) for t in TERMS)

    def active_terms(self) -> tuple[str, ...]:
        """The terms with a tolerance above zero."""
        return tuple(t for t in TERMS if float(self.tolerance[t].max()) > 0.0)

    def gap_map(self) -> NDArray:
        """A, (2, z, n, m): the gap change dg[side, r, j] = A[side, r, j] . x (side 0 =
        nut-roller), x in mm (K for the temperatures); read-only."""
        return self._map

    def _build_map(self) -> NDArray:
        n, z = self.n, self.z
        A = np.zeros((2, z, n, self.size))
        NR, RS = 0, 1
        r_idx, j_idx = np.meshgrid(np.arange(z), np.arange(n), indexing="ij")
        c = self.columns("screw_flank").start
        A[RS, :, j_idx[0], c + j_idx[0]] = 1.0
        c = self.columns("nut_flank").start
        A[NR, :, j_idx[0], c + j_idx[0]] = -1.0
        c = self.columns("roller_screw_flank").start
        A[RS, r_idx, j_idx, c + r_idx * n + j_idx] = -1.0
        c = self.columns("roller_nut_flank").start
        A[NR, r_idx, j_idx, c + r_idx * n + j_idx] = 1.0
        c = self.columns("roller_diameter").start
        rr = np.arange(z)
        A[NR, rr, :, c + rr] = -0.5 * self.closure_nr[1]
        A[RS, rr, :, c + rr] = -0.5 * self.closure_rs[1]
        theta = 2.0 * math.pi * rr / z
        c = self.columns("screw_eccentricity").start
        ang = theta + self.contact_angle_rs
        A[RS, :, :, c] = -self.closure_rs[0] * np.cos(ang)[:, None]
        A[RS, :, :, c + 1] = -self.closure_rs[0] * np.sin(ang)[:, None]
        c = self.columns("nut_eccentricity").start
        ang = theta + self.contact_angle_nr
        A[NR, :, :, c] = self.closure_nr[0] * np.cos(ang)[:, None]
        A[NR, :, :, c + 1] = self.closure_nr[0] * np.sin(ang)[:, None]
        # base pitch change dp per pitch: (j - 1) dp at tooth j (0-based j here)
        ramp = np.arange(n, dtype=np.float64)
        per_pitch = 1.0 / max(n - 1, 1)            # lead tolerance is over (n - 1) pitches
        c = self.columns("lead").start
        A[RS, :, :, c] = ramp * per_pitch                                   # screw
        A[NR, rr, :, c + 1 + rr] = ramp * per_pitch                         # roller r
        A[RS, rr, :, c + 1 + rr] = -ramp * per_pitch
        A[NR, :, :, c + 1 + z] = -ramp * per_pitch                          # nut
        c = self.columns("temperature").start
        a_s, a_r, a_n = self.expansion
        p = self.pitch_mm
        A[RS, :, :, c] = ramp * p * a_s
        A[NR, :, :, c + 1] = ramp * p * a_r
        A[RS, :, :, c + 1] = -ramp * p * a_r
        A[NR, :, :, c + 2] = -ramp * p * a_n
        A.setflags(write=False)
        return A

    def with_tolerances(self, **tolerance: Any) -> "ErrorModel":
        """The same geometry with other half-widths for the named terms (mm or K)."""
        tol = dict(self.tolerance)
        for term, v in tolerance.items():
            tol[term] = np.broadcast_to(np.asarray(v, dtype=np.float64), (self.width(term),)).copy()
        return replace(self, tolerance=tol)

    def only(self, terms: Sequence[str]) -> "ErrorModel":
        """The model with every term outside ``terms`` switched off."""
        return self.with_tolerances(**{t: 0.0 for t in TERMS if t not in terms})

    def scaled(self, terms: Sequence[str], factor: float) -> "ErrorModel":
        """The model with the tolerances of ``terms`` multiplied by ``factor``."""
        return self.with_tolerances(**{t: self.tolerance[t] * factor for t in terms})

    def standard_deviation(self) -> NDArray:
        """Standard deviation of every error value (m,): T / sqrt(3) uniform, T / 3 normal;
        an eccentricity uniform over the disc of radius T: T / 2 per component."""
        out = np.empty(self.size)
        for t in TERMS:
            T = self.tolerance[t]
            if self.distribution == "normal":
                s = T / 3.0
            elif t in ("screw_eccentricity", "nut_eccentricity"):
                s = T / 2.0
            else:
                s = T / math.sqrt(3.0)
            out[self.columns(t)] = s
        return out

    def sample(self, seed: np.random.SeedSequence | int, count: int) -> NDArray:
        """``count`` samples of x, (count, m), drawn from ``seed`` only.

        Every term draws its standardised values from its own child stream of ``seed`` (in
        the order of :data:`TERMS`) whether or not its tolerance is zero, so that switching a
        term off or scaling it leaves the draws of every other term unchanged (common random
        numbers for the importance ranking and the synthesis)."""
        ss = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
        # the children spawn() would make, built without spawn(): spawn() counts its calls on
        # the parent, so a second sample() from the same object would draw other numbers
        streams = [np.random.SeedSequence(ss.entropy, spawn_key=ss.spawn_key + (k,), pool_size=ss.pool_size)
                   for k in range(len(TERMS))]
        x = np.empty((count, self.size))
        for t, child in zip(TERMS, streams):
            rng = np.random.default_rng(child)
            T = self.tolerance[t]
            w = self.width(t)
            if self.distribution == "normal":
                xi = rng.standard_normal((count, w)) / 3.0
            elif t in ("screw_eccentricity", "nut_eccentricity"):
                u = rng.random((count, 2))
                rad, ang = np.sqrt(u[:, 0]), 2.0 * math.pi * u[:, 1]
                xi = np.stack([rad * np.cos(ang), rad * np.sin(ang)], axis=1)
            else:
                xi = rng.uniform(-1.0, 1.0, (count, w))
            x[:, self.columns(t)] = xi * T
        return x

    def gaps(self, x: NDArray) -> tuple[NDArray, NDArray]:
        """Gap changes (B, z, n) of both sides for errors x (B, m)."""
        A = self._map.reshape(2 * self.z * self.n, self.size)
        dg = (np.asarray(x, dtype=np.float64) @ A.T).reshape(-1, 2, self.z, self.n)
        return dg[:, 0], dg[:, 1]


def _radial_closure(point: Sequence[float], normal: Sequence[float], centre: tuple[float, float]) -> float:
    """|n . e_r| / |n_z| at a contact point: the axial gap change per unit radial move of the
    surface of the body whose axis passes through ``centre`` (x, y) of the screw frame."""
    px, py, _ = point
    er = np.array([px - centre[0], py - centre[1], 0.0])
    er /= np.linalg.norm(er)
    n = np.asarray(normal, dtype=np.float64)
    return float(abs(n @ er) / abs(n[2]))


def error_model(design: PRSDesign, contact: ContactResult, tolerances: Tolerances) -> ErrorModel:
    """The :class:`ErrorModel` of ``design`` with the half-widths of ``tolerances`` (um and
    K, converted to mm) and the contact geometry of the contact stage."""
    n, z = design.thread.engaged_teeth, design.roller.count
    um = 1e-3
    flank = tolerances.flank_tolerances_um(n)
    tol = {
        "screw_flank": np.array(flank["screw_flank_um"]) * um,
        "roller_screw_flank": np.tile(np.array(flank["roller_screw_flank_um"]) * um, z),
        "roller_nut_flank": np.tile(np.array(flank["roller_nut_flank_um"]) * um, z),
        "nut_flank": np.array(flank["nut_flank_um"]) * um,
        "roller_diameter": np.full(z, tolerances.roller_diameter_um * um),
        "screw_eccentricity": np.full(2, tolerances.screw_eccentricity_um * um),
        "nut_eccentricity": np.full(2, tolerances.nut_eccentricity_um * um),
        "lead": np.full(z + 2, tolerances.lead_um * um),
        "temperature": np.full(3, tolerances.temperature_k),
    }
    rs, nr = contact.screw_roller["upper_at_theoretical"], contact.roller_nut["lower"]
    a = design.centre_distance_mm
    mats = design.materials
    return ErrorModel(
        n=n, z=z, pitch_mm=design.thread.pitch_mm, distribution=tolerances.distribution, tolerance=tol,
        closure_rs=(_radial_closure(rs.point_mm, rs.normal, (0.0, 0.0)),
                    _radial_closure(rs.point_mm, rs.normal, (a, 0.0))),
        closure_nr=(_radial_closure(nr.point_mm, nr.normal, (0.0, 0.0)),
                    _radial_closure(nr.point_mm, nr.normal, (a, 0.0))),
        contact_angle_rs=math.atan2(rs.point_mm[1], rs.point_mm[0]),
        contact_angle_nr=math.atan2(nr.point_mm[1], nr.point_mm[0]),
        expansion=(mats.screw.thermal_expansion_per_k, mats.roller.thermal_expansion_per_k,
                   mats.nut.thermal_expansion_per_k))


# --------------------------------------------------------------------------- evaluation
@dataclass(frozen=True)
class StudyProblem:
    """Everything a chunk of a tolerance study needs (picklable, no design object):
    the load model, the designed gaps (z, n) of each side and the loads (N)."""

    model: LoadModel
    g_nr: NDArray
    g_rs: NDArray
    loads_n: tuple[float, ...]
    errors: ErrorModel

    def with_gaps(self, g_nr: NDArray, g_rs: NDArray) -> "StudyProblem":
        return replace(self, g_nr=np.asarray(g_nr, dtype=np.float64), g_rs=np.asarray(g_rs, dtype=np.float64))


def study_problem(design: PRSDesign, model: LoadModel, errors: ErrorModel,
                  load_fractions: Sequence[float], roller: NDArray | None = None,
                  nut: Sequence[float] | None = None) -> StudyProblem:
    """The :class:`StudyProblem` of ``design`` (or of other pitch lists ``roller`` /
    ``nut``) at ``load_fractions`` of its design load. The smallest load must suit the load
    model (:func:`~prs_geom.analysis.loads.check_load_scale`: a
    :class:`~prs_geom.model.errors.DesignError` on ``tolerances.load_fractions[k]`` if not)."""
    g_nr, g_rs = gap_terms_rollers(design, roller, nut)
    F0 = design.loading.axial_load_n
    loads = tuple(float(f) * F0 for f in load_fractions)
    if loads:
        k = int(np.argmin(loads))
        check_load_scale(design, model, loads[k], f"tolerances.load_fractions[{k}]", load_fractions[k],
                         gaps=[(g_nr, g_rs)])
    return StudyProblem(model, g_nr, g_rs, loads, errors)


@dataclass(frozen=True)
class SampleStats:
    """Per-sample results of a chunk: arrays (L, B) over the L loads and B samples.

    ``worst_nr`` / ``worst_rs``: the largest coefficient f / (F / n z) of any roller and tooth
    on that side; ``share_max`` / ``share_min``: the largest and smallest roller load share
    times z (1 = equal sharing); ``open_teeth``: contacts out of contact."""

    worst_nr: NDArray
    worst_rs: NDArray
    share_max: NDArray
    share_min: NDArray
    open_teeth: NDArray

    @property
    def worst(self) -> NDArray:
        """Worst coefficient of both sides, (L, B)."""
        return np.maximum(self.worst_nr, self.worst_rs)

    @staticmethod
    def concatenate(parts: Sequence["SampleStats"]) -> "SampleStats":
        return SampleStats(*(np.concatenate([getattr(p, k) for p in parts], axis=1)
                             for k in ("worst_nr", "worst_rs", "share_max", "share_min", "open_teeth")))


def solve_samples(problem: StudyProblem, x: NDArray, load: float, linear_at: float | None = None) -> RollerLoadResult:
    """Tooth loads of every roller for the error samples x (B, m) at ``load`` (N)."""
    dn, ds = problem.errors.gaps(x)
    return solve_loads_rollers(problem.model, load, problem.g_nr + dn, problem.g_rs + ds, linear_at=linear_at)


def evaluate(problem: StudyProblem, x: NDArray) -> SampleStats:
    """Worst coefficients and roller shares of the samples x (B, m) at every load: one
    batched solve of all loads and samples together."""
    B, L = x.shape[0], len(problem.loads_n)
    dn, ds = problem.errors.gaps(x)
    g_nr = np.broadcast_to(problem.g_nr + dn, (L, B) + dn.shape[1:]).reshape((L * B,) + dn.shape[1:])
    g_rs = np.broadcast_to(problem.g_rs + ds, (L, B) + ds.shape[1:]).reshape((L * B,) + ds.shape[1:])
    loads = np.repeat(np.asarray(problem.loads_n, dtype=np.float64), B)
    res = solve_loads_rollers(problem.model, loads, g_nr, g_rs)
    per = res.ldc_per_roller
    z = problem.errors.z
    share = res.roller_load_share * z
    shape = (L, B)
    return SampleStats(per["nut_roller"].max(axis=(1, 2)).reshape(shape),
                       per["roller_screw"].max(axis=(1, 2)).reshape(shape),
                       share.max(axis=1).reshape(shape), share.min(axis=1).reshape(shape),
                       ((~res.active_nr).sum(axis=(1, 2)) + (~res.active_rs).sum(axis=(1, 2))).reshape(shape))


@dataclass(frozen=True)
class ChunkTask:
    """One chunk of a study: ``count`` samples drawn from ``seed``; ``variants`` are error
    models evaluated on the same standardised draws (the full model first, then e.g. one
    per term for the importance ranking)."""

    problem: StudyProblem
    seed: np.random.SeedSequence
    count: int
    variants: tuple[ErrorModel, ...] = ()


def run_chunk(task: ChunkTask) -> list[SampleStats]:
    """Evaluate one chunk: the study's error model, then each variant, on common draws."""
    out = []
    for errors in (task.problem.errors,) + tuple(task.variants):
        x = errors.sample(task.seed, task.count)
        out.append(evaluate(replace(task.problem, errors=errors), x))
    return out


# --------------------------------------------------------------------------- statistics
def summary(values: NDArray) -> dict[str, float]:
    """median, p95, p99, max, min and mean of a sample (linear quantiles)."""
    v = np.asarray(values, dtype=np.float64).ravel()
    out = {k: float(np.quantile(v, q)) for k, q in QUANTILES.items()}
    out.update(max=float(v.max()), min=float(v.min()), mean=float(v.mean()))
    return out


def clopper_pearson_lower(successes: int, trials: int, level: float = 0.95) -> float:
    """One-sided Clopper-Pearson lower confidence bound (at ``level``) of a probability
    from ``successes`` out of ``trials``."""
    if successes <= 0:
        return 0.0
    from scipy import stats     # scipy.stats takes 0.2 s to import: only studies with a confidence need it

    return float(stats.beta.ppf(1.0 - level, successes, trials - successes + 1))


def quantile_upper_bound(values: NDArray, q: float, level: float = 0.95) -> float | None:
    """Distribution-free upper confidence bound (at ``level``) of the q-quantile of the
    population a sample was drawn from: the order statistic X_(k) with the smallest k such that
    P(Binomial(N, q) < k) >= level. None when the sample is too small for that level."""
    v = np.sort(np.asarray(values, dtype=np.float64).ravel())
    from scipy import stats

    k = int(stats.binom.ppf(level, v.size, q)) + 1          # 1-based rank
    return float(v[k - 1]) if k <= v.size else None


def variance_shares(total: NDArray, per_term: dict[str, NDArray]) -> list[dict[str, Any]]:
    """Importance ranking: the variance of the worst coefficient with one term switched on
    at a time (common draws), as shares of their sum, largest first; ``interaction`` is the
    part of the full variance the single terms do not explain (1 - sum / total)."""
    var_total = float(np.var(total))
    var = {k: float(np.var(v)) for k, v in per_term.items()}
    s = sum(var.values())
    rows = [{"term": k, "variance": v, "share": (v / s) if s > 0 else 0.0,
             "std_alone": math.sqrt(v)} for k, v in var.items()]
    rows.sort(key=lambda r: -r["variance"])
    for r in rows:
        r["interaction_of_total"] = (1.0 - s / var_total) if var_total > 0 else 0.0
    return rows


# --------------------------------------------------------------------------- linear model
def linear_influence(problem: StudyProblem, load: float, step_mm: float = 1e-6) -> tuple[NDArray, RollerLoadResult]:
    """Influence matrix G (2, z, n, m) of the linearised model: d ldc[side, r, j] / d x
    (per mm; per K for temperatures), and the linearised solution at zero error.

    The linear model replaces Hertz by its tangent at the mean tooth load F / (n z) (the
    linear model B f = x of docs/theory/loads.md); while every tooth stays in contact its
    loads are affine in the gaps, so one-sided differences of ``step_mm`` are exact up to
    rounding (about 1e-10 relative)."""
    e = problem.errors
    m = e.size
    n, z = e.n, e.z
    mean = load / (n * z)
    x = np.vstack([np.zeros(m), np.eye(m) * step_mm])
    dn, ds = e.gaps(x)
    res = solve_loads_rollers(problem.model, load, problem.g_nr + dn, problem.g_rs + ds, linear_at=mean)
    f = np.stack([res.f_nr, res.f_rs], axis=1) / mean                   # (m + 1, 2, z, n)
    if not (np.all(res.active_nr) and np.all(res.active_rs)):
        raise DesignError("tolerances", "linear model", "a tooth is out of contact at zero error: the "
                          "linearised influence is not defined")
    G = np.moveaxis((f[1:] - f[0]) / step_mm, 0, -1)
    base = RollerLoadResult(load, res.f_nr[0], res.f_rs[0], res.approach_nr_mm[0], res.approach_rs_mm[0],
                            int(res.iterations[0]), res.active_nr[0], res.active_rs[0], bool(res.barrier[0]))
    return G, base


def linear_moments(G: NDArray, errors: ErrorModel) -> tuple[NDArray, NDArray]:
    """Closed-form change of mean (0: the errors have zero mean) and standard deviation of
    every coefficient (2, z, n) of the linearised model: sqrt(diag(G S G^T)) with S the
    (diagonal) covariance of the errors."""
    s = errors.standard_deviation()
    Gf = G.reshape(-1, G.shape[-1])
    std = np.sqrt(((Gf * s) ** 2).sum(axis=1)).reshape(G.shape[:-1])
    return np.zeros(G.shape[:-1]), std


def flank_influence(G: NDArray, errors: ErrorModel) -> dict[str, NDArray]:
    """Per flank field and tooth: the largest |d ldc / d e| (per um) over every coefficient,
    roller flanks taken on roller 0 (all rollers are alike)."""
    n = errors.n
    out = {}
    for fld, term in zip(FLANK_FIELDS, ("screw_flank", "roller_screw_flank", "roller_nut_flank", "nut_flank")):
        cols = G[..., errors.columns(term)]
        cols = cols[..., :n]                                     # roller terms: roller 0 first
        out[fld] = np.abs(cols).reshape(-1, n).max(axis=0) * 1e-3
    return out


def allocation_weights(influence: dict[str, NDArray], spread: float = 10.0) -> dict[str, NDArray]:
    """Per-tooth weights w (mean 1 over all flanks) with T = w T_mean: inversely proportional
    to the influence (a flank that moves the coefficients less may be looser), limited to
    ``spread`` times the smallest weight so that no flank goes unchecked."""
    inv = {k: 1.0 / np.maximum(v, 1e-300) for k, v in influence.items()}
    allw = np.concatenate(list(inv.values()))
    lo = allw.min()
    clipped = {k: np.minimum(v, spread * lo) for k, v in inv.items()}
    mean = np.concatenate(list(clipped.values())).mean()
    return {k: v / mean for k, v in clipped.items()}
