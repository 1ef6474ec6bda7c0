"""STEP export of the threaded parts as closed B-rep solids (optional extra ``step``).

This module owns the B-rep of each threaded part (screw, roller, nut) built from the
analytic thread surface, the checks that make the solid trustworthy (OpenCascade's
``BRepCheck_Analyzer``, the volume against the part's triangle mesh, the measured
deviation of the B-spline faces from the analytic surface) and the STEP AP214 file with one
named solid per part. OpenCascade comes from ``cadquery-ocp`` (module ``OCP``), imported
inside the functions only, so importing this module works without the extra; calling one
without it raises :class:`~prs_geom.model.errors.EnvironmentFailure` with the install
command. docs/step.md explains the construction, the tolerance and the limits.

Construction (no boolean at all)
--------------------------------
The thread surface of a part is cut into *bands*, one per piece of the axial profile of
every start: lower flank, crest, upper flank, root (from a tooth's upper root corner to the
next tooth's lower root corner, where graded-pitch teeth take up their pitch change, as in
:func:`prs_geom.mesh.thread.thread_mesh`). A band is parametrised by (v, z): v in [0, 1]
across the band (the radius on a flank, the axial offset on a crest, the blend between the
two root corners on a root), z the axial position itself. A point of a flank at radius r
and height z of the tooth with helix coordinate m_k at theta = 0 is

    theta = 2 pi (W^-1(z -+ t(r)) - m_k) / L,     (r cos theta, r sin theta, z)

(W the graded-pitch warp of :mod:`prs_geom.geometry.helix`, t the axial tooth half-width,
L the lead; right hand, a left-hand part is the mirror image y -> -y). Because z is a
surface parameter, every band ends *exactly* on the end planes z = z_lo and z = z_hi: no
trimming is needed, and the end faces are plane faces bounded by the bands' iso-curves
z = const. Each band is a B-spline surface of degree ``DEGREE`` interpolating a grid of
analytic points (tensor-product not-a-knot interpolation, done here with scipy so that the
knots are known and the iso-curves two bands share are the same curve). The grid is refined
until the deviation measured between the grid points (the exact distance in the axial
half-plane to the analytic profile, :func:`prs_geom.mesh.thread.profile_distance`) is
within the target (``DEVIATION_SHARE`` of the chord tolerance, tighter on small parts).
Each band is cut into faces of at most one turn (``TURNS_PER_FACE``). These faces, the end
faces, the nut's body cylinder and the five faces of the angular datum slot B
(:mod:`prs_geom.geometry.datum`, a rectangular hole in face A) are sewn into one shell
(``BRepBuilderAPI_Sewing``), made a solid and oriented outward.
"""
from __future__ import annotations

import contextlib
import math
import os
import secrets
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import BSpline, make_interp_spline

from prs_geom.model.errors import EnvironmentFailure

if TYPE_CHECKING:  # pragma: no cover
    from prs_geom.geometry.profiles import ThreadProfile
    from prs_geom.mesh.thread import ThreadMesh
    from prs_geom.model.design import PRSDesign

PARTS = ("screw", "roller", "nut")
#: Install command named by :class:`EnvironmentFailure` when OCP is missing.
INSTALL_HINT = 'pip install "prs-geom[step]"'
#: STEP schema written (``write.step.schema``): AP214 international standard.
STEP_SCHEMA = "AP214IS"
#: What the file header says about precision (FILE_DESCRIPTION).
AUTHORITY_NOTE = ("prs-geom B-rep of the analytic thread surfaces within the chord tolerance; "
                  "the machining sheet is the authority for sub-micrometre pitch grading")
#: Largest allowed deviation of a B-spline face from the analytic surface, as a share of
#: the chord tolerance: the B-rep should be far closer to the design than the mesh is.
DEVIATION_SHARE = 0.1
#: ... and at most this x (volume / area) of the part (mm), so that the B-rep's own volume
#: error (below the deviation x area / volume) stays under 1e-4 on small or coarse parts.
DEVIATION_VOLUME_SHARE = 1e-4
#: The reference mesh's tolerance is min(tol, this x (volume / area)): a mesh's inscribed
#: polygons lose c x tol x area / volume of the volume with c <= 0.35 measured over the
#: flank-angle range (0.33 on the default roller: 0.23 % at tol = 0.01 mm), so a mesh at the
#: design tolerance cannot judge a 0.1 % agreement; at 7.5e-4 V/A it loses at most 0.03 %.
MESH_REFERENCE_SHARE = 7.5e-4
#: Largest difference (mm) between the bounding box of a solid and of its copy read back
#: from the STEP file (on top of OCC's box gaps); measured: below 1e-12 mm.
REREAD_BBOX_TOLERANCE = 1e-6
#: Largest relative volume difference B-rep vs reference mesh that counts as valid.
VOLUME_REL_LIMIT = 1e-3
#: Sewing tolerance (mm): shared iso-curves are identical to rounding, so this only has to
#: absorb float64 noise, far below any tolerance a shop can see.
SEW_TOLERANCE = 1e-6
#: Degree of the B-spline faces in both directions: quintic needs about half the columns of
#: a cubic for the same deviation (fewer spans: faster checks, smaller files).
DEGREE = 5
#: Grid columns sampled beyond each end plane (see :func:`_fit_bands`).
EXTENSION = 3
#: Largest number of turns one thread face spans (the bands are cut into faces this long).
TURNS_PER_FACE = 1.0
#: Samples per knot span along z for the extent of the part (:func:`_sampled_bbox`).
SAMPLES_PER_SPAN = 32
#: Lower bound of the grid columns per turn along a strand, and the refinement limit.
MIN_SAMPLES_PER_TURN = 8
MAX_REFINEMENTS = 6
#: Largest overshoot (mm) of the faces' control points beyond the outer radius. CAD readers
#: take a fast bounding box from the B-spline poles, which stand outside a curved surface
#: by about 3 r (1 / cos(pi / n) - 1) for n columns per turn (measured: 0.053 mm on the
#: default screw at n = 60); more columns keep that box within this of the solid's.
POLE_OVERSHOOT_MM = 0.015


