"""The finite-element compliance of the contact pairs, for the load solver.

Pure math, no I/O. docs/theory/fe.md ("The FE compliance in the load model") explains it.

What each deformation is counted by
-----------------------------------
The load model (:mod:`prs_geom.analysis.loads`) writes the approach of a contact pair as

    Hertz (nonlinear, diagonal) + linear compliance C f + 1D bodies K f,

K the bars N p / (E A) of the nut, roller and screw (shared by all rollers). Each part's FE
influence matrix splits as C_FE = B + T + diag(local)
(:class:`~prs_geom.analysis.fe.teeth.PartInfluence`): B the body (the force passing the
tooth on its way to the support), T the teeth with their coupling, ``local`` the
half-plane indentation of the smeared band, which Hertz already counts and which is
therefore always left out. Per contact (a ring load on the screw or the nut stands for the
z contacts of one tooth, so the screw and nut matrices count z times), the pair matrix of
part matrices X is

* nut-roller block: z X_nut + X_roller[nut side, nut side];
* roller-screw block: z X_screw + X_roller[screw side, screw side];
* coupling: X_roller[nut side, screw side] (the roller's two flanks share its core; the nut
  and the screw see only their own contacts).

Body treatments (``FeVariant.bodies``)
--------------------------------------
* ``"fe"`` (the model): the FE bodies throughout, i.e. pair(C_FE - diag(local)) in
  total. It is carried as bars scaled to the FE body slope (``body_* x kappa``, kappa =
  the FE body per pitch over p / (E A): 0.98 screw, 0.93 roller, 0.98 nut on the default
  design), which the solver shares between the rollers exactly, plus
  C = pair(T) + [pair(B) - bars(kappa)], the part of the FE bodies the bars miss: the
  roller's Poisson step between its two flanks, the end effects, the constant from the
  support to tooth 1 (which no coefficient sees). With all rollers loaded alike this is
  pair(C_FE - diag(local)) exactly (tests/test_fe_compliance.py checks it against that
  direct assembly with the bars at zero).
* ``"1d"`` (an alternative): the bars N p / (E A) as the analytic model has them and
  C = pair(T): it drops kappa and the roller's Poisson step.

``bars(kappa)`` is the solver's body operator written from the support, as B is
(:meth:`~prs_geom.analysis.load_solver.LoadModel.support_body_operator`): the kernel
min(i, j) from tooth 1 for the nut, the roller and a tension-compression screw,
n - 1 - max(i, j) toward the far end for a compression-compression screw. C alone may then
be indefinite (a correction); C + bars(kappa), the parts' elastic compliance, is what must
be positive semi-definite, and is checked.

The matrices are ring loads: where the rollers carry unequal loads (``solve_loads_rollers``)
the nut's and the screw's teeth and the body corrections are those of every roller loaded
like the one in hand, an approximation; the bars themselves are shared exactly.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from prs_geom.analysis.fe.teeth import LOCAL_REFERENCES, InfluenceMatrices, PartInfluence
from prs_geom.analysis.load_details import FePartSummary, FeSummary
from prs_geom.analysis.load_solver import LoadModel, block_compliance
from prs_geom.model.errors import DesignError

__all__ = ["FeVariant", "MAIN_VARIANT", "ALTERNATIVES", "pair_matrix", "pair_compliance", "body_scale",
           "fe_load_model", "fe_summary"]


@dataclass(frozen=True)
class FeVariant:
    """One way to turn the FE matrices into the load model's compliance.

    Parameters
    ----------
    name : str
        The label reports use (``"fe"`` for the model itself).
    extended : bool
        True: the sections run past the engaged teeth (``EXTENSION_TEETH`` unloaded periods on
        the screw and the roller, the nut's real ends); False: they end at the engaged teeth.
    bodies : str
        ``"fe"`` (the FE bodies throughout) or ``"1d"`` (the analytic model's bars).
    local_reference : float
        The local term's reference point, as a fraction of the tooth thickness b from the
        flank (one of ``LOCAL_REFERENCES``).
    description : str
        One line for the reports.
    """

    name: str
    extended: bool = True
    bodies: str = "fe"
    local_reference: float = 0.5
    description: str = ""

    def __post_init__(self) -> None:
        if self.bodies not in ("fe", "1d"):
            raise ValueError(f"bodies is 'fe' or '1d', not {self.bodies!r}")
        if self.local_reference not in LOCAL_REFERENCES:
            raise ValueError(f"local_reference must be one of {LOCAL_REFERENCES}")


#: The FE model: extended sections, FE bodies, local term at b/2.
MAIN_VARIANT = FeVariant("fe", description="sections past the engaged teeth, FE bodies, local term at b/2")
#: The documented alternatives of the model-risk study, one modelling choice changed each.
ALTERNATIVES = (
    FeVariant("fe: sections end at the engaged teeth", extended=False,
              description="screw, roller and nut cut at the engaged teeth, as the earlier FE model had them"),
    FeVariant("fe: 1D bodies", bodies="1d",
              description="the analytic model's bars N p / (E A) instead of the FE bodies"),
    FeVariant("fe: local term at b/4", local_reference=0.25,
              description="the local term's reference point b/4 from the flank instead of b/2"),
    FeVariant("fe: local term at b", local_reference=1.0,
              description="the local term's reference point b from the flank instead of b/2"),
)


def _check(infl: InfluenceMatrices) -> int:
    k = infl.screw.teeth
    if infl.roller.teeth != k or infl.nut.teeth != k:
        raise ValueError("the three influence matrices must have the same number of teeth")
    if infl.roller.flanks != ("roller_nut_side", "roller_screw_side"):
        raise ValueError("the roller matrix must be ordered [nut side, screw side]")
    return k


def pair_matrix(infl: InfluenceMatrices, part_matrix) -> NDArray:
    """The (2n, 2n) per-contact pair matrix of the part matrices ``part_matrix(pi)`` (module
    docstring), order [nut-roller teeth 1..n, roller-screw teeth 1..n], made exactly
    symmetric."""
    k = _check(infl)
    screw = part_matrix(infl.screw) * infl.screw.contacts_per_ring[0]
    nut = part_matrix(infl.nut) * infl.nut.contacts_per_ring[0]
    roller = part_matrix(infl.roller)
    C = block_compliance(nut + roller[:k, :k], screw + roller[k:, k:], roller[:k, k:])
    # each part's matrix is symmetric to rounding (C = G^T K^-1 G); make the sum exactly so
    return 0.5 * (C + C.T)


def body_scale(pi: PartInfluence) -> float:
    """kappa: the FE body per pitch over the load model's p / (E A)."""
    return float(pi.body_per_pitch / pi.body_per_pitch_1d)


def pair_compliance(infl: InfluenceMatrices, model: LoadModel | None = None,
                    variant: FeVariant = MAIN_VARIANT) -> tuple[NDArray, LoadModel | None]:
    """The linear compliance C of ``variant`` and the load model whose bars go with it.

    ``model``: the design's analytic load model (its bars); needed for ``bodies="fe"``
    (the bars scaled by kappa and the part of the FE bodies they miss). Without it the
    result is pair(T), the ``"1d"`` treatment's C. Returns (C, model with the bars to use)."""
    ref = variant.local_reference
    C = pair_matrix(infl, lambda pi: pi.tooth_matrix(ref))
    if model is None or variant.bodies == "1d":
        return C, model
    scaled = replace(model, body_screw=model.body_screw * body_scale(infl.screw),
                     body_roller=model.body_roller * body_scale(infl.roller),
                     body_nut=model.body_nut * body_scale(infl.nut), compliance=None)
    C = C + pair_matrix(infl, lambda pi: pi.body_matrix()) - scaled.support_body_operator()
    return 0.5 * (C + C.T), scaled


def fe_load_model(model: LoadModel, infl: InfluenceMatrices, variant: FeVariant = MAIN_VARIANT) -> LoadModel:
    """``model`` (the design's analytic load model: Hertz, bodies) with the FE compliance
    of ``infl`` treated as ``variant`` says (module docstring).

    Raises :class:`~prs_geom.model.errors.DesignError` (field ``loads.compliance``) when the
    matrices were computed for another number of teeth or the compliance is not positive
    semi-definite (the split into bodies, teeth and local terms does not hold there)."""
    if infl.screw.teeth != model.n:
        raise DesignError("loads.compliance", "fe", f"the influence matrices have {infl.screw.teeth} teeth, "
                                                    f"the design engages {model.n}")
    if model.details is None:
        raise ValueError("the FE load model extends an analytic model built by build_model (it has details)")
    C, bars = pair_compliance(infl, model, variant)
    total = C + bars.support_body_operator()
    scale = float(np.abs(total).max())
    lowest = float(np.linalg.eigvalsh(total).min())
    if lowest < -1e-10 * scale:
        raise DesignError("loads.compliance", "fe",
                          f"the finite-element tooth compliance of this geometry is not positive semi-definite "
                          f"(lowest eigenvalue {lowest:.3g} mm/N against {scale:.3g}): the split into body, "
                          f"tooth and local terms does not hold here; use loads.compliance = \"analytic\"")
    fe = replace(bars, compliance=C)
    return replace(fe, details=replace(model.details, compliance="fe", fe=fe_summary(infl, fe, variant)))


def fe_summary(infl: InfluenceMatrices, model: LoadModel, variant: FeVariant = MAIN_VARIANT) -> FeSummary:
    """The FE compliance a load model carries: mesh level, teeth, degrees of freedom,
    symmetry, the variant and the sections, and the per-contact tooth compliances of the
    middle tooth next to the diagonal Yamamoto terms they replace (mm/N)."""
    C = np.asarray(model.compliance)
    n = model.n
    mid = n // 2
    parts = {}
    for p in infl:
        parts[p.part] = FePartSummary(n_dofs=int(p.n_dofs), asymmetry=p.asymmetry, seconds=float(p.seconds),
                                      body_per_pitch_ratio_to_1d=body_scale(p))
    lowest, highest = (float(v) for v in np.linalg.eigvalsh(C)[[0, -1]])
    tooth = pair_matrix(infl, lambda pi: pi.tooth_matrix(variant.local_reference))
    return FeSummary(
        mesh_level=int(infl.screw.level), teeth=int(infl.screw.teeth), n_dofs=int(infl.n_dofs), parts=parts,
        pair_compliance_middle_tooth_mm_per_N={"nut_roller": float(tooth[mid, mid]),
                                               "roller_screw": float(tooth[n + mid, n + mid]),
                                               "flank_coupling": float(tooth[mid, n + mid])},
        pair_compliance_uniform_mm_per_N={"nut_roller": float(tooth[mid, :n].sum()),
                                          "roller_screw": float(tooth[n + mid, n:].sum())},
        yamamoto_mm_per_N={"nut_roller": model.tooth_nr, "roller_screw": model.tooth_rs},
        eigenvalues_mm_per_N=(lowest, highest), variant=variant.name, bodies=variant.bodies,
        local_reference=variant.local_reference, extension_teeth=tuple(int(e) for e in infl.screw_extension),
        nut_end_lengths_mm=tuple(float(e) for e in infl.nut_end_lengths_mm))
