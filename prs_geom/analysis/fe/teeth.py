"""Finite-element influence matrices of the thread teeth and the Yamamoto width calibration.

Pure math, no I/O. docs/theory/fe.md derives and discusses what is computed here.

Model
-----
Each part's engaged thread is an axisymmetric section of ``teeth`` whole thread periods
(the helix is ignored: annular teeth with the axial-section profile of
:mod:`prs_geom.geometry.profiles`), linear-elastic, meshed by
:func:`prs_geom.analysis.fe.mesh.thread_section_mesh` and solved by
:class:`prs_geom.analysis.fe.axisym.AxisymmetricModel`:

* screw: solid shaft with the theoretical (corrected) screw profile of the contact stage;
  loaded on the lower flanks (facing -z) by the rollers, force +z on the screw;
* roller: solid, both flanks loaded on one mesh: nut side on the lower flanks (force +z
  on the roller), screw side on the upper flanks (force -z);
* nut: ring from its thread to ``nut.outer_diameter_mm``; loaded on the upper flanks,
  force -z on the nut.

Frame: z = 0 is the loaded end (tooth 1 side), z grows toward the free end; tooth j has
its mid-plane at z = (j - 1/2) p. Supports as the load model has them (module doc of
:mod:`prs_geom.analysis.loads`): u_z = 0 on the end face z = 0 for the nut, the roller and a
tension-compression screw, on the far face z = teeth p for a compression-compression
screw; u_r is free there (a frictionless seat), u_r = 0 on the axis.

Loads and the measured displacement
-----------------------------------
A tooth load is a ring load of total axial force F (N) along the flank's inward normal d
of the meridian profile at the contact radius of the contact stage, spread over a band
of the flank centred on the contact point with the line-load shape 1 - s^2 / a_m^2
(|s| <= a_m, s the arclength along the flank, a_m the Hertz semi-axis in the meridian plane
at the design load per contact, :func:`~prs_geom.analysis.fe.halfplane.hertz_semi_axes`).
The measured displacement is its work-conjugate: U = W / F, W the work of the band
traction on the displacement field, i.e. the load-weighted mean of u . d over the band
divided by the axial component of d; a rigid axial shift U (in the force's axial sense)
reads U.

Influence matrices (compliance sign convention): C[i, j] is the displacement U at load
point i, in the axial sense of the force at i, per newton of total ring axial force at load
point j (mm/N). C is symmetric (Maxwell-Betti: C = G^T K^-1 G exactly) and positive
definite. Orders: screw and nut teeth 1..k; roller [nut side 1..k, screw side 1..k], the
order of :class:`prs_geom.analysis.load_solver.LoadModel`. A ring load is the force of all
contacts of one tooth: z f on screw and nut (one contact per roller), f on a roller side
(one contact per roller tooth and side).

Decomposition (what the 1D load model counts elsewhere)
-------------------------------------------------------
C[i, i] = body_i + tooth_i + local_i:

* body_i: the displacement of load point i when the same axial force passes the tooth
  on its way to the support: computed with a unit axial traction on the free end face,
  pulling away from the support (Saint-Venant: a load far beyond tooth i acts on it like
  this). It carries the shaft (or ring) segments between the support and the tooth, which
  the load model counts as N p / (E A), and the Poisson constant of the axial stress; its
  slope per pitch is compared with p / (E A) of the load model
  (:attr:`PartInfluence.body_per_pitch`).
* local_i: the half-plane local indentation of the band (Hertz counts the contact;
  :func:`~prs_geom.analysis.fe.halfplane.local_term`).
* tooth_i: what is left, the tooth's own structural compliance, the counterpart of
  Yamamoto's five terms. The matrix T = C - B - diag(local) (B the body part of every
  pair, :meth:`PartInfluence.tooth_matrix`) also holds the coupling of neighbouring teeth
  (shared root, radial expansion of the nut ring), which a diagonal model lacks.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from prs_geom.analysis.contact import ContactResult, analyse_contact
from prs_geom.analysis.fe.halfplane import HertzEllipse, band_weight, hertz_semi_axes, local_term
from prs_geom.analysis.fe.mesh import ThreadSection, thread_section_mesh
from prs_geom.analysis.loads import build_model
from prs_geom.geometry.profiles import ThreadProfile, ThreadProfiles
from prs_geom.model.design import PRSDesign

if TYPE_CHECKING:  # pragma: no cover
    from prs_geom.analysis.fe.axisym import AxisymmetricModel

__all__ = ["LoadedFlank", "PartSection", "PartInfluence", "InfluenceMatrices", "ConvergenceStudy",
           "ToothCalibration", "WidthCalibration", "part_sections", "band_loads", "part_influence",
           "influence_matrices", "richardson", "convergence_study", "calibrate_tooth_width", "DEFAULT_TEETH",
           "CONVERGED_LEVEL", "EXTENSION_TEETH", "LOCAL_REFERENCES", "nut_end_lengths"]

#: Teeth of an influence-matrix section: the middle tooth (4 of 7) has three on each side.
DEFAULT_TEETH = 7
#: The coarsest level whose diagonal entries agree with the next finer level within 0.5 %
#: on the default design (tests/test_fe.py; docs/theory/fe.md has the convergence table).
CONVERGED_LEVEL = 1
#: Unloaded thread periods the screw and roller sections carry before tooth 1 and after the
#: last engaged tooth: the real parts go on past the nut. Chosen by the convergence of the
#: end teeth (docs/theory/fe.md, "Section ends"): with 4 the end teeth's tooth part is
#: within 3 % of the interior ones and doubling it moves the worst coefficient by < 0.001.
EXTENSION_TEETH = 4
#: Where Yamamoto's beam takes its deflection, as a fraction of the tooth thickness b from
#: the loaded flank: the local term's reference point. 1/2 is the model's; 1/4 and 1 are
#: the documented alternatives of the model-risk study.
LOCAL_REFERENCES = (0.25, 0.5, 1.0)


# --------------------------------------------------------------------------- sections
@dataclass(frozen=True)
class LoadedFlank:
    """One loaded flank side of a part.

    Parameters
    ----------
    name : str
        ``"screw"``, ``"nut"``, ``"roller_nut_side"`` or ``"roller_screw_side"``.
    flank : int
        +1: the upper flank (facing +z) is loaded, -1: the lower flank.
    contact_radius_mm : float
        Radius of the contact point on this part (contact stage), mm.
    ellipse : HertzEllipse
        Contact ellipse at the design load per contact.
    contacts_per_ring : int
        Contacts one ring load stands for: z on screw and nut, 1 on a roller side.
    """

    name: str
    flank: int
    contact_radius_mm: float
    ellipse: HertzEllipse
    contacts_per_ring: int

    def __post_init__(self) -> None:
        if self.flank not in (-1, 1):
            raise ValueError("flank is +1 (upper) or -1 (lower)")
        if not self.contact_radius_mm > 0 or self.contacts_per_ring < 1:
            raise ValueError("contact radius must be positive and contacts_per_ring >= 1")


@dataclass(frozen=True)
class PartSection:
    """What the finite-element model of one part needs from the design.

    Parameters
    ----------
    part : str
        ``"screw"``, ``"roller"`` or ``"nut"``.
    profile : ThreadProfile
        Axial-section thread profile (the corrected one for the screw).
    far_radius_mm : float
        0 for screw and roller (solid), the nut's outer radius D0 / 2 (mm).
    youngs_modulus_mpa, poisson_ratio : float
        Material (MPa, -).
    flanks : tuple of LoadedFlank
        The loaded flank sides, in matrix block order.
    support_face : str
        ``"face_z0"`` (loaded end) or ``"face_z1"`` (far end): u_z = 0 there.
    body_area_mm2 : float
        The load model's body section A (screw and roller root circle, nut ring from the
        groove root to D0), for the 1D comparison p / (E A).
    unloaded_teeth : (int, int)
        Unloaded thread periods before the first engaged tooth and after the last: the
        screw and the roller go on past the nut (``EXTENSION_TEETH``).
    end_lengths_mm : (float, float)
        Plain body beyond the thread, before and after it (mm): the nut's ends (ring gear,
        end bores) as a ring from the thread's root radius to D0 / 2.
    """

    part: str
    profile: ThreadProfile
    far_radius_mm: float
    youngs_modulus_mpa: float
    poisson_ratio: float
    flanks: tuple[LoadedFlank, ...]
    support_face: str
    body_area_mm2: float
    unloaded_teeth: tuple[int, int] = (0, 0)
    end_lengths_mm: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        if self.part not in ("screw", "roller", "nut"):
            raise ValueError(f"unknown part {self.part!r}")
        if self.support_face not in ("face_z0", "face_z1"):
            raise ValueError("support_face is 'face_z0' or 'face_z1'")
        if not self.flanks:
            raise ValueError("a part section needs at least one loaded flank")
        if len(self.unloaded_teeth) != 2 or min(self.unloaded_teeth) < 0:
            raise ValueError("unloaded_teeth are two counts >= 0")
        if len(self.end_lengths_mm) != 2 or min(self.end_lengths_mm) < 0.0:
            raise ValueError("end_lengths_mm are two lengths >= 0")

    def span_mm(self, teeth: int) -> tuple[float, float]:
        """(z0, z1) of the section's end faces with ``teeth`` engaged teeth, mm, in the mesh
        frame (z = 0 at the start of the first thread period, unloaded ones included)."""
        lead, trail = self.unloaded_teeth
        return -self.end_lengths_mm[0], (lead + teeth + trail) * self.profile.pitch + self.end_lengths_mm[1]

    def support_z_mm(self, teeth: int) -> float:
        """z of the supported end face (mm, mesh frame)."""
        return self.span_mm(teeth)[0 if self.support_face == "face_z0" else 1]

    def flank_geometry(self, flank: LoadedFlank) -> dict[str, float]:
        """Contact-point geometry of a loaded flank in the axial section.

        Returns the tooth-relative axial offset of the contact point ``u_mm``
        (= flank x t(r_c)), the unit load direction (``d_r``, ``d_z``) (into the part), the
        flank angle from the radial line ``phi_rad`` (tan phi = |dt/dr|), the axial tooth
        thickness at the contact radius ``b_mm`` and the band's radial half-extent
        ``band_dr_mm`` = a_m cos(phi).
        """
        rc = flank.contact_radius_mm
        t = float(self.profile.tooth_half_width(rc))
        dt = float(self.profile.tooth_half_width_slope(rc))
        norm = math.hypot(1.0, dt)
        # outward normal of the flank z = z_mid + xi t(r) is (-t', xi) / norm; the load pushes in
        d_r, d_z = dt / norm, -flank.flank / norm
        phi = math.atan(abs(dt))
        return {"u_mm": flank.flank * t, "d_r": d_r, "d_z": d_z, "phi_rad": phi, "b_mm": 2.0 * t,
                "band_dr_mm": flank.ellipse.meridian_semi_axis_mm * math.cos(phi)}

    def thread_section(self, teeth: int) -> ThreadSection:
        """The meshable section with ``teeth`` engaged periods, the unloaded ones and the end
        pieces, and a break point at every band."""
        bands = tuple((f.contact_radius_mm, self.flank_geometry(f)["band_dr_mm"]) for f in self.flanks)
        return ThreadSection(pitch=self.profile.pitch, teeth=teeth + sum(self.unloaded_teeth),
                             root_radius=self.profile.root_radius, crest_radius=self.profile.crest_radius,
                             far_radius=self.far_radius_mm, half_width=self.profile.tooth_half_width, bands=bands,
                             end_lengths=tuple(float(e) for e in self.end_lengths_mm))


def _design_contact(design: PRSDesign, contact: ContactResult | None) -> ContactResult:
    return contact if contact is not None else analyse_contact(design)


def nut_end_lengths(design: PRSDesign) -> tuple[float, float]:
    """How far the complete nut reaches beyond its thread at the loaded end (tooth 1 side)
    and at the far end, mm: its ring gears and end pieces
    (:func:`prs_geom.geometry.part_sections.part_section`; the flange sits on the outside
    of that length and is left out). (0, 0) for a nut that is only its thread."""
    from prs_geom.geometry.frames import thread_length
    from prs_geom.geometry.part_sections import part_section

    zones = [zn for zn in part_section(design, "nut").zones if zn.name != "flange"]
    length = thread_length(design)
    lo = max(0.0, -min(zn.z[0] for zn in zones))
    hi = max(0.0, max(zn.z[1] for zn in zones) - length)
    return lo, hi


def part_sections(design: PRSDesign, contact: ContactResult | None = None,
                  extension: int = EXTENSION_TEETH) -> dict[str, PartSection]:
    """The three part sections of a design (screw, roller, nut), with the contact points of
    the contact stage and the Hertz bands at the design load (module docstring).

    ``extension``: unloaded thread periods of the screw and the roller at each end; the nut
    gets its real ends (:func:`nut_end_lengths`). ``extension=0`` gives the sections that
    end at the engaged teeth (all three parts): the model-risk alternative."""
    if extension < 0:
        raise ValueError("extension is a number of thread periods >= 0")
    contact = _design_contact(design, contact)
    prof = ThreadProfiles.from_design(design)
    mats = design.materials
    beta = design.thread.beta
    z = design.roller.count
    c_rs = contact.screw_roller["upper_at_theoretical"]
    c_nr = contact.roller_nut["lower"]
    rt = design.roller.arc_radius_mm
    sb = math.sin(beta)
    f_contact = design.loading.axial_load_n / (design.thread.engaged_teeth * z)

    def eta(a: str, b: str) -> float:
        ma, mb = getattr(mats, a), getattr(mats, b)
        return (1 - ma.poisson_ratio ** 2) / ma.youngs_modulus_mpa + (1 - mb.poisson_ratio ** 2) / mb.youngs_modulus_mpa

    # the load model's curvatures: roller sphere 1/r_T, flank 0 in the meridian and
    # +-sin(beta)/r_c across it; Q = f / n_z with the contact normal's axial component
    e_rs = hertz_semi_axes((1 / rt, 0.0), (1 / rt, sb / c_rs.part_radius_mm), eta("roller", "screw"),
                           f_contact / abs(c_rs.normal[2]))
    e_nr = hertz_semi_axes((1 / rt, 0.0), (1 / rt, -sb / c_nr.part_radius_mm), eta("roller", "nut"),
                           f_contact / abs(c_nr.normal[2]))
    A_s = math.pi * design.screw.minor_diameter_mm ** 2 / 4.0
    A_r = math.pi * design.roller.minor_diameter_mm ** 2 / 4.0
    A_n = math.pi * (design.nut.outer_diameter_mm ** 2 - design.nut.major_diameter_mm ** 2) / 4.0
    screw_support = "face_z0" if design.loading.installation == "tension-compression" else "face_z1"
    ext = (int(extension), int(extension))
    ends = nut_end_lengths(design) if extension else (0.0, 0.0)
    return {
        "screw": PartSection("screw", contact.theoretical.profile, 0.0, mats.screw.youngs_modulus_mpa,
                             mats.screw.poisson_ratio,
                             (LoadedFlank("screw", -1, c_rs.part_radius_mm, e_rs, z),), screw_support, A_s,
                             unloaded_teeth=ext),
        "roller": PartSection("roller", prof.roller, 0.0, mats.roller.youngs_modulus_mpa, mats.roller.poisson_ratio,
                              (LoadedFlank("roller_nut_side", -1, c_nr.roller_radius_mm, e_nr, 1),
                               LoadedFlank("roller_screw_side", +1, c_rs.roller_radius_mm, e_rs, 1)),
                              "face_z0", A_r, unloaded_teeth=ext),
        "nut": PartSection("nut", prof.nut, 0.5 * design.nut.outer_diameter_mm, mats.nut.youngs_modulus_mpa,
                           mats.nut.poisson_ratio, (LoadedFlank("nut", +1, c_nr.part_radius_mm, e_nr, z),),
                           "face_z0", A_n, end_lengths_mm=ends),
    }


# --------------------------------------------------------------------------- influence
@dataclass(frozen=True)
class PartInfluence:
    """Finite-element influence matrix of one part (module docstring for conventions).

    Parameters
    ----------
    part : str
        ``"screw"``, ``"roller"`` or ``"nut"``.
    flanks : tuple of str
        Names of the flank blocks, in order (one for screw and nut, two for the roller).
    level : int
        Mesh level.
    teeth : int
        Teeth k in the section.
    n_dofs : int
        Degrees of freedom of the model.
    matrix : (m k, m k) array
        C[i, j], mm/N per unit total ring axial load (compliance sign convention).
    axial_position_mm : (m k,) array
        z of each load point (contact point), mm.
    axial_sign : (m k,) array
        +1 or -1: the axial sense of the force at each load point.
    body : (m k,) array
        Body displacement of each load point per unit axial force passing it toward the
        support, mm/N (module docstring).
    local : (m,) array
        Half-plane local term of each flank's band, mm/N per unit ring axial load.
    contacts_per_ring : (m,) array
        Contacts one ring load stands for, per flank block.
    band_half_width_mm : (m,) array
        Meridian Hertz semi-axis a_m of each flank's band, mm.
    body_per_pitch : float
        Slope of ``body`` per pitch over the interior teeth, mm/N.
    body_per_pitch_1d : float
        The load model's p / (E A), mm/N.
    pitch_mm : float
        Axial pitch p, mm.
    support_face : str
        ``"face_z0"`` or ``"face_z1"``: the end face where u_z = 0.
    support_z_mm : float
        z of that face (mm, the frame of ``axial_position_mm``).
    local_by_reference : (3, m) array
        The local term of each flank with its reference point at b/4, b/2 and b from the
        flank (``LOCAL_REFERENCES``); row 1 is ``local``.
    unloaded_teeth : (int, int)
        Unloaded thread periods of the section before the first engaged tooth and after the
        last (:class:`PartSection`).
    end_lengths_mm : (float, float)
        Plain body beyond the thread at either end, mm (the nut's ends).
    seconds : float
        Wall time of mesh, assembly, factorisation and solves, s.
    """

    part: str
    flanks: tuple[str, ...]
    level: int
    teeth: int
    n_dofs: int
    matrix: NDArray
    axial_position_mm: NDArray
    axial_sign: NDArray
    body: NDArray
    local: NDArray
    contacts_per_ring: NDArray
    band_half_width_mm: NDArray
    body_per_pitch: float
    body_per_pitch_1d: float
    pitch_mm: float
    support_face: str
    support_z_mm: float
    local_by_reference: NDArray
    unloaded_teeth: tuple[int, int] = (0, 0)
    end_lengths_mm: tuple[float, float] = (0.0, 0.0)
    seconds: float = field(default=0.0, compare=False)

    def __post_init__(self) -> None:
        m, k = len(self.flanks), self.teeth
        C = np.array(self.matrix, dtype=np.float64)
        if C.shape != (m * k, m * k) or not np.all(np.isfinite(C)):
            raise ValueError(f"matrix must be a finite ({m * k}, {m * k}) array")
        for name in ("axial_position_mm", "axial_sign", "body"):
            if np.shape(getattr(self, name)) != (m * k,):
                raise ValueError(f"{name} must have {m * k} entries")
        for name in ("local", "contacts_per_ring", "band_half_width_mm"):
            if np.shape(getattr(self, name)) != (m,):
                raise ValueError(f"{name} must have {m} entries")
        if np.shape(self.local_by_reference) != (len(LOCAL_REFERENCES), m):
            raise ValueError(f"local_by_reference must be a ({len(LOCAL_REFERENCES)}, {m}) array")
        C.setflags(write=False)
        object.__setattr__(self, "matrix", C)

    @property
    def asymmetry(self) -> float:
        """max |C - C^T| / max |C| (Maxwell-Betti: rounding only)."""
        return float(np.abs(self.matrix - self.matrix.T).max() / np.abs(self.matrix).max())

    def block(self, a: str, b: str | None = None) -> NDArray:
        """The (k, k) block of flanks a (rows) and b (columns, default a)."""
        k = self.teeth
        i, j = self.flanks.index(a), self.flanks.index(b or a)
        return self.matrix[i * k:(i + 1) * k, j * k:(j + 1) * k]

    def body_matrix(self) -> NDArray:
        """B[i, j]: the body part of C[i, j]: the load at j passes the support-side one of
        the two load points, whose body displacement it shares, s_i s_j body[nearer]."""
        dist = np.abs(self.axial_position_mm - self.support_z_mm)
        nearer = np.where(dist[:, None] <= dist[None, :], np.arange(dist.size)[:, None], np.arange(dist.size)[None, :])
        s = self.axial_sign
        return s[:, None] * s[None, :] * self.body[nearer]

    def local_matrix(self, reference: float = 0.5) -> NDArray:
        """diag(local) with the local term's reference point at ``reference`` x b from the
        flank (one of ``LOCAL_REFERENCES``), mm/N per unit ring load."""
        row = LOCAL_REFERENCES.index(reference)
        return np.diag(np.repeat(np.asarray(self.local_by_reference)[row], self.teeth))

    def tooth_matrix(self, reference: float = 0.5) -> NDArray:
        """T = C - B - diag(local): the teeth's own compliance with their coupling, mm/N per
        unit ring load (module docstring)."""
        return self.matrix - self.body_matrix() - self.local_matrix(reference)


def band_loads(model: AxisymmetricModel, sec: PartSection, flank: LoadedFlank, teeth: int,
               first: int = 0) -> tuple[NDArray, NDArray]:
    """Load vectors (N_dofs, teeth) of a unit total axial ring force on the band of
    ``flank`` at every engaged tooth (mesh teeth ``first + 1 .. first + teeth``: the
    unloaded periods before them are skipped), and the axial positions of the contact
    points (mm, mesh frame).

    All bands of the flank side are assembled at once (one facet basis); each tooth's
    vector is then cut out by its own facets' degrees of freedom and scaled by its own
    axial total (the sum of its u_z entries: the basis is a partition of unity), so every
    column carries exactly 1 N axially."""
    g = sec.flank_geometry(flank)
    side = "upper" if flank.flank > 0 else "lower"
    facets = [model.facets_of(f"flank_{j}_{side}") for j in range(first + 1, first + teeth + 1)]
    rc, a_m = flank.contact_radius_mm, flank.ellipse.meridian_semi_axis_mm
    cos_phi = math.cos(g["phi_rad"])
    d_r, d_z = g["d_r"], g["d_z"]

    def traction(x: NDArray) -> tuple[NDArray, NDArray]:
        # arclength along the flank from the contact point (straight within the band)
        w = band_weight((x[0] - rc) / cos_phi, a_m)
        return w * d_r, w * d_z

    vec = model.facet_load(np.concatenate(facets), traction)
    out = np.zeros((vec.size, teeth))
    for j, fj in enumerate(facets):
        dofs = model.dofs_of(fj)
        Fz = vec[model.dofs_of(fj, comp=1)].sum()
        out[dofs, j] = vec[dofs] / abs(Fz)
    z_c = (np.arange(teeth) + first + 0.5) * sec.profile.pitch + g["u_mm"]
    return out, z_c


def _end_pull(model: AxisymmetricModel, sec: PartSection) -> NDArray:
    """Load vector of a unit axial force on the free end face, pulling away from the support."""
    free_face = "face_z1" if sec.support_face == "face_z0" else "face_z0"
    sign = 1.0 if free_face == "face_z1" else -1.0
    facets = model.facets_of(free_face)
    r0, r1 = sorted((sec.profile.root_radius, sec.far_radius_mm))
    area = math.pi * (r1 ** 2 - r0 ** 2)
    return model.facet_load(facets, lambda x: (0.0 * x[0], np.full_like(x[0], sign / area)))


def _middle(teeth: int) -> NDArray:
    """Indices of the middle half of ``teeth`` load points (at least one)."""
    lo, hi = math.ceil(teeth / 4), (3 * teeth) // 4
    return np.arange(lo, max(hi, lo + 2))


def part_influence(sec: PartSection, level: int = CONVERGED_LEVEL, teeth: int = DEFAULT_TEETH) -> PartInfluence:
    """The influence matrix of one part section at a mesh level (module docstring)."""
    if teeth < 3:
        raise ValueError("a section needs at least 3 teeth (an interior tooth)")
    t0 = time.perf_counter()
    # scikit-fem is imported only to compute: the sections, the matrices' type and a cache
    # reader need numpy alone
    from prs_geom.analysis.fe.axisym import AxisymmetricModel

    mesh = thread_section_mesh(sec.thread_section(teeth), level)
    model = AxisymmetricModel(mesh, sec.youngs_modulus_mpa, sec.poisson_ratio, fixed=((sec.support_face, 1),))
    loads, zc, sign = [], [], []
    for f in sec.flanks:
        v, z = band_loads(model, sec, f, teeth, sec.unloaded_teeth[0])
        loads.append(v)
        zc.append(z)
        sign.append(np.full(teeth, 1.0 if sec.flank_geometry(f)["d_z"] > 0 else -1.0))
    G = np.concatenate(loads, axis=1)                        # unit axial ring force each
    pull = _end_pull(model, sec)
    U = model.solve(np.concatenate([G, pull[:, None]], axis=1))
    C = G.T @ U[:, :-1]                                      # work-conjugate, compliance convention
    sign_arr = np.concatenate(sign)
    # G's column i reads s_i x (the +z displacement) at load point i; the pull moves the
    # part toward pull_sense (+z when supported at z = 0): the displacement a force at i
    # passing the tooth toward the support would give, read along that force, is
    # s_i (G_i . u_pull) pull_sense (>= 0)
    pull_sense = 1.0 if sec.support_face == "face_z0" else -1.0
    body = (G.T @ U[:, -1]) * sign_arr * pull_sense
    z_arr = np.concatenate(zc)
    p = sec.profile.pitch
    # body slope per pitch over the middle half of the first flank block (away from the
    # end effects of the support and the free end)
    inner = _middle(teeth)
    slope = np.polyfit(z_arr[inner], body[inner], 1)[0] * p
    if sec.support_face == "face_z1":
        slope = -slope
    local = np.array([[_local_term(sec, f, ref) for f in sec.flanks] for ref in LOCAL_REFERENCES])
    return PartInfluence(
        part=sec.part, flanks=tuple(f.name for f in sec.flanks), level=level, teeth=teeth, n_dofs=model.n_dofs,
        matrix=C, axial_position_mm=z_arr, axial_sign=sign_arr, body=body, local=local[1],
        contacts_per_ring=np.array([f.contacts_per_ring for f in sec.flanks], dtype=np.float64),
        band_half_width_mm=np.array([f.ellipse.meridian_semi_axis_mm for f in sec.flanks]),
        body_per_pitch=float(slope), body_per_pitch_1d=p / (sec.youngs_modulus_mpa * sec.body_area_mm2),
        pitch_mm=p, support_face=sec.support_face, support_z_mm=sec.support_z_mm(teeth), local_by_reference=local,
        unloaded_teeth=tuple(int(e) for e in sec.unloaded_teeth),
        end_lengths_mm=tuple(float(e) for e in sec.end_lengths_mm), seconds=time.perf_counter() - t0)


def _local_term(sec: PartSection, flank: LoadedFlank, reference: float) -> float:
    """The half-plane local term of a flank's band per unit ring axial load (mm/N), its
    reference point ``reference`` x b from the flank."""
    g = sec.flank_geometry(flank)
    u_n = local_term(flank.ellipse.meridian_semi_axis_mm, reference * g["b_mm"], g["phi_rad"],
                     sec.youngs_modulus_mpa, sec.poisson_ratio)
    return u_n / (2.0 * math.pi * flank.contact_radius_mm * g["d_z"] ** 2)


@dataclass(frozen=True)
class InfluenceMatrices:
    """The three parts' influence matrices of a design at one mesh level.

    ``screw`` (k, k), ``nut`` (k, k), ``roller`` (2k, 2k) [nut side, screw side]; mm/N per
    unit total ring axial load, compliance sign convention (module docstring).
    """

    screw: PartInfluence
    roller: PartInfluence
    nut: PartInfluence

    def __iter__(self):
        return iter((self.screw, self.roller, self.nut))

    @property
    def n_dofs(self) -> int:
        """Degrees of freedom of the three models together."""
        return sum(p.n_dofs for p in self)

    @property
    def screw_extension(self) -> tuple[int, int]:
        """Unloaded thread periods of the screw section before and after the engaged teeth."""
        return self.screw.unloaded_teeth

    @property
    def nut_end_lengths_mm(self) -> tuple[float, float]:
        """The nut section's plain ends beyond its thread, mm."""
        return self.nut.end_lengths_mm


def influence_matrices(design: PRSDesign, level: int = CONVERGED_LEVEL, teeth: int = DEFAULT_TEETH,
                       contact: ContactResult | None = None, extension: int = EXTENSION_TEETH) -> InfluenceMatrices:
    """Screw, roller and nut influence matrices of ``design`` (module docstring;
    ``extension`` as in :func:`part_sections`)."""
    secs = part_sections(design, contact, extension)
    return InfluenceMatrices(*(part_influence(secs[p], level, teeth) for p in ("screw", "roller", "nut")))


# --------------------------------------------------------------------------- convergence
@dataclass(frozen=True)
class ConvergenceStudy:
    """Diagonal entries of the influence matrices over three nested mesh levels.

    Parameters
    ----------
    levels : tuple of 3 int
        The mesh levels, coarse to fine (element size halves per level).
    n_dofs : dict[str, tuple of int]
        Degrees of freedom per part and level.
    diagonals : dict[str, (3, m k) array]
        diag(C) per part (rows: levels), mm/N per unit ring load.
    order : dict[str, (m k,) array]
        Observed convergence order log2(|d0 - d1| / |d1 - d2|) per entry (nan where the
        differences change sign or vanish).
    extrapolated : dict[str, (m k,) array]
        Richardson limit d2 + (d2 - d1) / (2^q - 1) with the observed order q clipped to
        [1, 4] (q = 1 where undefined: the most cautious estimate).
    error_estimate : dict[str, (m k,) array]
        |d2 - extrapolated| / |extrapolated|: the estimated relative discretisation error of
        the finest level.
    finest_change : dict[str, float]
        max |d2 - d1| / |d2| over the entries: the agreement of the two finest levels.
    """

    levels: tuple[int, int, int]
    n_dofs: dict[str, tuple[int, ...]]
    diagonals: dict[str, NDArray]
    order: dict[str, NDArray]
    extrapolated: dict[str, NDArray]
    error_estimate: dict[str, NDArray]
    finest_change: dict[str, float]

    def __post_init__(self) -> None:
        if len(self.levels) != 3 or list(self.levels) != sorted(set(self.levels)):
            raise ValueError("three increasing levels")


def richardson(values: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """(order, extrapolated, relative error estimate of the finest) from a (3, ...) array of
    a quantity on three levels whose element size halves per level (see
    :class:`ConvergenceStudy`)."""
    d0, d1, d2 = np.asarray(values, dtype=np.float64)
    e01, e12 = d0 - d1, d1 - d2
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = e01 / e12
        order = np.where((ratio > 0) & np.isfinite(ratio), np.log2(np.abs(ratio)), np.nan)
    q = np.clip(np.where(np.isnan(order), 1.0, order), 1.0, 4.0)
    extrap = d2 + (d2 - d1) / (2.0 ** q - 1.0)
    err = np.abs(d2 - extrap) / np.abs(extrap)
    return order, extrap, err


def convergence_study(design: PRSDesign, levels: tuple[int, int, int] = (0, 1, 2), teeth: int = DEFAULT_TEETH,
                      contact: ContactResult | None = None, extension: int = EXTENSION_TEETH) -> ConvergenceStudy:
    """Diagonals of all influence matrices over three levels with the Richardson estimate."""
    secs = part_sections(design, contact, extension)
    dofs: dict[str, tuple[int, ...]] = {}
    diags: dict[str, NDArray] = {}
    order, extrap, err, change = {}, {}, {}, {}
    for part in ("screw", "roller", "nut"):
        runs = [part_influence(secs[part], lv, teeth) for lv in levels]
        dofs[part] = tuple(r.n_dofs for r in runs)
        d = np.stack([np.diag(r.matrix) for r in runs])
        diags[part] = d
        order[part], extrap[part], err[part] = richardson(d)
        change[part] = float(np.max(np.abs(d[2] - d[1]) / np.abs(d[2])))
    return ConvergenceStudy(tuple(levels), dofs, diags, order, extrap, err, change)


# --------------------------------------------------------------------------- calibration
@dataclass(frozen=True)
class ToothCalibration:
    """FE tooth compliance of one part side against Yamamoto's, per contact.

    All compliances are axial displacement per newton of axial load of one contact
    (mm/N); widths in mm.

    Parameters
    ----------
    name : str
        ``"screw"``, ``"nut"``, ``"roller_nut_side"`` or ``"roller_screw_side"``.
    tooth : int
        The tooth of the section the numbers are taken at (the middle one).
    contacts_per_ring : int
        z for screw and nut, 1 for a roller side.
    fe_diagonal : float
        C[i, i] x contacts_per_ring: the raw FE displacement per contact.
    fe_body : float
        The body part of it (module docstring), per contact.
    fe_local : float
        The half-plane local term of the band, per contact (counted by Hertz).
    fe_tooth : float
        fe_diagonal - fe_body - fe_local: the FE tooth compliance per contact.
    fe_tooth_uniform : float
        The row sum of the tooth matrix at this tooth over every load point of the part
        (all teeth, both sides of the roller) x contacts_per_ring: the tooth's displacement
        per contact when every contact of the part carries the same load (includes the
        coupling of neighbours: shear lag of the screw core, the nut ring's radial
        expansion, the roller tooth loaded from both sides).
    yamamoto_per_width : float
        Yamamoto's five terms summed for a unit width, mm / (N/mm) = mm^2/N.
    yamamoto_terms : dict[str, float]
        The five terms per unit width (bending, shear, root_tilt, root_shear, radial).
    widths_mm : dict[str, float]
        The conventions: ``"unit"`` (1 mm), ``"contact_ellipse"`` (2 x the circumferential
        Hertz semi-axis), ``"pitch_circle_share"`` (pi d / z on screw and nut, pi d on the
        roller: what the load model uses today).
    equivalent_width_mm : float
        yamamoto_per_width / fe_tooth: the width at which Yamamoto matches the FE tooth.
    equivalent_width_uniform_mm : float
        The same with fe_tooth_uniform.
    ratio_fe_to_yamamoto : dict[str, float]
        fe_tooth / (yamamoto_per_width / w) for each width w above.
    ratio_fe_uniform_to_yamamoto : dict[str, float]
        fe_tooth_uniform / (yamamoto_per_width / w) for each width w above.
    """

    name: str
    tooth: int
    contacts_per_ring: int
    fe_diagonal: float
    fe_body: float
    fe_local: float
    fe_tooth: float
    fe_tooth_uniform: float
    yamamoto_per_width: float
    yamamoto_terms: dict[str, float]
    widths_mm: dict[str, float]
    equivalent_width_mm: float
    equivalent_width_uniform_mm: float
    ratio_fe_to_yamamoto: dict[str, float]
    ratio_fe_uniform_to_yamamoto: dict[str, float]

    def __post_init__(self) -> None:
        if not (self.fe_tooth > 0 and self.yamamoto_per_width > 0):
            raise ValueError("tooth compliances must be positive")
        if abs(self.fe_diagonal - self.fe_body - self.fe_local - self.fe_tooth) > 1e-9 * abs(self.fe_diagonal):
            raise ValueError("fe_tooth must equal fe_diagonal - fe_body - fe_local")


@dataclass(frozen=True)
class WidthCalibration:
    """The width calibration of a design (:func:`calibrate_tooth_width`).

    Parameters
    ----------
    rows : dict[str, ToothCalibration]
        Keyed ``"screw"``, ``"roller_screw_side"``, ``"roller_nut_side"``, ``"nut"``.
    influence : InfluenceMatrices
        The matrices the rows were taken from.
    tooth_spread : dict[str, float]
        max/min - 1 of the FE tooth compliance (diagonal of the tooth matrix) over the
        middle half of the teeth of each side: how well the body separation holds for a
        load nearer the support and one farther from it.
    body_ratio : dict[str, float]
        FE body slope per pitch / the load model's p / (E A), per part.
    """

    rows: dict[str, ToothCalibration]
    influence: InfluenceMatrices
    tooth_spread: dict[str, float]
    body_ratio: dict[str, float]


def calibrate_tooth_width(design: PRSDesign, level: int = CONVERGED_LEVEL, teeth: int | None = None,
                          contact: ContactResult | None = None, extension: int = EXTENSION_TEETH) -> WidthCalibration:
    """The equivalent Yamamoto width of every part side (module docstring, docs/theory/fe.md).

    The FE tooth compliance is taken at the middle tooth (``teeth // 2 + 1``) of a section
    of ``teeth`` teeth, by default the design's engaged teeth: the coupling of the nut
    ring's radial expansion reaches over about five pitches and the screw core's shear lag
    over three or four, so a short section misses part of the uniform-load compliance.
    """
    contact = _design_contact(design, contact)
    teeth = design.thread.engaged_teeth if teeth is None else int(teeth)
    secs = part_sections(design, contact, extension)
    infl = InfluenceMatrices(*(part_influence(secs[p], level, teeth) for p in ("screw", "roller", "nut")))
    details = build_model(design, contact).details
    yamamoto = {"screw": details.tooth_screw, "nut": details.tooth_nut,
                "roller_nut_side": details.tooth_roller_nut_side, "roller_screw_side": details.tooth_roller_screw_side}
    pitch_share = {"screw": math.pi * 2.0 * contact.theoretical.profile.pitch_radius / design.roller.count,
                   "nut": math.pi * design.nut.pitch_diameter_mm / design.roller.count,
                   "roller_nut_side": math.pi * design.roller.pitch_diameter_mm,
                   "roller_screw_side": math.pi * design.roller.pitch_diameter_mm}
    mid = teeth // 2                                  # 0-based index of the middle tooth
    rows: dict[str, ToothCalibration] = {}
    spread: dict[str, float] = {}
    for pi in infl:
        T = pi.tooth_matrix()
        sec = secs[pi.part]
        for b, fl in enumerate(sec.flanks):
            i = b * teeth + mid
            n_c = fl.contacts_per_ring
            diag = pi.matrix[i, i] * n_c
            body = pi.body[i] * n_c
            loc = pi.local[b] * n_c
            tooth = diag - body - loc
            block = slice(b * teeth, (b + 1) * teeth)
            uniform = float(T[i].sum()) * n_c
            interior = np.diag(T)[block][_middle(teeth)]
            spread[fl.name] = float(interior.max() / interior.min() - 1.0)
            terms_per_width = yamamoto[fl.name]
            w_model = terms_per_width.width_mm
            terms = {k_: getattr(terms_per_width, k_) * w_model
                     for k_ in ("bending", "shear", "root_tilt", "root_shear", "radial")}
            lam = sum(terms.values())
            widths = {"unit": 1.0, "contact_ellipse": 2.0 * fl.ellipse.circumferential_semi_axis_mm,
                      "pitch_circle_share": pitch_share[fl.name]}
            rows[fl.name] = ToothCalibration(
                name=fl.name, tooth=mid + 1, contacts_per_ring=n_c, fe_diagonal=diag, fe_body=body, fe_local=loc,
                fe_tooth=tooth, fe_tooth_uniform=uniform, yamamoto_per_width=lam, yamamoto_terms=terms,
                widths_mm=widths, equivalent_width_mm=lam / tooth, equivalent_width_uniform_mm=lam / uniform,
                ratio_fe_to_yamamoto={k_: tooth / (lam / w) for k_, w in widths.items()},
                ratio_fe_uniform_to_yamamoto={k_: uniform / (lam / w) for k_, w in widths.items()})
    ratio = {pi.part: pi.body_per_pitch / pi.body_per_pitch_1d for pi in infl}
    order = ("screw", "roller_screw_side", "roller_nut_side", "nut")
    return WidthCalibration({k_: rows[k_] for k_ in order}, infl, spread, ratio)