# --------------------------------------------------------------------------- results
@dataclass(frozen=True)
class StepSolid:
    """One part as a B-rep solid and the checks made on it.

    Attributes
    ----------
    part : str
        "screw", "roller" or "nut".
    shape : TopoDS_Shape or None
        The solid in the part frame (mm, z along the part axis, face A at the lower z),
        None when it could not be built at all.
    valid : bool
        True when ``BRepCheck_Analyzer`` accepts the shape, it is one closed solid, its
        volume agrees with the reference mesh within ``VOLUME_REL_LIMIT``, its B-spline
        faces stay within ``deviation_target_mm`` of the analytic surface and OCC holds
        the same surfaces as were fitted.
    reason : str
        Empty when valid, else what failed.
    volume_mm3 : float
        Volume of the B-rep (``BRepGProp``), datum slot cut (mm^3).
    mesh_volume_mm3 : float
        Volume of the part's triangle mesh with its datum slot
        (:func:`prs_geom.mesh.assembly.build_part` at ``mesh_tolerance_mm``) (mm^3).
    volume_rel_diff : float
        (volume_mm3 - mesh_volume_mm3) / mesh_volume_mm3.
    bbox : tuple of float
        (xmin, ymin, zmin, xmax, ymax, zmax) of the solid in the part frame (mm): its
        extent, sampled on the fitted faces (:func:`_sampled_bbox`, error about 1e-5 mm).
        NaN when no solid was built.
    build_time_s : float
        Wall time of the whole call: surfaces, sewing, slot, checks (s).
    faces : int
        Number of B-rep faces.
    chord_tolerance_mm : float
        The tolerance the part was built for (mm).
    mesh_tolerance_mm : float
        The chord tolerance of the reference mesh (mm).
    max_deviation_mm : float
        Largest measured distance of the B-spline faces from the analytic surface (mm).
    analytic_volume_mm3 : float or None
        Exact volume for constant pitch (closed form minus the slot), None when graded.
    design_mesh_volume_mm3 : float
        Volume of the part's mesh at the design tolerance ``chord_tolerance_mm`` (mm^3),
        for comparison: its inscribed polygons make it smaller by up to about 0.3 %.
    deviation_target_mm : float
        The deviation the B-spline faces were fitted to: min(``DEVIATION_SHARE`` x tol,
        ``DEVIATION_VOLUME_SHARE`` x volume / area) (mm).
    max_tolerance_mm : float
        Largest OpenCascade tolerance of a vertex, edge or face of the solid (mm): how
        closely the sewn topology fits together (1e-7, the minimum, on every part so far).
    grid : dict
        Sampling of the B-spline faces: degree, grid columns per turn and along the part,
        points across each band kind.
    """

    part: str
    shape: Any
    valid: bool
    reason: str
    volume_mm3: float
    mesh_volume_mm3: float
    volume_rel_diff: float
    bbox: tuple[float, float, float, float, float, float]
    build_time_s: float
    faces: int
    chord_tolerance_mm: float = 0.0
    mesh_tolerance_mm: float = 0.0
    max_deviation_mm: float = math.nan
    analytic_volume_mm3: float | None = None
    design_mesh_volume_mm3: float = math.nan
    deviation_target_mm: float = math.nan
    max_tolerance_mm: float = math.nan
    grid: dict[str, Any] = field(default_factory=dict)

    def report(self) -> dict[str, Any]:
        """The per-part entry of the report section ``step`` (JSON types only; a value that
        could not be measured is None)."""
        def num(x: float | None) -> float | None:
            return None if x is None or not math.isfinite(x) else float(x)

        return {
            "valid": self.valid,
            "reason": self.reason,
            "volume_mm3": num(self.volume_mm3),
            "mesh_volume_mm3": num(self.mesh_volume_mm3),
            "volume_rel_diff": num(self.volume_rel_diff),
            "analytic_volume_mm3": num(self.analytic_volume_mm3),
            "design_mesh_volume_mm3": num(self.design_mesh_volume_mm3),
            "faces": self.faces,
            "time_s": self.build_time_s,
            "chord_tolerance_mm": self.chord_tolerance_mm,
            "mesh_tolerance_mm": self.mesh_tolerance_mm,
            "max_deviation_mm": num(self.max_deviation_mm),
            "deviation_target_mm": num(self.deviation_target_mm),
            "max_tolerance_mm": num(self.max_tolerance_mm),
            "bbox_mm": [num(x) for x in self.bbox],
            "grid": dict(self.grid),
        }


# --------------------------------------------------------------------------- OCP
def require_ocp() -> None:
    """Raise :class:`EnvironmentFailure` with the install command when OCP is missing."""
    try:
        import OCP  # noqa: F401
    except ImportError:
        raise EnvironmentFailure("the STEP export needs OpenCascade (the optional extra 'step', "
                                 f"package cadquery-ocp), which is not installed: {INSTALL_HINT}") from None


# --------------------------------------------------------------------------- bands (numpy)
@dataclass(frozen=True)
class _Band:
    """A piece of the thread surface sampled on a (v, z) grid (right-hand part frame).

    ``points`` has shape (n_v, n_z, 3); row v = 0 and v = 1 lie on the band's bounding
    strands, column z = z_lo and z = z_hi on the end planes.
    """

    kind: str
    start: int
    v: NDArray[np.float64]
    z: NDArray[np.float64]
    points: NDArray[np.float64]


def _polar(r: NDArray, theta: NDArray, z: NDArray) -> NDArray[np.float64]:
    r, theta, z = np.broadcast_arrays(r, theta, z)
    return np.stack([r * np.cos(theta), r * np.sin(theta), z], axis=-1)


def _root_helix_coordinate(warp, z: NDArray, w: NDArray, t_root: float, pitch: float) -> NDArray:
    """m with (1 - w)(W(m) + t_r) + w (W(m + p) - t_r) = z: the point at fraction w across
    the root band between tooth m (upper root corner) and tooth m + p (lower root corner).

    Fixed point m <- z - (1 - 2w) t_r - w p - [(1 - w) c(m) + w c(m + p)], converging like
    :meth:`PitchWarp.inverse` (ratio max|c'|); exact at once for constant pitch.
    """
    base = z - (1.0 - 2.0 * w) * t_root - w * pitch
    if warp.is_identity:
        return base
    m = base.copy()
    for _ in range(60):
        m_new = base - ((1.0 - w) * warp.correction(m) + w * warp.correction(m + pitch))
        if np.max(np.abs(m_new - m), initial=0.0) <= 1e-15 * max(1.0, float(np.max(np.abs(z)))):
            return m_new
        m = m_new
    return m


