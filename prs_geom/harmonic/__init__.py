"""The stepless harmonic friction drive: the second product line.

Its own design model and analysis (:mod:`~prs_geom.harmonic.model`) and exports
(:mod:`~prs_geom.harmonic.exports`). It uses only public names of the core packages; no
core package imports it (checked by import-linter).
"""

__all__ = []
