"""Monte Carlo studies of a design, run in chunks that any backend can execute
(docs/theory/tolerances.md, docs/scaleout.md).

Sits at the pipeline layer: it builds the problems from the design (:mod:`prs_geom.analysis`),
cuts the samples into chunks of :data:`CHUNK_SAMPLES` whatever the number of workers, gives
every chunk its own :class:`numpy.random.SeedSequence` stream (``spawn_seeds(seed, k)``)
and runs them through :func:`prs_geom.runtime.scaleout.run_chunks` (serial, joblib or Dask). The
results are gathered in chunk order, so the same seed gives the same numbers, bit for bit,
on any backend and any number of workers.

* :func:`tolerance_study`: the distribution of the worst load-distribution coefficient, of
  each side and of the roller load share under the design's error model, per load; the
  importance ranking of the error terms.
* :func:`synthesise`: the largest flank tolerance (uniform, and allocated per tooth) that
  keeps the worst coefficient <= a target with a stated confidence, re-checked by an
  independent run.
* :func:`robust_pitch`: pitch lists that minimise a quantile of the worst coefficient over a
  load spectrum and the error model, reported beside the constant and equal-load lists.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, Sequence

import numpy as np
from numpy.typing import NDArray

from prs_geom.analysis import tolerance as tol
from prs_geom.analysis.contact import ContactResult, analyse_contact
from prs_geom.analysis.loads import LoadModel, build_model, design_pitches, forward, pitch_gaps, with_pitch_lists
from prs_geom.analysis.robust import PitchFamily, weighted_quantile
from prs_geom.exports.report import tolerances_dict
from prs_geom.model.design import FLANK_FIELDS, PRSDesign, Tolerances
from prs_geom.model.errors import DesignError
from prs_geom.model.spectrum import Spectrum
from prs_geom.runtime.progress import ProgressFn
from prs_geom.runtime.scaleout import run_chunks, spawn_seeds

__all__ = ["CHUNK_SAMPLES", "CP_LEVEL", "TOLERANCE_STEP_UM", "SYNTHESIS_MAX_UM", "NO_ERROR_MODEL", "Execution",
           "ToleranceStudy", "SynthesisResult", "RobustResult", "check_probability", "require_error_model",
           "tolerance_study", "synthesise", "robust_pitch"]

#: Samples per chunk: fixed, so that the draws do not depend on the worker count.
CHUNK_SAMPLES = 250
#: Confidence level of the Clopper-Pearson bound of a synthesis.
CP_LEVEL = 0.95
#: Resolution of a synthesised tolerance (um): a shop states tolerances to 0.01 um at best.
TOLERANCE_STEP_UM = 0.01
#: Largest tolerance a synthesis tries (um).
SYNTHESIS_MAX_UM = 50.0


@dataclass(frozen=True)
class Execution:
    """Where chunks run: ``workers`` joblib processes (default: one per CPU; 1 = in this
    process), or Dask (``scheduler`` "local" or "tcp://host:port", ``dask_workers`` for a
    local cluster); ``progress`` callback. The numbers do not depend on the choice."""

    workers: int | None = None
    scheduler: Any = None
    dask_workers: int | None = None
    progress: ProgressFn | None = field(default=None, compare=False)

    def map(self, task, payloads, stage: str, sizes=None) -> list:
        """``[task(p) for p in payloads]`` through :func:`~prs_geom.runtime.scaleout.run_chunks`
        on this execution's backend, in payload order; progress under ``stage``."""
        return run_chunks(task, payloads, workers=self.workers, scheduler=self.scheduler,
                          dask_workers=self.dask_workers, progress=self.progress, stage=stage, sizes=sizes)


