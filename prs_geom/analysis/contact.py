"""Analytic contact points of screw-roller and roller-nut (docs/theory/contact.md).

Pure math, no I/O. All computations in the right-hand screw frame (z along the axis);
results for a left-hand design are the mirror image y -> -y (angles change sign).

Flank surfaces
--------------
A flank of part i in its own frame, at polar coordinates (r, theta):

    Z(r, theta) = W(m + L theta / 2 pi) + xi t(r)

m the helix coordinate of the tooth at theta = 0, W the graded-pitch warp
(:mod:`prs_geom.helix`), t the axial tooth half-width (:mod:`prs_geom.profiles`), xi = +1
for the tooth's upper flank (facing +z), -1 for its lower flank.

Which flanks touch: the roller tooth's *upper* flank touches the *lower* flank of the
screw (or nut) tooth above it ("upper contact"); the roller's lower flank touches the upper
flank of the tooth below ("lower contact"). The two are mirror images (rotation by pi about
the line of centres): equal radii and gap, opposite angles.

Angles reported: the screw or nut angle theta of the contact from the line of centres
(screw axis -> roller axis), positive in the right-hand sense about +z; the roller angle
phi in the roller frame from the direction pointing away from the screw axis, so screw-side
contacts lie near 180 deg and nut-side contacts near 0 deg.

Method 1 (``solve_collinear``): unknowns r, theta (screw or nut) and rho, phi (roller); the
points coincide in x and y and the surface gradients (dZ/dx, dZ/dy) are equal, i.e. the
unit normals are collinear. Newton-Raphson with the analytic Jacobian, vectorised over any
number of contacts. The axial mismatch at the solution is the gap, positive = clearance.

Method 2 (``solve_gap_stationary``): the stationary point of the axial gap function
g(x, y) = Z_A(x, y) - Z_B(x, y) in Cartesian coordinates, found by scipy's hybrid root
finder with its own finite-difference Jacobian. Used to cross-check method 1.

The screw's theoretical pitch radius (``theoretical_screw``) keeps the centre distance and
the screw's lead angle at its nominal radius, and lowers the pitch radius in the profile
h_s(r) = p cos(lambda_s)/4 + tan(beta)(r - r_s) until the gap equals the design clearance.
With lambda_s held, a change of r_s is a pure axial shift of the flank, so the contact
point does not move and the iteration converges in one or two secant steps.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy import optimize

from prs_geom.geometry.frames import FIRST_MID_PITCHES, carrier_angles, part_warps, roller_spin
from prs_geom.model.design import PRSDesign
from prs_geom.model.errors import ConvergenceError
from prs_geom.geometry.helix import PitchWarp
from prs_geom.geometry.profiles import ThreadProfile, ThreadProfiles

__all__ = ["PartFlanks", "ContactBatch", "NewtonResult", "solve_collinear", "solve_gap_stationary",
           "euclidean_distance", "part_flanks", "tooth_contacts", "ContactPoint", "contact_point",
           "TheoreticalScrew", "corrected_screw_profile", "theoretical_screw", "tooth_gaps",
           "ContactResult", "analyse_contact"]

TWO_PI = 2.0 * math.pi


# --------------------------------------------------------------------------- surfaces
@dataclass(frozen=True)
class PartFlanks:
    """The flank surfaces of one part (profile + warp); per-contact tooth data is passed
    as arrays (helix coordinate m, side xi)."""

    profile: ThreadProfile
    warp: PitchWarp

    def z_derivatives(self, r: NDArray, th: NDArray, m: NDArray, xi: NDArray):
        """Z, Z_r, Z_theta, Z_rr, Z_thth (Z_rtheta = 0) at (r, theta), vectorised."""
        prof, w = self.profile, self.warp
        k = prof.lead / TWO_PI
        arg = m + k * th
        Z = w(arg) + xi * prof.tooth_half_width(r)
        Zr = xi * prof.tooth_half_width_slope(r)
        Zrr = xi * prof.tooth_half_width_curvature(r)
        Zt = (1.0 + w.correction_slope(arg)) * k
        Ztt = w.correction_curvature(arg) * k * k
        return Z, Zr, Zt, Zrr, Ztt


def _grad_local(r, th, Zr, Zt, Zrr, Ztt):
    """(dZ/dx, dZ/dy) in the part frame and their derivatives w.r.t. r and theta."""
    c, s = np.cos(th), np.sin(th)
    gx = Zr * c - Zt * s / r
    gy = Zr * s + Zt * c / r
    gx_r = Zrr * c + Zt * s / r ** 2
    gx_t = -Zr * s - Ztt * s / r - Zt * c / r
    gy_r = Zrr * s - Zt * c / r ** 2
    gy_t = Zr * c + Ztt * c / r - Zt * s / r
    return gx, gy, gx_r, gx_t, gy_r, gy_t


@dataclass
class ContactBatch:
    """N contacts between a screw-or-nut flank (A, screw frame) and a roller flank (B).

    Arrays of length N: ``m_a``, ``xi_a``, ``m_b``, ``xi_b`` (tooth helix coordinates and
    sides); ``ox``, ``oy`` roller axis position; ``alpha`` roller frame orientation
    (carrier angle + spin); ``z_offset`` an extra axial shift of the roller (mm, for
    verification at a known separation).
    """

    A: PartFlanks
    B: PartFlanks
    m_a: NDArray
    xi_a: NDArray
    m_b: NDArray
    xi_b: NDArray
    ox: NDArray
    oy: NDArray
    alpha: NDArray
    z_offset: NDArray

    @property
    def n(self) -> int:
        return len(self.m_a)

    def points(self, q: NDArray) -> tuple[NDArray, NDArray]:
        """World points (N, 3) on A and B for parameters q = (r, theta, rho, phi)."""
        r, th, rho, ph = q.T
        Za = self.A.z_derivatives(r, th, self.m_a, self.xi_a)[0]
        Zb = self.B.z_derivatives(rho, ph, self.m_b, self.xi_b)[0] + self.z_offset
        pa = np.column_stack([r * np.cos(th), r * np.sin(th), Za])
        pb = np.column_stack([self.ox + rho * np.cos(ph + self.alpha),
                              self.oy + rho * np.sin(ph + self.alpha), Zb])
        return pa, pb

    def normals(self, q: NDArray) -> tuple[NDArray, NDArray]:
        """Unit normals (N, 3) of A and B, oriented with +z component."""
        r, th, rho, ph = q.T
        _, Zr, Zt, Zrr, Ztt = self.A.z_derivatives(r, th, self.m_a, self.xi_a)
        gxa, gya = _grad_local(r, th, Zr, Zt, Zrr, Ztt)[:2]
        _, Zr, Zt, Zrr, Ztt = self.B.z_derivatives(rho, ph, self.m_b, self.xi_b)
        gxl, gyl = _grad_local(rho, ph, Zr, Zt, Zrr, Ztt)[:2]
        ca, sa = np.cos(self.alpha), np.sin(self.alpha)
        gxb, gyb = ca * gxl - sa * gyl, sa * gxl + ca * gyl
        na = np.column_stack([-gxa, -gya, np.ones_like(gxa)])
        nb = np.column_stack([-gxb, -gyb, np.ones_like(gxb)])
        return na / np.linalg.norm(na, axis=1)[:, None], nb / np.linalg.norm(nb, axis=1)[:, None]

    def residual_and_jacobian(self, q: NDArray) -> tuple[NDArray, NDArray]:
        r, th, rho, ph = q.T
        _, Zr, Zt, Zrr, Ztt = self.A.z_derivatives(r, th, self.m_a, self.xi_a)
        gxa, gya, gxa_r, gxa_t, gya_r, gya_t = _grad_local(r, th, Zr, Zt, Zrr, Ztt)
        _, Zr, Zt, Zrr, Ztt = self.B.z_derivatives(rho, ph, self.m_b, self.xi_b)
        gxl, gyl, gxl_r, gxl_t, gyl_r, gyl_t = _grad_local(rho, ph, Zr, Zt, Zrr, Ztt)
        ca, sa = np.cos(self.alpha), np.sin(self.alpha)
        rot = lambda x, y: (ca * x - sa * y, sa * x + ca * y)  # noqa: E731
        gxb, gyb = rot(gxl, gyl)
        gxb_r, gyb_r = rot(gxl_r, gyl_r)
        gxb_t, gyb_t = rot(gxl_t, gyl_t)
        c, s = np.cos(th), np.sin(th)
        cb, sb = np.cos(ph + self.alpha), np.sin(ph + self.alpha)
        F = np.column_stack([
            r * c - (self.ox + rho * cb),
            r * s - (self.oy + rho * sb),
            gxa - gxb,
            gya - gyb,
        ])
        J = np.zeros((self.n, 4, 4))
        J[:, 0, 0], J[:, 0, 1], J[:, 0, 2], J[:, 0, 3] = c, -r * s, -cb, rho * sb
        J[:, 1, 0], J[:, 1, 1], J[:, 1, 2], J[:, 1, 3] = s, r * c, -sb, -rho * cb
        J[:, 2, 0], J[:, 2, 1], J[:, 2, 2], J[:, 2, 3] = gxa_r, gxa_t, -gxb_r, -gxb_t
        J[:, 3, 0], J[:, 3, 1], J[:, 3, 2], J[:, 3, 3] = gya_r, gya_t, -gyb_r, -gyb_t
        return F, J

    def gap(self, q: NDArray) -> NDArray:
        """Axial gap at the solution (mm), positive = clearance (sign of the roller flank side)."""
        pa, pb = self.points(q)
        return self.xi_b * (pa[:, 2] - pb[:, 2])


# --------------------------------------------------------------------------- method 1
@dataclass
class NewtonResult:
    q: NDArray            # (N, 4): r, theta, rho, phi
    gap: NDArray          # (N,) axial gap, mm
    residual: NDArray     # (N,) max |F| at the end
    iterations: int


def solve_collinear(batch: ContactBatch, q0: NDArray, tol: float = 1e-14, max_iter: int = 50) -> NewtonResult:
    """Newton-Raphson on the collinear-normal equations, all contacts at once.

    Raises :class:`ConvergenceError` if any contact has not converged (no numbers are
    returned for a batch that did not converge).
    """
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        return _newton(batch, q0, tol, max_iter)


def _newton(batch: ContactBatch, q0: NDArray, tol: float, max_iter: int) -> NewtonResult:
    q = np.array(q0, dtype=np.float64)
    for it in range(1, max_iter + 1):
        F, J = batch.residual_and_jacobian(q)
        try:
            dq = np.linalg.solve(J, -F[..., None])[..., 0]
        except np.linalg.LinAlgError as exc:
            raise ConvergenceError(f"contact Newton: singular Jacobian at iteration {it}") from exc
        q += dq
        if np.all(np.abs(dq) <= tol * np.maximum(1.0, np.abs(q))):
            F, _ = batch.residual_and_jacobian(q)
            return NewtonResult(q, batch.gap(q), np.abs(F).max(axis=1), it)
        if not np.all(np.isfinite(q)):
            break
    F, _ = batch.residual_and_jacobian(q)
    bad = int(np.sum(~np.isfinite(F).all(axis=1) | (np.abs(F).max(axis=1) > 1e-9)))
    raise ConvergenceError(f"contact Newton did not converge in {max_iter} iterations "
                           f"({bad} of {batch.n} contacts)")


# --------------------------------------------------------------------------- method 2
def solve_gap_stationary(batch: ContactBatch, xy0: NDArray, theta0: NDArray, phi0: NDArray) -> NDArray:
    """Stationary points (x, y) of g(x, y) = Z_A - Z_B, one scipy root solve per contact.

    theta0/phi0 only pick the branch of the polar angles (continuous near the start).
    Returns (N, 3): x, y and the axial gap (positive = clearance).
    """
    out = np.empty((batch.n, 3))
    with np.errstate(invalid="ignore", divide="ignore"):
        for i in range(batch.n):
            out[i] = _gap_stationary_one(batch, i, xy0, theta0, phi0)
    return out


def _gap_stationary_one(batch: ContactBatch, i: int, xy0: NDArray, theta0: NDArray, phi0: NDArray) -> NDArray:
    """Stationary point of the axial gap function for contact i (see solve_gap_stationary)."""
    sl = slice(i, i + 1)
    ox, oy, al = batch.ox[i], batch.oy[i], batch.alpha[i]

    def polar(x, y):
        r = math.hypot(x, y)
        th = theta0[i] + math.atan2(-x * math.sin(theta0[i]) + y * math.cos(theta0[i]),
                                    x * math.cos(theta0[i]) + y * math.sin(theta0[i]))
        lx, ly = x - ox, y - oy
        rho = math.hypot(lx, ly)
        ref = phi0[i] + al
        ph = phi0[i] + math.atan2(-lx * math.sin(ref) + ly * math.cos(ref),
                                  lx * math.cos(ref) + ly * math.sin(ref))
        return r, th, rho, ph

    def zs(v):
        r, th, rho, ph = polar(*v)
        za = batch.A.z_derivatives(np.array([r]), np.array([th]), batch.m_a[sl], batch.xi_a[sl])
        zb = batch.B.z_derivatives(np.array([rho]), np.array([ph]), batch.m_b[sl], batch.xi_b[sl])
        return r, th, rho, ph, za, zb

    def grad_g(v):
        r, th, rho, ph, za, zb = zs(v)
        _, Zr, Zt = za[0][0], za[1][0], za[2][0]
        gxa = Zr * math.cos(th) - Zt * math.sin(th) / r
        gya = Zr * math.sin(th) + Zt * math.cos(th) / r
        _, Zr, Zt = zb[0][0], zb[1][0], zb[2][0]
        a = ph + al
        gxb = Zr * math.cos(a) - Zt * math.sin(a) / rho
        gyb = Zr * math.sin(a) + Zt * math.cos(a) / rho
        return [gxa - gxb, gya - gyb]

    sol = optimize.root(grad_g, xy0[i], method="hybr", tol=1e-14)
    x = np.array(sol.x, dtype=np.float64)
    F = np.array(grad_g(x))
    # scipy's quasi-Newton can stall on a nearly flat gap function (|grad g| ~ 1e-9); polish
    # with Newton steps on a central-difference Jacobian: the root is that of the exact
    # residual, the difference Jacobian only sets the convergence rate
    for _ in range(20):
        if np.max(np.abs(F)) <= 1e-13:
            break
        h = 1e-6
        J = np.column_stack([(np.array(grad_g(x + e)) - np.array(grad_g(x - e))) / (2 * h)
                             for e in (np.array([h, 0.0]), np.array([0.0, h]))])
        x_new = x - np.linalg.solve(J, F)
        F_new = np.array(grad_g(x_new))
        if np.max(np.abs(F_new)) >= np.max(np.abs(F)):
            break
        x, F = x_new, F_new
    if np.max(np.abs(F)) > 1e-10:
        raise ConvergenceError(f"gap-function root did not converge: {sol.message} "
                               f"(|grad g| = {np.max(np.abs(F)):.3g})")
    r, th, rho, ph, za, zb = zs(x)
    return np.array([x[0], x[1], batch.xi_b[i] * (za[0][0] - (zb[0][0] + batch.z_offset[i]))])


# --------------------------------------------------------------------------- Euclidean
def euclidean_distance(batch: ContactBatch, q0: NDArray, tol: float = 1e-14,
                       max_iter: int = 50) -> tuple[NDArray, NDArray]:
    """Signed minimum Euclidean distance between the two flank surfaces near q0.

    Solves the common-normal equations: the normals of both surfaces are collinear and the
    vector P_A - P_B lies along them (for a clearance this is the minimum distance; for an
    interference, the depth along the common normal). Newton with the analytic Jacobian,
    started from the collinear-normal solution. Sign: positive = clearance.
    Returns (distance (N,), q (N, 4)).
    """
    q = np.array(q0, dtype=np.float64)
    for _ in range(max_iter):
        r, th, rho, ph = q.T
        Za, Zra, Zta, Zrra, Ztta = batch.A.z_derivatives(r, th, batch.m_a, batch.xi_a)
        gxa, gya, gxa_r, gxa_t, gya_r, gya_t = _grad_local(r, th, Zra, Zta, Zrra, Ztta)
        Zb, Zrb, Ztb, Zrrb, Zttb = batch.B.z_derivatives(rho, ph, batch.m_b, batch.xi_b)
        F_norm, J_norm = batch.residual_and_jacobian(q)
        a = ph + batch.alpha
        c, s, cb, sb = np.cos(th), np.sin(th), np.cos(a), np.sin(a)
        dx = r * c - batch.ox - rho * cb
        dy = r * s - batch.oy - rho * sb
        dz = Za - Zb - batch.z_offset
        # d/dq of (dx, dy, dz): columns r, theta, rho, phi
        Dx = np.column_stack([c, -r * s, -cb, rho * sb])
        Dy = np.column_stack([s, r * c, -sb, -rho * cb])
        Dz = np.column_stack([Zra, Zta, -Zrb, -Ztb])
        z0 = np.zeros_like(r)
        F = np.column_stack([dx + gxa * dz, dy + gya * dz, F_norm[:, 2], F_norm[:, 3]])
        J = np.empty((batch.n, 4, 4))
        J[:, 0] = Dx + gxa[:, None] * Dz + dz[:, None] * np.column_stack([gxa_r, gxa_t, z0, z0])
        J[:, 1] = Dy + gya[:, None] * Dz + dz[:, None] * np.column_stack([gya_r, gya_t, z0, z0])
        J[:, 2:] = J_norm[:, 2:]
        dq = np.linalg.solve(J, -F[..., None])[..., 0]
        q += dq
        if np.all(np.abs(dq) <= tol * np.maximum(1.0, np.abs(q))):
            pa, pb = batch.points(q)
            return np.sign(batch.gap(q)) * np.linalg.norm(pa - pb, axis=1), q
    raise ConvergenceError("Euclidean distance Newton did not converge")


# --------------------------------------------------------------------------- design level
def part_flanks(design: PRSDesign, screw_profile: ThreadProfile | None = None) -> dict[str, PartFlanks]:
    prof = ThreadProfiles.from_design(design)
    w = part_warps(design)
    # computed in the right-hand frame; a left-hand design is its mirror image
    right = lambda pr: replace(pr, hand_sign=1)  # noqa: E731
    return {
        "screw": PartFlanks(right(screw_profile or prof.screw), w["screw"]),
        "roller": PartFlanks(right(prof.roller), w["roller"]),
        "nut": PartFlanks(right(prof.nut), w["nut"]),
    }


def _grid(value: NDArray, base: float, p: float) -> NDArray:
    """The point of base + k p nearest value."""
    return base + p * np.round((value - base) / p)


def tooth_contacts(design: PRSDesign, side: str, flank: str, rollers: NDArray | None = None,
                   teeth: NDArray | None = None, screw_profile: ThreadProfile | None = None,
                   z_offset: float = 0.0) -> tuple[ContactBatch, NDArray, dict[str, NDArray]]:
    """The contact batch of roller tooth turns ``teeth`` (1..n) of ``rollers`` on ``side``
    ("screw" or "nut"), ``flank`` "upper" or "lower"; with the Newton start values.

    Roller tooth turn j has its mid-plane at W_r((j - 1/2) p) at the roller's local
    theta = 0 (teeth numbered from the loaded end). The screw or nut tooth it meets
    is the one whose mid-plane at the contact is nearest p/2 above (upper) or below (lower).
    """
    fl = part_flanks(design, screw_profile)
    p = design.thread.pitch_mm
    n = design.thread.engaged_teeth
    rollers = np.arange(design.roller.count) if rollers is None else np.asarray(rollers)
    teeth = np.arange(1, n + 1) if teeth is None else np.asarray(teeth)
    kk, jj = np.meshgrid(rollers, teeth, indexing="ij")
    kk, jj = kk.ravel(), jj.ravel()
    psi = carrier_angles(design)[kk]
    chi = np.array([roller_spin(design, a) for a in psi])
    alpha = psi + chi
    a = design.centre_distance_mm
    A = fl[side]
    B = fl["roller"]
    # local roller angle of the line of centres: toward the screw (pi) or the nut (0)
    phi_c = (math.pi if side == "screw" else 0.0) - chi
    phi_c = (phi_c + math.pi) % TWO_PI - math.pi
    m_b = (jj - 0.5) * p
    roller_mid_axial = m_b + B.profile.lead * phi_c / TWO_PI
    sgn = 1.0 if flank == "upper" else -1.0
    lead_a = A.profile.lead
    base_a = FIRST_MID_PITCHES[side] * p
    m_a = _grid(roller_mid_axial + sgn * 0.5 * p - lead_a * psi / TWO_PI, base_a, p)
    N = len(kk)
    batch = ContactBatch(A, B, m_a.astype(float), np.full(N, -sgn), m_b.astype(float), np.full(N, sgn),
                         a * np.cos(psi), a * np.sin(psi), alpha, np.full(N, float(z_offset)))
    r_a = A.profile.pitch_radius
    q0 = np.column_stack([np.full(N, r_a), psi, np.full(N, B.profile.pitch_radius), phi_c])
    return batch, q0, {"roller": kk, "tooth": jj, "psi": psi, "z_nominal": roller_mid_axial}


@dataclass(frozen=True)
class ContactPoint:
    """One contact, in the right-hand screw frame (mirror y for a left-hand design)."""

    side: str
    flank: str
    part_radius_mm: float
    part_angle_deg: float
    roller_radius_mm: float
    roller_angle_deg: float
    point_mm: tuple[float, float, float]
    normal: tuple[float, float, float]
    gap_mm: float
    residual: float
    iterations: int

    def as_dict(self) -> dict[str, Any]:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.__dict__.items()}


def contact_point(design: PRSDesign, side: str, flank: str = "upper",
                  screw_profile: ThreadProfile | None = None) -> ContactPoint:
    """The contact of roller 0, middle tooth, on ``side``; collinear-normal Newton."""
    n = design.thread.engaged_teeth
    batch, q0, _ = tooth_contacts(design, side, flank, rollers=np.array([0]),
                                  teeth=np.array([(n + 1) // 2]), screw_profile=screw_profile)
    res = solve_collinear(batch, q0)
    pa, _ = batch.points(res.q)
    na, _ = batch.normals(res.q)
    r, th, rho, ph = res.q[0]
    h = design.thread.hand_sign
    mirror = np.array([1.0, h, 1.0])
    wrap = lambda deg: (deg + 180.0) % 360.0 - 180.0  # noqa: E731
    return ContactPoint(side, flank, float(r), wrap(math.degrees(th)) * h, float(rho),
                        wrap(math.degrees(ph)) * h, tuple(map(float, pa[0] * mirror)),
                        tuple(map(float, na[0] * mirror)), float(res.gap[0]),
                        float(res.residual[0]), res.iterations)


@dataclass(frozen=True)
class TheoreticalScrew:
    nominal_pitch_diameter_mm: float
    theoretical_pitch_diameter_mm: float
    gap_at_nominal_mm: float
    gap_at_theoretical_mm: float
    iterations: int
    profile: ThreadProfile


def corrected_screw_profile(design: PRSDesign, pitch_radius: float) -> ThreadProfile:
    """The design's screw profile with another pitch radius and the nominal lead angle."""
    s = ThreadProfiles.from_design(design).screw
    return replace(s, pitch_radius=pitch_radius, lead_radius=s.pitch_radius)


