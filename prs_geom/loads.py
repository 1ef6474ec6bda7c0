"""Load distribution over the thread teeth and equal-load pitch design (DOMAIN.md section 4).

Pure math, no I/O.

Load path and signs (fixed here, used everywhere)
-------------------------------------------------
Tooth 1 is at the loaded end (z = 0), tooth n at the far end. The external load F0 is
carried screw -> rollers -> nut and flows toward -z: the screw tooth above each roller
tooth presses it down (roller *upper* flank, the "upper" screw-roller contact of
:mod:`prs_geom.contact`), and the roller tooth presses the nut tooth below it (roller
*lower* flank, nut tooth j the one below roller tooth j). The nut is supported at the
loaded end, so its body is in compression; the screw is pulled at the loaded end
(tension-compression: body in tension) or pushed at the far end (compression-compression).
All rollers carry the same loads (one roller is modelled): f_nr,j (nut-roller) and
f_rs,j (roller-screw), axial components, N.

Compatibility between teeth j and j + 1 (D = contact + tooth deflection, axial, mm):

    D_nr(f_nr,j) - D_nr(f_nr,j+1) = d_n,j + d_r,j + (p_r,j - p_n,j)
    D_rs(f_rs,j) - D_rs(f_rs,j+1) = s d_s,j - d_r,j + (p_s - p_r,j)

with the body deformations over one pitch d_i,j = N_i,j p / (E_i A_i), segment forces
N_n,j = z sum_{k>j} f_nr,k (compression), N_r,j = sum_{k>j} (f_nr,k - f_rs,k) (tension),
N_s,j = z sum_{k>j} f_rs,k (tension-compression, s = +1) or z sum_{k<=j} f_rs,k
(compression-compression, s = -1); equilibrium sum f_nr = sum f_rs = F0 / z.

Equal load (every coefficient 1): contact and tooth terms cancel and d_r = 0, so

    p_r,j = p_s + F0 p (n - j) / (n E_s A_s)     (tension-compression)
    p_r,j = p_s - F0 p j / (n E_s A_s)           (compression-compression)
    p_n,j = p_r,j + F0 p (n - j) / (n E_n A_n)   (both)

DOMAIN.md writes the nut relation with a minus sign and leaves the convention open; with
the nut supported at the loaded end the far nut teeth move toward the support the most,
so they must start closer to the roller teeth: the nut pitch is the larger one.

Compliances
-----------
* Hertz point contact of the roller's spherical flank (radius r_T) with the screw's or
  nut's straight flank, curvatures 1/r_T, 1/r_T and 0, +-sin(beta)/r_c at the actual contact
  radius r_c of the contact solver; ellipticity k from the complete elliptic integrals
  (scipy); normal approach delta = C Q^(2/3); the axial load is F = Q n_z, with n_z the axial
  component of the contact normal from the contact solver (about cos(beta) cos(lambda)), so
  the axial approach is C (F / n_z)^(2/3) / n_z.
* Thread teeth (Yamamoto, Appendix A): bending, shear, root tilt, root shear and radial
  terms. Yamamoto's terms are per unit circumferential width. Width convention: a roller's
  tooth load is spread over pi d_s / z on the screw and pi d_n / z on the nut (the z rollers
  share the circumference) and over the whole roller circumference pi d_r on the roller.
  Tooth geometry at the load line: b = axial tooth thickness at the contact radius,
  c = radial distance from the root to the contact radius, a = b + 2 c tan(beta).
* Bodies: screw and roller root sections pi d_root^2 / 4, nut pi (D0^2 - d_root^2) / 4 with
  d_root the nut's groove-root (major) diameter.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, Sequence

import numpy as np
from numpy.typing import NDArray
from scipy import optimize, special

from .design import PRSDesign
from .errors import ConvergenceError, DesignError
from .profiles import ThreadProfiles


# --------------------------------------------------------------------------- Hertz
def ellipticity(F_rho: float) -> float:
    """k >= 1 with F(rho) = [(k^2 + 1) E(e) - 2 K(e)] / [(k^2 - 1) E(e)], e^2 = 1 - 1/k^2."""
    if F_rho <= 1e-12:
        return 1.0

    def f(k: float) -> float:
        m = 1.0 - 1.0 / (k * k)
        E, K = special.ellipe(m), special.ellipk(m)
        return ((k * k + 1.0) * E - 2.0 * K) / ((k * k - 1.0) * E) - F_rho

    return optimize.brentq(f, 1.0 + 1e-9, 1e4, xtol=1e-14, rtol=1e-15)


def hertz_constant(curvatures: Sequence[float], eta: float) -> tuple[float, dict[str, float]]:
    """C with normal approach delta = C Q^(2/3) (mm, Q in N) for principal curvatures
    (rho11, rho12, rho21, rho22) (1/mm) and eta = sum (1 - nu^2)/E (1/MPa)."""
    r11, r12, r21, r22 = curvatures
    sum_rho = r11 + r12 + r21 + r22
    if sum_rho <= 0:
        raise DesignError("roller.arc_radius_mm", None, "the contact curvature sum must be positive")
    F_rho = (abs(r11 - r12) + abs(r21 - r22)) / sum_rho
    k = ellipticity(F_rho)
    m = 1.0 - 1.0 / (k * k)
    E, K = float(special.ellipe(m)), float(special.ellipk(m))
    C = (2.0 * K / math.pi) * (math.pi / (2.0 * k * k * E)) ** (1.0 / 3.0) \
        * (3.0 * eta / (2.0 * sum_rho)) ** (2.0 / 3.0) * sum_rho / 2.0
    return C, {"sum_rho_per_mm": sum_rho, "F_rho": F_rho, "ellipticity_k": k}


# --------------------------------------------------------------------------- Yamamoto
def yamamoto_compliance(beta: float, a: float, b: float, c: float, P: float, d: float,
                        E: float, nu: float, nut_outer: float | None = None) -> dict[str, float]:
    """Axial tooth deflection per unit load per unit width, mm / (N/mm), term by term."""
    ta = math.tan(beta)
    cot = 1.0 / ta
    lam1 = (1 - nu ** 2) * 3.0 / (4.0 * E) * ((1 - (2 - b / a) ** 2 + 2 * math.log(a / b)) * cot ** 3
                                               - 4 * (c / a) ** 2 * ta)
    lam2 = (1 + nu) * 6.0 / (5.0 * E) * cot * math.log(a / b)
    lam3 = (1 - nu ** 2) * 12.0 * c / (math.pi * E * a ** 2) * (c - 0.5 * b * ta)
    lam4 = (1 - nu ** 2) * 2.0 / (math.pi * E) * ((P / a) * math.log((P + 0.5 * a) / (P - 0.5 * a))
                                                  + 0.5 * math.log(4 * P ** 2 / a ** 2 - 1))
    if nut_outer is None:
        lam5 = (1 - nu) * ta ** 2 / 2.0 * (d / P) / E
    else:
        lam5 = ((nut_outer ** 2 + d ** 2) / (nut_outer ** 2 - d ** 2) + nu) * ta ** 2 / 2.0 * (d / P) / E
    return {"bending": lam1, "shear": lam2, "root_tilt": lam3, "root_shear": lam4, "radial": lam5}


# --------------------------------------------------------------------------- model
@dataclass(frozen=True)
class LoadModel:
    """Everything the tooth-load equations need, in N and mm."""

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
    details: dict[str, Any] = field(default_factory=dict, compare=False)

    # D(F) = contact + tooth, axial, and its derivative
    def deflection(self, side: str, f: NDArray) -> NDArray:
        h, t = (self.hertz_nr, self.tooth_nr) if side == "nr" else (self.hertz_rs, self.tooth_rs)
        f = np.asarray(f, dtype=np.float64)
        return h * np.sign(f) * np.abs(f) ** (2.0 / 3.0) + t * f

    def deflection_slope(self, side: str, f: NDArray) -> NDArray:
        h, t = (self.hertz_nr, self.tooth_nr) if side == "nr" else (self.hertz_rs, self.tooth_rs)
        return (2.0 / 3.0) * h * np.abs(f) ** (-1.0 / 3.0) + t

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


def _section_areas(design: PRSDesign) -> dict[str, float]:
    return {
        "screw": math.pi * design.screw.minor_diameter_mm ** 2 / 4.0,
        "roller": math.pi * design.roller.minor_diameter_mm ** 2 / 4.0,
        "nut": math.pi * (design.nut.outer_diameter_mm ** 2 - design.nut.major_diameter_mm ** 2) / 4.0,
    }


def build_model(design: PRSDesign) -> LoadModel:
    """Compliances of a design (contact geometry from the contact solver)."""
    from .contact import contact_point, theoretical_screw

    prof = ThreadProfiles.from_design(design)
    mats = design.materials
    beta = design.thread.beta
    p = design.thread.pitch_mm
    z = design.roller.count
    theo = theoretical_screw(design)
    c_rs = contact_point(design, "screw", "upper", theo.profile)
    c_nr = contact_point(design, "nut", "lower")
    rt = design.roller.arc_radius_mm
    sb = math.sin(beta)
    eta_rs = (1 - mats.roller.poisson_ratio ** 2) / mats.roller.youngs_modulus_mpa + \
        (1 - mats.screw.poisson_ratio ** 2) / mats.screw.youngs_modulus_mpa
    eta_nr = (1 - mats.roller.poisson_ratio ** 2) / mats.roller.youngs_modulus_mpa + \
        (1 - mats.nut.poisson_ratio ** 2) / mats.nut.youngs_modulus_mpa
    C_rs, h_rs = hertz_constant((1 / rt, 1 / rt, 0.0, sb / c_rs.part_radius_mm), eta_rs)
    C_nr, h_nr = hertz_constant((1 / rt, 1 / rt, 0.0, -sb / c_nr.part_radius_mm), eta_nr)
    nz_rs, nz_nr = abs(c_rs.normal[2]), abs(c_nr.normal[2])
    hertz_rs = C_rs * nz_rs ** (-5.0 / 3.0)
    hertz_nr = C_nr * nz_nr ** (-5.0 / 3.0)

    def tooth(part: str, r_c: float, width: float, profile) -> tuple[float, dict[str, float]]:
        b = 2.0 * float(profile.tooth_half_width(r_c))
        c = abs(r_c - profile.root_radius)
        a = b + 2.0 * c * math.tan(beta)
        mat = getattr(mats, part)
        terms = yamamoto_compliance(beta, a, b, c, p, 2 * profile.pitch_radius, mat.youngs_modulus_mpa,
                                    mat.poisson_ratio,
                                    design.nut.outer_diameter_mm if part == "nut" else None)
        return sum(terms.values()) / width, {"a_mm": a, "b_mm": b, "c_mm": c, "width_mm": width,
                                             **{k: v / width for k, v in terms.items()}}

    t_s, d_s = tooth("screw", c_rs.part_radius_mm, math.pi * 2 * theo.profile.pitch_radius / z, theo.profile)
    t_rs_r, d_rs_r = tooth("roller", c_rs.roller_radius_mm, math.pi * design.roller.pitch_diameter_mm, prof.roller)
    t_nr_r, d_nr_r = tooth("roller", c_nr.roller_radius_mm, math.pi * design.roller.pitch_diameter_mm, prof.roller)
    t_n, d_n = tooth("nut", c_nr.part_radius_mm, math.pi * design.nut.pitch_diameter_mm / z, prof.nut)
    A = _section_areas(design)
    inst = design.loading.installation
    return LoadModel(
        n=design.thread.engaged_teeth, z=z, pitch=p,
        sign_screw=1 if inst == "tension-compression" else -1,
        hertz_nr=hertz_nr, hertz_rs=hertz_rs, tooth_nr=t_nr_r + t_n, tooth_rs=t_rs_r + t_s,
        body_screw=p / (mats.screw.youngs_modulus_mpa * A["screw"]),
        body_roller=p / (mats.roller.youngs_modulus_mpa * A["roller"]),
        body_nut=p / (mats.nut.youngs_modulus_mpa * A["nut"]),
        details={"hertz_rs": {**h_rs, "normal_axial_component": nz_rs, "C_normal": C_rs},
                 "hertz_nr": {**h_nr, "normal_axial_component": nz_nr, "C_normal": C_nr},
                 "tooth_screw": d_s, "tooth_roller_screw_side": d_rs_r,
                 "tooth_roller_nut_side": d_nr_r, "tooth_nut": d_n, "section_areas_mm2": A},
    )


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


def gap_terms(design: PRSDesign, roller: Sequence[float] | None = None,
              nut: Sequence[float] | None = None) -> tuple[NDArray, NDArray]:
    """Cumulative initial gaps g_j = sum_{k<j} (p_r,k - p_n,k) and
    g'_j = sum_{k<j} (p_s - p_r,k), as differences (full precision), mm."""
    p = design.thread.pitch_mm
    pr = np.asarray(roller if roller is not None else design.pitch_list("roller"), dtype=np.float64)
    pn = np.asarray(nut if nut is not None else design.pitch_list("nut"), dtype=np.float64)
    g_nr = np.concatenate([[0.0], np.cumsum((pr - p) - (pn - p))])
    g_rs = np.concatenate([[0.0], np.cumsum(-(pr - p))])
    return g_nr, g_rs