def _bands(profile: "ThreadProfile", warp, first_mid: float, z: NDArray[np.float64],
           n_cross: dict[str, int]) -> list[_Band]:
    """All bands of the thread surface between z[0] and z[-1] (right-hand frame).

    Per start k (tooth with helix coordinate m_k = first_mid + k p at theta = 0): lower
    flank, crest, upper flank, root to tooth m_k + p; each band's v = 1 row is the next
    band's v = 0 row, computed once so that the shared iso-curves are identical.
    """
    L, p = profile.lead, profile.pitch
    rr, rc = profile.root_radius, profile.crest_radius
    two_pi = 2.0 * math.pi
    tr = float(profile.tooth_half_width(rr))
    tc = float(profile.tooth_half_width(rc))
    Z = z[None, :]

    def theta(u: NDArray, m_k: float) -> NDArray:
        # point at axial offset u from the mid-plane of the tooth m_k, at height z
        return two_pi * (warp.inverse(Z - u[:, None]) - m_k) / L

    out: list[_Band] = []
    vf = np.linspace(0.0, 1.0, n_cross["flank"])
    vc = np.linspace(0.0, 1.0, n_cross["crest"])
    vr = np.linspace(0.0, 1.0, n_cross["root"])
    r_f = rr + vf * (rc - rr)
    r_f[-1] = rc
    t_f = profile.tooth_half_width(r_f)
    t_f[0], t_f[-1] = tr, tc
    u_c = -tc + vc * 2.0 * tc
    u_c[-1] = tc
    for k in range(profile.starts):
        m_k = first_mid + k * p
        lower = _polar(r_f[:, None], theta(-t_f, m_k), Z)
        upper = _polar(r_f[::-1, None], theta(t_f[::-1], m_k), Z)
        crest = _polar(np.full((len(vc), 1), rc), theta(u_c, m_k), Z)
        crest[0], crest[-1] = lower[-1], upper[0]
        # root: between this tooth's upper root corner and the next tooth's lower one
        W_ = np.broadcast_to(vr[:, None], (len(vr), len(z)))
        m = _root_helix_coordinate(warp, np.broadcast_to(Z, W_.shape), W_, tr, p)
        root = _polar(np.full((len(vr), 1), rr), two_pi * (m - m_k) / L, Z)
        root[0] = upper[-1]
        out += [_Band("lower_flank", k, vf, z, lower), _Band("crest", k, vc, z, crest),
                _Band("upper_flank", k, vf, z, upper), _Band("root", k, vr, z, root)]
    # the last root band ends on start 0's lower root corner one lead on: the same curve
    # in 3D (theta - 2 pi), taken from start 0 so that the two rows are identical
    for k in range(profile.starts):
        nxt = out[4 * ((k + 1) % profile.starts)].points[0]
        out[4 * k + 3].points[-1] = nxt
    return out


# --------------------------------------------------------------------------- splines
@dataclass(frozen=True)
class _Net:
    """B-spline surface of degree ``DEGREE``: poles (n_v, n_z, 3), full knot vectors in v
    and z. In z it spans the extended grid; the face uses [z_lo, z_hi] of it."""

    poles: NDArray[np.float64]
    tv: NDArray[np.float64]
    tz: NDArray[np.float64]


def _interpolate(band: _Band) -> _Net:
    """Tensor-product not-a-knot interpolation of the band's grid, z then v.

    Across the band (v) the knots are clamped at the strands, so the v = 0 and v = 1 pole
    rows are the z-interpolations of the boundary data rows alone: two bands sharing a data
    row share the iso-curve exactly, which is what lets them sew at 1e-6 mm.
    """
    sz = make_interp_spline(band.z, band.points, k=DEGREE, axis=1, bc_type="not-a-knot")  # c: (n_z, n_v, 3)
    sv = make_interp_spline(band.v, sz.c, k=DEGREE, axis=1, bc_type="not-a-knot")         # c: (n_v, n_z, 3)
    return _Net(np.ascontiguousarray(sv.c), sv.t, sz.t)


def _evaluate(net: _Net, v: NDArray, z: NDArray) -> NDArray[np.float64]:
    """Points (len(v), len(z), 3) of the surface (scipy; the same polynomial as OCC's)."""
    # BSpline's ``axis`` names the coefficient axis of c (and of the result)
    along_v = BSpline(net.tv, net.poles, DEGREE, axis=0)(v)     # (nv_eval, n_z, 3): poles in z
    return BSpline(net.tz, along_v, DEGREE, axis=1)(z)          # (nv_eval, nz_eval, 3)


def _midpoints(x: NDArray) -> NDArray:
    return 0.5 * (x[1:] + x[:-1])


def _band_deviation(tm: "ThreadMesh", band: _Band, net: _Net) -> float:
    """Largest distance (mm) from the analytic profile (exact, in the axial half-plane:
    :func:`prs_geom.mesh.thread.profile_distance`) at the midpoints and quarter points of
    the grid cells between the end planes, where the interpolation error peaks, and along
    the band's two boundary strands between grid columns."""
    from prs_geom.mesh.thread import profile_distance

    # the boundary rows too: they are the edges the neighbouring faces share
    v = np.concatenate([_midpoints(band.v), 0.75 * band.v[:-1] + 0.25 * band.v[1:], band.v[[0, -1]]])
    zs = band.z[(band.z >= tm.z_lo) & (band.z <= tm.z_hi)]
    z = np.concatenate([_midpoints(zs), 0.75 * zs[:-1] + 0.25 * zs[1:]])
    P = _evaluate(net, v, z).reshape(-1, 3)
    r = np.hypot(P[:, 0], P[:, 1])
    th = np.arctan2(P[:, 1], P[:, 0])
    return float(profile_distance(tm, th, r, P[:, 2]).max(initial=0.0))


def _samples_per_turn(r_max: float, target: float) -> int:
    """Grid columns per turn along a strand for a degree-DEGREE interpolant of a circle of
    radius r_max: error about C r_max h^(DEGREE + 1), C = 2e-3 measured for DEGREE = 5
    (quintic, default roller: 1.7e-5 mm at 12 columns per turn) with a factor 2 margin; and
    enough columns to keep the control points within ``POLE_OVERSHOOT_MM`` of the surface."""
    h = (0.5 * target / (2e-3 * r_max)) ** (1.0 / (DEGREE + 1))
    poles = math.pi / math.acos(1.0 / (1.0 + POLE_OVERSHOOT_MM / (3.0 * r_max)))
    return max(MIN_SAMPLES_PER_TURN, int(math.ceil(2.0 * math.pi / h)), int(math.ceil(poles)))


def _cross_counts(profile: "ThreadProfile", per_turn: int) -> dict[str, int]:
    """Points across each band kind: the angle the band sweeps at fixed z divided by the
    angular step of the grid, plus one, at least DEGREE + 2."""
    L, p = profile.lead, profile.pitch
    tr = float(profile.tooth_half_width(profile.root_radius))
    tc = float(profile.tooth_half_width(profile.crest_radius))
    step = L / per_turn                       # axial offset per angular step
    n_min = DEGREE + 2
    return {"flank": max(n_min, int(math.ceil(abs(tr - tc) / step)) + 1),
            "crest": max(n_min, int(math.ceil(2.0 * tc / step)) + 1),
            "root": max(n_min, int(math.ceil((p - 2.0 * tr) / step)) + 1)}


