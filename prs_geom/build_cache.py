"""What each build stage reads, and the stage cache's keys built from exactly that.

A build stage (:data:`prs_geom.pipeline.STAGES`) is a function of some design fields, of
the stages upstream of it, of the code and, for some, of the build's options and date.
:data:`STAGE_INPUTS` says which, and :func:`stage_keys` turns that into one key per stage:
the SHA-256 of a description holding

* the values of the design fields of the stage and of every stage upstream of it (its
  *closure*, :func:`closure`), each spelled exactly (``repr`` of the frozen section or value);
* :func:`prs_geom.runtime.stage_cache.source_fingerprint` (the package's files and the
  libraries' versions: the version string does not change with each edit);
* the build date the files print (``SOURCE_DATE_EPOCH`` or today) and the options that
  change what the stage writes (:func:`option_inputs`).

A rebuild whose key for a stage is one the cache holds restores that stage's record
(:mod:`prs_geom.runtime.stage_cache`) instead of running it. The declarations are checked
against the fields the stages really read (``tests/test_build_cache.py`` watches a build
read its design, field by field).

Path forms of :data:`STAGE_INPUTS`:

* ``"*"``: the whole design;
* ``"definition"``: what :func:`prs_geom.model.io.design_hash` covers, the design less its
  operating fields (:data:`~prs_geom.model.io.OPERATING_FIELDS`), plus the sizes those fields
  set (the flange bolt sized from the load: :func:`~prs_geom.model.io.operating_sizes`).
  The stages that print the design hash in their files read exactly this;
* ``"thread"``: a whole section; ``"loading.installation"``: one field of a section;
* ``"rating?"``: only whether an optional section is present.

Pure: no I/O beyond reading the package's own files for the fingerprint.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
from typing import Any

from prs_geom.model.design import PRSDesign
from prs_geom.model.io import OPERATING_FIELDS, definition_dict, design_to_dict

__all__ = ["ALL", "DEFINITION", "STAGE_INPUTS", "closure", "covers", "input_values", "inputs", "option_inputs",
           "stage_keys"]

ALL = "*"
DEFINITION = "definition"
_PARTS = ("thread", "screw", "roller", "nut")
#: the end gears' sizes (no accuracy grade: that is the drawings' and the meshes')
_GEAR_SIZE = ("gears.enabled", "gears.module_mm", "gears.pressure_angle_deg", "gears.backlash_mm", "gears.face_width_mm")
#: the carriers, journals and rings as the layout sizes them (no fit of the carrier bore)
_MECH_LAYOUT = ("mechanism.enabled", "mechanism.journal_diameter_mm", "mechanism.journal_fit",
                "mechanism.carrier_thickness_mm", "mechanism.carrier_guidance", "mechanism.carrier_radial_clearance_mm",
                "mechanism.roller_end_play_mm", "mechanism.ring_play_mm", "mechanism.ring_bore_mm",
                "mechanism.length_tolerance")
#: the per-part flank tolerances and the target the load stage's equal-load design aims at
_LOAD_TOLERANCES = ("tolerances.screw_flank_um", "tolerances.roller_screw_flank_um", "tolerances.roller_nut_flank_um",
                    "tolerances.nut_flank_um", "tolerances.target_ldc")

#: Per stage: (the design fields it reads itself, the stages whose results it uses). Found
#: by watching builds of the examples read their designs (``tests/stage_reads.py``); the
#: presence reads (``"rating?"``) come from copying the design with new pitch lists.
STAGE_INPUTS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "design": ((ALL,), ()),
    "pitch": (("thread.pitch_mm", "thread.engaged_teeth", "roller.pitch_list_mm", "nut.pitch_list_mm"), ()),
    "contact": ((*_PARTS, "contact", "mechanism.enabled", "actuator.enabled", "name", "rating?", "supports?",
                 "tolerances?"), ()),
    "gears": (("thread.pitch_mm", "screw.starts", "roller.pitch_diameter_mm", "roller.count",
               "roller.major_diameter_mm", "nut.pitch_diameter_mm", *_GEAR_SIZE), ()),
    "loads": (("materials.screw", "materials.roller", "materials.nut", "loading", "loads", *_LOAD_TOLERANCES),
              ("contact",)),
    "rating": (("materials.screw", "loading", *_GEAR_SIZE, *_MECH_LAYOUT, "actuator", "supports", "rating"),
               ("contact", "loads")),
    # see _TOLERANCE_STUDY: a design without a [tolerances] section has no study
    "tolerance": (("tolerances?",), ()),
    "meshes": ((DEFINITION,), ("contact", "gears")),
    "mechanism": (("materials", "loading.installation", *_GEAR_SIZE, *_MECH_LAYOUT, "actuator", "name"),
                  ("contact", "meshes")),
    # the flange bolts' check compares their proof loads with the load itself
    "actuator": (("actuator", "loading", *_GEAR_SIZE, *_MECH_LAYOUT, "thread.pitch_mm", "thread.engaged_teeth",
                  "screw.pitch_diameter_mm", "screw.starts", "screw.major_diameter_mm", "screw.minor_diameter_mm",
                  "screw.length_mm", "roller.pitch_diameter_mm", "roller.count", "roller.major_diameter_mm",
                  "roller.minor_diameter_mm", "nut.pitch_diameter_mm", "nut.outer_diameter_mm",
                  "nut.minor_diameter_mm"), ()),
    "checks": (("loading.installation", "mesh", *_GEAR_SIZE, *_MECH_LAYOUT, "actuator"), ("contact", "meshes")),
    "manufacturing": ((DEFINITION,), ("contact",)),
    "html": ((ALL,), ("design", "pitch", "contact", "gears", "loads", "rating", "tolerance", "meshes", "mechanism",
                      "actuator", "checks", "manufacturing")),
}
#: The tolerance stage of a design with a ``[tolerances]`` section: the Monte Carlo study.
_TOLERANCE_STUDY: tuple[tuple[str, ...], tuple[str, ...]] = (
    # what the study samples and solves; its source, target and confidence only go to the report
    (*(f"tolerances.{f}" for f in ("distribution", "flank_um", "screw_flank_um", "roller_screw_flank_um",
                                   "roller_nut_flank_um", "nut_flank_um", "roller_diameter_um", "screw_eccentricity_um",
                                   "nut_eccentricity_um", "lead_um", "temperature_k", "samples", "seed",
                                   "load_fractions")),
     "loading.axial_load_n", "materials.screw", "materials.roller", "materials.nut", "name"),
    ("contact", "loads"))


def inputs(stage: str, design: PRSDesign) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(design paths, upstream stages) of ``stage`` for ``design`` (:data:`STAGE_INPUTS`)."""
    if stage == "tolerance" and design.tolerances is not None:
        return _TOLERANCE_STUDY
    return STAGE_INPUTS[stage]


