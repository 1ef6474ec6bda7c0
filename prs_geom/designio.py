"""Reading and writing design files (TOML and JSON).

A design file has the top-level key ``name`` and the tables ``[thread]``, ``[screw]``,
``[roller]``, ``[nut]``, ``[materials.screw]``, ``[materials.roller]``,
``[materials.nut]``, ``[loading]``, ``[contact]`` and ``[mesh]``; every table and key is
optional and falls back to the built-in default design. Unknown keys are errors (a
misspelt key silently ignored would build the wrong part).

Floats are written with Python's shortest round-trip representation, so a written
design reads back to an equal :class:`~prs_geom.design.PRSDesign`, bit for bit.
"""
from __future__ import annotations

import dataclasses
import json
import math
import tomllib
from pathlib import Path
from typing import Any

from .design import Materials, PRSDesign
from .errors import DesignError

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
    "screw.length_mm": "threaded length of the screw (mm), >= n p",
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
    "kind": '"prs" (default) or "harmonic"',
    "flexspline.neutral_radius_mm": "flexspline neutral-layer radius r0 (mm)",
    "flexspline.length_mm": "flexspline length L from the bottom (mm)",
    "flexspline.arc_radius_mm": "contact arc radius r_s (mm)",
    "flexspline.arc_centre_offset_mm": "arc centre offset c_s inside the neutral layer (mm)",
    "flexspline.wall_thickness_mm": "cup wall thickness for the mesh (mm)",
    "circular_spline.bore_small_radius_mm": "cone bore radius b1 at the small end (mm)",
    "circular_spline.bore_large_radius_mm": "cone bore radius b2 at the big end (mm)",
    "circular_spline.bore_length_mm": "cone bore length H (mm)",
    "circular_spline.outer_radius_mm": "outer radius of the circular spline ring (mm)",
    "positions.min_mm": "smallest position a of the cone small end from the flexspline bottom (mm)",
    "positions.max_mm": "largest position a (mm), below the infinite-ratio position",
    "positions.drawing_mm": "positions a drawn in the DXF (mm)",
}


# --------------------------------------------------------------------------- dict form
def design_to_dict(design: PRSDesign) -> dict[str, Any]:
    """Plain nested dict of a (resolved) design; pitch lists as lists, absent ones omitted."""

    def conv(obj: Any) -> Any:
        if dataclasses.is_dataclass(obj):
            out = {}
            for f in dataclasses.fields(obj):
                v = getattr(obj, f.name)
                if v is None:
                    continue
                out[f.name] = conv(v)
            return out
        if isinstance(obj, tuple):
            return [conv(v) for v in obj]
        return obj

    return conv(design)


def _build(cls: type, data: Any, path: str) -> Any:
    if not isinstance(data, dict):
        raise DesignError(path, data, "must be a table of keys")
    known = {f.name: f for f in dataclasses.fields(cls)}
    kwargs: dict[str, Any] = {}
    for key, value in data.items():
        if key not in known:
            raise DesignError(f"{path}.{key}" if path else key, value,
                              "unknown key; allowed: " + ", ".join(sorted(known)))
        sub = _nested_type(cls, key)
        kwargs[key] = _build(sub, value, f"{path}.{key}" if path else key) if sub else value
    try:
        return cls(**kwargs)
    except DesignError as exc:
        raise exc.prefixed(path) if path and not exc.field.startswith(path + ".") else exc


def _nested_type(cls: type, key: str) -> type | None:
    """The dataclass type of a section, or None for a plain value."""
    from .design import ContactSettings, Loading, Material, MeshSettings, Nut, Roller, Screw, Thread
    from .harmonic import CircularSpline, Flexspline, HarmonicDesign, HarmonicMesh, Positions

    table = {
        HarmonicDesign: {"flexspline": Flexspline, "circular_spline": CircularSpline,
                         "positions": Positions, "mesh": HarmonicMesh},
        PRSDesign: {"thread": Thread, "screw": Screw, "roller": Roller, "nut": Nut,
                    "materials": Materials, "loading": Loading, "contact": ContactSettings,
                    "mesh": MeshSettings},
        Materials: {"screw": Material, "roller": Material, "nut": Material},
    }
    return table.get(cls, {}).get(key)


#: Top-level ``kind`` of a design file: a PRS (default) or a harmonic friction drive.
KINDS = ("prs", "harmonic")


def design_from_dict(data: dict[str, Any]):
    """Validate a nested dict into a :class:`PRSDesign`, or a
    :class:`~prs_geom.harmonic.HarmonicDesign` when ``kind = "harmonic"`` (errors name the
    dotted field)."""
    from .harmonic import HarmonicDesign

    if isinstance(data, dict) and "kind" in data:
        data = dict(data)
        kind = data.pop("kind")
        if kind not in KINDS:
            raise DesignError("kind", kind, "must be one of " + ", ".join(repr(k) for k in KINDS))
        if kind == "harmonic":
            return _build(HarmonicDesign, data, "")
    return _build(PRSDesign, data, "")


# --------------------------------------------------------------------------- TOML
def toml_string(text: str) -> str:
    """A TOML basic string: quotes, backslashes and control characters escaped."""
    out = []
    for ch in text:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


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
    from .harmonic import HarmonicDesign

    data = design_to_dict(design)
    if isinstance(design, HarmonicDesign):
        data = {"kind": "harmonic", **data}
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
            note = FIELD_COMMENTS.get(key) or FIELD_COMMENTS.get(k)
            if comments and note:
                lines.append(f"# {note}")
            lines.append(f"{k} = {_toml_value(v)}")
        if scalars:
            lines.append("")
        for k, v in subs.items():
            emit(v, f"{path}.{k}" if path else k)

    emit(data, "")
    return "\n".join(lines).rstrip() + "\n"


def loads_toml(text: str) -> PRSDesign:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise DesignError("<file>", "TOML", f"is not valid TOML: {exc}") from None
    return design_from_dict(data)


# --------------------------------------------------------------------------- JSON
def dumps_json(design) -> str:
    from .harmonic import HarmonicDesign

    data = design_to_dict(design)
    if isinstance(design, HarmonicDesign):
        data = {"kind": "harmonic", **data}
    return json.dumps(data, indent=2) + "\n"


def loads_json(text: str) -> PRSDesign:
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise DesignError("<file>", "JSON", f"is not valid JSON: {exc}") from None
    return design_from_dict(data)


# --------------------------------------------------------------------------- files
def load_design(path: str | Path) -> PRSDesign:
    """Read a design from a ``.toml`` or ``.json`` file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise DesignError("<file>", str(path), f"cannot be read: {exc.strerror}") from None
    if path.suffix.lower() == ".json":
        return loads_json(text)
    return loads_toml(text)


def save_design(design: PRSDesign, path: str | Path) -> None:
    """Write a design as TOML (``.toml``) or JSON (``.json``)."""
    path = Path(path)
    text = dumps_json(design) if path.suffix.lower() == ".json" else dumps_toml(design)
    path.write_text(text, encoding="utf-8")
