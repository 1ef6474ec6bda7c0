"""The tooth-load solver: a complementarity problem with guaranteed termination.

Pure math, no I/O. :mod:`prs_geom.analysis.loads` builds the :class:`LoadModel` of a design
(compliances, bodies) and the initial gaps; this module solves for the tooth loads, for one
problem, a batch of samples or z rollers side by side, with one code path.

The complementarity problem and its energy
------------------------------------------
Summing the compatibility equations from tooth 1 gives, per tooth and side,

    w_j = D(f_j) + (L f)_j + g_j - a >= 0,   f_j >= 0,   f_j w_j = 0,

with g_j the cumulative initial gap (:func:`gap_terms`), a the tooth-1 approach of the side
(a Lagrange multiplier) and L = C + K: C the linear tooth compliance (diagonal, or the dense
``compliance``) and K f the cumulative body deformations. w_j > 0 is an open gap. K is
symmetric in the loads f: the coefficient of f_i in the body term of tooth j is
c min(i - 1, j - 1) for every body (nut, roller, screw). Only the compression-compression
screw, whose segment force is z sum_{k<=j} f_rs,k, is not; but with the equilibrium
z sum f_rs = F0 that force is F0 - z sum_{k>j} f_rs,k, so the screw term becomes the
symmetric one plus the known shift -F0 (j - 1) p / (E_s A_s) moved into the gaps. The
problem is then exactly the optimality (KKT) system of

    minimise  Pi(f) = sum_j [3/5 h f_j^(5/3) + t_j f_j^2 / 2] + f.L'f / 2 + g.f
    subject to f >= 0 and the equilibrium equations (linear),

a strictly convex function (Hertz f^(5/3) is strictly convex, L is positive semi-definite)
on a compact polytope: the loads exist and are unique, and any point that satisfies the
complementarity conditions is *the* answer.

Solver (:func:`solve_loads_batch`, one code for the scalar, batched and z-roller forms)
---------------------------------------------------------------------------------------
Face Newton: Newton on the equations of the teeth taken as in contact plus equilibrium,
the other teeth held at f_j = 0; the unknowns are the tooth deflections delta_j = D(f_j)
(loads by the exact inverse law), in which the equations stay smooth where Hertz has its
infinite slope (a tooth at or near zero load), unlike Newton in the loads.
1. Active set (``_Phase.ACTIVE_SET``): face Newton from equal loads (or ``start``)
   with all teeth in contact; a tooth leaves the moment its load would turn negative;
   after convergence teeth whose gap closed are brought back. It may cycle, so it is capped
   (``_HEURISTIC_ITER`` = 60 steps, ``_HEURISTIC_ROUNDS`` = 4 rounds of bringing back;
   across the documented range it needs at most 30 steps and 2 rounds).
2. Barrier (``_Phase.BARRIER``), only if the active set did not end in a checked solution:
   a primal log-barrier method.
   For mu_k = 0.1 sigma^k f_m D_m (sigma = 0.03; f_m the mean tooth load, D_m its
   deflection) minimise Pi(f) - mu sum log f_j under the equilibrium equations by damped
   Newton (fraction-to-boundary 0.995, Armijo backtracking on the barrier energy, evaluated
   without cancellation) until the squared Newton decrement is <= 4 mu (at most
   ``_STAGE_ITER`` = 60 steps). Each barrier problem is strictly convex and smooth on a
   compact sublevel set inside f > 0, so damped Newton converges to its unique minimiser
   globally, quadratically at the end, and these minimisers tend to the solution as
   mu -> 0. From mu <= 1e-3 f_m D_m on, every stage ends with a crossover: teeth with
   f_j >= sqrt(mu f_m / D_m) (i.e. f_j / f_m >= w_j / D_m, since f_j w_j = mu) are taken as
   in contact, face Newton (``_Phase.CROSSOVER``, at most ``_FACE_ITER`` = 30 steps and 4 rounds) polishes the
   loads, and the result is checked. Near the solution the face equations have a
   nonsingular Jacobian, so once mu is small enough to classify the teeth the crossover
   converges quadratically; degenerate teeth (zero load and zero gap) pass either way.
3. Check (the only way out with numbers, ``_Phase.SOLVED``): every tooth in contact has f_j > 0 and its
   equation solved (face Newton stops when the load step is <= ``tol`` (1e-13) x the load
   per roller and the approach step <= tol x max(1 mm, |a|); quadratic convergence leaves
   residuals at rounding level, |w_j| of about 1e-14 D_ref measured), every open tooth has
   w_j >= -1e-12 D_ref (D_ref the larger of the approach and D_m), equilibrium holds.
   Such a point is the unique solution of the convex problem.
Termination: every loop is capped and the barrier has a fixed number of stages (mu below
1e-15 f_m D_m ends it), so the solver stops after at most ``iteration_bound()`` = 1050
Newton steps per sample, with a checked solution or :class:`ConvergenceError` (no unchecked
number is ever returned). Measured across the documented range (2..500 teeth, both
installations, loads 1 % to 300 %, constant and equal-load graded pitch): the active set alone at
most 27 steps; the barrier path alone (``strategy="barrier"``) at most 77 steps.

Linear systems (``linear_solver``)
----------------------------------
The Newton steps are written with q = D'(f) df (deflection increments), which stays finite
where D' is infinite (Hertz at zero load, a tooth held open). z_m is the number of modelled
rollers: 1 for one roller standing for all z, z for all rollers side by side.

* "banded" (the default without a dense compliance): the unknowns are body deflections at
  every tooth, V of the nut, W of the screw (less the common approach increment) and X_r of
  each roller (less its nut-side approach increment); q follows tooth by tooth. Every body
  is a chain (its second differences are the loads its teeth carry), the teeth tie the
  chains together only at their own tooth, and the roller and total equilibria are the
  first rows of the free chains. The system is symmetric positive definite and, ordered
  tooth by tooth, banded with semi-bandwidth z_m + 2: the nut and the screw shared by all
  rollers are just two more unknowns per tooth. The whole chunk is one banded Cholesky
  (LAPACK pbsv) of the block-diagonal system, O(n (z_m + 2)^3) flops and O(n z_m^2) memory
  per sample and step (z_m = 10, n = 20: about 35 us for the Cholesky). See
  :meth:`_Linear._banded`.
* "segments" (an independent formulation of the same system): tooth-deflection
  increments and segment forces, banded LU (gbsv). Every tooth row of a roller holds the
  segment forces of all z_m rollers, so the bandwidth is about 4 z_m and a step costs
  about 256 n z_m^3 flops, about 150 times more than "banded" for z_m = 10 (and 30 times
  the memory).
* "dense" (the only one with a dense ``compliance``): batched dense LU
  (``np.linalg.solve``) of the 2 z_m n + z_m + 1 unknowns.

Batches are cut into chunks within a memory budget (``memory_mb``, :func:`chunk_size`).
"""
from __future__ import annotations

import enum
import functools
import math
from dataclasses import dataclass, field, fields, replace
from typing import Any, Sequence

import numpy as np
from numpy.typing import NDArray
from scipy import linalg

from prs_geom.analysis.load_details import LoadModelDetails
from prs_geom.model.errors import ConvergenceError, DesignError
from prs_geom.runtime.progress import ProgressFn

__all__ = ["LoadModel", "block_compliance", "MEMORY_MB", "iteration_bound", "chunk_size", "LoadResult",
           "LoadBatch", "RollerLoadResult", "solve_loads_batch", "solve_loads", "solve_loads_rollers"]


# --------------------------------------------------------------------------- model
def _min_kernel(n: int) -> NDArray:
    """M[j, i] = min(i, j) (0-based): the number of body segments shared by the load paths of
    teeth i and j, each counted from tooth 1."""
    k = np.arange(n, dtype=np.float64)
    return np.minimum.outer(k, k)