def closure(stage: str, design: PRSDesign) -> frozenset[str]:
    """The design paths ``stage`` depends on for ``design``: its own and those of every
    stage upstream."""
    paths, upstream = inputs(stage, design)
    return frozenset(paths).union(*(closure(u, design) for u in upstream))


def covers(paths: frozenset[str] | tuple[str, ...], field: str) -> bool:
    """Whether the design paths ``paths`` include the value of the dotted design field
    ``field`` (``"loading.axial_load_n"``; a derived size through ``definition`` does not
    count: a load that sizes the same bolt leaves the ``definition`` stages alone)."""
    section = field.split(".")[0]
    for p in paths:
        if p == ALL or p == field or p == section:
            return True
        if p == DEFINITION and not (field in OPERATING_FIELDS or section in OPERATING_FIELDS):
            return True
        if p.endswith("?") and p[:-1] == section and "." not in field:
            return True
    return False


def _value(design: PRSDesign, path: str) -> Any:
    if path == ALL:
        return design_to_dict(design)
    if path == DEFINITION:
        return definition_dict(design)
    if path.endswith("?"):
        return getattr(design, path[:-1]) is not None
    section, _, name = path.partition(".")
    value = getattr(design, section)
    if name:
        value = None if value is None else getattr(value, name)
    return repr(value)


def input_values(design: PRSDesign, paths: frozenset[str] | tuple[str, ...],
                 known: dict[str, Any] | None = None) -> dict[str, Any]:
    """The value of each design path (module docstring), as JSON-ready data; ``known``
    keeps the values found, for the next stage's paths (the whole design is several stages')."""
    known = {} if known is None else known
    for p in paths:
        if p not in known:
            known[p] = _value(design, p)
    return {p: known[p] for p in sorted(paths)}


def option_inputs(stage: str, options: Any) -> dict[str, Any]:
    """The build options that change what ``stage`` writes (:class:`prs_geom.pipeline.BuildOptions`)."""
    if stage == "meshes":
        return {"nominal_screw": options.nominal_screw, "step": options.step}
    if stage == "manufacturing":
        return {"drawings": options.wants("drawings")}
    if stage == "html":
        return dataclasses.asdict(options)
    return {}


def stage_keys(design: PRSDesign, stages: list[str], options: Any, date: str,
               fingerprint: str) -> dict[str, tuple[str, str]]:
    """``stage -> (key, description)`` for the stages ``stages`` (module docstring): the
    description is the JSON text of everything the key covers, the key its SHA-256."""
    out, known = {}, {}
    for stage in stages:
        description = json.dumps({"stage": stage, "source": fingerprint, "date": date,
                                  "options": option_inputs(stage, options),
                                  "inputs": input_values(design, closure(stage, design), known)},
                                 sort_keys=True, allow_nan=True, default=str)
        out[stage] = (hashlib.sha256(description.encode("utf-8")).hexdigest(), description)
    return out
