"""Reading and writing design files (TOML and JSON).

A design file has the top-level key ``name`` and the tables ``[thread]``, ``[screw]``,
``[roller]``, ``[nut]``, ``[materials.screw]``, ``[materials.roller]``,
``[materials.nut]``, ``[loading]``, ``[contact]`` and ``[mesh]``; every table and key is
optional and falls back to the built-in default design. Unknown keys are errors (a
misspelt key silently ignored would build the wrong part).

Floats are written with Python's shortest round-trip representation, so a written
design reads back to an equal :class:`~prs_geom.model.design.PRSDesign`, bit for bit.

Every file the user names (design, spectrum and ``design-pitch --target`` files) is read by
:func:`read_user_file` and parsed by :func:`parse_document`, under the limits below
(:data:`MAX_INPUT_BYTES`, :data:`MAX_TEXT_CHARS`, :data:`MAX_KEY_CHARS`,
:data:`MAX_NESTING`, :data:`MIN_INT`/:data:`MAX_INT`, JSON keys given once): a file beyond
them is bad input (:class:`~prs_geom.model.errors.DesignError`, exit 2), refused before it
can cost much memory or time.
"""
from __future__ import annotations

import contextlib
import dataclasses
import errno
import json
import math
import os
import re
import secrets
import stat
import sys
import tomllib
from pathlib import Path
from typing import Any, Iterator

from prs_geom.model.design import PRSDesign
from prs_geom.model.errors import DesignError, EnvironmentFailure, OutputRefused, key_name, quote

__all__ = ["DESIGN_FORMAT_VERSION", "FIELD_COMMENTS", "OPERATING_FIELDS", "MAX_INPUT_BYTES", "MAX_KEY_CHARS",
           "MAX_NESTING", "MAX_TEXT_CHARS", "PRS_KINDS", "build_section", "check_document", "check_format_version",
           "check_output_file", "decode_text", "definition_dict", "design_from_dict", "design_hash", "design_to_dict",
           "dumps_json", "operating_sizes",
           "dumps_toml", "is_office_lock", "load_design", "load_document", "load_spectrum", "loads_json", "loads_toml",
           "parse_document", "read_input_text", "read_user_file", "save_design", "toml_string", "write_file_atomic"]

