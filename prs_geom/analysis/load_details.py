"""What a load model was made from: the typed ``details`` of
:class:`~prs_geom.analysis.load_solver.LoadModel`.

Pure data, no computation. :func:`prs_geom.analysis.loads.build_model` fills the Hertz
constants, the Yamamoto tooth terms and the section areas;
:func:`prs_geom.analysis.fe.compliance.fe_load_model` adds the finite-element summary.
report.json prints them as ``loads.compliances.details``
(:func:`prs_geom.exports.report.load_details_dict`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

__all__ = ["HertzContact", "ToothTerms", "SectionAreas", "FePartSummary", "FeSummary", "LoadModelDetails"]


@dataclass(frozen=True)
class HertzContact:
    """The Hertz constants of one contact pair (screw-roller or roller-nut).

    Attributes
    ----------
    sum_rho_per_mm : float
        Sum of the four principal curvatures (1/mm).
    F_rho : float
        Curvature difference ratio (dimensionless).
    ellipticity_k : float
        Semi-major over semi-minor axis of the contact ellipse.
    semi_major_per_cbrt_N_mm, semi_minor_per_cbrt_N_mm : float
        Semi-axes of the contact ellipse per cube root of the normal load (mm N^(-1/3)).
    circumferential_semi_axis_per_cbrt_N_mm : float
        The semi-axis in the circumferential (rolling) direction (mm N^(-1/3)).
    normal_axial_component : float
        |n_z| of the contact normal: the axial share of a normal load.
    C_normal : float
        Normal approach per normal load to the 2/3 (mm N^(-2/3)).
    """

    sum_rho_per_mm: float
    F_rho: float
    ellipticity_k: float
    semi_major_per_cbrt_N_mm: float
    semi_minor_per_cbrt_N_mm: float
    circumferential_semi_axis_per_cbrt_N_mm: float
    normal_axial_component: float
    C_normal: float


@dataclass(frozen=True)
class ToothTerms:
    """Yamamoto's tooth compliance of one tooth at its contact, divided by the width the
    terms act over.

    ``a_mm``, ``b_mm``, ``c_mm``: root thickness, thickness at the contact and contact
    height above the root (mm); ``width_mm``: the circumferential width of the tooth-width
    convention (mm); the five terms (``bending`` ... ``radial``) in mm/N.
    """

    a_mm: float
    b_mm: float
    c_mm: float
    width_mm: float
    bending: float
    shear: float
    root_tilt: float
    root_shear: float
    radial: float


@dataclass(frozen=True)
class SectionAreas:
    """Cross-section areas of the 1D bodies (mm^2): screw core, roller core, nut ring."""

    screw: float
    roller: float
    nut: float


@dataclass(frozen=True)
class FePartSummary:
    """One part's finite-element influence matrix: degrees of freedom, relative asymmetry,
    computing time (s) and its body slope against the 1D body of the load model."""

    n_dofs: int
    asymmetry: float
    seconds: float
    body_per_pitch_ratio_to_1d: float


@dataclass(frozen=True)
class FeSummary:
    """The finite-element tooth compliance a load model carries.

    ``parts`` by part name; the pair compliances of the middle tooth (``nut_roller``,
    ``roller_screw``, ``flank_coupling``) and under a uniform load (``nut_roller``,
    ``roller_screw``), next to the diagonal Yamamoto terms they replace, all in mm/N;
    ``eigenvalues_mm_per_N``: the lowest and highest eigenvalue of the pair compliance.
    ``variant``, ``bodies``, ``local_reference``: how the matrices became the compliance
    (:class:`prs_geom.analysis.fe.compliance.FeVariant`); ``extension_teeth``: the screw's
    and roller's unloaded thread periods before and after the engaged teeth;
    ``nut_end_lengths_mm``: the nut section's ends beyond its thread.
    """

    mesh_level: int
    teeth: int
    n_dofs: int
    parts: Mapping[str, FePartSummary]
    pair_compliance_middle_tooth_mm_per_N: Mapping[str, float]
    pair_compliance_uniform_mm_per_N: Mapping[str, float]
    yamamoto_mm_per_N: Mapping[str, float]
    eigenvalues_mm_per_N: tuple[float, float]
    variant: str = "fe"
    bodies: str = "fe"
    local_reference: float = 0.5
    extension_teeth: tuple[int, int] = (0, 0)
    nut_end_lengths_mm: tuple[float, float] = (0.0, 0.0)


@dataclass(frozen=True)
class LoadModelDetails:
    """What the compliances of a load model were computed from.

    ``tooth_width``: the design's ``loads.tooth_width`` convention; ``hertz_rs`` /
    ``hertz_nr``: the contact pairs; the four tooth terms (screw, the roller at either side,
    nut); the body section areas; ``compliance``: ``"fe"`` when a finite-element compliance
    replaced the tooth terms (``fe`` its summary), None for the analytic model.
    """

    tooth_width: str
    hertz_rs: HertzContact
    hertz_nr: HertzContact
    tooth_screw: ToothTerms
    tooth_roller_screw_side: ToothTerms
    tooth_roller_nut_side: ToothTerms
    tooth_nut: ToothTerms
    section_areas_mm2: SectionAreas
    compliance: str | None = None
    fe: FeSummary | None = None

    def __post_init__(self) -> None:
        if (self.compliance == "fe") != (self.fe is not None):
            raise ValueError("the FE summary goes with compliance 'fe' and only with it")