def _chunks(samples: int, seed: int) -> list[tuple[np.random.SeedSequence, int]]:
    k = max(1, -(-samples // CHUNK_SAMPLES))
    seeds = spawn_seeds(seed, k)
    sizes = [min(CHUNK_SAMPLES, samples - i * CHUNK_SAMPLES) for i in range(k)]
    return list(zip(seeds, sizes))


def _run(problem: tol.StudyProblem, samples: int, seed: int, execution: Execution, stage: str,
         variants: Sequence[tol.ErrorModel] = ()) -> list[tol.SampleStats]:
    """Stats of the full model and of each variant over all chunks, in chunk order."""
    chunks = _chunks(samples, seed)
    tasks = [tol.ChunkTask(problem, s, c, tuple(variants)) for s, c in chunks]
    parts = execution.map(tol.run_chunk, tasks, stage, sizes=[c for _, c in chunks])
    return [tol.SampleStats.concatenate([p[i] for p in parts]) for i in range(1 + len(variants))]


# --------------------------------------------------------------------------- study
@dataclass(frozen=True)
class ToleranceStudy:
    """Result of :func:`tolerance_study`. ``stats``: per-sample results (L loads, B samples);
    ``deterministic``: worst coefficients (L, 2) with no error; ``importance``: variance
    shares of the active term groups; ``loads_n``: the loads of the study (N), fractions
    ``load_fractions`` of the design load ``design_load_n`` (N); ``engaged_teeth``: n of the
    design; ``chunk_samples``: samples per chunk of the draws. With a ``confidence``: the
    worst coefficient it holds with that probability in the sample (``worst_quantile``) and
    the Clopper-Pearson upper bound of that quantile at 95 % (``quantile_upper_bound``, None
    when the sample is too small). :func:`prs_geom.exports.report.tolerance_section`
    serialises it."""

    tolerances: Tolerances
    load_fractions: tuple[float, ...]
    stats: tol.SampleStats
    deterministic: NDArray
    importance: list[dict[str, Any]]
    loads_n: NDArray
    design_load_n: float
    engaged_teeth: int
    chunk_samples: int = CHUNK_SAMPLES
    confidence: float | None = None
    worst_quantile: float | None = None
    quantile_upper_bound: float | None = None

    @property
    def worst(self) -> NDArray:
        """Each sample's worst coefficient over both sides and every load, (B,)."""
        return self.stats.worst.max(axis=0)


def _context(design: PRSDesign, contact: ContactResult | None, model: LoadModel | None):
    contact = contact if contact is not None else analyse_contact(design)
    model = model if model is not None else build_model(design, contact)
    return contact, model


#: What to write when a study has no error model (the design field, not a CLI flag: the
#: command line maps it to its own flags).
NO_ERROR_MODEL = ("the design has no error model: add a [tolerances] section with at least one tolerance "
                  "(e.g. tolerances.flank_um = 0.5; docs/theory/tolerances.md); a Monte Carlo study of zero "
                  "errors would only repeat the loads")


def check_probability(parameter: str, value: float) -> float:
    """``value`` when it is a probability strictly inside (0, 1).

    Raises
    ------
    DesignError
        On field ``parameter`` (the name of the argument that carried it) otherwise.
    """
    if not 0.0 < value < 1.0:
        raise DesignError(parameter, value, "must be in (0, 1)")
    return value


def require_error_model(design: PRSDesign, tolerances: Tolerances | None = None) -> Tolerances:
    """The error model of a study: ``tolerances``, else the design's ``[tolerances]``.

    Raises
    ------
    DesignError
        On field ``tolerances`` when neither is given. (An explicit model whose terms are
        all 0 is accepted: asked for on purpose, it reproduces the deterministic loads.)
    """
    tolerances = tolerances or design.tolerances
    if tolerances is None:
        raise DesignError("tolerances", None, NO_ERROR_MODEL)
    return tolerances


def tolerance_study(design: PRSDesign, tolerances: Tolerances | None = None, *,
                    contact: ContactResult | None = None, model: LoadModel | None = None,
                    execution: Execution = Execution(), importance: bool = True,
                    loads_n: Sequence[float] | None = None, confidence: float | None = None) -> ToleranceStudy:
    """Monte Carlo study of ``design`` under ``tolerances`` (default: the design's
    ``[tolerances]``): ``tolerances.samples`` samples from ``tolerances.seed`` at its load
    fractions (or at ``loads_n``, N), all z rollers side by side.

    Examples
    --------
    Flank positions within +-2 um on every tooth, 400 samples:

    >>> import prs_geom as pg
    >>> from dataclasses import replace
    >>> from prs_geom.model.design import Tolerances
    >>> design = replace(pg.default_design(), tolerances=Tolerances(flank_um=2.0, samples=400, seed=1))
    >>> study = pg.tolerance_study(design)
    >>> study.worst.shape                        # each sample's worst load coefficient
    (400,)
    >>> round(float(study.deterministic.max()), 4)  # without errors: the constant-pitch worst tooth
    1.4292
    >>> bool(study.worst.mean() > study.deterministic.max())
    True
    """
    tolerances = require_error_model(design, tolerances)
    if confidence is not None:
        check_probability("confidence", confidence)
    contact, model = _context(design, contact, model)
    errors = tol.error_model(design, contact, tolerances)
    F0 = design.loading.axial_load_n
    fractions = tuple(tolerances.load_fractions) if loads_n is None else tuple(F / F0 for F in loads_n)
    problem = tol.study_problem(design, model, errors, fractions)
    groups = [g for g, terms in tol.GROUPS.items() if any(t in errors.active_terms() for t in terms)]
    variants = [errors.only(tol.GROUPS[g]) for g in groups] if importance and len(groups) > 0 else []
    results = _run(problem, tolerances.samples, tolerances.seed, execution, "tolerance", variants)
    stats = results[0]
    det = np.array([[float(r.ldc_nr.max()), float(r.ldc_rs.max())]
                    for r in (forward(design, F, model=model) for F in problem.loads_n)])
    ranking = tol.variance_shares(stats.worst.max(axis=0),
                                  {g: r.worst.max(axis=0) for g, r in zip(groups, results[1:])}) if variants else []
    worst = stats.worst.max(axis=0)
    return ToleranceStudy(
        tolerances=tolerances, load_fractions=fractions, stats=stats, deterministic=det, importance=ranking,
        loads_n=problem.loads_n, design_load_n=F0, engaged_teeth=design.thread.engaged_teeth,
        confidence=confidence, worst_quantile=None if confidence is None else float(np.quantile(worst, confidence)),
        quantile_upper_bound=None if confidence is None else tol.quantile_upper_bound(worst, confidence, CP_LEVEL))


# --------------------------------------------------------------------------- synthesis
@dataclass(frozen=True)
class SynthesisResult:
    """Result of :func:`synthesise` (tolerances in um; ``bound_level``: level of the one-sided
    Clopper-Pearson bound of the success fraction).
    :func:`prs_geom.exports.report.synthesis_section` serialises it."""

    target_ldc: float
    confidence: float
    feasible: bool
    uniform_um: float
    allocation_um: dict[str, tuple[float, ...]]
    influence_per_um: dict[str, NDArray]
    checks: dict[str, Any]
    tolerances: Tolerances | None
    bound_level: float = CP_LEVEL


def _success(problem: tol.StudyProblem, samples: int, seed: int, execution: Execution, target: float,
             stage: str) -> tuple[int, NDArray]:
    stats = _run(problem, samples, seed, execution, stage)[0]
    worst = stats.worst.max(axis=0)
    return int((worst <= target).sum()), worst


def _check_synthesis_request(target_ldc: float, confidence: float, samples: int) -> None:
    """The arguments of :func:`synthesise` that make a synthesis impossible, named by parameter."""
    if not (math.isfinite(target_ldc) and target_ldc >= 1.0):
        raise DesignError("target_ldc", target_ldc, "must be a number >= 1 (the mean tooth carries 1)")
    check_probability("confidence", confidence)
    if tol.clopper_pearson_lower(samples, samples, CP_LEVEL) < confidence:
        # even every sample meeting the target would not prove the confidence
        need = math.ceil(math.log(1.0 - CP_LEVEL) / math.log(confidence))
        raise DesignError("samples", samples, f"too few to show probability {confidence:g} at "
                                              f"{CP_LEVEL:.0%} confidence even if every sample met the "
                                              f"target: use at least {need}")


@dataclass(frozen=True)
class _FlankSearch:
    """The flank-tolerance trials of one synthesis: every trial uses the same draws
    (``samples`` from ``seed``), the other error terms of ``base`` and ``problem``'s loads."""

    design: PRSDesign
    contact: ContactResult
    base: Tolerances
    problem: tol.StudyProblem
    samples: int
    seed: int
    execution: Execution
    target_ldc: float
    confidence: float

    def errors(self, per_tooth_um: dict[str, NDArray]) -> tol.ErrorModel:
        """The error model with these per-tooth flank tolerances (um) on top of ``base``."""
        t = replace(self.base, **{k: tuple(map(float, v)) for k, v in per_tooth_um.items()})
        return tol.error_model(self.design, self.contact, t)

    def per_tooth(self, units: int, weights: dict[str, NDArray] | None) -> dict[str, NDArray]:
        """Flank tolerances (um) of ``units`` grid steps: uniform, or allocated by ``weights``."""
        mean_um = units * TOLERANCE_STEP_UM
        n = self.design.thread.engaged_teeth
        return {k: (np.full(n, mean_um) if weights is None else _round_down(weights[k] * mean_um))
                for k in FLANK_FIELDS}

    def passes(self, units: int, weights: dict[str, NDArray] | None) -> tuple[bool, int]:
        """(the tolerance of ``units`` steps meets the target at the confidence, successes)."""
        problem = replace(self.problem, errors=self.errors(self.per_tooth(units, weights)))
        # the trial tolerance in the stage name: each trial's sample count restarts, and a
        # log should say which tolerance a count belongs to
        label = (f"synthesis, {'uniform' if weights is None else 'allocated'} flank tolerance "
                 f"{units * TOLERANCE_STEP_UM:.2f} µm, samples")
        k, _ = _success(problem, self.samples, self.seed, self.execution, self.target_ldc, label)
        return tol.clopper_pearson_lower(k, self.samples, CP_LEVEL) >= self.confidence, k

    def largest(self, weights: dict[str, NDArray] | None) -> tuple[int, int, bool]:
        """(largest passing tolerance in grid steps, -1 when exact flanks fail; the successes of
        exact flanks when they fail, else 0; True when the search stopped at
        :data:`SYNTHESIS_MAX_UM`): doubling from 0.5 um, then bisection."""
        ok0, k0 = self.passes(0, weights)
        if not ok0:
            return -1, k0, False
        lo, hi = 0, 50                                   # 0.5 um
        limit = int(round(SYNTHESIS_MAX_UM / TOLERANCE_STEP_UM))
        while True:
            ok, _ = self.passes(hi, weights)
            if not ok:
                break
            lo = hi
            if hi >= limit:
                return limit, self.samples, True
            hi = min(2 * hi, limit)
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if self.passes(mid, weights)[0]:
                lo = mid
            else:
                hi = mid
        return lo, 0, False

    def check(self, per_tooth_um: dict[str, NDArray], verify_seed: int) -> dict[str, Any]:
        """Successes of a chosen tolerance on the search's draws and on an independent run."""
        problem = replace(self.problem, errors=self.errors(per_tooth_um))
        k_s, _ = _success(problem, self.samples, self.seed, self.execution, self.target_ldc, "synthesis")
        k_v, worst_v = _success(problem, self.samples, verify_seed, self.execution, self.target_ldc, "verification")
        n = self.samples
        return {
            "successes": k_s, "fraction": k_s / n,
            "clopper_pearson_lower": tol.clopper_pearson_lower(k_s, n, CP_LEVEL),
            "verification": {"successes": k_v, "fraction": k_v / n,
                             "clopper_pearson_lower": tol.clopper_pearson_lower(k_v, n, CP_LEVEL),
                             "meets_confidence": bool(k_v / n >= self.confidence),
                             "worst_ldc": tol.summary(worst_v)},
        }


def _flank_influence(search: _FlankSearch) -> tuple[dict[str, NDArray], dict[str, NDArray]]:
    """(linearised influence of each flank on the worst coefficient at the design load, per
    um; the allocation weights inverse to it), with a unit flank model."""
    unit = tol.error_model(search.design, search.contact, replace(search.base, flank_um=1.0))
    G, _ = tol.linear_influence(replace(search.problem, errors=unit), search.design.loading.axial_load_n)
    influence = tol.flank_influence(G, unit)
    return influence, tol.allocation_weights(influence)


def synthesise(design: PRSDesign, target_ldc: float, confidence: float, base: Tolerances | None = None, *,
               samples: int = 1000, seed: int = 0, verify_seed: int | None = None,
               load_fractions: Sequence[float] = (1.0,), contact: ContactResult | None = None,
               model: LoadModel | None = None, execution: Execution = Execution()) -> SynthesisResult:
    """Largest flank tolerance with P(worst coefficient <= ``target_ldc``) >= ``confidence``.

    The other error terms keep the values of ``base`` (default: none). The flank tolerance
    is searched on a grid of :data:`TOLERANCE_STEP_UM` by bisection on common draws; a
    tolerance passes when the one-sided Clopper-Pearson lower bound (:data:`CP_LEVEL`) of the
    success probability is >= ``confidence``. Two forms: uniform (every flank the same T) and
    allocated (T_j = w_j T_mean with w_j from :func:`~prs_geom.analysis.tolerance.allocation_weights`,
    inverse to each flank's linearised influence). Each is re-checked by an independent run
    from ``verify_seed`` (default seed + 1).

    Raises
    ------
    DesignError
        On the parameter ``target_ldc`` (not a number >= 1), ``confidence`` (not in (0, 1))
        or ``samples`` (too few to show the confidence even if every sample met the target).
    """
    _check_synthesis_request(target_ldc, confidence, samples)
    contact, model = _context(design, contact, model)
    base = replace(base or Tolerances(), flank_um=0.0, screw_flank_um=None, roller_screw_flank_um=None,
                   roller_nut_flank_um=None, nut_flank_um=None)
    search = _FlankSearch(design=design, contact=contact, base=base,
                          problem=tol.study_problem(design, model, tol.error_model(design, contact, base),
                                                    load_fractions),
                          samples=samples, seed=seed, execution=execution, target_ldc=target_ldc,
                          confidence=confidence)
    verify_seed = seed + 1 if verify_seed is None else verify_seed
    influence, weights = _flank_influence(search)
    units_uniform, k_zero, capped_uniform = search.largest(None)
    if units_uniform < 0:
        checks = {"zero_flank_tolerance_successes": k_zero, "samples": samples,
                  "reason": "the target is not met even with exact flanks (the other error terms or the "
                            "pitch lists alone exceed it)"}
        return SynthesisResult(target_ldc, confidence, False, 0.0, {}, influence, checks, None)
    units_allocated, _, capped_allocated = search.largest(weights)
    uniform_um = round(units_uniform * TOLERANCE_STEP_UM, 6)
    allocation = {k: tuple(map(float, _round_down(weights[k] * units_allocated * TOLERANCE_STEP_UM)))
                  for k in FLANK_FIELDS}
    checks: dict[str, Any] = {"samples": samples, "seed": seed, "verify_seed": verify_seed,
                              "load_fractions": list(load_fractions),
                              "capped_at_um": SYNTHESIS_MAX_UM if capped_uniform or capped_allocated else None}
    n = design.thread.engaged_teeth
    checks["uniform"] = search.check({k: np.full(n, uniform_um) for k in FLANK_FIELDS}, verify_seed)
    checks["allocated"] = search.check({k: np.array(v) for k, v in allocation.items()}, verify_seed)
    source = (f"synthesised by prs-geom tolerance: target worst LDC {target_ldc:g} with probability "
              f"{confidence:g} ({CP_LEVEL:.0%} Clopper-Pearson bound), {samples} samples, seed {seed}, "
              f"re-checked with seed {verify_seed}; uniform alternative {uniform_um:.2f} um")
    written = replace(base, **allocation, flank_um=uniform_um, source=source, target_ldc=target_ldc,
                      confidence=confidence, seed=seed, samples=samples, load_fractions=tuple(load_fractions))
    return SynthesisResult(target_ldc, confidence, True, uniform_um, allocation, influence, checks, written)


def _round_down(values_um: NDArray) -> NDArray:
    """Down to the grid of TOLERANCE_STEP_UM, as the decimal a drawing states (0.57, not
    0.5700000000000001)."""
    steps = np.floor(np.asarray(values_um) / TOLERANCE_STEP_UM + 1e-9)
    return np.round(steps * TOLERANCE_STEP_UM, 6)


# --------------------------------------------------------------------------- robust pitch
@dataclass(frozen=True)
class _RobustTask:
    problem: tol.StudyProblem
    family: PitchFamily
    point: tuple[float, float]
    seeds: tuple[tuple[np.random.SeedSequence, int], ...]


def _robust_eval(task: _RobustTask) -> NDArray:
    """Worst coefficients (L, B) of one member of the family on the study's draws."""
    e = task.problem.errors
    roller, nut = task.family.lists(*task.point)
    # gaps of the member's lists: the designed gaps, the same for every roller
    g_nr, g_rs = (np.tile(g, (e.z, 1)) for g in pitch_gaps(task.family.pitch_mm, roller, nut))
    prob = task.problem.with_gaps(g_nr, g_rs)
    parts = [tol.evaluate(prob, e.sample(s, c)).worst for s, c in task.seeds]
    return np.concatenate(parts, axis=1)


@dataclass(frozen=True)
class RobustResult:
    """Result of :func:`robust_pitch`: the chosen member (a_nr, a_rs), its pitch lists and
    the comparison of constant, equal-at-design-load and robust on the same samples.
    :func:`prs_geom.exports.report.robust_section` serialises it."""

    a_nr: float
    a_rs: float
    design: PRSDesign
    comparison: dict[str, Any]
    evaluations: int


def robust_pitch(design: PRSDesign, spectrum: Spectrum, tolerances: Tolerances | None = None, *,
                 quantile: float = 0.95, samples: int = 200, seed: int = 0,
                 contact: ContactResult | None = None, model: LoadModel | None = None,
                 execution: Execution = Execution(), grid: Sequence[float] = (0.0, 0.25, 0.5, 0.75, 1.0, 1.25),
                 name: str | None = None) -> RobustResult:
    """Pitch lists minimising the ``quantile`` of the worst coefficient over ``spectrum``
    and the error model ``tolerances`` (default: the design's, else no errors): a grid over
    the family of :mod:`prs_geom.analysis.robust` (run in parallel), then Nelder-Mead from
    the best grid point, on common draws. Constant pitch (0, 0) and equal-at-design-load
    (1, 1) are members of the grid, so the result is never worse than either on the
    objective.

    Examples
    --------
    A duty of 70 % of the time at 10 kN and 30 % at 20 kN, without manufacturing errors:

    >>> import prs_geom as pg
    >>> from prs_geom.model.spectrum import LoadCase, Spectrum
    >>> duty = Spectrum((LoadCase(10000.0, 0.7), LoadCase(20000.0, 0.3)))
    >>> robust = pg.robust_pitch(pg.default_design(), duty, samples=1)
    >>> c = robust.comparison
    >>> round(c["constant_pitch"]["objective"], 3), round(c["equal_at_design_load"]["objective"], 3)
    (1.429, 1.17)
    >>> round(c["robust"]["objective"], 3)
    1.093
    """
    from scipy import optimize
    check_probability("quantile", quantile)
    tolerances = tolerances or design.tolerances or Tolerances()
    contact, model = _context(design, contact, model)
    errors = tol.error_model(design, contact, tolerances)
    F0 = design.loading.axial_load_n
    problem = tol.study_problem(design, model, errors, [F / F0 for F in spectrum.loads_n])
    family = PitchFamily.from_equal_load(design, design_pitches(design, model=model))
    seeds = tuple(_chunks(samples, seed))
    weights = spectrum.weights
    points = [(a, b) for a in grid for b in grid]
    if (1.0, 1.0) not in points:
        points.append((1.0, 1.0))
    tasks = [_RobustTask(problem, family, pt, seeds) for pt in points]
    worst = execution.map(_robust_eval, tasks, "robust grid")
    cache = {pt: w for pt, w in zip(points, worst)}

    def objective(v: NDArray) -> float:
        pt = (float(v[0]), float(v[1]))
        if pt not in cache:
            cache[pt] = _robust_eval(_RobustTask(problem, family, pt, seeds))
        return weighted_quantile(cache[pt], weights, quantile)

    best = min(points, key=lambda pt: objective(np.array(pt)))
    res = optimize.minimize(objective, np.array(best), method="Nelder-Mead",
                            options={"xatol": 1e-3, "fatol": 1e-7, "maxfev": 60,
                                     "initial_simplex": np.array(best) + np.array([[0, 0], [0.1, 0], [0, 0.1]])})
    cand = [tuple(map(float, res.x)), best]
    a_nr, a_rs = min(cand, key=lambda pt: objective(np.array(pt)))

    def describe(pt: tuple[float, float]) -> dict[str, Any]:
        w = cache[pt]
        return {"objective": weighted_quantile(w, weights, quantile),
                "cases": [{"load_N": F, "weight": float(wt), **{k: v for k, v in tol.summary(w[i]).items()}}
                          for i, (F, wt) in enumerate(zip(spectrum.loads_n, weights))]}

    comparison = {
        "objective": f"{quantile:g} quantile of the worst LDC over the spectrum (weighted by "
                     f"{spectrum.weighting}) and {samples} error samples (seed {seed})",
        "quantile": quantile, "samples": samples, "seed": seed, "spectrum": spectrum.as_dict(),
        "tolerances": tolerances_dict(tolerances, design.thread.engaged_teeth),
        "constant_pitch": describe((0.0, 0.0)),
        "equal_at_design_load": describe((1.0, 1.0)),
        "robust": describe((a_nr, a_rs)),
    }
    new = with_pitch_lists(design, family.pitch_design(a_nr, a_rs), name)
    return RobustResult(a_nr, a_rs, new, comparison, len(cache))