#: Comments written by ``prs-geom init`` above each key (unit and meaning).
FIELD_COMMENTS: dict[str, str] = {
    "name": "design name; also the default output folder exports/<name>",
    "thread.pitch_mm": "axial pitch p (mm), shared by screw, rollers and nut",
    "thread.flank_half_angle_deg": "flank half-angle beta (deg) in the normal section, from the radial line",
    "thread.hand": '"right" or "left"; all three threads share the hand',
    "thread.engaged_teeth": "engaged roller teeth n; roller and nut thread length = n p",
    "screw.pitch_diameter_mm": "screw nominal pitch diameter d_s (mm)",
    "screw.starts": "screw starts n_s; lead = n_s p",
    "screw.major_diameter_mm": "crest (outside) diameter (mm)",
    "screw.minor_diameter_mm": "root diameter (mm)",
    "screw.length_mm": "threaded length of the screw (mm), >= n p; omit for what the actuator's stroke needs",
    "roller.pitch_diameter_mm": "roller pitch diameter d_r (mm)",
    "roller.count": "number of rollers z, evenly spaced",
    "roller.arc_radius_mm": "flank arc radius r_T (mm), arc centred on the roller axis",
    "roller.major_diameter_mm": "crest diameter (mm)",
    "roller.minor_diameter_mm": "root diameter (mm)",
    "roller.pitch_list_mm": "n-1 tooth-to-tooth pitches (mm) from the loaded end; omit for constant pitch",
    "nut.pitch_diameter_mm": "nut pitch diameter d_n (mm)",
    "nut.starts": "nut starts n_n",
    "nut.outer_diameter_mm": "nut body outer diameter D0 (mm)",
    "nut.major_diameter_mm": "groove root diameter (mm), the largest thread diameter",
    "nut.minor_diameter_mm": "crest (bore) diameter (mm)",
    "nut.pitch_list_mm": "n-1 tooth-to-tooth pitches (mm) from the loaded end; omit for constant pitch",
    "youngs_modulus_mpa": "Young's modulus E (MPa)",
    "poisson_ratio": "Poisson's ratio nu",
    "loading.axial_load_n": "external axial load F0 (N) shared by all rollers",
    "loading.installation": '"tension-compression" or "compression-compression"',
    "contact.clearance_mm": "axial clearance left at the screw-roller contact by the corrected screw diameter (mm)",
    "contact.precision_mm": "precision of that clearance (mm)",
    "mesh.chord_tolerance_mm": "largest mesh deviation from the analytic surface (mm)",
    "gears.enabled": "roller end gears and nut ring gears in the meshes, checks and report",
    "gears.module_mm": "gear module m (mm); omit for the largest ISO 54 module that fits (m z_g = d_r)",
    "gears.pressure_angle_deg": "gear pressure angle alpha (deg)",
    "gears.backlash_mm": "total circumferential backlash of each roller/ring gear pair (mm)",
    "gears.face_width_mm": "gear face width (mm); omit for two thread pitches",
    "gears.accuracy_grade": "ISO 1328-1 flank tolerance class of the gears on the drawings (1 to 11)",
    "gears.thickness_tolerance_mm": "tooth thickness tolerance T_sn below the thinned tooth (mm): lower deviation of W_k and over-pins",
    "gears.tip_tolerance": 'ISO 286 shaft zone of the roller gear tip diameter (e.g. "h11")',
    "gears.ring_tip_tolerance": 'ISO 286 hole zone of the ring gear tip diameter (e.g. "H11")',
    "screw.pitch_diameter_tolerance": 'ISO 286 shaft zone of the screw pitch diameter on its drawing (e.g. "h6")',
    "roller.pitch_diameter_tolerance": 'ISO 286 shaft zone of the roller pitch diameter on its drawing (e.g. "h5")',
    "nut.pitch_diameter_tolerance": 'ISO 286 hole zone of the nut pitch diameter on its drawing (e.g. "H6")',
    "thermal_expansion_per_k": "linear thermal expansion coefficient alpha (1/K)",
    "density_kg_m3": "density (kg/m^3), for the masses of the parts list",
    **{f"materials.{part}.name": "material name printed in the parts list"
       for part in ("screw", "roller", "nut", "carrier", "retaining_ring")},
    **{f"materials.{part}.grade": 'material grade on the part drawing, e.g. "100Cr6 (1.3505)"; "" = not specified'
       for part in ("screw", "roller", "nut", "carrier", "retaining_ring")},
    **{f"materials.{part}.heat_treatment": 'heat treatment on the part drawing, e.g. "hardened, 58-62 HRC"; "" = none given'
       for part in ("screw", "roller", "nut", "carrier", "retaining_ring")},
    "mechanism.enabled": "carriers, roller journals, retaining rings and nut ends in the meshes, checks and parts list",
    "mechanism.journal_diameter_mm": "roller journal diameter (mm); omit for 0.6 x roller root diameter, down to 0.5 mm",
    "mechanism.journal_fit": 'ISO 286 fit of journal in carrier bore, hole/shaft (e.g. "H7/g6")',
    "mechanism.carrier_thickness_mm": "carrier thickness (mm); omit for 1.5 x journal diameter, up to 0.5 mm",
    "mechanism.carrier_guidance": '"clear" (carrier runs clear of screw and nut) or "nut" (guided in the nut bore)',
    "mechanism.carrier_fit": 'ISO 286 fit of carrier in nut bore when guided there (e.g. "H8/f7")',
    "mechanism.carrier_radial_clearance_mm": "radial clearance of the carrier to the screw crest and to the nut bore (mm)",
    "mechanism.roller_end_play_mm": "axial gap between each roller gear face and its carrier (mm)",
    "mechanism.ring_play_mm": "axial gap between each carrier and its retaining ring (mm)",
    "mechanism.ring_bore_mm": "DIN 472 ring size = nut end bore (mm); omit for the smallest that fits",
    "mechanism.length_tolerance": 'ISO 286 zone of the axial lengths in the stack-up (e.g. "js11")',
    "loads.tooth_width": 'width of the Yamamoto tooth terms: "circumference-share", "ring", "contact-ellipse" or "unit"',
    "loads.compliance": 'tooth compliance of the load model: "analytic" (Yamamoto) or "fe" (finite-element '
                        'influence matrices; needs prs-geom[fe])',
    "tolerances.distribution": '"uniform" (within +-T) or "normal" (T = 3 sigma)',
    "tolerances.flank_um": "axial position tolerance of every loaded flank (um)",
    "tolerances.screw_flank_um": "per-tooth tolerance of the screw flank (um), overrides flank_um",
    "tolerances.roller_screw_flank_um": "per-tooth tolerance of the roller's screw-side flank (um)",
    "tolerances.roller_nut_flank_um": "per-tooth tolerance of the roller's nut-side flank (um)",
    "tolerances.nut_flank_um": "per-tooth tolerance of the nut flank (um)",
    "tolerances.roller_diameter_um": "roller pitch-diameter tolerance (um, on the diameter)",
    "tolerances.screw_eccentricity_um": "screw thread axis offset (um, half the radial run-out)",
    "tolerances.nut_eccentricity_um": "nut thread axis offset (um, half the radial run-out)",
    "tolerances.lead_um": "base-lead error accumulated over the engaged length (um)",
    "tolerances.temperature_k": "temperature difference between parts (K)",
    "tolerances.samples": "Monte Carlo samples of the build's tolerance study",
    "tolerances.seed": "random seed of the study (same seed, same numbers)",
    "tolerances.load_fractions": "loads of the study, as fractions of loading.axial_load_n",
    "tolerances.source": "where these tolerances come from",
    "tolerances.target_ldc": "worst load-distribution coefficient the synthesis targeted",
    "tolerances.confidence": "probability of meeting target_ldc the synthesis guaranteed",
    "supports.unsupported_length_mm": "free screw length between the supports (mm); omit to take it from the "
                                      "actuator's bearings (or screw.length_mm without an actuator)",
    "supports.critical_speed_ends": 'end fixity for the critical speed: "fixed-fixed", "fixed-supported", '
                                    '"supported-supported" or "fixed-free"',
    "supports.buckling_ends": 'end fixity for buckling: "fixed-fixed", "fixed-supported", '
                              '"supported-supported" or "fixed-free"',
    "supports.buckling_safety": "safety on the Euler buckling load (>= 1)",
    "supports.critical_speed_factor": "permissible fraction of the first whirling speed (0 to 1)",
    "rating.friction_coefficient": "flank friction coefficient mu (efficiency and torque)",
    "rating.speed_rpm": "mean screw speed (rpm) for the life in hours when no spectrum is given",
    "rating.life_hours": "target life (h) for the required dynamic load rating",
    "rating.reliability_pct": "reliability of the stated life (90 to 99 %)",
    "rating.operating_factor": "operating factor f_w >= 1 on the load",
    "rating.static_pressure_limit_mpa": "Hertz pressure of the static load rating (MPa)",
    "rating.preload_n": "double-nut preload (N); omit for design load / 2.83",
    "rating.dn_limit_mm_rpm": "nut speed limit as nominal diameter x speed (mm/min)",
    "rating.required_static_safety": "smallest static safety s0 = C_0a / F_max the limit checks accept "
                                     "(1 to 20; catalogue: 2 without, 5 with vibration or impact)",
    "actuator.enabled": "build the screw and nut as an actuator: stroke, screw ends, nut mounting (docs/theory/actuator.md)",
    "actuator.stroke_mm": "nut travel along the screw (mm)",
    "actuator.over_travel_mm": "full thread beyond each stroke end, for an end stop (mm)",
    "actuator.screw_run_out_mm": "grinding-wheel exit at each screw thread end (mm); omit for one lead",
    "actuator.thread_chamfer_mm": "45 deg chamfer ending the roller and nut threads (mm); omit for 0.8 x crest to pitch",
    "actuator.fixed_end.bearing_series": 'ISO 15 dimension series of the 72xx B pair: "02" or "03"',
    "actuator.fixed_end.bearing_bore_mm": "bearing bore (mm); omit for the largest below the screw root - 1 mm",
    "actuator.fixed_end.bearing_width_mm": "bearing width (mm); omit for the ISO 15 table's",
    "actuator.fixed_end.bearing_outer_diameter_mm": "bearing outside diameter (mm); omit for the ISO 15 table's",
    "actuator.fixed_end.seat_tolerance": "ISO 286 zone of the bearing seat",
    "actuator.fixed_end.locknut_thread_mm": "KM locknut thread diameter (mm, ISO 261 fine); omit for the bore",
    "actuator.fixed_end.locknut_tolerance": "ISO 965-1 tolerance class of the locknut thread",
    "actuator.fixed_end.undercut_width_mm": "thread undercut width (mm); omit for 3 x the thread pitch",
    "actuator.floating_end.enabled": "false: no floating bearing (a fixed-free screw)",
    "actuator.floating_end.bearing_series": 'ISO 15 dimension series of the 62xx bearing: "02" or "03"',
    "actuator.floating_end.bearing_bore_mm": "bearing bore (mm); omit for the largest below the screw root - 1 mm",
    "actuator.floating_end.bearing_width_mm": "bearing width (mm); omit for the ISO 15 table's",
    "actuator.floating_end.bearing_outer_diameter_mm": "bearing outside diameter (mm); omit for the ISO 15 table's",
    "actuator.floating_end.seat_tolerance": "ISO 286 zone of the bearing seat",
    "actuator.drive.kind": '"key" (DIN 6885-1) or "flat" on the drive journal',
    "actuator.drive.diameter_mm": "drive journal diameter (mm, ISO 775); omit for the largest the locknut passes",
    "actuator.drive.length_mm": "drive journal length (mm); omit for the ISO 775 short series",
    "actuator.drive.fit": "ISO 286 zone of the drive journal",
    "actuator.drive.key_length_mm": "key (or flat) length (mm); omit for the longest standard <= journal - 4 mm",
    "actuator.drive.flat_depth_mm": "depth of the flat (mm); omit for 0.1 x the journal diameter",
    "actuator.nut_mount.kind": '"flange" (bolted, at the nut\'s loaded end; the one mounting so far)',
    "actuator.nut_mount.bolt": 'flange bolts, ISO 4762 class 8.8 ("M6"); omit for the smallest carrying 2 x the load',
    "actuator.nut_mount.bolt_count": "number of flange bolts",
    "actuator.nut_mount.bolt_circle_diameter_mm": "bolt circle (mm); omit for nut diameter + head + 1 mm",
    "actuator.nut_mount.flange_diameter_mm": "flange outside diameter (mm); omit for bolt circle + head + 2 mm",
    "actuator.nut_mount.flange_thickness_mm": "flange thickness (mm); omit for 1.5 x the bolt diameter",
    "actuator.nut_mount.bolt_length_mm": "flange bolt length (mm); omit for flange + 1.5 x bolt diameter, up to ISO 4762",
    "kind": 'kind of design: "prs" (default) or another product line',
    "format_version": "design-file format version (files without it are version 1)",
}


