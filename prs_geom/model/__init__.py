"""The design model: what a designer writes down.

Owns the frozen, validated design dataclasses (:mod:`~prs_geom.model.design`), the
validators they share with the harmonic line (:mod:`~prs_geom.model.validation`), the
plausibility warnings of a valid design (:mod:`~prs_geom.model.plausibility`), the error
types (:mod:`~prs_geom.model.errors`) and reading and writing design files in TOML and JSON
(:mod:`~prs_geom.model.io`), and standard data: ISO 286 limits and fits, DIN 472 retaining
rings (:mod:`~prs_geom.model.standards`). The bottom layer: it imports nothing else of prs_geom.
"""

__all__: list[str] = []