def _fit_bands(tm: "ThreadMesh", target: float) -> tuple[list[_Band], list[_Net], float, dict[str, Any]]:
    """Bands and their B-spline nets, refined until the measured deviation is within
    ``target`` (mm).

    The z grid runs EXTENSION columns beyond each end plane (the analytic surface goes on
    there): a not-a-knot interpolant is several times less accurate in its end intervals,
    so the faces are taken from the interior part of the spline (``Segment`` in OCC) and end
    exactly on the end planes, which are grid columns.
    """
    prof = tm.profile
    per_turn = _samples_per_turn(prof.outer_radius, target)
    scale = 1.0
    turns = (tm.z_hi - tm.z_lo) / prof.lead
    for _ in range(MAX_REFINEMENTS + 1):
        n_in = max(DEGREE + 1, int(math.ceil(turns * per_turn)))
        z_in = np.linspace(tm.z_lo, tm.z_hi, n_in + 1)
        z_in[0], z_in[-1] = tm.z_lo, tm.z_hi
        h = (tm.z_hi - tm.z_lo) / n_in
        ext = h * np.arange(1, EXTENSION + 1)
        z = np.concatenate([tm.z_lo - ext[::-1], z_in, tm.z_hi + ext])
        cross = {k: int(math.ceil(n * scale)) for k, n in _cross_counts(prof, per_turn).items()}
        bands = _bands(prof, tm.warp, tm.first_mid, z, cross)
        nets = [_interpolate(b) for b in bands]
        dev = max(_band_deviation(tm, b, n) for b, n in zip(bands, nets))
        if dev <= target:
            break
        per_turn = int(math.ceil(per_turn * 1.25))
        scale *= 1.25
    grid = {"degree": DEGREE, "samples_per_turn": per_turn, "axial_samples": int(n_in + 1),
            "cross_samples": cross}
    return bands, nets, dev, grid


# --------------------------------------------------------------------------- OCC faces
def _occ_surface(net: _Net, mirror: bool, z_lo: float, z_hi: float):
    """The net as a Geom_BSplineSurface (U across the band, V along z), segmented to
    z_lo <= V <= z_hi."""
    from OCP.collections import Array1_double, Array1_int, Array2_gp_Pnt
    from OCP.Geom import Geom_BSplineSurface
    from OCP.gp import gp_Pnt

    P = net.poles * (np.array([1.0, -1.0, 1.0]) if mirror else 1.0)
    nu, nv = P.shape[0], P.shape[1]
    poles = Array2_gp_Pnt(1, nu, 1, nv)
    for i in range(nu):
        for j, (x, y, zz) in enumerate(P[i].tolist()):
            poles.SetValue(i + 1, j + 1, gp_Pnt(x, y, zz))

    def knots(t: NDArray):
        vals, counts = np.unique(t, return_counts=True)
        kn, mu = Array1_double(1, len(vals)), Array1_int(1, len(vals))
        for i, (a, c) in enumerate(zip(vals.tolist(), counts.tolist())):
            kn.SetValue(i + 1, a)
            mu.SetValue(i + 1, int(c))
        return kn, mu

    uk, um = knots(net.tv)
    vk, vm = knots(net.tz)
    surf = Geom_BSplineSurface(poles, uk, vk, um, vm, DEGREE, DEGREE, False, False)
    surf.Segment(float(net.tv[0]), float(net.tv[-1]), z_lo, z_hi)
    return surf


def _end_wire(surfaces: list, z_end: float):
    """The closed wire of the band iso-curves V = z_end, in band order."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeWire

    mk = BRepBuilderAPI_MakeWire()
    for s in surfaces:
        mk.Add(BRepBuilderAPI_MakeEdge(s.VIso(z_end)).Edge())
    if not mk.IsDone():
        raise RuntimeError(f"the end curve at z = {z_end:g} mm does not close (wire error {mk.Error()})")
    return mk.Wire()


def _circle_wire(radius: float, z_end: float):
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeWire
    from OCP.gp import gp_Ax2, gp_Circ, gp_Dir, gp_Pnt

    circ = gp_Circ(gp_Ax2(gp_Pnt(0.0, 0.0, z_end), gp_Dir(0.0, 0.0, 1.0)), radius)
    return BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(circ).Edge()).Wire()


def _plane_face(z_end: float, wires: Sequence):
    """Plane face z = z_end bounded by ``wires`` (outer first), wire orientation fixed."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.gp import gp_Dir, gp_Pln, gp_Pnt
    from OCP.ShapeFix import ShapeFix_Face

    mk = BRepBuilderAPI_MakeFace(gp_Pln(gp_Pnt(0.0, 0.0, z_end), gp_Dir(0.0, 0.0, 1.0)), wires[0], True)
    for w in wires[1:]:
        mk.Add(w)
    if not mk.IsDone():
        raise RuntimeError(f"the end face at z = {z_end:g} mm could not be made (error {mk.Error()})")
    fix = ShapeFix_Face(mk.Face())
    fix.FixOrientation()   # a hole's wire must run opposite to the outer one
    fix.Perform()
    return fix.Face()


def _body_face(radius: float, z_lo: float, z_hi: float):
    """The nut's outer cylinder between the end planes (an exact cylindrical face)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.Geom import Geom_CylindricalSurface
    from OCP.gp import gp_Ax3, gp_Dir, gp_Pnt

    cyl = Geom_CylindricalSurface(gp_Ax3(gp_Pnt(0.0, 0.0, 0.0), gp_Dir(0.0, 0.0, 1.0)), radius)
    return BRepBuilderAPI_MakeFace(cyl, 0.0, 2.0 * math.pi, z_lo, z_hi, 1e-7).Face()


def _sew_solid(faces: list):
    """Sew the faces into one shell and make it an outward-oriented solid.

    Returns (solid or None, reason)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeSolid, BRepBuilderAPI_Sewing
    from OCP.BRepLib import BRepLib
    from OCP.TopAbs import TopAbs_SHELL
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    sew = BRepBuilderAPI_Sewing(SEW_TOLERANCE)
    for f in faces:
        sew.Add(f)
    sew.Perform()
    if sew.NbFreeEdges() or sew.NbMultipleEdges() or sew.NbDegeneratedShapes():
        return None, (f"sewing left {sew.NbFreeEdges()} free, {sew.NbMultipleEdges()} multiple edges and "
                      f"{sew.NbDegeneratedShapes()} degenerated shapes")
    shells = []
    ex = TopExp_Explorer(sew.SewedShape(), TopAbs_SHELL)
    while ex.More():
        shells.append(TopoDS.Shell(ex.Current()))
        ex.Next()
    if len(shells) != 1:
        return None, f"sewing gave {len(shells)} shells, not one"
    solid = BRepBuilderAPI_MakeSolid(shells[0]).Solid()
    if not BRepLib.OrientClosedSolid_s(solid):
        return None, "the sewn shell does not enclose a volume (OrientClosedSolid failed)"
    return solid, ""


