"""Finite-element model of the thread teeth (axisymmetric, linear elastic, scikit-fem).

Owns the structured graded meshes of a part's section (the engaged teeth with the unloaded
thread or the plain ends beyond them)
(:mod:`~prs_geom.analysis.fe.mesh`), the axisymmetric elasticity form and solver
(:mod:`~prs_geom.analysis.fe.axisym`), the Hertz band and its half-plane local term
(:mod:`~prs_geom.analysis.fe.halfplane`) and, from a design, the teeth's influence
matrices and the calibration of Yamamoto's tooth width (:mod:`~prs_geom.analysis.fe.teeth`).
Pure math like the rest of :mod:`prs_geom.analysis`: numpy, scipy and scikit-fem, no file
I/O and no mesh library; :mod:`~prs_geom.analysis.fe.compliance` turns the matrices into the
load model's coupled tooth compliance. docs/theory/fe.md explains the model.

scikit-fem is the optional extra ``fe`` (in the test extra): without it, importing this
package raises :class:`~prs_geom.model.errors.EnvironmentFailure` (exit code 3 in the CLI)
with the install command.
"""
import importlib.util

# found, not imported (0.6 s): a cached matrix needs numpy alone; axisym imports it to compute
if importlib.util.find_spec("skfem") is None:  # pragma: no cover - tests/test_fe.py blocks the import
    from prs_geom.model.errors import EnvironmentFailure

    raise EnvironmentFailure('the finite-element model needs scikit-fem: pip install "prs-geom[fe]"')

from prs_geom.analysis.fe.teeth import (CONVERGED_LEVEL, DEFAULT_TEETH, EXTENSION_TEETH, LOCAL_REFERENCES,
                                        ConvergenceStudy, InfluenceMatrices, LoadedFlank, PartInfluence, PartSection,
                                        ToothCalibration, WidthCalibration, band_loads, calibrate_tooth_width,
                                        convergence_study, influence_matrices, nut_end_lengths, part_influence,
                                        part_sections, richardson)

__all__ = ["CONVERGED_LEVEL", "DEFAULT_TEETH", "EXTENSION_TEETH", "LOCAL_REFERENCES", "ConvergenceStudy",
           "InfluenceMatrices", "LoadedFlank", "PartInfluence", "PartSection", "ToothCalibration",
           "WidthCalibration", "band_loads", "calibrate_tooth_width", "convergence_study", "influence_matrices",
           "nut_end_lengths", "part_influence", "part_sections", "richardson"]
