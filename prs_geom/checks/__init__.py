"""Checks of the meshes against the analysis: FCL distances (:mod:`~prs_geom.checks.fcl`)
and interference of the placed parts (:mod:`~prs_geom.checks.interference`)."""
