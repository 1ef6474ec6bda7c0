"""Checks of the meshes against the analysis: FCL distances (:mod:`~prs_geom.checks.fcl`)
interference of the placed parts (:mod:`~prs_geom.checks.interference`) and the fits,
journal clearances and stack-up of the mechanism parts (:mod:`~prs_geom.checks.mechanism`)."""

__all__: list[str] = []
