"""prs_geom: planetary roller screw design to manufacturable geometry and trustworthy numbers.

The package follows its data flow, each folder a layer that imports only the ones below it
(checked by import-linter)::

    cli, pipeline      the edge: command line, stage orchestration, this API
    exports/           files for people and tools
    checks/            FCL comparison, interference
    mesh/              triangle meshes and the placed assembly
    analysis/          contact, theoretical diameter, loads, pitch design, machining data
    geometry/          analytic surfaces in pure numpy
    model/             design dataclasses, validation, design files, errors
    harmonic/          the second product line, beside the rest

Python API (``import prs_geom as pg``; see README "Python API")::

    d = pg.default_design()                # or pg.load_design("design.toml")
    res = pg.analyse(d)
    res.contact.theoretical_screw_pitch_diameter_mm, res.loads.max_ldc
    graded = pg.design_pitch(d, target="equal")
    pg.save_design(graded, "graded.toml")
    meshes = pg.build_meshes(graded)       # named trimesh meshes
    report = pg.build(graded, "exports/graded")
    rating = pg.analyse_rating(d)          # load ratings, life, limits, efficiency
    study = pg.tolerance_study(d)          # Monte Carlo under the design's [tolerances]
    robust = pg.robust_pitch(d, spectrum)  # pitch lists for a duty cycle
    table = pg.design_sweep(d, rollers=[8, 10])  # a design-space sweep
    pg.write_step(d, "parts.step")         # STEP solids (the 'step' extra)

Importing the package is light: every name loads its module on first use, so
``import prs_geom`` imports no mesh, CAD or plotting library.
"""
from __future__ import annotations

import importlib
from typing import Any

from prs_geom._version import __version__

#: public name -> (module, attribute)
_API: dict[str, tuple[str, str]] = {
    "PRSDesign": ("prs_geom.model.design", "PRSDesign"),
    "default_design": ("prs_geom.model.design", "default_design"),
    "HarmonicDesign": ("prs_geom.harmonic.model", "HarmonicDesign"),
    "load_design": ("prs_geom.pipeline", "load_any_design"),
    "save_design": ("prs_geom.model.io", "save_design"),
    "analyse": ("prs_geom.pipeline", "analyse"),
    "Analysis": ("prs_geom.pipeline", "Analysis"),
    "design_pitch": ("prs_geom.pipeline", "design_pitch"),
    "build_meshes": ("prs_geom.pipeline", "build_meshes"),
    "build": ("prs_geom.pipeline", "build"),
    "analyse_rating": ("prs_geom.analysis.rating", "analyse_rating"),
    "tolerance_study": ("prs_geom.studies", "tolerance_study"),
    "robust_pitch": ("prs_geom.studies", "robust_pitch"),
    # not "sweep": that is the name of the submodule prs_geom.sweep, which the import system
    # binds on the package once imported
    "design_sweep": ("prs_geom.sweep", "sweep"),
    "write_step": ("prs_geom.exports.step", "write_step"),
    "PRSGeomError": ("prs_geom.model.errors", "PRSGeomError"),
    "DesignError": ("prs_geom.model.errors", "DesignError"),
    "DesignWarning": ("prs_geom.model.errors", "DesignWarning"),
    "ConvergenceError": ("prs_geom.model.errors", "ConvergenceError"),
    "EnvironmentFailure": ("prs_geom.model.errors", "EnvironmentFailure"),
    "OutputRefused": ("prs_geom.model.errors", "OutputRefused"),
}

__all__ = ["__version__", *_API]


def __getattr__(name: str) -> Any:
    try:
        module, attr = _API[name]
    except KeyError:
        raise AttributeError(f"module 'prs_geom' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(module), attr)
    globals()[name] = value   # later lookups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_API))