def solve_loads(model: LoadModel, load: float, g_nr: NDArray, g_rs: NDArray,
                linear_at: float | None = None, tol: float = 1e-13, max_iter: int = 100) -> LoadResult:
    """Tooth loads for axial load ``load`` (N) and initial gaps (mm).

    Unknowns: f_nr, f_rs and the tooth-1 approaches a_n, a_s; equations
    D(f_j) = a - g_j - S_j(f) per side and the two equilibria; Newton with the analytic
    Jacobian inside an active set (a tooth whose gap stays open carries no load).
    ``linear_at`` replaces the Hertz law by its tangent at that tooth load (N): the linear
    model B f = x of DOMAIN.md section 4.
    """
    n, z = model.n, model.z
    Snr, Srs = model.body_matrices()
    share = load / z
    f = np.full(2 * n, share / n)
    a = np.array([float(model.deflection("nr", share / n)), float(model.deflection("rs", share / n))])
    active = np.ones(2 * n, bool)
    g = np.concatenate([g_nr, g_rs])
    S = np.vstack([Snr, Srs])

    def D(x: NDArray) -> tuple[NDArray, NDArray]:
        if linear_at is None:
            d = np.concatenate([model.deflection("nr", x[:n]), model.deflection("rs", x[n:])])
            s = np.concatenate([model.deflection_slope("nr", np.maximum(x[:n], 1e-300)),
                                model.deflection_slope("rs", np.maximum(x[n:], 1e-300))])
        else:
            k = np.concatenate([np.full(n, model.deflection_slope("nr", linear_at)),
                                np.full(n, model.deflection_slope("rs", linear_at))])
            d0 = np.concatenate([np.full(n, model.deflection("nr", linear_at)),
                                 np.full(n, model.deflection("rs", linear_at))])
            d, s = d0 + k * (x - linear_at), k
        return d, s

    total_iter = 0
    for _ in range(2 * n + 2):
        for it in range(max_iter):
            total_iter += 1
            d, s = D(f)
            a_vec = np.concatenate([np.full(n, a[0]), np.full(n, a[1])])
            R = np.where(active, d - a_vec + g + S @ f, f)
            R = np.concatenate([R, [f[:n].sum() - share, f[n:].sum() - share]])
            J = np.zeros((2 * n + 2, 2 * n + 2))
            J[:2 * n, :2 * n] = np.where(active[:, None], S + np.diag(s), np.eye(2 * n))
            J[:n, 2 * n] = np.where(active[:n], -1.0, 0.0)
            J[n:2 * n, 2 * n + 1] = np.where(active[n:], -1.0, 0.0)
            J[2 * n, :n] = 1.0
            J[2 * n + 1, n:] = 1.0
            dx = np.linalg.solve(J, -R)
            f_new = f + dx[:2 * n]
            # a contact cannot pull: a tooth whose load would go negative leaves the active
            # set at once (the outer loop brings it back if its gap closes again)
            neg = active & (f_new <= 0)
            if np.any(neg):
                active = active & ~neg
                if not active[:n].any() or not active[n:].any():
                    raise ConvergenceError("no tooth in contact on one side")
                f = np.where(active, np.maximum(f_new, 1e-6 * share / n), 0.0)
                a = a + dx[2 * n:]
                continue
            f = f_new
            a = a + dx[2 * n:]
            if np.max(np.abs(dx[:2 * n])) <= tol * share and \
                    np.max(np.abs(dx[2 * n:])) <= tol * max(1.0, np.max(np.abs(a))):
                break
        else:
            raise ConvergenceError(f"tooth-load Newton did not converge in {max_iter} iterations "
                                   f"at {load} N")
        # active-set update: drop teeth pulled into tension, add teeth whose gap closed
        a_vec = np.concatenate([np.full(n, a[0]), np.full(n, a[1])])
        closure = a_vec - g - S @ f
        new_active = np.where(active, f > 0, closure > 1e-15)
        if np.array_equal(new_active, active):
            if not np.all(np.isfinite(f)):
                raise ConvergenceError("tooth-load solution is not finite")
            f = np.where(active, f, 0.0)
            return LoadResult(load, f[:n].copy(), f[n:].copy(), float(a[0]), float(a[1]),
                              total_iter, active[:n].copy(), active[n:].copy())
        active = new_active
        if not active[:n].any() or not active[n:].any():
            raise ConvergenceError("no tooth in contact on one side")
        f = np.where(active, np.maximum(f, share / n * 1e-3), 0.0)
    raise ConvergenceError("tooth-load active set did not settle")