@dataclass(frozen=True)
class LoadModel:
    """Everything the tooth-load equations need, in N and mm.

    ``compliance`` (optional): dense linear compliance of the 2n contact pairs, mm/N, rows and
    columns ordered [nut-roller teeth 1..n, roller-screw teeth 1..n] of one roller
    (deflection of pair i per unit load at pair j, teeth of both mating parts). It must be
    symmetric, and positive semi-definite together with the bodies
    (``compliance + support_body_operator()``: the elastic influence matrix of the mating
    parts is); a correction to the bodies may make ``compliance`` alone indefinite
    (:mod:`prs_geom.analysis.fe.compliance`). It replaces the diagonal ``tooth_nr`` /
    ``tooth_rs`` terms; the Hertz terms stay. See :func:`block_compliance` to build it from
    two per-side (n, n) matrices.
    """

    n: int
    z: int
    pitch: float
    sign_screw: int                 # +1 tension-compression, -1 compression-compression
    hertz_nr: float                 # axial approach = hertz * F^(2/3)
    hertz_rs: float
    tooth_nr: float                 # axial tooth deflection per N (roller + nut teeth)
    tooth_rs: float
    body_screw: float               # p / (E A) (mm / N)
    body_roller: float
    body_nut: float
    #: what the compliances were computed from (None for a model made by hand)
    details: LoadModelDetails | None = field(default=None, compare=False)
    compliance: NDArray | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        if self.compliance is None:
            return
        n2 = 2 * self.n
        C = np.array(self.compliance, dtype=np.float64)
        if C.shape != (n2, n2):
            raise DesignError("compliance", f"array of shape {C.shape}", f"must be a ({n2}, {n2}) array")
        if not np.all(np.isfinite(C)):
            raise DesignError("compliance", "array", "must be finite")
        scale = float(np.abs(C).max()) or 1.0
        if np.abs(C - C.T).max() > 1e-10 * scale:
            raise DesignError("compliance", "array", "must be symmetric (Maxwell-Betti reciprocity)")
        C = 0.5 * (C + C.T)
        total = C + self.support_body_operator()
        if float(np.linalg.eigvalsh(total).min()) < -1e-10 * float(np.abs(total).max()):
            raise DesignError("compliance", "array", "must be positive semi-definite with the bodies")
        C.setflags(write=False)
        object.__setattr__(self, "compliance", C)

    # D(F) = contact + tooth, axial, and its derivative
    def deflection(self, side: str, f: NDArray) -> NDArray:
        h, t = (self.hertz_nr, self.tooth_nr) if side == "nr" else (self.hertz_rs, self.tooth_rs)
        f = np.asarray(f, dtype=np.float64)
        return h * np.sign(f) * np.abs(f) ** (2.0 / 3.0) + t * f

    def body_matrices(self) -> tuple[NDArray, NDArray]:
        """Linear maps (n, 2n) from loads [f_nr, f_rs] to the cumulative body terms

        S_nr,j = sum_{k<j} (d_n,k + d_r,k),  S_rs,j = sum_{k<j} (s d_s,k - d_r,k)."""
        n, z = self.n, self.z
        beyond = np.triu(np.ones((n, n)), 1)        # beyond[k, i] = 1 for i > k (segment k..k+1)
        upto = np.tril(np.ones((n, n)))             # upto[k, i] = 1 for i <= k
        seg_n = np.hstack([z * beyond, np.zeros((n, n))]) * self.body_nut
        seg_r = np.hstack([beyond, -beyond]) * self.body_roller
        screw_sum = beyond if self.sign_screw > 0 else upto
        seg_s = np.hstack([np.zeros((n, n)), z * screw_sum]) * self.body_screw
        cum = np.tril(np.ones((n, n)), -1)          # cum[j, k] = 1 for k < j
        return cum @ (seg_n + seg_r), cum @ (self.sign_screw * seg_s - seg_r)

    def body_operator(self, rollers: int | None = None) -> NDArray:
        """The symmetric body matrix K of the energy (module docstring), mm/N.

        ``rollers=None``: one roller standing for all z, (2n, 2n), order [f_nr, f_rs]; equal
        to ``vstack(body_matrices())`` in tension-compression. ``rollers=z``: all rollers
        side by side, (2 z n, 2 z n), order [roller 1: f_nr, f_rs; roller 2: ...]. In
        compression-compression the screw term is written with the equilibrium (module
        docstring) and the shift goes into the gaps (:func:`_effective_gaps`)."""
        R, m = (1, self.z) if rollers is None else (int(rollers), 1)
        M = _min_kernel(self.n)
        K = np.zeros((R, 2, self.n, R, 2, self.n))
        K[:, 0, :, :, 0, :] += m * self.body_nut * M[:, None, :]
        K[:, 1, :, :, 1, :] += m * self.body_screw * M[:, None, :]
        for r in range(R):
            K[r, 0, :, r, 0, :] += self.body_roller * M
            K[r, 1, :, r, 1, :] += self.body_roller * M
            K[r, 0, :, r, 1, :] -= self.body_roller * M
            K[r, 1, :, r, 0, :] -= self.body_roller * M
        return K.reshape(2 * R * self.n, 2 * R * self.n)

    def support_body_operator(self) -> NDArray:
        """The body operator (one roller for all z, (2n, 2n), mm/N) written from each part's
        support: :meth:`body_operator`, except the compression-compression screw, whose
        kernel n - 1 - max(i, j) counts from the far end. It equals the solver's symmetric
        kernel with the known shift in the gaps up to a term that is the same on every tooth
        of a side (absorbed by that side's approach), and it is what a finite-element body
        matrix, measured from the support, compares with."""
        K = self.body_operator()
        if self.sign_screw < 0:
            n = self.n
            i = np.arange(n, dtype=np.float64)
            K[n:, n:] += self.z * self.body_screw * ((n - 1) - np.maximum.outer(i, i) - np.minimum.outer(i, i))
        return K

    def linear_compliance(self) -> NDArray:
        """The (2n, 2n) linear compliance of the contact pairs: ``compliance`` or the diagonal
        of ``tooth_nr`` / ``tooth_rs``."""
        if self.compliance is not None:
            return np.array(self.compliance)
        return np.diag(np.concatenate([np.full(self.n, self.tooth_nr), np.full(self.n, self.tooth_rs)]))

    def with_compliance(self, compliance: NDArray | None) -> "LoadModel":
        """The same model with a dense linear compliance (None: back to the diagonal)."""
        return replace(self, compliance=compliance)


def block_compliance(nr: NDArray, rs: NDArray, coupling: NDArray | None = None) -> NDArray:
    """A (2n, 2n) compliance from per-side (n, n) matrices; ``coupling`` (n, n) is the
    nut-roller deflection per unit roller-screw load (its transpose fills the other block)."""
    nr, rs = np.asarray(nr, dtype=np.float64), np.asarray(rs, dtype=np.float64)
    c = np.zeros_like(nr) if coupling is None else np.asarray(coupling, dtype=np.float64)
    return np.block([[nr, c], [c.T, rs]])


# --------------------------------------------------------------------------- solver
#: Newton steps and re-activation rounds of the active-set phase (face Newton from equal loads)
#: before the barrier takes over (across the documented range it needs at most 30 steps
#: and 2 rounds; a cycling active set comes back round after round).
_HEURISTIC_ITER = 60
_HEURISTIC_ROUNDS = 4
#: Newton steps allowed per barrier stage and per crossover Newton (module docstring).
_STAGE_ITER = 60
_FACE_ITER = 30
#: Barrier parameter, in units of f_m D_m: start, first crossover, end; reduction per stage.
_MU0, _MU_CROSS, _MU_MIN, _SIGMA = 1e-1, 1e-3, 1e-15, 0.03
#: A barrier stage ends when the squared Newton decrement is below _THETA mu.
_THETA = 4.0
#: An open tooth may have w_j >= -_OPEN_TOL D_ref (rounding).
_OPEN_TOL = 1e-12
#: Default memory budget of one batch chunk (MB).
MEMORY_MB = 256.0
_N_STAGES = math.ceil(math.log(_MU0 / _MU_MIN) / math.log(1.0 / _SIGMA)) + 1


def iteration_bound() -> int:
    """Newton steps after which the solver gives up (ConvergenceError): the active set, then every
    barrier stage with one crossover (module docstring)."""
    return _HEURISTIC_ITER + _N_STAGES * (_STAGE_ITER + _FACE_ITER)


@dataclass(frozen=True)
class _Problem:
    """B independent problems of R rollers side by side (the nut and screw bodies carry
    ``m`` times the loads of the modelled rollers: m = z for one roller standing for all,
    m = 1 for all z rollers). Loads and gaps have shape (B, R, 2, n), side 0 = nut-roller."""

    n: int
    R: int
    m: float
    bn: float
    br: float
    bs: float
    h: NDArray                    # (B, 1, 2, 1) Hertz coefficient (0 in the linear model)
    e0: NDArray                   # (B, 1, 2, 1) affine tooth law e0 + e1 f (linear model)
    e1: NDArray
    cdiag: NDArray | None         # (1, 1, 2, 1) diagonal linear compliance, or
    cdense: NDArray | None        # (2n, 2n) dense linear compliance of one roller
    g: NDArray                    # (B, R, 2, n) cumulative gaps (installation shift included)
    F: NDArray                    # (B,) total axial load
    hertz: bool = False           # h > 0 everywhere and e0 = e1 = 0 (the law is pure Hertz)

    @property
    def B(self) -> int:
        return self.g.shape[0]

    def take(self, idx: NDArray) -> "_Problem":
        """The problems ``idx`` (sorted, distinct): all of them is this problem itself."""
        if idx.size == self.B:
            return self
        return replace(self, h=self.h[idx], e0=self.e0[idx], e1=self.e1[idx], g=self.g[idx], F=self.F[idx])


def _make_problem(model: LoadModel, loads: Any, g_nr: Any, g_rs: Any, linear_at: Any,
                  rollers: bool) -> _Problem:
    n = model.n
    gn = np.array(g_nr, dtype=np.float64)
    gs = np.array(g_rs, dtype=np.float64)
    want = 3 if rollers else 2
    if gn.ndim != want or gn.shape != gs.shape or gn.shape[-1] != n:
        shape = "(B, z, n)" if rollers else "(B, n)"
        raise ValueError(f"gaps must both have shape {shape} with n = {n}; got {gn.shape} and {gs.shape}")
    if not rollers:
        gn, gs = gn[:, None, :], gs[:, None, :]
    B, R = gn.shape[0], gn.shape[1]
    if rollers and R != model.z:
        raise ValueError(f"gaps are given for {R} rollers, the model has z = {model.z}")
    F = np.array(np.broadcast_to(np.asarray(loads, dtype=np.float64), (B,)))
    if not (np.all(np.isfinite(F)) and np.all(F > 0)):
        raise ValueError("loads must be finite and > 0")
    if not (np.all(np.isfinite(gn)) and np.all(np.isfinite(gs))):
        raise ValueError("gaps must be finite")
    g = np.stack([gn, gs], axis=2)
    if model.sign_screw < 0:
        # compression-compression: z sum_{k<=j} f_rs = F0 - z sum_{k>j} f_rs (module docstring)
        g[:, :, 1, :] -= model.body_screw * F[:, None, None] * np.arange(n)
    hz = np.array([model.hertz_nr, model.hertz_rs]).reshape(1, 1, 2, 1)
    if linear_at is None:
        h = np.broadcast_to(hz, (B, 1, 2, 1)).copy()
        e0 = np.zeros((B, 1, 2, 1))
        e1 = np.zeros((B, 1, 2, 1))
    else:
        f0 = np.broadcast_to(np.asarray(linear_at, dtype=np.float64), (B,)).reshape(B, 1, 1, 1)
        if not (np.all(np.isfinite(f0)) and np.all(f0 > 0)):
            raise ValueError("linear_at must be finite and > 0")
        # the tangent of h f^(2/3) at f0: e0 + e1 f
        e1 = (2.0 / 3.0) * hz * f0 ** (-1.0 / 3.0)
        e0 = hz * f0 ** (2.0 / 3.0) - e1 * f0
        h = np.zeros((B, 1, 2, 1))
    if model.compliance is None:
        cdiag, cdense = np.array([model.tooth_nr, model.tooth_rs]).reshape(1, 1, 2, 1), None
    else:
        cdiag, cdense = None, np.asarray(model.compliance)
    return _Problem(n=n, R=R, m=float(1 if rollers else model.z), bn=model.body_nut, br=model.body_roller,
                    bs=model.body_screw, h=h, e0=e0, e1=e1, cdiag=cdiag, cdense=cdense, g=g, F=F,
                    hertz=linear_at is None and bool(np.all(hz > 0)))