def _slot(mark) -> tuple[Any, list]:
    """The datum slot B built directly as faces (no boolean): the rectangle it opens in face
    A (a wire to add to face A as a hole) and its four walls and floor.

    The slot is the box of :meth:`prs_geom.geometry.datum.DatumMark.box` below face A,
    wholly inside material (the sizing rule keeps it off every thread surface), symmetric in
    y, so it is the same on right- and left-hand parts.
    """
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakePolygon
    from OCP.gp import gp_Pnt

    (x0, y0, z0), (x1, y1, z1) = mark.box()

    def quad(*pts):
        poly = BRepBuilderAPI_MakePolygon(*(gp_Pnt(*q) for q in pts), True)
        return poly.Wire()

    rect = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
    opening = quad(*((x, y, z0) for x, y in rect))
    faces = [BRepBuilderAPI_MakeFace(quad(*((x, y, z1) for x, y in rect)), True).Face()]   # floor
    for (xa, ya), (xb, yb) in zip(rect, rect[1:] + rect[:1]):                               # walls
        faces.append(BRepBuilderAPI_MakeFace(quad((xa, ya, z0), (xb, yb, z0), (xb, yb, z1), (xa, ya, z1)),
                                             True).Face())
    return opening, faces


# --------------------------------------------------------------------------- measurements
def _count(shape, kind) -> int:
    from OCP.TopExp import TopExp_Explorer

    n = 0
    ex = TopExp_Explorer(shape, kind)
    while ex.More():
        n += 1
        ex.Next()
    return n