# --------------------------------------------------------------------------- dict form
def design_to_dict(design: PRSDesign, omit: frozenset[str] | tuple[str, ...] = ()) -> dict[str, Any]:
    """Plain nested dict of a (resolved) design; pitch lists as lists, absent ones omitted.
    ``omit``: dotted field paths (``"loads"``, ``"loading.axial_load_n"``) left out, and not
    even read."""

    def conv(obj: Any, path: str) -> Any:
        if dataclasses.is_dataclass(obj):
            out = {}
            for f in dataclasses.fields(obj):
                here = f"{path}.{f.name}" if path else f.name
                if here in omit:
                    continue
                v = getattr(obj, f.name)
                if v is None:
                    continue
                out[f.name] = conv(v, here)
            return out
        if isinstance(obj, tuple):
            return [conv(v, path) for v in obj]
        return obj

    return conv(design, "")


def build_section(cls: type, data: Any, path: str = "") -> Any:
    """Validate the nested dict ``data`` into the dataclass ``cls``.

    A field whose default is made by another dataclass (``field(default_factory=Thread)``)
    is a table of the file and is built recursively; unknown keys are errors naming the
    dotted path; errors from validation get the path of their table in front.
    """
    if not isinstance(data, dict):
        raise DesignError(path, data, "must be a table of keys")
    known = {f.name: f for f in dataclasses.fields(cls)}
    kwargs: dict[str, Any] = {}
    for key, value in data.items():
        if key not in known:
            raise DesignError(f"{path}.{key_name(key)}" if path else key_name(key), value,
                              "unknown key; allowed: " + ", ".join(sorted(known)))
        sub = _nested_type(known[key])
        kwargs[key] = build_section(sub, value, f"{path}.{key}" if path else key) if sub else value
    try:
        return dataclasses.replace(cls, **kwargs) if not isinstance(cls, type) else cls(**kwargs)
    except DesignError as exc:
        raise exc.prefixed(path) if path and not exc.field.startswith(path + ".") else exc