def _body(p: _Problem, f: NDArray) -> NDArray:
    """Cumulative body deformations K f, shape of f, O(n) by cumulative sums."""
    out = np.zeros_like(f)
    if p.n == 1:
        return out
    P = np.cumsum(f[..., :0:-1], axis=-1)[..., ::-1]          # P_k = sum_{i>k} f_i, k < n - 1
    roll = p.br * (P[:, :, 0] - P[:, :, 1])
    nut = (p.m * p.bn) * P[:, :, 0].sum(axis=1, keepdims=True)
    scr = (p.m * p.bs) * P[:, :, 1].sum(axis=1, keepdims=True)
    out[:, :, 0, 1:] = np.cumsum(nut + roll, axis=-1)
    out[:, :, 1, 1:] = np.cumsum(scr - roll, axis=-1)
    return out


def _clin(p: _Problem, f: NDArray) -> NDArray:
    """Linear tooth compliance C f."""
    if p.cdense is None:
        return p.cdiag * f
    b, R, _, n = f.shape
    return (f.reshape(b, R, 2 * n) @ p.cdense).reshape(f.shape)      # C symmetric


def _law(p: _Problem, f: NDArray) -> NDArray:
    """Nonlinear contact law: Hertz (odd extension below 0) or its tangent, mm."""
    cf = np.cbrt(f)                          # sign(f) |f|^(2/3) = cbrt(f) |cbrt(f)|
    if p.hertz:
        return p.h * (cf * np.abs(cf))
    return p.h * (cf * np.abs(cf)) + p.e0 + p.e1 * f


def _law_and_slope(p: _Problem, f: NDArray) -> tuple[NDArray, NDArray]:
    """The contact law (:func:`_law`) and its slope (mm/N; infinite for Hertz at f = 0) from
    one cube root."""
    cf = np.cbrt(f)
    a = np.abs(cf)
    with np.errstate(divide="ignore", invalid="ignore"):
        if p.hertz:
            return p.h * (cf * a), (2.0 / 3.0) * p.h / a
        slope = np.where(p.h > 0, (2.0 / 3.0) * p.h / a, 0.0) + p.e1
    return p.h * (cf * a) + p.e0 + p.e1 * f, slope


def _law_slope(p: _Problem, f: NDArray) -> NDArray:
    return _law_and_slope(p, f)[1]


def _cdiag_part(p: _Problem) -> NDArray | float:
    return p.cdiag if p.cdiag is not None else 0.0


def _tooth(p: _Problem, f: NDArray) -> NDArray:
    """Deflection of the diagonal tooth law (contact law + diagonal linear compliance)."""
    return _law(p, f) + _cdiag_part(p) * f


