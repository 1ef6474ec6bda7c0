"""B-spline bands of a thread surface: the numeric half of the STEP B-rep (no OpenCascade).

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
surface parameter, every band ends *exactly* on the end planes z = z_lo and z = z_hi, so the
end faces are plane faces bounded by the bands' iso-curves z = const. Each band is a
B-spline surface of degree :data:`DEGREE` interpolating a grid of analytic points
(tensor-product not-a-knot interpolation with scipy, so that the knots are known and the
iso-curves two bands share are the same curve). The grid is refined until the deviation
measured between the grid points (the exact distance in the axial half-plane to the
analytic profile, :func:`prs_geom.mesh.thread.profile_distance`) is within the target
(:func:`thread_solid_reference`). :mod:`prs_geom.exports.step` turns the nets into
OpenCascade faces; :mod:`prs_geom.checks.brep` judges the solid.

All lengths are mm, in the right-hand part frame (z along the part axis).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import BSpline, make_interp_spline

if TYPE_CHECKING:  # pragma: no cover
    from prs_geom.geometry.helix import PitchWarp
    from prs_geom.geometry.profiles import ThreadProfile
    from prs_geom.mesh.thread import ThreadMesh
    from prs_geom.model.design import PRSDesign

__all__ = ["DEGREE", "DEVIATION_SHARE", "DEVIATION_VOLUME_SHARE", "EXTENSION", "MAX_REFINEMENTS",
           "MESH_REFERENCE_SHARE", "MIN_SAMPLES_PER_TURN", "POLE_OVERSHOOT_MM", "SAMPLES_PER_SPAN",
           "TURNS_PER_FACE", "Band", "BandFit", "BSplineNet", "ThreadSolidReference", "band_deviation",
           "cross_counts", "evaluate_net", "face_z_cuts", "fit_bands", "interpolate_band", "sampled_bbox",
           "samples_per_turn", "thread_bands", "thread_solid_reference"]

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
#: Degree of the B-spline faces in both directions: quintic needs about half the columns of
#: a cubic for the same deviation (fewer spans: faster checks, smaller files).
DEGREE = 5
#: Grid columns sampled beyond each end plane (see :func:`fit_bands`).
EXTENSION = 3
#: Largest number of turns one thread face spans (the bands are cut into faces this long).
TURNS_PER_FACE = 1.0
#: Samples per knot span along z for the extent of the part (:func:`sampled_bbox`).
SAMPLES_PER_SPAN = 32
#: Lower bound of the grid columns per turn along a strand, and the refinement limit.
MIN_SAMPLES_PER_TURN = 8
MAX_REFINEMENTS = 6
#: Largest overshoot (mm) of the faces' control points beyond the outer radius. CAD readers
#: take a fast bounding box from the B-spline poles, which stand outside a curved surface
#: by about 3 r (1 / cos(pi / n) - 1) for n columns per turn (measured: 0.053 mm on the
#: default screw at n = 60); more columns keep that box within this of the solid's.
POLE_OVERSHOOT_MM = 0.015


# --------------------------------------------------------------------------- reference
@dataclass(frozen=True)
class ThreadSolidReference:
    """What a threaded part's B-rep is fitted to and judged against.

    Attributes
    ----------
    design_mesh : ThreadMesh
        The part's mesh at the design chord tolerance ``chord_tolerance_mm`` (with its datum
        slot, frames and warp exactly as the mesh export has them).
    mesh : ThreadMesh
        The reference mesh, at min(tol, ``MESH_REFERENCE_SHARE`` x volume / area): fine
        enough to judge a 0.1 % volume agreement (``design_mesh`` itself when that is tol).
    chord_tolerance_mm : float
        The design chord tolerance (mm).
    mesh_volume_mm3 : float
        Volume of ``mesh`` (mm^3).
    design_mesh_volume_mm3 : float
        Volume of ``design_mesh`` (mm^3).
    deviation_target_mm : float
        The deviation the B-spline faces are fitted to: min(``DEVIATION_SHARE`` x tol,
        ``DEVIATION_VOLUME_SHARE`` x volume / area of ``mesh``) (mm).
    analytic_volume_mm3 : float or None
        Exact volume for constant pitch (closed form minus the datum slot), None when graded.
    """

    design_mesh: "ThreadMesh"
    mesh: "ThreadMesh"
    chord_tolerance_mm: float
    mesh_volume_mm3: float
    design_mesh_volume_mm3: float
    deviation_target_mm: float
    analytic_volume_mm3: float | None

    @property
    def mirror(self) -> bool:
        """True for a left-hand part (the mirror image y -> -y of the right-hand frame)."""
        return self.mesh.profile.hand_sign < 0


def thread_solid_reference(design: "PRSDesign", part: str, tol: float,
                           screw_profile: "ThreadProfile | None" = None) -> ThreadSolidReference:
    """The meshes, volumes and deviation target a threaded part's B-rep is built for.

    Parameters
    ----------
    design : PRSDesign
        The design.
    part : {"screw", "roller", "nut"}
        Which part.
    tol : float
        The design chord tolerance (mm).
    screw_profile : ThreadProfile, optional
        The screw profile to mesh; the design's nominal screw when omitted.
    """
    from prs_geom.geometry.profiles import ThreadProfiles
    from prs_geom.mesh.assembly import build_part
    from prs_geom.mesh.thread import analytic_thread_volume

    prof = ThreadProfiles.from_design(design)
    # the B-rep is the thread body (its B-spline bands follow the thread surface); an
    # actuator's run-outs are the meshes' until the complete solids carry them too
    coarse = build_part(design, part, tol, prof, screw_profile, run_outs=())
    coarse_mesh = coarse.to_trimesh()
    ref_tol = min(tol, MESH_REFERENCE_SHARE * float(coarse_mesh.volume) / float(coarse_mesh.area))
    fine = coarse if ref_tol >= tol else build_part(design, part, ref_tol, prof, screw_profile, run_outs=())
    fine_mesh = fine.to_trimesh()
    mesh_volume = float(fine_mesh.volume)
    target = min(DEVIATION_SHARE * tol, DEVIATION_VOLUME_SHARE * mesh_volume / float(fine_mesh.area))
    analytic = None
    if fine.warp.is_identity:
        analytic = (analytic_thread_volume(fine.profile, fine.z_hi - fine.z_lo, fine.body_radius)
                    - fine.datum_mark.volume)
    return ThreadSolidReference(design_mesh=coarse, mesh=fine, chord_tolerance_mm=tol, mesh_volume_mm3=mesh_volume,
                                design_mesh_volume_mm3=float(coarse_mesh.volume), deviation_target_mm=target,
                                analytic_volume_mm3=analytic)


# --------------------------------------------------------------------------- bands
@dataclass(frozen=True)
class Band:
    """A piece of the thread surface sampled on a (v, z) grid (right-hand part frame).

    ``points`` has shape (n_v, n_z, 3) (mm); row v = 0 and v = 1 lie on the band's bounding
    strands, column z = z_lo and z = z_hi on the end planes. ``kind`` is "lower_flank",
    "crest", "upper_flank" or "root"; ``start`` the thread start (0-based).
    """

    kind: str
    start: int
    v: NDArray[np.float64]
    z: NDArray[np.float64]
    points: NDArray[np.float64]


def _polar(r: NDArray, theta: NDArray, z: NDArray) -> NDArray[np.float64]:
    r, theta, z = np.broadcast_arrays(r, theta, z)
    return np.stack([r * np.cos(theta), r * np.sin(theta), z], axis=-1)


def _root_helix_coordinate(warp: "PitchWarp", z: NDArray, w: NDArray, t_root: float, pitch: float) -> NDArray:
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


def _start_bands(profile: "ThreadProfile", warp: "PitchWarp", m_k: float, start: int,
                 z: NDArray[np.float64], n_cross: dict[str, int]) -> list[Band]:
    """The four bands of one start (tooth with helix coordinate m_k at theta = 0): lower
    flank, crest, upper flank and the root to tooth m_k + p, sharing their boundary rows."""
    lead, pitch = profile.lead, profile.pitch
    r_root, r_crest = profile.root_radius, profile.crest_radius
    two_pi = 2.0 * math.pi
    t_root = float(profile.tooth_half_width(r_root))
    t_crest = float(profile.tooth_half_width(r_crest))
    Z = z[None, :]

    def theta(u: NDArray) -> NDArray:
        # point at axial offset u from the mid-plane of the tooth m_k, at height z
        return two_pi * (warp.inverse(Z - u[:, None]) - m_k) / lead

    v_flank = np.linspace(0.0, 1.0, n_cross["flank"])
    v_crest = np.linspace(0.0, 1.0, n_cross["crest"])
    v_root = np.linspace(0.0, 1.0, n_cross["root"])
    r_flank = r_root + v_flank * (r_crest - r_root)
    r_flank[-1] = r_crest
    t_flank = profile.tooth_half_width(r_flank)
    t_flank[0], t_flank[-1] = t_root, t_crest
    u_crest = -t_crest + v_crest * 2.0 * t_crest
    u_crest[-1] = t_crest
    lower = _polar(r_flank[:, None], theta(-t_flank), Z)
    upper = _polar(r_flank[::-1, None], theta(t_flank[::-1]), Z)
    crest = _polar(np.full((len(v_crest), 1), r_crest), theta(u_crest), Z)
    crest[0], crest[-1] = lower[-1], upper[0]
    # root: between this tooth's upper root corner and the next tooth's lower one
    blend = np.broadcast_to(v_root[:, None], (len(v_root), len(z)))
    m = _root_helix_coordinate(warp, np.broadcast_to(Z, blend.shape), blend, t_root, pitch)
    root = _polar(np.full((len(v_root), 1), r_root), two_pi * (m - m_k) / lead, Z)
    root[0] = upper[-1]
    return [Band("lower_flank", start, v_flank, z, lower), Band("crest", start, v_crest, z, crest),
            Band("upper_flank", start, v_flank, z, upper), Band("root", start, v_root, z, root)]


def thread_bands(profile: "ThreadProfile", warp: "PitchWarp", first_mid: float, z: NDArray[np.float64],
                 n_cross: dict[str, int]) -> list[Band]:
    """All bands of the thread surface between z[0] and z[-1] (right-hand frame), four per
    start in the order lower flank, crest, upper flank, root.

    Start k is the tooth with helix coordinate m_k = first_mid + k p at theta = 0; each
    band's v = 1 row is the next band's v = 0 row, computed once so that the shared
    iso-curves are identical. ``n_cross`` gives the points across each band kind
    ("flank", "crest", "root").
    """
    out: list[Band] = []
    for k in range(profile.starts):
        out += _start_bands(profile, warp, first_mid + k * profile.pitch, k, z, n_cross)
    # the last root band ends on start 0's lower root corner one lead on: the same curve
    # in 3D (theta - 2 pi), taken from start 0 so that the two rows are identical
    for k in range(profile.starts):
        nxt = out[4 * ((k + 1) % profile.starts)].points[0]
        out[4 * k + 3].points[-1] = nxt
    return out


# --------------------------------------------------------------------------- splines
@dataclass(frozen=True)
class BSplineNet:
    """B-spline surface of degree :data:`DEGREE`: poles (n_v, n_z, 3) (mm), full knot
    vectors ``tv`` across the band and ``tz`` along z. In z it spans the extended grid; the
    face uses [z_lo, z_hi] of it."""

    poles: NDArray[np.float64]
    tv: NDArray[np.float64]
    tz: NDArray[np.float64]


def interpolate_band(band: Band) -> BSplineNet:
    """Tensor-product not-a-knot interpolation of the band's grid, z then v.

    Across the band (v) the knots are clamped at the strands, so the v = 0 and v = 1 pole
    rows are the z-interpolations of the boundary data rows alone: two bands sharing a data
    row share the iso-curve exactly, which is what lets them sew at 1e-6 mm.
    """
    sz = make_interp_spline(band.z, band.points, k=DEGREE, axis=1, bc_type="not-a-knot")  # c: (n_z, n_v, 3)
    sv = make_interp_spline(band.v, sz.c, k=DEGREE, axis=1, bc_type="not-a-knot")         # c: (n_v, n_z, 3)
    return BSplineNet(np.ascontiguousarray(sv.c), sv.t, sz.t)


def evaluate_net(net: BSplineNet, v: NDArray, z: NDArray) -> NDArray[np.float64]:
    """Points (len(v), len(z), 3) (mm) of the surface (scipy; the same polynomial as OCC's)."""
    # BSpline's ``axis`` names the coefficient axis of c (and of the result)
    along_v = BSpline(net.tv, net.poles, DEGREE, axis=0)(v)     # (nv_eval, n_z, 3): poles in z
    return BSpline(net.tz, along_v, DEGREE, axis=1)(z)          # (nv_eval, nz_eval, 3)


def _midpoints(x: NDArray) -> NDArray:
    return 0.5 * (x[1:] + x[:-1])


def band_deviation(tm: "ThreadMesh", band: Band, net: BSplineNet) -> float:
    """Largest distance (mm) from the analytic profile (exact, in the axial half-plane:
    :func:`prs_geom.mesh.thread.profile_distance`) at the midpoints and quarter points of
    the grid cells between the end planes, where the interpolation error peaks, and along
    the band's two boundary strands between grid columns."""
    from prs_geom.mesh.thread import profile_distance

    # the boundary rows too: they are the edges the neighbouring faces share
    v = np.concatenate([_midpoints(band.v), 0.75 * band.v[:-1] + 0.25 * band.v[1:], band.v[[0, -1]]])
    zs = band.z[(band.z >= tm.z_lo) & (band.z <= tm.z_hi)]
    z = np.concatenate([_midpoints(zs), 0.75 * zs[:-1] + 0.25 * zs[1:]])
    P = evaluate_net(net, v, z).reshape(-1, 3)
    r = np.hypot(P[:, 0], P[:, 1])
    th = np.arctan2(P[:, 1], P[:, 0])
    return float(profile_distance(tm, th, r, P[:, 2]).max(initial=0.0))


def samples_per_turn(r_max: float, target: float) -> int:
    """Grid columns per turn along a strand for a degree-DEGREE interpolant of a circle of
    radius r_max (mm) within ``target`` (mm): error about C r_max h^(DEGREE + 1), C = 2e-3
    measured for DEGREE = 5 (quintic, default roller: 1.7e-5 mm at 12 columns per turn) with
    a factor 2 margin; and enough columns to keep the control points within
    ``POLE_OVERSHOOT_MM`` of the surface."""
    h = (0.5 * target / (2e-3 * r_max)) ** (1.0 / (DEGREE + 1))
    poles = math.pi / math.acos(1.0 / (1.0 + POLE_OVERSHOOT_MM / (3.0 * r_max)))
    return max(MIN_SAMPLES_PER_TURN, int(math.ceil(2.0 * math.pi / h)), int(math.ceil(poles)))


def cross_counts(profile: "ThreadProfile", per_turn: int) -> dict[str, int]:
    """Points across each band kind ("flank", "crest", "root"): the angle the band sweeps at
    fixed z divided by the angular step of the grid, plus one, at least DEGREE + 2."""
    lead, pitch = profile.lead, profile.pitch
    t_root = float(profile.tooth_half_width(profile.root_radius))
    t_crest = float(profile.tooth_half_width(profile.crest_radius))
    step = lead / per_turn                    # axial offset per angular step
    n_min = DEGREE + 2
    return {"flank": max(n_min, int(math.ceil(abs(t_root - t_crest) / step)) + 1),
            "crest": max(n_min, int(math.ceil(2.0 * t_crest / step)) + 1),
            "root": max(n_min, int(math.ceil((pitch - 2.0 * t_root) / step)) + 1)}


@dataclass(frozen=True)
class BandFit:
    """The fitted bands of a part: ``bands`` and their ``nets`` (same order), the largest
    measured deviation ``max_deviation_mm`` (mm) and the ``grid`` sampling (degree, columns
    per turn, axial samples, points across each band kind)."""

    bands: list[Band]
    nets: list[BSplineNet]
    max_deviation_mm: float
    grid: dict[str, Any] = field(default_factory=dict)


def _extended_z_grid(tm: "ThreadMesh", columns: int) -> NDArray[np.float64]:
    """``columns`` + 1 equal steps from z_lo to z_hi (both exact) and EXTENSION more beyond
    each end plane."""
    z_in = np.linspace(tm.z_lo, tm.z_hi, columns + 1)
    z_in[0], z_in[-1] = tm.z_lo, tm.z_hi
    h = (tm.z_hi - tm.z_lo) / columns
    ext = h * np.arange(1, EXTENSION + 1)
    return np.concatenate([tm.z_lo - ext[::-1], z_in, tm.z_hi + ext])


def fit_bands(tm: "ThreadMesh", target: float) -> BandFit:
    """Bands and their B-spline nets, refined until the measured deviation is within
    ``target`` (mm), or after ``MAX_REFINEMENTS`` refinements (the caller checks the
    deviation it gets).

    The z grid runs EXTENSION columns beyond each end plane (the analytic surface goes on
    there): a not-a-knot interpolant is several times less accurate in its end intervals,
    so the faces are taken from the interior part of the spline and end exactly on the end
    planes, which are grid columns.
    """
    prof = tm.profile
    per_turn = samples_per_turn(prof.outer_radius, target)
    scale = 1.0
    turns = (tm.z_hi - tm.z_lo) / prof.lead
    for _ in range(MAX_REFINEMENTS + 1):
        columns = max(DEGREE + 1, int(math.ceil(turns * per_turn)))
        z = _extended_z_grid(tm, columns)
        cross = {k: int(math.ceil(n * scale)) for k, n in cross_counts(prof, per_turn).items()}
        bands = thread_bands(prof, tm.warp, tm.first_mid, z, cross)
        nets = [interpolate_band(b) for b in bands]
        dev = max(band_deviation(tm, b, n) for b, n in zip(bands, nets))
        if dev <= target:
            break
        per_turn = int(math.ceil(per_turn * 1.25))
        scale *= 1.25
    grid = {"degree": DEGREE, "samples_per_turn": per_turn, "axial_samples": int(columns + 1),
            "cross_samples": cross}
    return BandFit(bands, nets, dev, grid)


def face_z_cuts(z_lo: float, z_hi: float, lead: float) -> list[float]:
    """Where the bands are cut into faces (mm): equal pieces of at most ``TURNS_PER_FACE``
    turns from z_lo to z_hi, both ends exact."""
    n_pieces = max(1, math.ceil((z_hi - z_lo) / (TURNS_PER_FACE * lead) - 1e-9))
    cuts = np.linspace(z_lo, z_hi, n_pieces + 1).tolist()
    cuts[0], cuts[-1] = z_lo, z_hi
    return cuts


# --------------------------------------------------------------------------- extent
def sampled_bbox(nets: Sequence[BSplineNet], tm: "ThreadMesh", mirror: bool) -> tuple[float, ...]:
    """Extent (xmin, ymin, zmin, xmax, ymax, zmax) (mm) of the solid in the part frame (the
    mirror image y -> -y when ``mirror``): the B-spline faces evaluated SAMPLES_PER_SPAN
    times per knot span along z (error below r (pi / (columns per turn x
    SAMPLES_PER_SPAN))^2 / 2, about 1e-5 mm here) and 8 times across, the end planes and the
    nut's body cylinder exactly. OpenCascade's tight box (``BRepBndLib.AddOptimal_s``)
    agrees within 1.2e-5 mm on the default parts but takes 1-3 s per part; this takes
    milliseconds."""
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
            P = evaluate_net(net, v, z[i:i + 4096]).reshape(-1, 3)
            lo[:2] = np.minimum(lo[:2], P[:, :2].min(axis=0))
            hi[:2] = np.maximum(hi[:2], P[:, :2].max(axis=0))
    if tm.body_radius is not None:
        lo[:2] = np.minimum(lo[:2], -tm.body_radius)
        hi[:2] = np.maximum(hi[:2], tm.body_radius)
    if mirror:
        lo[1], hi[1] = -hi[1], -lo[1]
    return tuple(float(x) for x in np.concatenate([lo, hi]))