def _nested_type(fld: dataclasses.Field) -> type | None:
    """The dataclass type of a table field (its default factory, or ``metadata["section"]``
    for an optional table that is None when absent), or None for a value."""
    if "section" in fld.metadata:
        return fld.metadata["section"]
    factory = fld.default_factory
    if isinstance(factory, type) and dataclasses.is_dataclass(factory):
        return factory
    if factory is dataclasses.MISSING:
        return None
    # a factory function making a dataclass with other defaults (the thread parts' material):
    # the table's keys replace those of its default instance, not of the class
    made = factory()
    return made if dataclasses.is_dataclass(made) else None


#: Design classes by the top-level ``kind`` of a file; a class may declare ``FILE_KIND``
#: (the kind it writes) and ``FIELD_COMMENTS``. The model knows only the PRS; other product
#: lines pass their own table (see :func:`prs_geom.pipeline.load_any_design`).
PRS_KINDS: dict[str, type] = {"prs": PRSDesign}
#: Version of the design-file format this prs_geom writes. Files without the key are the
#: first format (version 1, identical keys); a newer version is refused with a message.
#: Version 2 adds the ``[actuator]`` section. A version-1 file (or one without the key) that
#: gives ``screw.length_mm`` (then the whole screw) reads as it did, without an actuator
#: (``actuator.enabled = false``), unless it has the section. Version 3 adds the harmonic
#: drive's ``[drive]`` and ``[generator]`` sections (fixed member, flexspline material, pressing,
#: adjusting; the wave generator); a version-2 harmonic file reads with their defaults (the
#: published example's arrangement).
DESIGN_FORMAT_VERSION = 3


def check_format_version(value: Any, what: str = "design file") -> int:
    """The ``format_version`` of a file this prs_geom can read, else a :class:`DesignError`."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise DesignError("format_version", value, "must be a whole number >= 1")
    if value > DESIGN_FORMAT_VERSION:
        from prs_geom._version import __version__
        raise DesignError("format_version", value,
                          f"this {what} was written by a newer prs-geom; prs_geom {__version__} reads "
                          f"format versions 1 to {DESIGN_FORMAT_VERSION}: upgrade prs-geom")
    return value


def design_from_dict(data: dict[str, Any], kinds: dict[str, type] | None = None):
    """Validate a nested dict into a design: a :class:`PRSDesign`, or the class ``kinds``
    maps the file's ``kind`` to (errors name the dotted field)."""
    kinds = PRS_KINDS if kinds is None else kinds
    if not isinstance(data, dict):
        raise DesignError("design", data, "must be a table of keys (name, thread, screw, ...)")
    data = dict(data)
    version = check_format_version(data.pop("format_version")) if "format_version" in data else 1
    kind = data.pop("kind", "prs")
    if not isinstance(kind, str) or kind not in kinds:
        raise DesignError("kind", kind, "must be one of " + ", ".join(f'"{k}"' for k in kinds))
    screw = data.get("screw")
    if (kind == "prs" and version < 2 and "actuator" not in data and isinstance(screw, dict)
            and "length_mm" in screw):
        # in version 1 screw.length_mm was the whole screw: such a file reads as it did, with no
        # stroke or ends (its screw is shorter than an actuator needs); one without it (an empty
        # file) is today's default design, the actuator included
        data["actuator"] = {"enabled": False}
    return build_section(kinds[kind], data, "")