def shape_volume(shape) -> float:
    """Volume (mm^3) of a shape (``BRepGProp.VolumeProperties_s``)."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    # adaptive integration: the default Gauss rule misjudges long B-spline faces by 2e-4
    BRepGProp.VolumeProperties_s(shape, props, 1e-6, False)
    return float(props.Mass())


def occ_bbox(shape) -> tuple[float, float, float, float, float, float]:
    """OpenCascade's bounding box (``BRepBndLib.Add_s``, no triangulation): (xmin, ymin,
    zmin, xmax, ymax, zmax) (mm), enlarged by the shape tolerances and the box's gap.

    Fast and deterministic, so it compares a solid with its re-imported copy; on B-spline
    faces it encloses the control points, which stand off a quintic helix band (0.2 mm
    beyond the default roller, 0.6 mm beyond the screw), so it is not the part's extent
    (see :attr:`StepSolid.bbox`).
    """
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box, False)
    lo, hi = box.CornerMin(), box.CornerMax()
    return (lo.X(), lo.Y(), lo.Z(), hi.X(), hi.Y(), hi.Z())


def _sampled_bbox(nets: Sequence[_Net], tm: "ThreadMesh", mirror: bool) -> tuple[float, ...]:
    """Extent (mm) of the solid: the B-spline faces evaluated SAMPLES_PER_SPAN times per
    knot span along z (error below r (pi / (columns per turn x SAMPLES_PER_SPAN))^2 / 2,
    about 1e-5 mm here) and 8 times across, the end planes and the nut's body cylinder
    exactly. ``BRepBndLib.AddOptimal_s``, OpenCascade's tight box, agrees within 1.2e-5 mm
    on the default parts but takes 1-3 s per part; this takes milliseconds."""
    lo = np.array([np.inf, np.inf, tm.z_lo])
    hi = np.array([-np.inf, -np.inf, tm.z_hi])
    for net in nets:
        kv = np.unique(net.tv)
        kz = np.unique(net.tz)
        kz = kz[(kz >= tm.z_lo) & (kz <= tm.z_hi)]
        kz = np.unique(np.concatenate([kz, [tm.z_lo, tm.z_hi]]))
        v = np.unique(np.concatenate([np.linspace(a, b, 9) for a, b in zip(kv[:-1], kv[1:])]))
        z = np.unique(np.concatenate([np.linspace(a, b, SAMPLES_PER_SPAN + 1) for a, b in zip(kz[:-1], kz[1:])]))
        for i in range(0, len(z), 4096):              # bounded memory on long parts
            P = _evaluate(net, v, z[i:i + 4096]).reshape(-1, 3)
            lo[:2] = np.minimum(lo[:2], P[:, :2].min(axis=0))
            hi[:2] = np.maximum(hi[:2], P[:, :2].max(axis=0))
    if tm.body_radius is not None:
        lo[:2] = np.minimum(lo[:2], -tm.body_radius)
        hi[:2] = np.maximum(hi[:2], tm.body_radius)
    if mirror:
        lo[1], hi[1] = -hi[1], -lo[1]
    return tuple(float(x) for x in np.concatenate([lo, hi]))


def _occ_matches_nets(surfaces: Sequence, nets: Sequence[_Net], mirror: bool) -> float:
    """Largest distance (mm) between OCC's surfaces and the scipy splines at a few
    parameter points per face: catches a wrong knot or pole hand-over."""
    worst = 0.0
    for surf, net in zip(surfaces, nets):
        u0, u1 = float(net.tv[0]), float(net.tv[-1])
        z0, z1 = surf.Bounds()[2:]
        us = np.array([u0, 0.37 * u0 + 0.63 * u1, u1])
        zs = np.array([z0, 0.71 * z0 + 0.29 * z1, 0.5 * (z0 + z1), z1])
        ref = _evaluate(net, us, zs)
        if mirror:
            ref = ref * np.array([1.0, -1.0, 1.0])
        for i, u in enumerate(us.tolist()):
            for j, z in enumerate(zs.tolist()):
                q = surf.Value(u, z)
                worst = max(worst, math.dist((q.X(), q.Y(), q.Z()), ref[i, j]))
    return worst


def is_valid_shape(shape) -> bool:
    """``BRepCheck_Analyzer(shape).IsValid()``."""
    from OCP.BRepCheck import BRepCheck_Analyzer

    return bool(BRepCheck_Analyzer(shape).IsValid())


# --------------------------------------------------------------------------- public API
def _meshes(design: "PRSDesign", part: str, tol: float, screw_profile) -> tuple["ThreadMesh", "ThreadMesh"]:
    """The part's mesh at the design tolerance and the reference mesh (frames, warp and
    datum slot exactly as the mesh export has them) fine enough to judge a 0.1 % volume
    agreement (``MESH_REFERENCE_SHARE``)."""
    from prs_geom.geometry.profiles import ThreadProfiles
    from prs_geom.mesh.assembly import build_part

    prof = ThreadProfiles.from_design(design)
    coarse = build_part(design, part, tol, prof, screw_profile)
    m = coarse.to_trimesh()
    ref_tol = min(tol, MESH_REFERENCE_SHARE * float(m.volume) / float(m.area))
    fine = coarse if ref_tol >= tol else build_part(design, part, ref_tol, prof, screw_profile)
    return coarse, fine


def step_solid(design: "PRSDesign", part: str, tol: float | None = None,
               screw_profile: "ThreadProfile | None" = None) -> StepSolid:
    """One threaded part as a closed B-rep solid in its part frame, with its checks.

    Parameters
    ----------
    design : PRSDesign
        The design.
    part : {"screw", "roller", "nut"}
        Which part. Frames: :mod:`prs_geom.geometry.frames` (z along the part axis, mm;
        roller and nut from z = 0 to n p, the screw over ``screw_z_range``).
    tol : float, optional
        Chord tolerance (mm); ``design.mesh.chord_tolerance_mm`` when omitted. The B-spline
        faces keep within ``DEVIATION_SHARE`` x tol of the analytic surface, tighter on
        small parts (``deviation_target_mm``), measured.
    screw_profile : ThreadProfile, optional
        The screw profile to build (e.g. ``theoretical_screw(design).profile``); the
        design's nominal screw when omitted.

    Returns
    -------
    StepSolid
        ``valid`` False with a ``reason`` when any check fails; the shape is then not to be
        written (:func:`write_step` leaves it out).

    Raises
    ------
    EnvironmentFailure
        OCP (the optional extra ``step``) is not installed.
    """
    require_ocp()
    from prs_geom.mesh.thread import analytic_thread_volume
    from OCP.ShapeAnalysis import ShapeAnalysis_ShapeTolerance
    from OCP.TopAbs import TopAbs_FACE, TopAbs_SHAPE, TopAbs_SOLID

    if part not in PARTS:
        raise ValueError(f"unknown part {part!r}; one of {', '.join(PARTS)}")
    t0 = time.perf_counter()
    tol = float(tol or design.mesh.chord_tolerance_mm)
    coarse, tm = _meshes(design, part, tol, screw_profile)
    ref = tm.to_trimesh()
    mesh_volume = float(ref.volume)
    target = min(DEVIATION_SHARE * tol, DEVIATION_VOLUME_SHARE * mesh_volume / float(ref.area))
    mark = tm.datum_mark
    prof = tm.profile
    analytic = None
    if tm.warp.is_identity:
        analytic = analytic_thread_volume(prof, tm.z_hi - tm.z_lo, tm.body_radius) - mark.volume

    def result(shape, reason: str, volume=math.nan, bbox=(math.nan,) * 6, faces=0, dev=math.nan,
               grid=None, max_tol=math.nan) -> StepSolid:
        rel = (volume - mesh_volume) / mesh_volume if math.isfinite(volume) else math.nan
        return StepSolid(part, shape, not reason, reason, volume, mesh_volume, rel, bbox,
                         time.perf_counter() - t0, faces, tol, tm.chord_tolerance, dev, analytic,
                         float(coarse.to_trimesh().volume), target, max_tol, grid or {})

    bands, nets, dev, grid = _fit_bands(tm, target)
    mirror = prof.hand_sign < 0
    try:
        shape, surfaces, reason = _build_solid(tm, nets, mirror)
        if shape is None:
            return result(None, reason, dev=dev, grid=grid)
        volume = shape_volume(shape)
        bbox = _sampled_bbox(nets, tm, mirror)
        n_faces = _count(shape, TopAbs_FACE)
        max_tol = ShapeAnalysis_ShapeTolerance().Tolerance(shape, 1, TopAbs_SHAPE)
        problems = []
        if not is_valid_shape(shape):
            problems.append("BRepCheck_Analyzer rejects the shape")
        n_solids = _count(shape, TopAbs_SOLID)
        if n_solids != 1:
            problems.append(f"{n_solids} solids instead of one")
        handover = _occ_matches_nets(surfaces, nets, mirror)
    except Exception as exc:  # noqa: BLE001 - OCC raises its own Standard_Failure types
        return result(None, f"OpenCascade failed: {type(exc).__name__}: {exc}", dev=dev, grid=grid)
    rel = (volume - mesh_volume) / mesh_volume
    if not abs(rel) <= VOLUME_REL_LIMIT:
        problems.append(f"volume {volume:.6g} mm^3 differs from the mesh's {mesh_volume:.6g} mm^3 by "
                        f"{100 * rel:.3g} % (limit {100 * VOLUME_REL_LIMIT:g} %)")
    if not dev <= target:
        problems.append(f"B-spline faces deviate {dev:.3g} mm from the analytic surface "
                        f"(limit {target:.3g} mm)")
    if not handover <= 1e-9 * max(1.0, abs(tm.z_hi), abs(tm.z_lo)):
        problems.append(f"OpenCascade's faces differ from the fitted splines by {handover:.3g} mm")
    return result(shape, "; ".join(problems), volume, bbox, n_faces, dev, grid, max_tol)


def _build_solid(tm: "ThreadMesh", nets: Sequence[_Net], mirror: bool):
    """Faces of the part (bands, end planes, slot, nut body), sewn into one solid.

    Returns (solid or None, the band surfaces, reason)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.Geom import Geom_BSplineSurface

    prof, mark = tm.profile, tm.datum_mark
    surfaces = [_occ_surface(n, mirror, tm.z_lo, tm.z_hi) for n in nets]
    # one face per band and (at most) TURNS_PER_FACE turns, each on its own segment of the
    # band's spline (a face on the whole surface would write all of it into the file once per
    # face): tessellators (CAD viewers, BRepMesh) handle one-turn faces far better than
    # 20-turn ones, and the cut edges, the same iso-curve from both sides, sew exactly
    n_pieces = max(1, math.ceil((tm.z_hi - tm.z_lo) / (TURNS_PER_FACE * prof.lead) - 1e-9))
    cuts = np.linspace(tm.z_lo, tm.z_hi, n_pieces + 1).tolist()
    cuts[0], cuts[-1] = tm.z_lo, tm.z_hi
    faces = []
    for surf in surfaces:
        u0, u1 = surf.Bounds()[:2]
        for za, zb in zip(cuts[:-1], cuts[1:]):
            piece = Geom_BSplineSurface(surf)
            if n_pieces > 1:
                piece.Segment(u0, u1, za, zb)
            faces.append(BRepBuilderAPI_MakeFace(piece, 1e-7).Face())
    opening, slot_faces = _slot(mark)
    for z_end in (tm.z_lo, tm.z_hi):
        wires = [_end_wire(surfaces, z_end)]
        if prof.internal:
            wires.insert(0, _circle_wire(tm.body_radius, z_end))
        if z_end == mark.z_face:
            wires.append(opening)
        faces.append(_plane_face(z_end, wires))
    if prof.internal:
        faces.append(_body_face(tm.body_radius, tm.z_lo, tm.z_hi))
    shape, reason = _sew_solid(faces + slot_faces)
    return shape, surfaces, reason


# --------------------------------------------------------------------------- STEP file
@dataclass(frozen=True)
class StepFileContent:
    """What a STEP file holds, read back through XCAF (``STEPCAFControl_Reader``).

    Attributes
    ----------
    names : tuple of str
        Names of the free shapes (one per part), in file order.
    shapes : tuple of TopoDS_Shape
        The shapes, same order.
    schema : str
        The FILE_SCHEMA identifier of the header.
    description : tuple of str
        The FILE_DESCRIPTION strings of the header.
    """

    names: tuple[str, ...]
    shapes: tuple[Any, ...]
    schema: str
    description: tuple[str, ...]