def forward(design: PRSDesign, load: float | None = None, model: LoadModel | None = None,
            roller: Sequence[float] | None = None, nut: Sequence[float] | None = None,
            linear_at: float | None = None) -> LoadResult:
    """Tooth loads of ``design`` (or with other pitch lists) at ``load`` (N, default design load)."""
    model = model or build_model(design)
    g_nr, g_rs = gap_terms(design, roller, nut)
    return solve_loads(model, design.loading.axial_load_n if load is None else load, g_nr, g_rs,
                       linear_at=linear_at)


def axial_stiffness(design: PRSDesign, model: LoadModel | None = None, load: float | None = None) -> dict[str, float]:
    """Secant F0 / delta and tangent dF/d delta axial stiffness of the engaged threads (N/um)."""
    model = model or build_model(design)
    F = design.loading.axial_load_n if load is None else load
    r = forward(design, F, model)
    r2 = forward(design, F * 1.001, model)
    return {"secant_N_per_um": F / r.axial_deflection_mm / 1e3,
            "tangent_N_per_um": (0.001 * F) / (r2.axial_deflection_mm - r.axial_deflection_mm) / 1e3,
            "axial_deflection_um": r.axial_deflection_mm * 1e3}


# --------------------------------------------------------------------------- inverse
@dataclass(frozen=True)
class PitchDesign:
    roller_mm: tuple[float, ...]
    nut_mm: tuple[float, ...]
    screw_mm: float
    target_nr: NDArray
    target_rs: NDArray


