"""prs_geom: planetary roller screw design to manufacturable geometry.

Stages, each in its own module, data flowing one way:
design (:mod:`prs_geom.design`) -> profiles and helices (:mod:`prs_geom.profiles`,
:mod:`prs_geom.helix`) -> meshes (:mod:`prs_geom.mesh`, :mod:`prs_geom.assembly`) ->
exports and report (:mod:`prs_geom.pipeline`, :mod:`prs_geom.cli`).
"""
from .design import PRSDesign, default_design
from .designio import load_design, save_design
from .errors import ConvergenceError, DesignError, DesignWarning, PRSGeomError

__version__ = "0.1.0"

__all__ = [
    "PRSDesign", "default_design", "load_design", "save_design",
    "DesignError", "DesignWarning", "ConvergenceError", "PRSGeomError", "__version__",
]
