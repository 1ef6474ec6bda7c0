"""Analysis: the numbers a designer trusts, from the analytic geometry.

Owns the contact points and the screw's theoretical pitch diameter
(:mod:`~prs_geom.analysis.contact`), the load distribution and graded-pitch design
(:mod:`~prs_geom.analysis.loads` with its complementarity solver
:mod:`~prs_geom.analysis.load_solver`), the manufacturing-error model and its statistics
(:mod:`~prs_geom.analysis.tolerance`), the robust pitch family
(:mod:`~prs_geom.analysis.robust`), the finite-element tooth model
(:mod:`~prs_geom.analysis.fe`, optional extra ``fe``), Hertz point contact
(:mod:`~prs_geom.analysis.hertz`), the over-wire / over-ball inspection
values (:mod:`~prs_geom.analysis.inspection`), the machining data
(:mod:`~prs_geom.analysis.machining`) and the kinematics of the running mechanism
(:mod:`~prs_geom.analysis.kinematics`). Pure numpy/scipy (scikit-fem for the FE): importing
it loads no mesh library (trimesh, FCL, manifold3d) and does no I/O; each stage returns a
frozen result.
"""

# the API lives in the modules; importing the package loads none of them
__all__: list[str] = []