def design_pitches(design: PRSDesign, target_nr: Sequence[float] | None = None,
                   target_rs: Sequence[float] | None = None, model: LoadModel | None = None) -> PitchDesign:
    """Pitch lists of roller and nut that give the target coefficients at the design load.

    Targets are load-distribution coefficients per tooth (mean 1; None = equal). The tooth
    loads are fixed by the target, so the compatibility equations give the pitch
    differences directly: x = B f (DOMAIN.md section 4).
    """
    model = model or build_model(design)
    n, z = model.n, model.z
    F0 = design.loading.axial_load_n
    mean = F0 / (n * z)
    t_nr = np.ones(n) if target_nr is None else np.asarray(target_nr, dtype=np.float64)
    t_rs = np.ones(n) if target_rs is None else np.asarray(target_rs, dtype=np.float64)
    for name, t in (("target.nut_roller", t_nr), ("target.roller_screw", t_rs)):
        if t.shape != (n,):
            raise DesignError(name, list(t), f"must have engaged_teeth = {n} coefficients")
        if not np.all(np.isfinite(t)) or np.any(t <= 0):
            raise DesignError(name, list(t), "coefficients must be finite and > 0")
        if abs(t.mean() - 1.0) > 1e-9:
            raise DesignError(name, list(t), f"coefficients must average 1 (mean is {t.mean():.12g})")
    f = np.concatenate([t_nr, t_rs]) * mean
    Snr, Srs = model.body_matrices()
    # per-tooth body terms d_j = S_{j+1} - S_j
    body_nr = np.diff(Snr @ f)
    body_rs = np.diff(Srs @ f)
    D_nr = model.deflection("nr", f[:n])
    D_rs = model.deflection("rs", f[n:])
    p = design.thread.pitch_mm
    # D_j - D_{j+1} = body_j + (gap step):  gap step nr = p_r - p_n, rs = p_s - p_r
    step_rs = (D_rs[:-1] - D_rs[1:]) - body_rs      # p_s - p_r,j
    step_nr = (D_nr[:-1] - D_nr[1:]) - body_nr      # p_r,j - p_n,j
    corr_r = -step_rs                                # p_r,j - p  (p_s = p)
    corr_n = corr_r - step_nr                        # p_n,j - p
    return PitchDesign(tuple(float(p + c) for c in corr_r), tuple(float(p + c) for c in corr_n),
                       p, t_nr, t_rs)