@contextlib.contextmanager
def _quiet_occ():
    """Silence OpenCascade's default messenger (the STEP translator prints transfer
    statistics to stdout) below failures, for the duration of the block."""
    from OCP.Message import Message, Message_Gravity

    printers = Message.DefaultMessenger_s().Printers()
    saved = []
    for i in range(1, printers.Length() + 1):
        pr = printers.Value(i)
        saved.append((pr, pr.GetTraceLevel()))
        pr.SetTraceLevel(Message_Gravity.Message_Fail)
    try:
        yield
    finally:
        for pr, level in saved:
            pr.SetTraceLevel(level)


def _new_document():
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDocStd import TDocStd_Document
    from OCP.XCAFApp import XCAFApp_Application

    doc = TDocStd_Document(TCollection_ExtendedString("XmlXCAF"))
    XCAFApp_Application.GetApplication_s().InitDocument(doc)
    return doc


def read_step(path: str | os.PathLike) -> StepFileContent:
    """Read a STEP file with its part names (XCAF) and header.

    Parameters
    ----------
    path : str or PathLike
        The file.

    Returns
    -------
    StepFileContent
        The free shapes with their names, the schema and the FILE_DESCRIPTION.

    Raises
    ------
    EnvironmentFailure
        OCP missing, or the file cannot be read as STEP.
    """
    require_ocp()
    from OCP.collections import Sequence_TDF_Label
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.STEPCAFControl import STEPCAFControl_Reader
    from OCP.TDataStd import TDataStd_Name
    from OCP.XCAFDoc import XCAFDoc_DocumentTool, XCAFDoc_ShapeTool

    reader = STEPCAFControl_Reader()
    reader.SetNameMode(True)
    with _quiet_occ():
        if reader.ReadFile(str(path)) != IFSelect_RetDone:
            raise EnvironmentFailure(f"cannot read {path} as a STEP file")
        doc = _new_document()
        if not reader.Transfer(doc):
            raise EnvironmentFailure(f"cannot transfer the shapes of {path}")
    tool = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    labels = Sequence_TDF_Label()
    tool.GetFreeShapes(labels)
    names, shapes = [], []
    for i in range(1, labels.Length() + 1):
        label = labels.Value(i)
        attr = TDataStd_Name()
        names.append(attr.Get().ToExtString() if label.FindAttribute(TDataStd_Name.GetID_s(), attr) else "")
        shapes.append(XCAFDoc_ShapeTool.GetShape_s(label))
    model = reader.Reader().StepModel()
    from OCP.APIHeaderSection import APIHeaderSection_MakeHeader

    header = APIHeaderSection_MakeHeader(model)
    description = tuple(header.DescriptionValue(k).ToCString() for k in range(1, header.NbDescription() + 1))
    schema = header.SchemaIdentifiersValue(1).ToCString() if header.NbSchemaIdentifiers() else ""
    return StepFileContent(tuple(names), tuple(shapes), schema, description)


def _write_file(path: str, solids: Sequence[StepSolid], target: Path) -> None:
    """One STEP AP214 file: each solid a free shape named after its part (XCAF label name ->
    PRODUCT name), the authority note in FILE_DESCRIPTION."""
    from OCP.APIHeaderSection import APIHeaderSection_MakeHeader
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.Interface import Interface_Static
    from OCP.STEPCAFControl import STEPCAFControl_Writer
    from OCP.STEPControl import STEPControl_AsIs
    from OCP.TCollection import TCollection_ExtendedString, TCollection_HAsciiString
    from OCP.TDataStd import TDataStd_Name
    from OCP.XCAFDoc import XCAFDoc_DocumentTool

    from prs_geom._version import __version__

    doc = _new_document()
    tool = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    for s in solids:
        label = tool.AddShape(s.shape, False)
        TDataStd_Name.Set_s(label, TCollection_ExtendedString(s.part))
    # the schema is a process-wide setting read when the writer makes its model: set it for
    # this file only and put the previous value back
    previous = Interface_Static.CVal_s("write.step.schema")
    Interface_Static.SetCVal_s("write.step.schema", STEP_SCHEMA)
    try:
        with _quiet_occ():
            writer = STEPCAFControl_Writer()
            writer.SetNameMode(True)
            if not writer.Transfer(doc, STEPControl_AsIs):
                raise RuntimeError("the STEP writer refused the shapes")
            # the header exists once the shapes are transferred; MakeHeader edits it in place
            header = APIHeaderSection_MakeHeader(writer.ChangeWriter().Model())
            header.SetName(TCollection_HAsciiString(target.name))
            header.SetDescriptionValue(1, TCollection_HAsciiString(AUTHORITY_NOTE))
            header.SetOriginatingSystem(TCollection_HAsciiString(f"prs-geom {__version__}"))
            if writer.Write(path) != IFSelect_RetDone:
                raise EnvironmentFailure(f"cannot write {target}: the STEP writer failed (does the folder "
                                         "exist and is it writable?)")
    finally:
        Interface_Static.SetCVal_s("write.step.schema", previous)


def _bbox_gap(shape) -> float:
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box, False)
    return float(box.GetGap())


def write_step(design: "PRSDesign", path: str | os.PathLike, parts: Sequence[str] = PARTS,
               tol: float | None = None, screw_profile: "ThreadProfile | None" = None) -> dict[str, Any]:
    """Build the parts (:func:`step_solid`) and write one STEP AP214 file with one named
    solid per valid part, each in its own part frame (:func:`write_solids`).

    Parameters
    ----------
    design : PRSDesign
        The design.
    path : str or PathLike
        The file to write (``.step``).
    parts : sequence of {"screw", "roller", "nut"}
        The parts; their names in the file are these.
    tol : float, optional
        Chord tolerance (mm); ``design.mesh.chord_tolerance_mm`` when omitted.
    screw_profile : ThreadProfile, optional
        The screw to export, normally ``theoretical_screw(design).profile``
        (:mod:`prs_geom.analysis.contact`); the nominal screw when omitted.

    Returns
    -------
    dict
        The report section ``step`` (:func:`write_solids`).

    Raises
    ------
    EnvironmentFailure
        OCP (the optional extra ``step``) is not installed, or the file cannot be written.
    """
    require_ocp()
    for p in parts:
        if p not in PARTS:
            raise ValueError(f"unknown part {p!r}; one of {', '.join(PARTS)}")
    return write_solids([step_solid(design, p, tol, screw_profile) for p in parts], path)