def theoretical_screw(design: PRSDesign, max_iter: int = 30) -> TheoreticalScrew:
    """Screw pitch diameter giving the design clearance at the screw-roller contact
    (secant iteration on the pitch radius, centre distance fixed).

    The diameter is a property of the thread forms and the centre distance, not of the
    grading: it is computed on the design without its pitch lists, where every tooth of every
    roller meets the screw alike (roller 0's middle tooth stands for all). The graded teeth
    sit micrometres off those positions axially; the roller's axial float and the load model's
    gaps take that, and a diameter taken from one graded tooth would instead carry that tooth's
    cumulative shift into the screw (5.7 um on the default equal-load design).
    docs/theory/contact.md, "The theoretical diameter of a graded design"."""
    if design.graded:
        design = design.constant_pitch()
    target = design.contact.clearance_mm
    prec = design.contact.precision_mm
    r0 = 0.5 * design.screw.pitch_diameter_mm

    def gap(r: float) -> float:
        return contact_point(design, "screw", "upper", corrected_screw_profile(design, r)).gap_mm

    g0 = gap(r0)
    xs, gs = [r0], [g0]
    # first step from the flank slope: dgap/dr_s = -tan(beta) / cos(lambda_s)
    prof = ThreadProfiles.from_design(design).screw
    slope = -math.tan(prof.beta) / prof.cos_lead
    x = r0 + (target - g0) / slope
    for it in range(1, max_iter + 1):
        g = gap(x)
        xs.append(x)
        gs.append(g)
        if abs(g - target) <= prec:
            return TheoreticalScrew(2 * r0, 2 * x, g0, g, it, corrected_screw_profile(design, x))
        x = xs[-1] + (target - gs[-1]) * (xs[-1] - xs[-2]) / (gs[-1] - gs[-2])
    raise ConvergenceError(f"screw pitch diameter iteration did not reach the clearance "
                           f"{target} mm within {prec} mm in {max_iter} steps")