# --------------------------------------------------------------------------- TOML
def toml_string(text: str) -> str:
    """A TOML basic string: quotes, backslashes and non-printable characters escaped."""
    return quote(text)


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"cannot write non-finite float {v!r} to TOML")
        return repr(v)
    if isinstance(v, str):
        return toml_string(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def dumps_toml(design, comments: bool = True, header: str | None = None) -> str:
    """TOML text of a design that :func:`loads_toml` reads back to an equal object."""
    data = _file_dict(design)
    notes = {**FIELD_COMMENTS, **getattr(type(design), "FIELD_COMMENTS", {})}
    lines: list[str] = []
    if header:
        lines += [f"# {h}" if h else "#" for h in header.splitlines()] + [""]

    def emit(table: dict[str, Any], path: str) -> None:
        scalars = {k: v for k, v in table.items() if not isinstance(v, dict)}
        subs = {k: v for k, v in table.items() if isinstance(v, dict)}
        if path and scalars:
            lines.append(f"[{path}]")
        for k, v in scalars.items():
            key = f"{path}.{k}" if path else k
            note = notes.get(key) or notes.get(k)
            if comments and note:
                lines.append(f"# {note}")
            lines.append(f"{k} = {_toml_value(v)}")
        if scalars:
            lines.append("")
        for k, v in subs.items():
            emit(v, f"{path}.{k}" if path else k)

    emit(data, "")
    return "\n".join(lines).rstrip() + "\n"


def loads_toml(text: str, source: str = "<text>", kinds: dict[str, type] | None = None) -> PRSDesign:
    """A design from TOML text; ``source`` names the file in error messages."""
    return design_from_dict(parse_document(text.removeprefix("\ufeff"), source, "design file", "toml"), kinds)


# --------------------------------------------------------------------------- JSON
def _file_dict(design, omit: frozenset[str] = frozenset()) -> dict[str, Any]:
    """The dict a design file holds: format version, kind (for other product lines), fields
    (less the dotted paths ``omit``, :func:`design_to_dict`)."""
    kind = getattr(type(design), "FILE_KIND", None)
    head: dict[str, Any] = {"format_version": DESIGN_FORMAT_VERSION}
    if kind is not None:
        head["kind"] = kind
    return {**head, **design_to_dict(design, omit)}


def dumps_json(design) -> str:
    """JSON text of a design that :func:`loads_json` reads back to an equal object."""
    return json.dumps(_file_dict(design), indent=2) + "\n"


def loads_json(text: str, source: str = "<text>", kinds: dict[str, type] | None = None) -> PRSDesign:
    """A design from JSON text; ``source`` names the file in error messages. A key given
    twice in one object is an error (as in TOML), not the last one silently winning."""
    return design_from_dict(parse_document(text.removeprefix("\ufeff"), source, "design file", "json"), kinds)


def decode_text(raw: bytes, source: str, what: str = "design file") -> str:
    """UTF-8 text of a design file, with or without a byte-order mark.

    Any other encoding is a :class:`DesignError` naming the file and the byte offset of the
    first byte that is not UTF-8 (UTF-16 and UTF-32 files are recognised by their mark).
    """
    for bom, name in ((b"\xff\xfe\x00\x00", "UTF-32"), (b"\x00\x00\xfe\xff", "UTF-32"),
                      (b"\xff\xfe", "UTF-16"), (b"\xfe\xff", "UTF-16")):
        if raw.startswith(bom):
            raise DesignError.about_file(source, f"is not UTF-8: it starts with a {name} byte-order "
                                                 f"mark; save it as UTF-8", what)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise DesignError.about_file(source, f"is not UTF-8 text: byte 0x{raw[exc.start]:02x} at byte "
                                             f"offset {exc.start}; save it as UTF-8", what) from None
    if "\x00" in text:
        raise DesignError.about_file(source, f"is not text: NUL byte at byte offset {raw.index(0)}", what)
    return text.removeprefix("\ufeff")


# --------------------------------------------------------------------------- input limits
#: Largest input file prs-geom reads (design, spectrum and target files), in bytes. Real
#: files are a few kB (a 500-tooth design with every per-tooth list is under 100 kB). The
#: size is checked on the opened file before reading, and at most this many bytes plus one
#: are read, so a file that grows while it is read is refused too.
MAX_INPUT_BYTES = 4 * 1024 * 1024
#: Longest text value of an input file, in characters. The model's own rules are tighter
#: (design names 1-64, material names 1-60 characters); this cap holds for every text value,
#: so that no text of any length reaches a rule, a message or an output file.
MAX_TEXT_CHARS = 1000
#: Longest key of an input file, in characters (the longest key of a design file has 36).
MAX_KEY_CHARS = 100
#: Deepest nesting of tables and lists of an input file (a design file uses 3 levels, e.g.
#: ``materials.screw.name``); deeper files are refused, and one too deep for the parser
#: itself (a recursion error) is refused with the same message.
MAX_NESTING = 32
#: Whole numbers are 64-bit signed integers, as the TOML specification has them (JSON
#: files are held to the same range); a larger number is written as a float (``1e20``).
MIN_INT, MAX_INT = -(2 ** 63), 2 ** 63 - 1

_NOT_REGULAR = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a named pipe (FIFO)"),
                (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                (stat.S_ISSOCK, "a socket"))


def _size_text(n: int) -> str:
    return f"{n / 1024 ** 2:g} MiB ({n} bytes)" if n >= 1024 ** 2 else f"{n} bytes"


def _check_kind(st: os.stat_result, source: str, what: str, limit: int) -> None:
    """Refuse what is not a regular file, or one larger than ``limit`` bytes."""
    if not stat.S_ISREG(st.st_mode):
        kind = next((name for test, name in _NOT_REGULAR if test(st.st_mode)), "not a regular file")
        raise DesignError.about_file(source, f"is {kind}; a {what} must be a regular file", what)
    if st.st_size > limit:
        raise DesignError.about_file(source, f"is {_size_text(st.st_size)}, larger than the {_size_text(limit)} "
                                             f"a {what} may have", what)


def _open_error(exc: OSError, source: str, what: str) -> Exception:
    """A path that names no file is bad input (exit 2); one that cannot be read here (a
    permission, an I/O error) an :class:`EnvironmentFailure` (exit 3)."""
    if exc.errno in (errno.ENOENT, errno.ENOTDIR):
        return DesignError.about_file(source, "does not exist", what)
    if exc.errno in (errno.ELOOP, errno.ENAMETOOLONG, errno.ENXIO, errno.ENODEV):
        return DesignError.about_file(source, f"cannot be opened: {exc.strerror or exc}", what)
    return EnvironmentFailure(f"cannot read {source}: {exc.strerror or exc}")


def read_user_file(path: str | os.PathLike[str], what: str = "design file",
                   limit: int = MAX_INPUT_BYTES) -> bytes:
    """The bytes of an input file the user named, read within bounds.

    Only a regular file is read (a symlink is followed, and its target must be a regular
    file): a folder, a named pipe (FIFO), a device or a socket is refused before anything is
    read, and the file is opened non-blocking, so a FIFO without a writer cannot hang the
    program. A file larger than ``limit`` bytes (:data:`MAX_INPUT_BYTES`) is refused by its
    size, and at most ``limit + 1`` bytes are ever read (a file growing while it is read is
    refused too). Errors are :class:`DesignError` naming ``what`` and the path (exit 2), or
    :class:`EnvironmentFailure` for a file that exists but cannot be read here (exit 3).
    """
    source = os.fspath(path)
    try:
        _check_kind(os.stat(source), source, what, limit)
        fd = os.open(source, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
                     | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_BINARY", 0))
    except OSError as exc:
        raise _open_error(exc, source, what) from None
    try:
        _check_kind(os.fstat(fd), source, what, limit)   # what was opened, not what was looked at
        chunks: list[bytes] = []
        total = 0
        while total <= limit:
            chunk = os.read(fd, min(1 << 16, limit + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
    except OSError as exc:
        raise EnvironmentFailure(f"cannot read {source}: {exc.strerror or exc}") from None
    finally:
        os.close(fd)
    if total > limit:
        raise DesignError.about_file(source, f"has more than the {_size_text(limit)} a {what} may have "
                                             f"(found while reading: it grew, or its size was not known)", what)
    return b"".join(chunks)


def read_input_text(path: Path, what: str) -> str:
    """The UTF-8 text (:func:`decode_text`) of an input file the user named, read by
    :func:`read_user_file` (regular files only, at most :data:`MAX_INPUT_BYTES`).

    A path that does not exist, is not a regular file or is too large is a
    :class:`DesignError` on ``what`` (e.g. "design file"; bad input, exit 2); a file that
    exists but cannot be read is an :class:`EnvironmentFailure` (exit 3)."""
    return decode_text(read_user_file(path, what), os.fspath(path), what)


def _parse_text(text: str, source: str, what: str, fmt: str) -> tuple[Any, dict[int, list[str]]]:
    """Parse TOML or JSON text; syntax errors, nesting too deep for the parser and whole
    numbers too long to convert are :class:`DesignError` on the file. Also returns the keys
    given more than once in a JSON object, by the ``id`` of the object."""
    if len(text) > MAX_INPUT_BYTES:
        raise DesignError.about_file(source, f"has {len(text)} characters, more than the "
                                             f"{MAX_INPUT_BYTES} a {what} may have", what)
    duplicates: dict[int, list[str]] = {}
    name = "JSON" if fmt == "json" else "TOML"
    try:
        if fmt == "json":
            def pairs_hook(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
                obj = dict(pairs)
                if len(obj) != len(pairs):
                    seen: set[str] = set()
                    duplicates[id(obj)] = [k for k, _ in pairs if k in seen or seen.add(k)]
                return obj

            data = json.loads(text, object_pairs_hook=pairs_hook)
        else:
            data = tomllib.loads(text)
    except (json.JSONDecodeError, tomllib.TOMLDecodeError) as exc:
        raise DesignError.about_file(source, f"is not valid {name}: {exc}", what) from None
    except RecursionError:
        raise DesignError.about_file(source, f"is nested too deeply: at most {MAX_NESTING} levels of tables "
                                             f"and lists", what) from None
    except ValueError as exc:
        # the only other ValueError of both parsers: Python's limit on converting a long
        # decimal string to an integer (sys.get_int_max_str_digits())
        if "integer string conversion" in str(exc):
            raise DesignError.about_file(
                source, f"holds a whole number of more than {sys.get_int_max_str_digits()} digits (the "
                        f"reader's limit); whole numbers are 64-bit, -2^63 to 2^63 - 1: write a larger "
                        f"number as a float, e.g. 1e20", what) from None
        raise DesignError.about_file(source, f"is not valid {name}: {str(exc)[:100]}", what) from None
    return data, duplicates


def check_document(data: Any, prefix: str = "", duplicates: dict[int, list[str]] | None = None) -> None:
    """Check a parsed input file against the limits of every value: nesting at most
    :data:`MAX_NESTING` levels, text at most :data:`MAX_TEXT_CHARS` characters, keys at
    most :data:`MAX_KEY_CHARS`, whole numbers in :data:`MIN_INT` to :data:`MAX_INT`, and no
    key given twice (``duplicates``, from a JSON parse). The first value beyond a limit, in
    the order of the file, is a :class:`DesignError` naming its dotted path (after
    ``prefix``)."""
    duplicates = duplicates or {}
    stack: list[tuple[Any, str, int]] = [(data, prefix, 0)]
    while stack:
        value, path, depth = stack.pop()
        if isinstance(value, (dict, list)):
            if depth > MAX_NESTING:
                raise DesignError(path, value, f"is nested more than {MAX_NESTING} levels deep (tables and "
                                               f"lists)")
            children: list[tuple[Any, str, int]] = []
            if isinstance(value, dict):
                for key in duplicates.get(id(value), ())[:1]:
                    raise DesignError(f"{path}.{key_name(key)}" if path else key_name(key), value[key],
                                      "this key is given more than once in the same object; give it once "
                                      "(the last one would silently win)")
                for key, item in value.items():
                    sub = f"{path}.{key_name(key)}" if path else key_name(key)
                    if len(key) > MAX_KEY_CHARS:
                        raise DesignError(sub, item, f"has a key of {len(key)} characters; keys have at most "
                                                     f"{MAX_KEY_CHARS}")
                    children.append((item, sub, depth + 1))
            else:
                children = [(item, f"{path}[{k}]", depth + 1) for k, item in enumerate(value)]
            stack.extend(reversed(children))
        elif isinstance(value, str):
            if len(value) > MAX_TEXT_CHARS:
                raise DesignError(path, value, f"is {len(value)} characters long; a text value has at most "
                                               f"{MAX_TEXT_CHARS}")
        elif isinstance(value, int) and not isinstance(value, bool):
            if not MIN_INT <= value <= MAX_INT:
                raise DesignError(path, value, "is outside the 64-bit whole numbers, -2^63 to 2^63 - 1: write a "
                                               "larger number as a float, e.g. 1e20")


def parse_document(text: str, source: str, what: str, fmt: str, prefix: str = "") -> Any:
    """The parsed ``fmt`` (``"toml"`` or ``"json"``) text of an input file, checked by
    :func:`check_document`; every problem is a :class:`DesignError` (exit 2)."""
    data, duplicates = _parse_text(text, source, what, fmt)
    check_document(data, prefix, duplicates)
    return data


def load_document(path: str | os.PathLike[str], what: str, prefix: str = "") -> Any:
    """The checked contents of a ``.json`` (by its suffix) or TOML input file, read by
    :func:`read_user_file` and parsed by :func:`parse_document`."""
    source = os.fspath(path)
    text = read_input_text(Path(source), what)
    return parse_document(text, source, what, "json" if Path(source).suffix.lower() == ".json" else "toml",
                          prefix)


def load_design(path: str | Path, kinds: dict[str, type] | None = None) -> PRSDesign:
    """Read a design from a ``.toml`` or ``.json`` file (UTF-8, with or without BOM).

    A file that does not exist or is a folder is a :class:`DesignError` (bad input, exit 2);
    a file that exists but cannot be read is an :class:`EnvironmentFailure` (exit 3).
    """
    path = Path(path)
    source = str(path)
    text = read_input_text(path, "design file")
    if path.suffix.lower() == ".json":
        return loads_json(text, source, kinds)
    return loads_toml(text, source, kinds)


def save_design(design: PRSDesign, path: str | Path, overwrite: bool = False) -> None:
    """Write a design as TOML (``.toml``) or JSON (``.json``), atomically.

    An existing file is refused (:class:`~prs_geom.model.errors.OutputRefused`) unless
    ``overwrite``.

    Examples
    --------
    >>> import prs_geom as pg
    >>> pg.save_design(pg.default_design(), "design.toml")
    >>> pg.load_design("design.toml") == pg.default_design()
    True
    >>> try:
    ...     pg.save_design(pg.default_design(), "design.toml")
    ... except pg.OutputRefused:
    ...     print("kept")
    kept
    """
    path = check_output_file(path, force=overwrite)
    text = dumps_json(design) if path.suffix.lower() == ".json" else dumps_toml(design)
    try:
        write_file_atomic(path, text)
    except OSError as exc:
        raise EnvironmentFailure(f"cannot write {path}: {exc.strerror or exc}") from None


# --------------------------------------------------------------------------- safe single files
#: Lock files office programs keep beside an open document.
_LOCK_PATTERNS = (re.compile(r"^~\$.+"), re.compile(r"^\.~lock\..+#$"))


def is_office_lock(name: str) -> bool:
    """True for the lock file of a document open in an office program."""
    return any(p.match(name) for p in _LOCK_PATTERNS)


def check_output_file(target: str | os.PathLike[str], force: bool = False) -> Path:
    """Check that a single output file may be written (``init --out``, ``design-pitch --out``).

    An existing file is refused unless ``force``; a folder and an office lock file are
    always refused (:class:`~prs_geom.model.errors.OutputRefused`).
    """
    path = Path(target)
    if path.is_dir():
        raise OutputRefused(f"output file {str(target)!r} is an existing folder")
    if path.exists() and not force:
        raise OutputRefused(f"output file {str(target)!r} already exists: prs-geom does not "
                            f"overwrite it without --force")
    if path.name and is_office_lock(path.name):
        raise OutputRefused(f"output file {str(target)!r} is an office lock file")
    return path


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """A temporary path to write ``path`` through: yields the hidden sibling
    ``.<name>.tmp-<pid>-<random>`` (same folder, so the rename is atomic), which the block
    creates; when the block ends normally the file replaces ``path`` (``os.replace``).

    When the block raises (or the rename fails) the temporary file is removed and ``path``
    is left as it was: never half-written. For writers that take a file name (OpenCascade,
    lib3mf); :func:`write_file_atomic` writes text or bytes through it.
    """
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}-{secrets.token_hex(4)}")
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def write_file_atomic(path: str | os.PathLike, text: str | bytes) -> None:
    """Write ``text`` (UTF-8) or bytes to ``path`` through a temporary sibling and a rename
    (:func:`atomic_path`): ``path`` holds either its old content or all of the new."""
    with atomic_path(path) as tmp:
        if isinstance(text, bytes):
            tmp.write_bytes(text)
        else:
            tmp.write_text(text, encoding="utf-8")


def load_spectrum(path: str | Path):
    """A :class:`~prs_geom.model.spectrum.Spectrum` from a TOML file of ``[[case]]`` tables
    (UTF-8); errors name the file, the case and the key."""
    from prs_geom.model.spectrum import spectrum_from_dict
    path = Path(path)
    text = read_input_text(path, "spectrum file")
    data, duplicates = _parse_text(text, str(path), "spectrum file", "toml")
    try:
        check_document(data, "", duplicates)
        return spectrum_from_dict(data)
    except DesignError as exc:
        raise DesignError(f"spectrum file {str(path)!r}: {exc.field}", exc.value, exc.rule) from None


#: The fields of a planetary roller screw design that say how it is operated and analysed,
#: not what is made: the design load, the load model's settings, the rating settings and the
#: support conditions of the buckling and critical-speed checks. :func:`design_hash` leaves
#: them out, so that a new load case re-issues no drawing, sheet or mesh (their files, and
#: the stage cache's records of them, stay as they were).
OPERATING_FIELDS = frozenset({"loading.axial_load_n", "loads", "rating", "supports"})


def operating_sizes(design) -> dict[str, Any]:
    """The sizes of a part that the operating fields set (:data:`OPERATING_FIELDS`): the
    nut flange's bolt, sized from the design load when the design file gives none
    (:func:`prs_geom.model.machine_elements.load_sized_bolt`); empty for other designs.
    What :func:`design_hash` and the stage cache's keys hold in place of the load."""
    if not isinstance(design, PRSDesign) or not design.actuator.enabled or design.actuator.nut_mount.bolt is not None:
        return {}
    from prs_geom.model.machine_elements import load_sized_bolt

    count = design.actuator.nut_mount.bolt_count
    return {"sized.actuator.nut_mount.bolt": load_sized_bolt(count, design.loading.axial_load_n)}


def definition_dict(design) -> dict[str, Any]:
    """What is made: the design file's dict less :data:`OPERATING_FIELDS` (for a planetary
    roller screw) plus the sizes they set (:func:`operating_sizes`). What
    :func:`design_hash` and the stage cache's keys of the part stages cover."""
    omit = OPERATING_FIELDS if isinstance(design, PRSDesign) else frozenset()
    return {**_file_dict(design, omit), **operating_sizes(design)}


def design_hash(design) -> str:
    """The design's short identity, printed by the drawings' title blocks (whose revision it
    is), the machining sheets, the STL headers and report.html: the first 12 hex digits of
    the sha256 of :func:`definition_dict` as canonical JSON (one part definition, one hash,
    whatever load it is analysed under)."""
    import hashlib

    text = json.dumps(definition_dict(design), sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:12]