def _tooth_inv(p: _Problem, dl: NDArray) -> NDArray:
    """f with _tooth(p, f) = dl, N (odd extension).

    With x = dl - e0, t = |f|^(1/3), h the Hertz coefficient and c the linear slope,
    c t^3 + h t^2 = |x|; in s = c t / h this is s^2 (1 + s) = kappa = |x| c^2 / h^3 (one
    coefficient per entry), solved by Newton (quadratic; s^3 + s^2 is convex, so after the
    first step the iterates fall monotonically). The root lies in [s0 / sqrt 2, s0], s0 =
    min(sqrt kappa, cbrt kappa); three fixed-point steps s <- sqrt(kappa / (1 + s)) from s0
    bring s within 0.6 % of it (5e-6 for s <= 0.1, Hertz dominant, the usual case). Every
    entry then takes two Newton steps (to about 1e-20 in the usual case) and further steps
    until its own step is at rounding level (usually one, to see that): what an entry does
    depends on its own values only, so the result does not depend on the rest of the
    batch. With h = 0 or c = 0 the root is explicit."""
    c = p.e1 + _cdiag_part(p)
    h = p.h
    x = dl if p.hertz else dl - p.e0
    a = np.abs(x)
    both = (h > 0) & (c > 0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        ratio = np.where(both, h / c, 0.0)                          # t = s h / c
        kap = (a * np.where(both, c * c / (h * h * h), 0.0)).ravel()
        s0 = np.sqrt(kap)                                          # min(sqrt, cbrt): sqrt for kappa <= 1
        big = np.flatnonzero(kap > 1.0)
        if big.size:
            s0[big] = np.cbrt(kap[big])
        s = np.sqrt(kap / (1.0 + np.sqrt(kap / (1.0 + np.sqrt(kap / (1.0 + s0))))))
        idx = np.flatnonzero(kap > 0)
        sc, kc = s[idx], kap[idx]
        for _ in range(2):
            sc = sc - (sc * sc * (1.0 + sc) - kc) / (sc * (3.0 * sc + 2.0))
        going = np.ones(idx.size, bool)
        for _ in range(60):
            step = np.where(going, (sc * sc * (1.0 + sc) - kc) / (sc * (3.0 * sc + 2.0)), 0.0)
            sc = sc - step
            going &= np.abs(step) > 4e-16 * sc
            left = np.count_nonzero(going)
            if left == 0:
                break
            if left < 0.5 * going.size:               # iterate only the entries still moving
                s[idx] = sc
                idx, sc, kc, going = idx[going], sc[going], kc[going], going[going]
        s[idx] = sc
        t = s.reshape(a.shape) * ratio
        if not np.all(both):
            t = np.where(both, t, np.where(h > 0, np.sqrt(a / np.where(h > 0, h, 1.0)),
                                           np.cbrt(a / np.where(c > 0, c, 1.0))))
    return np.copysign(t * t * t, x)


def _dense_operator(p: _Problem) -> NDArray:
    """L = K (+ block-diagonal dense compliance), (2Rn, 2Rn)."""
    n, R = p.n, p.R
    M = _min_kernel(n)
    K = np.zeros((R, 2, n, R, 2, n))
    K[:, 0, :, :, 0, :] += p.m * p.bn * M[:, None, :]
    K[:, 1, :, :, 1, :] += p.m * p.bs * M[:, None, :]
    for r in range(R):
        K[r, 0, :, r, 0, :] += p.br * M
        K[r, 1, :, r, 1, :] += p.br * M
        K[r, 0, :, r, 1, :] -= p.br * M
        K[r, 1, :, r, 0, :] -= p.br * M
    K = K.reshape(2 * R * n, 2 * R * n)
    if p.cdense is not None:
        for r in range(R):
            s = slice(2 * n * r, 2 * n * (r + 1))
            K[s, s] += p.cdense
    return K


@dataclass(frozen=True)
class _SegmentLayout:
    """Sparsity layout of the "segments" Newton system of one sample (:func:`_band_layout`):
    ``size`` unknowns, lower and upper bandwidths ``kl``, ``ku``; entries as (rows, cols,
    values) for the constant part ``const`` and the body part ``body`` (values to multiply
    by kref); (rows, cols, flat tooth index) of the tooth stiffness entries ``tooth``; rows
    and columns of the roller equilibria ``roll`` (R, 4); columns of the scaled deflections
    ``colq`` (R, 2, n) and rows of the tooth differences ``rowdiff`` (R, 2, n - 1)."""

    size: int
    kl: int
    ku: int
    const: tuple[NDArray, NDArray, NDArray]
    body: tuple[NDArray, NDArray, NDArray]
    tooth: tuple[NDArray, NDArray, NDArray]
    roll: NDArray
    colq: NDArray
    rowdiff: NDArray


# A banded form of the Newton system in segment forces, an independent formulation
# (linear_solver="segments"). Unknowns per sample: [dlam, block 0, ..., block n-1], block j =
# [q_j (2R, scaled by kref), P_{j-1} (2R)] with P_k the segment-force increments
# sum_{i>k} df_i of each roller and side; rows: total equilibrium, roller equilibria,
# tooth-1 equations, then per tooth j the definitions P_{j-1} - P_j - (k_j/kref) q_j = 0 and
# the differences q_{j+1} - q_j + kref body_j(P_j) = ...  Every tooth row of a roller holds
# the segment forces of all R rollers (shared nut and screw), so the bandwidth is about 4R.
@functools.lru_cache(maxsize=32)
def _band_layout(n: int, R: int, m: float, bn: float, br: float, bs: float) -> _SegmentLayout:
    def cq(j, r, s):
        return 1 + 4 * R * j + 2 * r + s

    def cP(j, r, s):                     # P_j, j = -1 .. n-2
        return 1 + 4 * R * (j + 1) + 2 * R + 2 * r + s

    def rdef(j, r, s):
        return 1 + 2 * R + 4 * R * j + 2 * r + s

    def rdiff(j, r, s):
        return 1 + 4 * R + 4 * R * j + 2 * r + s

    const, body, kent = [], [], []
    for r in range(R):
        const.append((0, cP(-1, r, 1), m))
        const += [(1 + R + r, cq(0, r, 0), 1.0), (1 + R + r, cq(0, r, 1), 1.0), (1 + R + r, 0, -m)]
    bside = (bn, bs)
    for j in range(n):
        for r in range(R):
            for s in range(2):
                const.append((rdef(j, r, s), cP(j - 1, r, s), 1.0))
                if j <= n - 2:
                    const.append((rdef(j, r, s), cP(j, r, s), -1.0))
                kent.append((rdef(j, r, s), cq(j, r, s), (r * 2 + s) * n + j))
                if j <= n - 2:
                    const += [(rdiff(j, r, s), cq(j + 1, r, s), 1.0), (rdiff(j, r, s), cq(j, r, s), -1.0)]
                    for r2 in range(R):
                        body.append((rdiff(j, r, s), cP(j, r2, s), m * bside[s] + (br if r2 == r else 0.0)))
                    body.append((rdiff(j, r, s), cP(j, r, 1 - s), -br))
    roll = [(1 + r, cP(-1, r, 0), cP(-1, r, 1), cq(0, r, 0)) for r in range(R)]
    c_rows, c_cols, c_vals = (np.array(v) for v in zip(*const))
    b_rows, b_cols, b_vals = (np.array(v) for v in zip(*body)) if body else (np.zeros(0, int),) * 2 + (np.zeros(0),)
    k_rows, k_cols, k_idx = (np.array(v) for v in zip(*kent))
    roll = np.array(roll)
    rows = np.concatenate([c_rows, b_rows, k_rows, roll[:, 0], roll[:, 0], roll[:, 0]])
    cols = np.concatenate([c_cols, b_cols, k_cols, roll[:, 1], roll[:, 2], roll[:, 3]])
    kl, ku = int((rows - cols).max()), int((cols - rows).max())
    jj, rr, ss = np.meshgrid(np.arange(n), np.arange(R), np.arange(2), indexing="ij")
    colq = cq(jj, rr, ss).transpose(1, 2, 0)                       # (R, 2, n)
    jd, rd, sd = np.meshgrid(np.arange(n - 1), np.arange(R), np.arange(2), indexing="ij")
    rowdiff = rdiff(jd, rd, sd).transpose(1, 2, 0)                  # (R, 2, n-1)
    return _SegmentLayout(size=1 + 4 * R * n, kl=kl, ku=ku, const=(c_rows, c_cols, c_vals.astype(np.float64)),
                          body=(b_rows, b_cols, b_vals.astype(np.float64)), tooth=(k_rows, k_cols, k_idx),
                          roll=roll, colq=colq, rowdiff=rowdiff)


class _Linear:
    """Solver of the Newton systems of one chunk of samples:

        q + L' (k q) - dy = r,  sum_j (k q)_nr - sum_j (k q)_rs = rc_roll (per roller),
        m sum (k q)_rs = rc_tot,  dy_nr = du, dy_rs = delta - du,

    with d = k q the load increments (N), q the tooth-deflection increments (mm), L' = K
    ("banded", "segments") or K + C ("dense"). A roller whose teeth are all held open
    ("floating") gets du = 0 instead of its equilibrium row. ``kind``: "banded" (body
    deflections, banded Cholesky), "segments" (segment forces, banded LU) or "dense"."""

    def __init__(self, p: _Problem, kref: NDArray, kind: str) -> None:
        self.p, self.kref, self.kind = p, kref, kind
        if kind == "banded":
            self.tpl = self._chain_template()
        elif kind == "dense":
            self.L = _dense_operator(p)
        elif kind == "segments":
            lay = _band_layout(p.n, p.R, p.m, p.bn, p.br, p.bs)
            self.lay = lay
            N, kl, ku = lay.size, lay.kl, lay.ku
            tpl = np.zeros((kl + ku + 1, p.B, N))
            rows, cols, vals = lay.const
            tpl[ku + rows - cols, :, cols] = vals[:, None]
            rows, cols, vals = lay.body
            tpl[ku + rows - cols, :, cols] = vals[:, None] * kref[None, :]
            self.tpl = tpl

    def solve(self, live: NDArray, k: NDArray, r: NDArray, rc_roll: NDArray, rc_tot: NDArray,
              floating: NDArray) -> tuple[NDArray, NDArray]:
        """Increments (q, dy) of the samples ``live`` (indices into the chunk): ``k`` (b, R, 2,
        n) tangent stiffnesses (0 for a tooth held open), ``r`` residuals (0 there), mm;
        ``rc_roll`` (b, R) and ``rc_tot`` (b,) equilibrium residuals, N; ``floating`` (b, R)."""
        try:
            if self.kind == "banded":
                return self._banded(k, r, rc_roll, rc_tot, floating)
            if self.kind == "dense":
                return self._dense(live, k, r, rc_roll, rc_tot, floating)
            return self._segments(live, k, r, rc_roll, rc_tot, floating)
        except np.linalg.LinAlgError as e:
            raise ConvergenceError(f"tooth-load Newton system is singular ({e})") from None

    def _dy(self, q0: NDArray, r: NDArray, dlam: NDArray) -> NDArray:
        du = q0[:, :, 0] - r[:, :, 0, 0]
        return np.stack([du, self.p.m * dlam[:, None] - du], axis=2)

    def _segments(self, live, k, r, rc_roll, rc_tot, floating):
        p, lay = self.p, self.lay
        N, kl, ku = lay.size, lay.kl, lay.ku
        b, R, n = k.shape[0], p.R, p.n
        kref = self.kref[live]
        ab = self.tpl[:, live, :]
        rows, cols, kidx = lay.tooth
        ab[ku + rows - cols, :, cols] = (-k.reshape(b, -1)[:, kidx] / kref[:, None]).T
        roll = lay.roll
        fl = floating.astype(np.float64)                            # (b, R)
        ab[ku + roll[:, 0] - roll[:, 1], :, roll[:, 1]] = (1.0 - fl).T
        ab[ku + roll[:, 0] - roll[:, 2], :, roll[:, 2]] = -(1.0 - fl).T
        ab[ku + roll[:, 0] - roll[:, 3], :, roll[:, 3]] = fl.T
        rhs = np.zeros((b, N))
        rhs[:, 0] = rc_tot
        rhs[:, 1:1 + R] = np.where(floating, kref[:, None] * r[:, :, 0, 0], rc_roll)
        rhs[:, 1 + R:1 + 2 * R] = kref[:, None] * (r[:, :, 0, 0] + r[:, :, 1, 0])
        if n > 1:
            rhs[:, lay.rowdiff] = kref[:, None, None, None] * np.diff(r, axis=-1)
        x = linalg.solve_banded((kl, ku), ab.reshape(kl + ku + 1, b * N), rhs.reshape(-1),
                                overwrite_ab=True, overwrite_b=True, check_finite=False).reshape(b, N)
        qs = x[:, lay.colq]                                      # kref q, (b, R, 2, n)
        kr = kref[:, None, None, None]
        return qs / kr, self._dy(qs[..., 0] / kref[:, None, None], r, x[:, 0] / kref)

    def _chain_template(self) -> NDArray:
        """The load-independent part of the "banded" matrix of one sample: the three kinds of
        chains, (n, R + 2, R + 3) in the band layout of :meth:`_banded`."""
        p = self.p
        n, w = p.n, p.R + 2
        kd = w
        cn, cs, cr = 1.0 / (p.m * p.bn), 1.0 / (p.m * p.bs), 1.0 / p.br
        tpl = np.zeros((n, w, kd + 1))
        lap0 = np.full(n, 2.0)                                     # diagonal of L0 (of Lf: ends 1)
        lap0[-1] = 1.0
        lapf = lap0.copy()
        lapf[0] = 1.0 if n > 1 else 0.0
        tpl[:, 0, 0] = cn * lap0
        tpl[0, 0, 0] = cn                                          # V_0 = 0, a decoupled unknown
        tpl[:, 1, 0] = cs * lapf
        tpl[:, 2:, 0] = cr * lapf[:, None]
        tpl[:-1, :, kd] = -np.array([cn, cs] + [cr] * p.R)         # chain links, tooth j -- j+1
        tpl[0, 0, kd] = 0.0
        return tpl

    def _banded(self, k, r, rc_roll, rc_tot, floating):
        """The Newton system in body-deflection unknowns (module docstring, "Linear systems").

        Per tooth j = 1..n (0-based below) and sample: V_j, the cumulative deflection of the
        nut body; W_j = V'_j - delta, V' that of the screw body and delta = dy_nr + dy_rs the
        common approach increment; X_r,j = R_r,j - du_r, R_r that of roller r and du_r = dy_nr
        of roller r. Then q_r,nr = r_r,nr - V - X_r and q_r,rs = r_r,rs - W + X_r at every
        tooth (V_0 = 0, W_0 = -delta, X_r,0 = -du_r), and with d = k q the body relations
        K d = (nut, screw, roller deflections), the roller equilibria and the total one are

            L0 V / (m b_n) = sum_r d_r,nr,            tooth 2..n,
            Lf W / (m b_s) = sum_r d_r,rs - e_0 rc_tot / m,
            Lf X_r / b_r  = d_r,nr - d_r,rs - e_0 rc_roll_r,

        L0 the second differences of a chain fixed at tooth 1, Lf of a free one (row 0: the
        first segment force, which closes the equilibrium). Moving the d terms to the left
        adds k_nr (1, 0, 1)(1, 0, 1)^T + k_rs (0, 1, -1)(0, 1, -1)^T per roller and tooth on
        (V_j, W_j, X_r,j): the matrix is symmetric positive definite (a roller with a free
        tooth pins the constant modes; a floating roller gets X_r,0 = 0, i.e. du_r = 0) and,
        with the unknowns ordered tooth by tooth, banded with semi-bandwidth R + 2. All
        samples are one stacked banded Cholesky (LAPACK pbsv)."""
        p = self.p
        b, R, n = k.shape[0], p.R, p.n
        w = kd = R + 2                             # unknowns per tooth (V, W, X_1..X_R); links
        cr = 1.0 / p.br
        k0, k1 = k[:, :, 0], k[:, :, 1]                            # (b, R, n), N/mm
        r0, r1 = r[:, :, 0], r[:, :, 1]
        # lower band storage, ab[i - j, j] = A[i, j] for i >= j (LAPACK's lower variant is the
        # faster one), laid out (b, n, w, kd + 1): the (kd + 1, N) array LAPACK takes is then
        # a Fortran-ordered view, not a copy
        ab = np.empty((b, n, w, kd + 1))
        ab[...] = self.tpl
        diag = ab[..., 0]
        diag[:, 1:, 0] += k0[:, :, 1:].sum(axis=1)
        diag[:, :, 1] += k1.sum(axis=1)
        diag[:, :, 2:] += (k0 + k1).transpose(0, 2, 1)
        ab[:, 1:, 0, 2:w] = k0[:, :, 1:].transpose(0, 2, 1)        # V_j -- X_r,j (V_0: none)
        ab[:, :, 1, 1:w - 1] = -k1.transpose(0, 2, 1)              # W_j -- X_r,j
        rhs = np.empty((b, n, w))
        rhs[:, :, 0] = (k0 * r0).sum(axis=1)
        rhs[:, 0, 0] = 0.0
        rhs[:, :, 1] = (k1 * r1).sum(axis=1)
        rhs[:, 0, 1] -= rc_tot / p.m
        rhs[:, :, 2:] = (k0 * r0 - k1 * r1).transpose(0, 2, 1)
        rhs[:, 0, 2:] -= rc_roll
        fb, fr = np.nonzero(floating)
        if fb.size:                         # X_r,0 = 0 (du_r = 0); its k are 0, only the link goes
            ab[fb, 0, 2 + fr, 0] = cr
            ab[fb, 0, 2 + fr, kd] = 0.0
            rhs[fb, 0, 2 + fr] = 0.0
        N = b * n * w
        x = linalg.solveh_banded(ab.reshape(N, kd + 1).T, rhs.reshape(N), overwrite_ab=True, overwrite_b=True,
                                 lower=True, check_finite=False).reshape(b, n, w)
        V, W, X = x[:, None, :, 0], x[:, None, :, 1], x[:, :, 2:].transpose(0, 2, 1)
        q = np.empty_like(k)
        q[:, :, 0] = r0 - V - X
        q[:, :, 1] = r1 - W + X
        du, delta = -X[..., 0], -W[:, :, 0]
        return q, np.stack([du, delta - du], axis=2)

    def _dense(self, live, k, r, rc_roll, rc_tot, floating):
        p = self.p
        b, R, n = k.shape[0], p.R, p.n
        N2 = 2 * R * n
        N = N2 + R + 1
        kref = self.kref[live][:, None]
        kf = k.reshape(b, N2)
        M = np.zeros((b, N, N))
        M[:, :N2, :N2] = self.L[None] * kf[:, None, :]
        M[:, np.arange(N2), np.arange(N2)] += 1.0
        idx = np.arange(N2).reshape(R, 2, n)
        rs_all = idx[:, 1].ravel()
        for r_ in range(R):
            M[:, idx[r_, 0], N2 + r_] = -1.0
            M[:, idx[r_, 1], N2 + r_] = 1.0
            M[:, N2 + r_, idx[r_, 0]] = kf[:, idx[r_, 0]] / kref
            M[:, N2 + r_, idx[r_, 1]] = -kf[:, idx[r_, 1]] / kref
        M[:, rs_all, N2 + R] = -p.m
        M[:, N2 + R, rs_all] = p.m * kf[:, rs_all] / kref
        rhs = np.concatenate([r.reshape(b, N2), rc_roll / kref, rc_tot[:, None] / kref], axis=1)
        sb, sr = np.nonzero(floating)
        if sb.size:
            M[sb, N2 + sr, :] = 0.0
            M[sb, N2 + sr, N2 + sr] = 1.0
            rhs[sb, N2 + sr] = 0.0
        x = np.linalg.solve(M, rhs[..., None])[..., 0]
        du = x[:, N2:N2 + R]
        return x[:, :N2].reshape(k.shape), np.stack([du, p.m * x[:, -1][:, None] - du], axis=2)


def _bytes_per_sample(R: int, n: int, kind: str) -> float:
    """Memory of one sample in a chunk, bytes: the Newton system and the work arrays of the
    loop (about 50 arrays of R 2 n numbers). Measured peaks (tracemalloc) are 0.6 to 0.8 of
    these estimates for every kind."""
    if kind == "dense":
        N = 2 * R * n + R + 1
        return 8.0 * N * N * 3 + 400.0 * R * n
    if kind == "banded":
        w = R + 2                              # band storage n w (w + 1) and the right-hand side
        return 8.0 * n * w * (w + 1) * 2 + 400.0 * R * n
    N = 1 + 4 * R * n                          # "segments": LU storage of (2 kl + ku + 1) rows
    return 8.0 * N * (2 * 10 * R + 6) * 3 + 400.0 * R * n


def chunk_size(R: int, n: int, kind: str, memory_mb: float) -> int:
    """Samples per chunk of ``R`` modelled rollers and ``n`` teeth whose Newton systems of
    linear solver ``kind`` ("banded", "segments", "dense") fit ``memory_mb`` (at least 1)."""
    return max(1, int(memory_mb * 1e6 // _bytes_per_sample(R, n, kind)))


@dataclass(frozen=True)
class _Solution:
    """The state of every sample of a solved batch (chunks concatenated), rollers modelled R:
    loads ``f`` (B, R, 2, n) N, approaches ``y`` (B, R, 2) mm, teeth held open ``pinned``
    (B, R, 2, n), Newton steps ``iterations`` (B,), ``barrier`` (B,) whether the barrier
    phase ran, ``ok`` (B,) whether the sample ended with a checked solution, ``rounds`` (B,)
    re-activation rounds of the last face Newton."""

    f: NDArray
    y: NDArray
    pinned: NDArray
    iterations: NDArray
    barrier: NDArray
    ok: NDArray
    rounds: NDArray

    @staticmethod
    def concatenate(parts: Sequence["_Solution"]) -> "_Solution":
        """The solutions of consecutive chunks as one (batch axis first)."""
        return _Solution(**{fld.name: np.concatenate([getattr(s, fld.name) for s in parts], axis=0)
                            for fld in fields(_Solution)})


def _choose_linear_solver(p: _Problem, linear_solver: str) -> str:
    """The linear solver kind for ``linear_solver`` ("auto" resolved; module docstring)."""
    kind = linear_solver
    # the body-deflection form divides by the body compliances
    banded_ok = p.cdense is None and min(p.bn, p.br, p.bs) > 0
    if kind == "auto":
        kind = "dense" if p.cdense is not None else "banded" if banded_ok else "segments"
    if kind not in ("banded", "segments", "dense") or (kind == "banded" and not banded_ok) or \
            (kind == "segments" and p.cdense is not None):
        raise ValueError("linear_solver must be 'auto', 'dense' or, without a dense compliance, 'segments' or "
                         "(with positive body compliances) 'banded'")
    return kind


def _solve_problem(p: _Problem, tol: float, max_iter: int | None, strategy: str, linear_solver: str,
                   memory_mb: float, progress: Any = None,
                   start: tuple[NDArray, NDArray] | None = None) -> _Solution:
    """Solve the B problems of ``p`` chunk by chunk (memory budget ``memory_mb``, MB);
    ``progress(samples done, B)`` after every chunk; ``start``: loads (B, R, 2, n) N and
    approaches (B, R, 2) mm that start the active-set phase."""
    if strategy not in ("auto", "barrier"):
        raise ValueError("strategy must be 'auto' or 'barrier'")
    kind = _choose_linear_solver(p, linear_solver)
    chunk = chunk_size(p.R, p.n, kind, memory_mb)
    parts: list[_Solution] = []
    B = p.B
    for first in range(0, B, chunk):
        idx = np.arange(first, min(B, first + chunk))
        st = None if start is None else (start[0][idx], start[1][idx])
        parts.append(_solve_chunk(p.take(idx), tol, iteration_bound() if max_iter is None else int(max_iter),
                                  strategy, kind, st))
        if progress is not None:
            progress(int(idx[-1]) + 1, B)
    return _Solution.concatenate(parts)


class _Phase(enum.IntEnum):
    """Where a sample of a chunk stands (module docstring, "Solver"). The values live in a
    per-sample integer array; the running phases sort before the terminal ones."""

    ACTIVE_SET = 0      # face Newton from equal (or given) loads, teeth leave and come back
    BARRIER = 1         # a stage of the log-barrier method (damped Newton at fixed mu)
    CROSSOVER = 2       # face Newton from a barrier point with the teeth classified by mu
    SOLVED = 3          # a checked solution
    FAILED = 4          # a cap was reached without a checked solution


#: The largest phase value in which a sample still takes Newton steps.
_LAST_RUNNING = _Phase.CROSSOVER


@dataclass(frozen=True)
class _Chunk:
    """One chunk of B problems and its per-sample scales, (B,) unless stated: mean tooth load
    f_m (N; ``mean_load4`` shaped (B, 1, 1, 1)), mean linear tooth compliance ``compliance``
    ((1, 1, 2, 1), mm/N), mean tooth deflection D_m (mm), tooth tangent stiffness ``kref``
    (N/mm), energy scale f_m D_m (N mm), load per roller (N)."""

    p: _Problem
    tol: float
    max_iter: int
    mean_load: NDArray
    mean_load4: NDArray
    compliance: NDArray
    mean_deflection: NDArray
    kref: NDArray
    energy: NDArray
    load_per_roller: NDArray
    lin: _Linear

    @staticmethod
    def make(p: _Problem, tol: float, max_iter: int, kind: str) -> "_Chunk":
        """The scales of ``p`` and its linear solver of kind ``kind``."""
        fbar = p.F / (p.m * p.R * p.n)
        f4 = fbar.reshape(p.B, 1, 1, 1)
        cd = p.cdiag if p.cdense is None else np.diag(p.cdense).reshape(1, 1, 2, p.n).mean(axis=-1, keepdims=True)
        mean_deflection = (_law(p, f4) + cd * f4).max(axis=(1, 2, 3))
        kref = 1.0 / (_law_slope(p, f4) + cd).mean(axis=(1, 2, 3))
        return _Chunk(p=p, tol=tol, max_iter=max_iter, mean_load=fbar, mean_load4=f4, compliance=cd,
                      mean_deflection=mean_deflection, kref=kref, energy=fbar * mean_deflection,
                      load_per_roller=p.F / (p.m * p.R), lin=_Linear(p, kref, kind))

    def start_point(self, sel: NDArray) -> tuple[NDArray, NDArray]:
        """Equal loads f_m at every tooth of the samples ``sel`` and their tooth deflections as
        approaches."""
        p, f4 = self.p, self.mean_load4
        f0 = np.broadcast_to(f4[sel], (sel.size, p.R, 2, p.n)).copy()
        y0 = np.broadcast_to((_law(p.take(sel), f4[sel]) + self.compliance * f4[sel])[..., 0],
                             (sel.size, p.R, 2)).copy()
        return f0, y0


@dataclass
class _SolverState:
    """The mutable state of every sample of a chunk: loads ``f`` (B, R, 2, n) N, approaches
    ``y`` (B, R, 2) mm, teeth held open ``pinned``, ``phase`` (:class:`_Phase` values),
    barrier parameter ``mu`` (N mm), Newton steps in all and in the current phase, face
    re-activation ``rounds``, whether the barrier ran, and the barrier point (``f_barrier``,
    ``y_barrier``) a crossover started from."""

    f: NDArray
    y: NDArray
    pinned: NDArray
    phase: NDArray
    mu: NDArray
    it: NDArray
    it_phase: NDArray
    rounds: NDArray
    used_barrier: NDArray
    f_barrier: NDArray
    y_barrier: NDArray

    @staticmethod
    def initial(chunk: _Chunk, strategy: str, start: tuple[NDArray, NDArray] | None) -> "_SolverState":
        """Equal loads (or ``start`` with strategy "auto"), all teeth in contact; strategy
        "barrier" starts in the barrier phase."""
        p = chunk.p
        f, y = chunk.start_point(np.arange(p.B))
        if start is not None and strategy == "auto":
            f, y = start[0].copy(), start[1].copy()
        phase = np.full(p.B, int(_Phase.ACTIVE_SET if strategy == "auto" else _Phase.BARRIER))
        return _SolverState(f=f, y=y, pinned=np.zeros((p.B, p.R, 2, p.n), bool), phase=phase,
                            mu=_MU0 * chunk.energy, it=np.zeros(p.B, int), it_phase=np.zeros(p.B, int),
                            rounds=np.zeros(p.B, int), used_barrier=phase == _Phase.BARRIER,
                            f_barrier=f.copy(), y_barrier=y.copy())

    def running(self, max_iter: int) -> NDArray:
        """Indices of the samples that take the next Newton step; those at ``max_iter`` fail."""
        live = np.nonzero(self.phase <= _LAST_RUNNING)[0]
        over = live[self.it[live] >= max_iter]
        self.phase[over] = _Phase.FAILED
        return live[self.it[live] < max_iter]

    def to_barrier(self, chunk: _Chunk, sel: NDArray) -> None:
        """Samples ``sel`` leave the active-set phase: the barrier from equal loads."""
        if sel.size == 0:
            return
        f0, y0 = chunk.start_point(sel)
        self.f[sel], self.y[sel] = f0, y0
        self.pinned[sel] = False
        self.phase[sel] = _Phase.BARRIER
        self.mu[sel] = _MU0 * chunk.energy[sel]
        self.it_phase[sel] = 0
        self.used_barrier[sel] = True

    def end_barrier_stage(self, chunk: _Chunk, sel: NDArray) -> None:
        """A barrier stage of samples ``sel`` ended: a crossover once mu is small enough,
        else the next stage with a smaller mu."""
        if sel.size == 0:
            return
        energy = chunk.energy
        cross = sel[self.mu[sel] <= _MU_CROSS * energy[sel] * (1 + 1e-9)]
        lower = sel[self.mu[sel] > _MU_CROSS * energy[sel] * (1 + 1e-9)]
        self.mu[lower] *= _SIGMA
        self.it_phase[lower] = 0
        if cross.size:
            self._start_crossover(chunk, cross)

    def _start_crossover(self, chunk: _Chunk, cross: NDArray) -> None:
        """Keep the barrier point; teeth with f_j < sqrt(mu f_m / D_m) are held open."""
        f = self.f
        self.f_barrier[cross], self.y_barrier[cross] = f[cross], self.y[cross]
        thr = np.sqrt(self.mu[cross] * chunk.mean_load[cross] / chunk.mean_deflection[cross]).reshape(-1, 1, 1, 1)
        pin = f[cross] < thr
        # the most loaded roller keeps its most loaded tooth on each side (a load path)
        ar = np.arange(cross.size)
        top_r = f[cross].sum(axis=(2, 3)).argmax(axis=1)
        top_j = f[cross][ar, top_r].argmax(axis=-1)                  # (c, 2)
        pin[ar[:, None], top_r[:, None], np.arange(2)[None, :], top_j] = False
        self.pinned[cross] = pin
        f[cross] = np.where(pin, 0.0, f[cross])
        self.phase[cross] = _Phase.CROSSOVER
        self.it_phase[cross] = 0
        self.rounds[cross] = 0

    def crossover_failed(self, chunk: _Chunk, sel: NDArray) -> None:
        """Back to the barrier point of samples ``sel`` and on with a smaller mu; below the
        last stage the sample has failed."""
        if sel.size == 0:
            return
        self.f[sel], self.y[sel] = self.f_barrier[sel], self.y_barrier[sel]
        self.pinned[sel] = False
        self.phase[sel] = _Phase.BARRIER
        self.mu[sel] *= _SIGMA
        self.it_phase[sel] = 0
        self.phase[sel[self.mu[sel] < _MU_MIN * chunk.energy[sel] * (1 - 1e-9)]] = _Phase.FAILED

    def solution(self) -> _Solution:
        return _Solution(f=self.f, y=self.y, pinned=self.pinned, iterations=self.it, barrier=self.used_barrier,
                         ok=self.phase == _Phase.SOLVED, rounds=self.rounds)


def _has_load_path(pin: NDArray) -> NDArray:
    """(b,): some roller has a tooth in contact on both sides (R = 1: the roller)."""
    return (~pin).any(axis=3).all(axis=2).any(axis=1)


def _check_complementarity(chunk: _Chunk, sel: NDArray, fs: NDArray, ys: NDArray,
                           pin: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """The check of the module docstring for samples ``sel`` with loads ``fs``, approaches
    ``ys`` and open teeth ``pin``. Places floating rollers (all teeth open) midway in their
    admissible range. Returns (ok (b,), approaches (b, R, 2), gaps w (b, R, 2, n) mm, D_ref
    (b, 1, 1, 1) mm)."""
    ps = chunk.p.take(sel)
    c = _law(ps, np.zeros_like(fs)) + _body(ps, fs) + _clin(ps, fs) + ps.g
    ys = ys.copy()
    flo = pin.all(axis=(2, 3))
    ok = np.ones(sel.size, bool)
    if flo.any():
        delta = ys.sum(axis=2)                                   # common approach y_nr + y_rs
        lo = delta - c[:, :, 1].min(axis=-1)
        hi = c[:, :, 0].min(axis=-1)
        u = 0.5 * (lo + hi)
        ok &= ~(flo & (lo > hi)).any(axis=1)
        ys[:, :, 0] = np.where(flo, u, ys[:, :, 0])
        ys[:, :, 1] = np.where(flo, delta - u, ys[:, :, 1])
    w = c - ys[..., None]
    dref = np.maximum(np.abs(ys).max(axis=(1, 2)), chunk.mean_deflection[sel]).reshape(-1, 1, 1, 1)
    ok &= np.where(pin, w >= -_OPEN_TOL * dref, fs > 0).all(axis=(1, 2, 3))
    return ok, ys, w, dref


@dataclass(frozen=True)
class _NewtonStep:
    """One Newton step of the running samples ``live``: their problems, the state at the step
    (``f``, ``y``, ``pinned``, ``phase``, ``mu``), the contact law D(f), the linear terms L f
    and the energy gradient (mm), and the increments: deflections ``q`` (mm), approaches
    ``dy`` (mm), loads ``d`` (N)."""

    live: NDArray
    ps: _Problem
    f: NDArray
    y: NDArray
    pinned: NDArray
    phase: NDArray
    mu: NDArray
    law: NDArray
    linear: NDArray
    grad: NDArray
    q: NDArray
    dy: NDArray
    d: NDArray


def _newton_step(chunk: _Chunk, state: _SolverState, live: NDArray) -> _NewtonStep:
    """Assemble and solve the Newton system of the samples ``live`` (barrier terms for those
    in a barrier stage); counts the step."""
    ps = chunk.p.take(live)
    fl, yl, pl, ph, ml = state.f[live], state.y[live], state.pinned[live], state.phase[live], state.mu[live]
    bar = (ph == _Phase.BARRIER).reshape(-1, 1, 1, 1)
    mu4 = ml.reshape(-1, 1, 1, 1)
    lawf, slope = _law_and_slope(ps, fl)
    Lf = _body(ps, fl) + _clin(ps, fl)
    grad = lawf + Lf + ps.g
    S = slope + _cdiag_part(ps)
    if bar.any():                       # the barrier terms mu / f, mu / f^2
        with np.errstate(divide="ignore", invalid="ignore"):
            mf = np.where(bar, mu4 / np.where(bar, fl, 1.0), 0.0)
            S = S + mf / np.where(bar, fl, 1.0)
            grad = grad - mf
    with np.errstate(divide="ignore"):
        k = np.where(pl, 0.0, 1.0 / S)
    r = -(grad - yl[..., None])
    r = np.where(pl, 0.0, r)
    rc_roll = fl[:, :, 1].sum(axis=-1) - fl[:, :, 0].sum(axis=-1)
    rc_tot = ps.F - chunk.p.m * fl[:, :, 1].sum(axis=(1, 2))
    q, dy = chunk.lin.solve(live, k, r, rc_roll, rc_tot, pl.all(axis=(2, 3)))
    state.it[live] += 1
    state.it_phase[live] += 1
    return _NewtonStep(live=live, ps=ps, f=fl, y=yl, pinned=pl, phase=ph, mu=ml, law=lawf, linear=Lf,
                       grad=grad, q=q, dy=dy, d=k * q)


def _face_step(chunk: _Chunk, state: _SolverState, step: _NewtonStep) -> None:
    """The face-Newton update of the samples of ``step`` in the active-set or crossover
    phase: Newton in the tooth deflections (loads by the exact inverse law), a tooth whose
    load would turn negative is held open; converged samples are checked; caps and
    breakdowns move samples on."""
    face = np.nonzero(step.phase != _Phase.BARRIER)[0]
    if face.size == 0:
        return
    # (all running samples in face Newton, the usual case: no copies)
    sub = (lambda a: a) if face.size == step.live.size else (lambda a: a[face])
    sel = step.live[face]
    pin = sub(step.pinned)
    pf = step.ps.take(face)
    ff = sub(step.f)
    fn = np.where(pin, 0.0, _tooth_inv(pf, sub(step.law) + _cdiag_part(pf) * ff + sub(step.q)))
    yn = sub(step.y) + sub(step.dy)
    finite = np.isfinite(fn).all(axis=(1, 2, 3)) & np.isfinite(yn).all(axis=(1, 2))
    neg = ~pin & (fn <= 0)
    conv = finite & _face_converged(chunk, sel, ff, fn, yn, sub(step.dy), neg)
    # a tooth whose load would turn negative leaves the contact set
    newpin = pin | neg
    good = finite & _has_load_path(newpin)
    fn = np.where(newpin, 0.0, fn)
    state.f[sel], state.y[sel], state.pinned[sel] = np.where(good.reshape(-1, 1, 1, 1), fn, ff), yn, newpin
    if conv.any():
        _check_converged(chunk, state, sel[conv])
    _apply_face_caps(chunk, state, sel, sel[~good])


def _face_converged(chunk: _Chunk, sel: NDArray, f_old: NDArray, f_new: NDArray, y_new: NDArray,
                    dy: NDArray, neg: NDArray) -> NDArray:
    """(b,): no load turned negative, the load step is <= tol x the load per roller and the
    approach step <= tol x max(1 mm, |a|)."""
    tol = chunk.tol
    step = np.abs(f_new - f_old).max(axis=(1, 2, 3))
    dys = np.abs(dy).max(axis=(1, 2))
    return ~neg.any(axis=(1, 2, 3)) & (step <= tol * chunk.load_per_roller[sel]) & \
        (dys <= tol * np.maximum(1.0, np.abs(y_new).max(axis=(1, 2))))


def _check_converged(chunk: _Chunk, state: _SolverState, cs: NDArray) -> None:
    """Converged face samples ``cs``: checked ones are solved; the others bring back the
    teeth whose gap closed and solve the face again."""
    ok, ys, w, dref = _check_complementarity(chunk, cs, state.f[cs], state.y[cs], state.pinned[cs])
    state.y[cs] = np.where(ok.reshape(-1, 1, 1), ys, state.y[cs])
    state.phase[cs[ok]] = _Phase.SOLVED
    again = ~ok & (state.phase[cs] <= _LAST_RUNNING)
    re = cs[again]
    if re.size:
        closed = state.pinned[re] & (w[again] < -_OPEN_TOL * dref[again])
        state.pinned[re] &= ~closed
        state.rounds[re] += 1


def _apply_face_caps(chunk: _Chunk, state: _SolverState, sel: NDArray, bad: NDArray) -> None:
    """Face samples ``sel`` past their step or round cap, or broken down (``bad``: no finite
    step or no load path): the active-set phase hands over to the barrier, a crossover
    returns to its barrier point."""
    phase, it_phase, rounds = state.phase, state.it_phase, state.rounds
    p0 = sel[(phase[sel] == _Phase.ACTIVE_SET)
             & ((it_phase[sel] >= _HEURISTIC_ITER) | (rounds[sel] >= _HEURISTIC_ROUNDS))]
    state.to_barrier(chunk, np.union1d(p0, bad[phase[bad] == _Phase.ACTIVE_SET]))
    p2 = sel[(phase[sel] == _Phase.CROSSOVER) & ((it_phase[sel] >= _FACE_ITER) | (rounds[sel] >= _HEURISTIC_ROUNDS))]
    state.crossover_failed(chunk, np.union1d(p2, bad[phase[bad] == _Phase.CROSSOVER]))


def _barrier_step(chunk: _Chunk, state: _SolverState, step: _NewtonStep) -> None:
    """The damped barrier-Newton update of the samples of ``step`` in a barrier stage; a
    stage ends at a small Newton decrement, a rounding floor or its step cap."""
    bi = np.nonzero(step.phase == _Phase.BARRIER)[0]
    if bi.size == 0:
        return
    sel = step.live[bi]
    db = step.d[bi]
    slope = (step.grad[bi] * db).sum(axis=(1, 2, 3))
    done_stage = ~(-slope > _THETA * step.mu[bi]) | ~np.isfinite(slope)
    go = np.nonzero(~done_stage)[0]
    if go.size:
        gi = bi[go]
        fg, dg, mg = step.f[gi], db[go], step.mu[gi].reshape(-1, 1, 1, 1)
        pg = step.ps.take(gi)
        alpha, accepted = _barrier_line_search(pg, fg, dg, mg, step.linear[gi] + pg.g, slope[go])
        moved = sel[go[accepted]]
        state.f[moved] = fg[accepted] + alpha[accepted].reshape(-1, 1, 1, 1) * dg[accepted]
        state.y[moved] = step.y[gi[accepted]] + step.dy[gi[accepted]]
        done_stage[go[~accepted]] = True                     # rounding floor reached
    capped = state.it_phase[sel] >= _STAGE_ITER
    state.end_barrier_stage(chunk, sel[done_stage | capped])


def _barrier_line_search(pg: _Problem, fg: NDArray, dg: NDArray, mg: NDArray, grad_linear: NDArray,
                         slope: NDArray) -> tuple[NDArray, NDArray]:
    """Step lengths along the load steps ``dg`` from loads ``fg`` (N): fraction-to-boundary
    0.995, then Armijo backtracking (halving, at most 60 times) on the change of the barrier
    energy, written without cancellation (log1p, expm1). ``grad_linear`` = L f + g (mm),
    ``mg`` the barrier parameters (b, 1, 1, 1), ``slope`` the directional derivatives (b,).
    Returns (alpha (b,), accepted (b,))."""
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(dg < 0, fg / -dg, np.inf)
    alpha = np.minimum(1.0, 0.995 * ratio.min(axis=(1, 2, 3)))
    Ld = _body(pg, dg) + _clin(pg, dg)
    f53 = 0.6 * pg.h * fg ** (5.0 / 3.0)
    accepted = np.zeros(fg.shape[0], bool)
    for _ in range(60):
        a4 = alpha.reshape(-1, 1, 1, 1)
        x = a4 * dg / fg
        lp = np.log1p(x)
        dphi = (f53 * np.expm1((5.0 / 3.0) * lp) + pg.e0 * a4 * dg
                + pg.e1 * (a4 * fg * dg + 0.5 * a4 * a4 * dg * dg)
                + a4 * grad_linear * dg + 0.5 * a4 * a4 * dg * Ld - mg * lp).sum(axis=(1, 2, 3))
        ok = dphi <= 1e-4 * alpha * slope
        accepted |= ok
        if accepted.all():
            break
        alpha = np.where(accepted, alpha, 0.5 * alpha)
    return alpha, accepted


def _solve_chunk(p: _Problem, tol: float, max_iter: int, strategy: str, kind: str,
                 start: tuple[NDArray, NDArray] | None) -> _Solution:
    """Solve one chunk: Newton steps of every running sample until each is solved or has
    failed (module docstring, "Solver")."""
    chunk = _Chunk.make(p, tol, max_iter, kind)
    state = _SolverState.initial(chunk, strategy, start)
    while True:
        live = state.running(max_iter)
        if live.size == 0:
            break
        step = _newton_step(chunk, state, live)
        _face_step(chunk, state, step)
        _barrier_step(chunk, state, step)
    return state.solution()


# --------------------------------------------------------------------------- forward
@dataclass(frozen=True)
class LoadResult:
    """Tooth loads of one roller (N) and derived quantities; tooth 1 at the loaded end."""

    load_n: float
    f_nr: NDArray
    f_rs: NDArray
    approach_nr_mm: float          # a_n: tooth-1 deflection of the nut-roller contact
    approach_rs_mm: float
    iterations: int
    active_nr: NDArray
    active_rs: NDArray
    barrier: bool = False          # the barrier phase of the solver was needed

    @property
    def mean(self) -> float:
        return self.f_nr.sum() / len(self.f_nr)

    @property
    def ldc_nr(self) -> NDArray:
        """Load-distribution coefficients f_j / (F0 / n z), nut-roller side."""
        return self.f_nr / self.mean

    @property
    def ldc_rs(self) -> NDArray:
        return self.f_rs / self.mean

    @property
    def axial_deflection_mm(self) -> float:
        """Screw-to-nut axial displacement at the loaded end (contact + teeth at tooth 1)."""
        return self.approach_nr_mm + self.approach_rs_mm


@dataclass(frozen=True)
class LoadBatch:
    """B solutions of :func:`solve_loads_batch`: the fields of :class:`LoadResult` with a
    leading batch axis (loads (B,), tooth loads and contact flags (B, n), N and mm)."""

    load_n: NDArray
    f_nr: NDArray
    f_rs: NDArray
    approach_nr_mm: NDArray
    approach_rs_mm: NDArray
    iterations: NDArray
    active_nr: NDArray
    active_rs: NDArray
    barrier: NDArray

    def __len__(self) -> int:
        return len(self.load_n)

    def __getitem__(self, i: int) -> LoadResult:
        return LoadResult(float(self.load_n[i]), self.f_nr[i].copy(), self.f_rs[i].copy(),
                          float(self.approach_nr_mm[i]), float(self.approach_rs_mm[i]), int(self.iterations[i]),
                          self.active_nr[i].copy(), self.active_rs[i].copy(), bool(self.barrier[i]))

    @property
    def mean(self) -> NDArray:
        return self.f_nr.sum(axis=-1) / self.f_nr.shape[-1]

    @property
    def ldc_nr(self) -> NDArray:
        return self.f_nr / self.mean[:, None]

    @property
    def ldc_rs(self) -> NDArray:
        return self.f_rs / self.mean[:, None]

    @property
    def axial_deflection_mm(self) -> NDArray:
        return self.approach_nr_mm + self.approach_rs_mm


@dataclass(frozen=True)
class RollerLoadResult:
    """Tooth loads of all z rollers side by side (:func:`solve_loads_rollers`), N and mm.

    ``f_nr``, ``f_rs``, ``active_*``: (..., z, n), roller r, tooth j; approaches (..., z)
    (their sum, the screw-to-nut approach, is the same for every roller); a leading batch
    axis when the gaps had one."""

    load_n: NDArray | float
    f_nr: NDArray
    f_rs: NDArray
    approach_nr_mm: NDArray
    approach_rs_mm: NDArray
    iterations: NDArray | int
    active_nr: NDArray
    active_rs: NDArray
    barrier: NDArray | bool

    @property
    def z(self) -> int:
        return self.f_nr.shape[-2]

    @property
    def mean(self) -> NDArray | float:
        """The equal-share tooth load F0 / (n z)."""
        return np.asarray(self.load_n) / (self.f_nr.shape[-1] * self.z)

    @property
    def ldc_per_roller(self) -> dict[str, NDArray]:
        """Coefficients f_j / (F0 / n z) of every roller, (..., z, n) per side."""
        m = np.asarray(self.mean)[..., None, None]
        return {"nut_roller": self.f_nr / m, "roller_screw": self.f_rs / m}

    @property
    def ldc_nr(self) -> NDArray:
        """Coefficients of the tooth positions, all rollers together: sum_r f_r,j / (F0 / n),
        (..., n); with equal rollers the single-roller coefficients."""
        return self.f_nr.sum(axis=-2) / (np.asarray(self.load_n)[..., None] / self.f_nr.shape[-1])

    @property
    def ldc_rs(self) -> NDArray:
        return self.f_rs.sum(axis=-2) / (np.asarray(self.load_n)[..., None] / self.f_rs.shape[-1])

    @property
    def roller_load_share(self) -> NDArray:
        """Fraction of F0 carried by each roller, (..., z): its nut-side loads over those of all
        rollers (F0 to rounding), so the shares sum to 1 and a roller carrying everything
        has exactly 1, whatever the last bits of the equilibrium."""
        per = self.f_nr.sum(axis=-1)
        return per / per.sum(axis=-1, keepdims=True)

    @property
    def axial_deflection_mm(self) -> NDArray | float:
        return self.approach_nr_mm[..., 0] + self.approach_rs_mm[..., 0]


def _failed(res: _Solution, what: str) -> None:
    """Raise :class:`ConvergenceError` if a sample of ``res`` has no checked solution."""
    bad = np.nonzero(~res.ok)[0]
    if bad.size:
        raise ConvergenceError(
            f"tooth-load solver did not converge for {bad.size} {what} (first: index {int(bad[0])}) within "
            f"{int(res.iterations[bad].max())} Newton steps; no result is returned")


def solve_loads_batch(model: LoadModel, loads: float | Sequence[float] | NDArray, g_nr: NDArray, g_rs: NDArray,
                      linear_at: float | NDArray | None = None, tol: float = 1e-13, max_iter: int | None = None,
                      *, strategy: str = "auto", linear_solver: str = "auto", memory_mb: float = MEMORY_MB,
                      progress: ProgressFn | None = None, stage: str = "loads",
                      start: "LoadResult | LoadBatch | None" = None) -> LoadBatch:
    """Tooth loads of B independent problems at once (module docstring "Solver").

    ``loads``: axial load(s) F0, N, scalar or (B,); ``g_nr``, ``g_rs``: cumulative initial
    gaps (:func:`gap_terms`), mm, (B, n); ``linear_at``: tooth load(s) (N, scalar or (B,))
    at which Hertz is replaced by its tangent (the linear model B f = x of docs/theory
    section 4). The batch is solved in chunks that fit ``memory_mb``; ``progress(stage,
    samples done, B)`` is called after every chunk. ``strategy="barrier"`` skips the active-set phase;
    ``linear_solver``: "auto" ("banded" without, "dense" with a dense compliance),
    "banded", "segments" or "dense" (module docstring, "Linear systems"; the same loads to
    rounding).
    Raises :class:`ConvergenceError` if any sample does not converge within ``max_iter``
    Newton steps (default :func:`iteration_bound`). ``start``: a solution (one, or one per
    sample) whose loads and approaches start the active-set phase instead of equal loads (e.g. the
    unperturbed design in a tolerance study); it changes the path, not the answer."""
    p = _make_problem(model, loads, g_nr, g_rs, linear_at, rollers=False)
    cb = None if progress is None else (lambda done, total: progress(stage, done, total))
    st = None
    if start is not None:
        f0 = np.stack([np.asarray(start.f_nr, dtype=np.float64), np.asarray(start.f_rs, dtype=np.float64)], axis=-2)
        y0 = np.stack([np.asarray(start.approach_nr_mm, dtype=np.float64),
                       np.asarray(start.approach_rs_mm, dtype=np.float64)], axis=-1)
        f0 = np.broadcast_to(f0, (p.B, 2, model.n))[:, None].copy()
        y0 = np.broadcast_to(y0, (p.B, 2))[:, None].copy()
        if not (np.all(np.isfinite(f0)) and np.all(np.isfinite(y0))):
            raise ValueError("start must be finite")
        st = (f0, y0)
    res = _solve_problem(p, tol, max_iter, strategy, linear_solver, memory_mb, cb, st)
    _failed(res, "of the samples")
    f, y, act = res.f[:, 0], res.y[:, 0], ~res.pinned[:, 0]
    return LoadBatch(p.F.copy(), f[:, 0].copy(), f[:, 1].copy(), y[:, 0].copy(), y[:, 1].copy(), res.iterations,
                     act[:, 0].copy(), act[:, 1].copy(), res.barrier)


def solve_loads(model: LoadModel, load: float, g_nr: NDArray, g_rs: NDArray,
                linear_at: float | None = None, tol: float = 1e-13, max_iter: int | None = None,
                **options: Any) -> LoadResult:
    """Tooth loads for axial load ``load`` (N) and initial gaps (mm): the B = 1 case of
    :func:`solve_loads_batch` (same code, same numbers).

    The loads solve the complementarity problem of the module docstring (every tooth in
    contact with f_j > 0 and its compatibility equation, every other tooth with f_j = 0 and
    an open gap, equilibrium). ``linear_at`` replaces the Hertz law by its tangent at that
    tooth load (N): the linear model B f = x of docs/theory/loads.md.
    """
    g_nr = np.asarray(g_nr, dtype=np.float64)
    g_rs = np.asarray(g_rs, dtype=np.float64)
    return solve_loads_batch(model, load, g_nr[None], g_rs[None], linear_at, tol, max_iter, **options)[0]


def solve_loads_rollers(model: LoadModel, loads: float | Sequence[float] | NDArray, g_nr: NDArray, g_rs: NDArray,
                        linear_at: float | NDArray | None = None, tol: float = 1e-13, max_iter: int | None = None,
                        *, strategy: str = "auto", linear_solver: str = "auto",
                        memory_mb: float = MEMORY_MB) -> RollerLoadResult:
    """Tooth loads of all z rollers side by side, each with its own gaps.

    ``g_nr``, ``g_rs``: (z, n) or (B, z, n) cumulative gaps of each roller (mm; a common
    offset of both sides of a roller is a roller that engages earlier or later, an offset
    +c on the nut side and -c on the screw side only shifts the floating roller). The nut
    and the screw are single bodies (segment forces summed over the rollers); each roller
    is its own body, floats axially (sum of its nut-side loads = sum of its screw-side
    loads) and all rollers share the screw-to-nut approach; total load ``loads`` (N). With
    equal rollers the loads are those of :func:`solve_loads` (one roller standing for all).
    ``linear_at``, ``tol``, ``max_iter``, ``strategy``, ``linear_solver`` and ``memory_mb``
    as in :func:`solve_loads_batch`; with the default linear solver a Newton step costs
    O(n (z + 2)^3) flops per sample (module docstring, "Linear systems"; z = 10, n = 20:
    about 15 times faster than the "segments" form).
    """
    g_nr = np.asarray(g_nr, dtype=np.float64)
    g_rs = np.asarray(g_rs, dtype=np.float64)
    single = g_nr.ndim == 2
    if single:
        g_nr, g_rs = g_nr[None], g_rs[None]
    p = _make_problem(model, loads, g_nr, g_rs, linear_at, rollers=True)
    res = _solve_problem(p, tol, max_iter, strategy, linear_solver, memory_mb)
    _failed(res, "of the samples")
    f, y, act = res.f, res.y, ~res.pinned
    out = RollerLoadResult(p.F.copy(), f[:, :, 0], f[:, :, 1], y[:, :, 0], y[:, :, 1], res.iterations,
                           act[:, :, 0], act[:, :, 1], res.barrier)
    if single:
        return RollerLoadResult(float(out.load_n[0]), out.f_nr[0], out.f_rs[0], out.approach_nr_mm[0],
                                out.approach_rs_mm[0], int(out.iterations[0]), out.active_nr[0],
                                out.active_rs[0], bool(out.barrier[0]))
    return out