def tooth_gaps(design: PRSDesign, screw_profile: ThreadProfile | None = None) -> dict[str, Any]:
    """Unloaded gap at every tooth of every roller (signed minimum Euclidean distance
    between the two analytic flank surfaces, mm; negative = interference at the nominal
    axial position), per side and flank. ``settled`` subtracts the smallest gap of each
    roller and flank: the roller floats axially until its first tooth touches."""
    out: dict[str, Any] = {}
    for side in ("screw", "nut"):
        out[side] = {}
        for flank in ("upper", "lower"):
            batch, q0, info = tooth_contacts(design, side, flank, screw_profile=screw_profile)
            res = solve_collinear(batch, q0)
            dist, _ = euclidean_distance(batch, res.q)
            z, n = design.roller.count, design.thread.engaged_teeth
            g = dist.reshape(z, n)
            out[side][flank] = {"gap_mm": g.tolist(),
                                "settled_gap_mm": (g - g.min(axis=1, keepdims=True)).tolist()}
    return out


@dataclass(frozen=True)
class ContactResult:
    """The contact stage of a build, computed once and passed on.

    ``screw_roller`` holds the contacts ``upper_at_nominal``, ``lower_at_nominal``,
    ``upper_at_theoretical`` and ``lower_at_theoretical`` (roller 0, middle tooth);
    ``roller_nut`` holds ``upper`` and ``lower``; ``tooth_gaps`` the per-tooth gaps of a
    graded design (None for constant pitch). Every later stage takes the theoretical screw
    from here instead of solving it again.
    """

    design: PRSDesign
    theoretical: TheoreticalScrew
    screw_roller: dict[str, ContactPoint]
    roller_nut: dict[str, ContactPoint]
    interference_at_nominal_normal_mm: float
    tooth_gaps: dict[str, Any] | None

    @property
    def theoretical_screw_pitch_diameter_mm(self) -> float:
        """The screw pitch diameter that leaves the design clearance (mm)."""
        return self.theoretical.theoretical_pitch_diameter_mm

    @property
    def screw_profile(self) -> ThreadProfile:
        """The screw profile at the theoretical pitch diameter (nominal lead angle)."""
        return self.theoretical.profile

def analyse_contact(design: PRSDesign) -> ContactResult:
    """Contacts, the theoretical screw pitch diameter and (graded designs) the per-tooth
    gaps: the contact stage."""
    theo = theoretical_screw(design)
    sr = {f"{fl}_at_nominal": contact_point(design, "screw", fl) for fl in ("upper", "lower")}
    sr.update({f"{fl}_at_theoretical": contact_point(design, "screw", fl, theo.profile)
               for fl in ("upper", "lower")})
    batch, q0, _ = tooth_contacts(design, "screw", "upper", np.array([0]),
                                  np.array([(design.thread.engaged_teeth + 1) // 2]))
    res = solve_collinear(batch, q0)
    eu, _ = euclidean_distance(batch, res.q)
    rn = {fl: contact_point(design, "nut", fl) for fl in ("upper", "lower")}
    return ContactResult(design, theo, sr, rn, max(0.0, -float(eu[0])),
                         tooth_gaps(design, theo.profile) if design.graded else None)