def closed_form_equal_load(design: PRSDesign) -> tuple[NDArray, NDArray]:
    """The equal-load corrections p_r,j - p and p_n,j - p (mm) in closed form (module doc)."""
    n = design.thread.engaged_teeth
    p = design.thread.pitch_mm
    F0 = design.loading.axial_load_n
    A = _section_areas(design)
    Es, En = design.materials.screw.youngs_modulus_mpa, design.materials.nut.youngs_modulus_mpa
    j = np.arange(1, n)
    if design.loading.installation == "tension-compression":
        cr = F0 * p * (n - j) / (n * Es * A["screw"])
    else:
        cr = -F0 * p * j / (n * Es * A["screw"])
    cn = cr + F0 * p * (n - j) / (n * En * A["nut"])
    return cr, cn


def with_pitch_lists(design: PRSDesign, pd: PitchDesign, name: str | None = None) -> PRSDesign:
    """A new design carrying the designed pitch lists."""
    return design.with_changes(
        name=name or design.name,
        roller=replace(design.roller, pitch_list_mm=pd.roller_mm),
        nut=replace(design.nut, pitch_list_mm=pd.nut_mm),
    )


# --------------------------------------------------------------------------- reports
def off_design(design: PRSDesign, fractions: Sequence[float] = (0.25, 0.5, 1.0, 1.5),
               model: LoadModel | None = None) -> list[dict[str, Any]]:
    """Coefficients of the design's pitch lists at other loads."""
    model = model or build_model(design)
    out = []
    for fr in fractions:
        r = forward(design, fr * design.loading.axial_load_n, model)
        out.append({"load_fraction": fr, "load_N": fr * design.loading.axial_load_n,
                    "ldc_nut_roller": r.ldc_nr.tolist(), "ldc_roller_screw": r.ldc_rs.tolist(),
                    "max_ldc": float(max(r.ldc_nr.max(), r.ldc_rs.max())),
                    "teeth_out_of_contact": int((~r.active_nr).sum() + (~r.active_rs).sum())})
    return out