def write_solids(solids: Sequence[StepSolid], path: str | os.PathLike) -> dict[str, Any]:
    """Write the valid ``solids`` to one STEP AP214 file, read it back and check it.

    The file is written to a hidden sibling, read back (:func:`read_step`): every written
    part must be there by name with OpenCascade's bounding box unchanged (within
    ``REREAD_BBOX_TOLERANCE`` plus the boxes' gaps); only then is it moved into place
    (``os.replace``), so ``path`` is never left half-written or holding a broken file.

    Parameters
    ----------
    solids : sequence of StepSolid
        Parts from :func:`step_solid`; invalid ones (``valid`` False) are left out of the
        file and reported with their reason.
    path : str or PathLike
        The file to write.

    Returns
    -------
    dict
        The report section ``step``: ``file`` (the file name, None when nothing was
        written: no valid part, or the read-back check failed, see ``reread_problems``),
        ``schema``, ``authority`` (the note in the header), ``frames``, ``written`` (the
        part names in the file), ``parts`` (per part :meth:`StepSolid.report`, plus
        ``reread_name`` and ``reread_bbox_max_diff_mm`` (mm) for the written ones).
    """
    require_ocp()
    path = Path(path)
    good = [s for s in solids if s.valid]
    section: dict[str, Any] = {
        "file": None,
        "schema": STEP_SCHEMA,
        "authority": AUTHORITY_NOTE,
        "frames": "each solid in its own part frame (mm, z along the part axis, face A at the lower end; "
                  "prs_geom.geometry.frames); place the rollers with the assembly transforms",
        "written": [],
        "parts": {s.part: s.report() for s in solids},
    }
    if not good:
        return section
    # a hidden sibling (same folder, so os.replace is atomic), created by the writer itself
    # with the usual permissions
    tmp: str | None = str(path.with_name(f".{path.name}.tmp-{os.getpid()}-{secrets.token_hex(4)}"))
    try:
        _write_file(tmp, good, path)
        back = read_step(tmp)
        problems = []
        for s in good:
            row = section["parts"][s.part]
            row["reread_name"] = s.part in back.names
            if not row["reread_name"]:
                problems.append(f"the {s.part} is missing by name in the file read back")
                continue
            other = back.shapes[back.names.index(s.part)]
            a, b = occ_bbox(s.shape), occ_bbox(other)
            diff = max(abs(x - y) for x, y in zip(a, b))
            row["reread_bbox_max_diff_mm"] = diff
            if not diff <= REREAD_BBOX_TOLERANCE + max(_bbox_gap(s.shape), _bbox_gap(other)):
                problems.append(f"the {s.part}'s bounding box read back differs by {diff:.3g} mm")
        if problems:
            section["reread_problems"] = problems
            return section
        os.replace(tmp, path)
        tmp = None
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.remove(tmp)
    section["file"] = path.name
    section["written"] = [s.part for s in good]
    return section


# --------------------------------------------------------------------------- mechanism parts
#: The mechanism parts with a STEP file of their own (the journals and nut ends belong to the
#: roller's and the nut's bodies, whose STEP solids are the threads).
MECHANISM_STEP_PARTS = ("carrier", "retaining_ring")


def mechanism_step_solid(design: "PRSDesign", part: str, mesh: Any = None) -> StepSolid:
    """The carrier or the retaining ring (:mod:`prs_geom.geometry.mechanism`) as an exact
    B-rep: circular cylinders and planes (OpenCascade primitives and booleans), in its own
    frame (z = 0 at its face toward the nut end, as ``<part>.stl``), at the modelled sizes
    (fitted features at the middle of their ISO 286 zone).

    ``mesh_volume_mm3`` is the volume of the part's mesh (polygons at <= 1 um): ``mesh``
    (anything with a ``volume``, e.g. the build's placed ``<part>_lo``), meshed here when
    not given; ``analytic_volume_mm3`` is the closed form, which the B-rep's volume must
    agree with within ``VOLUME_REL_LIMIT``.
    """
    import time

    from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
    from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt

    from prs_geom.geometry.frames import carrier_angles
    from prs_geom.geometry.mechanism import RING_GAP_RAD, layout
    from prs_geom.mesh.mechanism import MECHANISM_CHORD_MM, mechanism_meshes

    require_ocp()
    t0 = time.perf_counter()
    lay = layout(design)
    if lay is None or part not in MECHANISM_STEP_PARTS:
        raise ValueError(f"no mechanism part {part!r} in this design (mechanism.enabled and one of "
                         f"{', '.join(MECHANISM_STEP_PARTS)})")

    def cylinder(r: float, h: float, x: float = 0.0, y: float = 0.0, z: float = 0.0, angle: float | None = None,
                 x_dir: tuple[float, float, float] = (1.0, 0.0, 0.0)):
        ax = gp_Ax2(gp_Pnt(x, y, z), gp_Dir(0.0, 0.0, 1.0), gp_Dir(*x_dir))
        maker = BRepPrimAPI_MakeCylinder(ax, r, h) if angle is None else BRepPrimAPI_MakeCylinder(ax, r, h, angle)
        return maker.Shape()

    def cut(a, b):
        op = BRepAlgoAPI_Cut(a, b)
        op.Build()
        return op.Shape()

    # the cutters run one unit past both end faces, so no cut face is coplanar with one
    if part == "carrier":
        h = lay.carrier_thickness_mm
        shape = cut(cylinder(lay.carrier_outer_radius_mm, h), cylinder(lay.carrier_inner_radius_mm, h + 2.0, z=-1.0))
        r_b = 0.5 * lay.journal_fit.hole_diameter_mm
        a = lay.centre_distance_mm
        for psi in carrier_angles(design):
            shape = cut(shape, cylinder(r_b, h + 2.0, a * math.cos(psi), a * math.sin(psi), -1.0))
        exact = lay.carrier_volume_mm3
    else:
        h = lay.ring.thickness_mm
        half = 0.5 * RING_GAP_RAD
        # a partial cylinder from the gap's edge round to its other edge, less the inner one
        outer = cylinder(lay.ring_outer_radius_mm, h, angle=2.0 * math.pi - RING_GAP_RAD,
                         x_dir=(math.cos(half), math.sin(half), 0.0))
        shape = cut(outer, cylinder(lay.ring_inner_radius_mm, h + 2.0, z=-1.0))
        exact = lay.ring_volume_mm3
    if mesh is None:
        mesh = mechanism_meshes(design, lay, MECHANISM_CHORD_MM)[f"{part}_lo"]
    mesh_volume = float(mesh.volume)
    volume = shape_volume(shape)
    from OCP.TopAbs import TopAbs_FACE, TopAbs_SOLID

    solids, faces = _count(shape, TopAbs_SOLID), _count(shape, TopAbs_FACE)
    ok = is_valid_shape(shape) and solids == 1
    rel = (volume - exact) / exact
    reason = "" if ok and abs(rel) <= VOLUME_REL_LIMIT else (
        "not one valid solid" if not ok else f"volume {volume:.6g} mm^3 differs from the closed form by {rel:.2e}")
    return StepSolid(part, shape, not reason, reason, volume, mesh_volume, (volume - mesh_volume) / mesh_volume,
                     occ_bbox(shape), time.perf_counter() - t0, faces, chord_tolerance_mm=0.0,
                     mesh_tolerance_mm=MECHANISM_CHORD_MM, max_deviation_mm=0.0, analytic_volume_mm3=exact,
                     design_mesh_volume_mm3=mesh_volume, deviation_target_mm=0.0, max_tolerance_mm=math.nan)
