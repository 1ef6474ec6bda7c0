"""The finite-element compliance of the contact pairs, for the load solver.

Pure math, no I/O. docs/theory/fe.md ("The FE compliance in the load model") explains it.

What each deformation is counted by
-----------------------------------
The load model (:mod:`prs_geom.analysis.loads`) writes the approach of a contact pair as

    Hertz (nonlinear, diagonal) + linear tooth compliance C f + 1D bodies K f.

With ``loads.compliance = "fe"``, C is the teeth's finite-element tooth matrices
T = C_FE - B - diag(local) (:meth:`~prs_geom.analysis.fe.teeth.PartInfluence.tooth_matrix`)
of the mating parts, per contact:

* nut-roller block: z T_nut + T_roller[nut side, nut side];
* roller-screw block: z T_screw + T_roller[screw side, screw side];
* coupling: T_roller[nut side, screw side] (the two flanks of one roller share its core;
  the nut and the screw see only their own contacts).

z: a ring load on the screw or the nut stands for the z contacts of one tooth, so the
displacement of one contact per unit load of every contact of the ring is z T. Hertz stays
the contact term; the half-plane local term of the smeared band (``local``), which is
what the ring band has of the near field Hertz already counts, is taken out of the FE, so
no deformation is counted twice. The bodies stay the load model's 1D segments
N p / (E A) (the FE body slope agrees with them within 2-7 %, docs/theory/fe.md), which
keeps the body terms of both models identical and carries the installation's screw
support exactly as the analytic model has it.

The result is the (2n, 2n) ``compliance`` of :class:`~prs_geom.analysis.load_solver.LoadModel`:
symmetric (Maxwell-Betti, every part) and checked positive semi-definite there.
"""
from __future__ import annotations

from dataclasses import replace
import numpy as np
from numpy.typing import NDArray

from prs_geom.analysis.fe.teeth import InfluenceMatrices
from prs_geom.analysis.load_details import FePartSummary, FeSummary
from prs_geom.analysis.load_solver import LoadModel, block_compliance
from prs_geom.model.errors import DesignError

__all__ = ["pair_compliance", "fe_load_model", "fe_summary"]


def pair_compliance(infl: InfluenceMatrices) -> NDArray:
    """The (2n, 2n) linear tooth compliance of the contact pairs of one roller, mm/N, order
    [nut-roller teeth 1..n, roller-screw teeth 1..n] (module docstring)."""
    k = infl.screw.teeth
    if infl.roller.teeth != k or infl.nut.teeth != k:
        raise ValueError("the three influence matrices must have the same number of teeth")
    if infl.roller.flanks != ("roller_nut_side", "roller_screw_side"):
        raise ValueError("the roller matrix must be ordered [nut side, screw side]")
    t_screw = infl.screw.tooth_matrix() * infl.screw.contacts_per_ring[0]
    t_nut = infl.nut.tooth_matrix() * infl.nut.contacts_per_ring[0]
    t_roller = infl.roller.tooth_matrix()
    nr = t_nut + t_roller[:k, :k]
    rs = t_screw + t_roller[k:, k:]
    C = block_compliance(nr, rs, t_roller[:k, k:])
    # each part's matrix is symmetric to rounding (C = G^T K^-1 G); make the sum exactly so
    return 0.5 * (C + C.T)


def fe_load_model(model: LoadModel, infl: InfluenceMatrices) -> LoadModel:
    """``model`` (the design's analytic load model: Hertz, bodies) with the FE tooth
    compliance of ``infl`` in place of the diagonal Yamamoto terms.

    Raises :class:`~prs_geom.model.errors.DesignError` (field ``loads.compliance``) when the
    matrices were computed for another number of teeth or the pair compliance is not
    positive semi-definite (the tooth/body/local split does not hold for that geometry)."""
    if infl.screw.teeth != model.n:
        raise DesignError("loads.compliance", "fe", f"the influence matrices have {infl.screw.teeth} teeth, "
                                                    f"the design engages {model.n}")
    C = pair_compliance(infl)
    scale = float(np.abs(C).max())
    lowest = float(np.linalg.eigvalsh(C).min())
    if lowest < -1e-10 * scale:
        raise DesignError("loads.compliance", "fe",
                          f"the finite-element tooth compliance of this geometry is not positive semi-definite "
                          f"(lowest eigenvalue {lowest:.3g} mm/N against {scale:.3g}): the split into body, "
                          f"tooth and local terms does not hold here; use loads.compliance = \"analytic\"")
    fe = replace(model, compliance=C)
    if model.details is None:
        raise ValueError("the FE load model extends an analytic model built by build_model (it has details)")
    return replace(fe, details=replace(model.details, compliance="fe", fe=fe_summary(infl, fe)))


def fe_summary(infl: InfluenceMatrices, model: LoadModel) -> FeSummary:
    """The FE compliance a load model carries: mesh level, teeth, degrees of freedom,
    symmetry, and the per-contact tooth compliances of the middle tooth next to the diagonal
    Yamamoto terms they replace (mm/N)."""
    C = np.asarray(model.compliance)
    n = model.n
    mid = n // 2
    parts = {}
    for p in infl:
        parts[p.part] = FePartSummary(n_dofs=int(p.n_dofs), asymmetry=p.asymmetry, seconds=float(p.seconds),
                                      body_per_pitch_ratio_to_1d=p.body_per_pitch / p.body_per_pitch_1d)
    lowest, highest = (float(v) for v in np.linalg.eigvalsh(C)[[0, -1]])
    return FeSummary(
        mesh_level=int(infl.screw.level), teeth=int(infl.screw.teeth), n_dofs=int(infl.n_dofs), parts=parts,
        pair_compliance_middle_tooth_mm_per_N={"nut_roller": float(C[mid, mid]),
                                               "roller_screw": float(C[n + mid, n + mid]),
                                               "flank_coupling": float(C[mid, n + mid])},
        pair_compliance_uniform_mm_per_N={"nut_roller": float(C[mid, :n].sum()),
                                          "roller_screw": float(C[n + mid, n:].sum())},
        yamamoto_mm_per_N={"nut_roller": model.tooth_nr, "roller_screw": model.tooth_rs},
        eigenvalues_mm_per_N=(lowest, highest))