def pitch_error_sensitivity(design: PRSDesign, error_mm: float = 1e-3,
                            model: LoadModel | None = None) -> dict[str, Any]:
    """Largest change of any coefficient when one roller or nut pitch is off by ``error_mm``."""
    model = model or build_model(design)
    base = forward(design, model=model)
    pr = np.array(design.pitch_list("roller"))
    pn = np.array(design.pitch_list("nut"))
    worst = {"roller": (0.0, 0), "nut": (0.0, 0)}
    for part in ("roller", "nut"):
        for j in range(len(pr)):
            r2, n2 = pr.copy(), pn.copy()
            (r2 if part == "roller" else n2)[j] += error_mm
            res = forward(design, model=model, roller=r2, nut=n2)
            dl = max(np.abs(res.ldc_nr - base.ldc_nr).max(), np.abs(res.ldc_rs - base.ldc_rs).max())
            if dl > worst[part][0]:
                worst[part] = (float(dl), j + 1)
    return {"pitch_error_um": error_mm * 1e3,
            **{f"max_ldc_change_{k}": v[0] for k, v in worst.items()},
            **{f"worst_pitch_index_{k}": v[1] for k, v in worst.items()}}


def loads_report(design: PRSDesign, model: LoadModel | None = None) -> dict[str, Any]:
    """The ``loads`` section of report.json."""
    model = model or build_model(design)
    r = forward(design, model=model)
    const = design.with_changes(roller=replace(design.roller, pitch_list_mm=None),
                                nut=replace(design.nut, pitch_list_mm=None))
    rc = forward(const, model=model)
    lin = forward(design, model=model, linear_at=r.mean)
    stiffness = axial_stiffness(design, model)
    return {
        "design_load_N": design.loading.axial_load_n,
        "installation": design.loading.installation,
        "ldc_nut_roller": r.ldc_nr.tolist(),
        "ldc_roller_screw": r.ldc_rs.tolist(),
        "max_ldc": float(max(r.ldc_nr.max(), r.ldc_rs.max())),
        "tooth_loads_N": {"nut_roller": r.f_nr.tolist(), "roller_screw": r.f_rs.tolist()},
        "teeth_out_of_contact": int((~r.active_nr).sum() + (~r.active_rs).sum()),
        "axial_stiffness_N_per_um": stiffness["secant_N_per_um"],
        "axial_stiffness": stiffness,
        "constant_pitch": {"ldc_nut_roller": rc.ldc_nr.tolist(), "ldc_roller_screw": rc.ldc_rs.tolist(),
                           "max_ldc": float(max(rc.ldc_nr.max(), rc.ldc_rs.max()))},
        "linear_model": {"ldc_nut_roller": lin.ldc_nr.tolist(), "ldc_roller_screw": lin.ldc_rs.tolist(),
                         "linearised_at_N": r.mean},
        "off_design": off_design(design, model=model),
        "sensitivity": pitch_error_sensitivity(design, model=model),
        "compliances": {"hertz_nr_mm_per_N2/3": model.hertz_nr, "hertz_rs_mm_per_N2/3": model.hertz_rs,
                        "tooth_nr_mm_per_N": model.tooth_nr, "tooth_rs_mm_per_N": model.tooth_rs,
                        "body_screw_mm_per_N": model.body_screw, "body_roller_mm_per_N": model.body_roller,
                        "body_nut_mm_per_N": model.body_nut, "details": model.details},
        "solver_iterations": r.iterations,
    }
