"""Self-contained HTML report (``report.html``): one file, no server, no network.

Sections, after a table of contents (:func:`toc`, a link to every ``<h2 id=...>``): an
interactive 3D view of the assembly, contact results, load distribution with its plots
(inline SVG), ratings, tolerances, checks, the synchronising gears (report.json
``gears``), mechanism, parts list, inspection, machining sheets, design table and mesh
checks.

Every number and boolean on the page is printed by :mod:`prs_geom.exports.numbers` (unit-
and precision-aware; no float noise, no Python literals) with the exact float64 in the
``title`` tooltip of its cell or span (:func:`table`, :func:`num`). Every table sits in
its own horizontally scrolling box (``div.tw``), so the page never scrolls sideways.

The 3D view is three.js (WebGL with a depth buffer, so no sorting seams; flat shading; the
nut cut open by a clipping plane through the axis facing the viewer; drag to rotate, wheel
to zoom, right-drag to pan), embedded unmodified from its npm package as ``data:`` URLs in
an import map (:func:`three_js`), so the page still fetches nothing. Its mesh is a display
tessellation of the assembly (coarser than the export meshes; the tolerance is stated on
the page), embedded as base64 float32/uint32 arrays, one mesh per distinct part and one
transform per placed part.

When the view has drawn its first frame it sets ``data-viewer="ok"`` and
``data-triangles`` on ``<body>``; script errors are collected in ``#errors`` and
``data-errors`` (the tests read these through a headless browser).
"""
from __future__ import annotations

import base64
import html
import json
import re
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from prs_geom.analysis.contact import ContactResult
from prs_geom.analysis.loads import LoadModel, LoadsResult, compliance_model
from prs_geom.analysis.machining import COLUMNS, MachiningSheet
from prs_geom.exports.numbers import exact, format_cell, format_quantity, key_label, unit_label
from prs_geom.exports.report import (MODEL_RISK_NOT_COMPUTED, BuildResults, contact_section, gears_section,
                                     inspection_section, loads_section, mechanism_section, rating_section,
                                     tolerance_section)
from prs_geom.mesh.assembly import build_assembly
from prs_geom.model.design import PRSDesign
from prs_geom.model.io import design_hash, design_to_dict

__all__ = ["DISPLAY_TOLERANCE_MM", "COLOURS", "scene_payload", "three_js", "Q", "Raw", "num", "prose", "TEXT_CLASS",
           "table", "design_rows", "page_template", "fill_template", "TOC_MARK", "page_head", "toc", "page_body",
           "svg_element", "write_html"]

#: Chordal tolerance (mm) of the display mesh: coarse enough for a light page.
DISPLAY_TOLERANCE_MM = 0.1

COLOURS = {"screw": "#8a9bb0", "nut": "#c9a66b", "roller": "#7fb37f", "gear": "#9a9aa4", "carrier": "#b4b4c0",
           "retaining": "#2e2e33", "bearing": "#b8bcc6", "locknut": "#3a3a40", "shaft": "#2e2e33",
           "flange": "#1c1c20", "drive": "#74747a"}


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


def scene_payload(design: PRSDesign, tol: float = DISPLAY_TOLERANCE_MM, screw_profile=None) -> dict[str, Any]:
    """The 3D view's data: the assembly at the display tolerance, with the theoretical screw
    ``screw_profile`` when given (as exported)."""
    asm = build_assembly(design, tol=tol, screw_profile=screw_profile)
    meshes, index, instances = [], {}, []
    for name, (mesh, T, kind) in asm.placed.items():
        if id(mesh) not in index:
            index[id(mesh)] = len(meshes)
            meshes.append({"v": _b64(np.asarray(mesh.vertices, dtype=np.float32)),
                           "f": _b64(np.asarray(mesh.faces, dtype=np.uint32))})
        colour = COLOURS["gear"] if kind == "gear" else COLOURS[name.split("_")[0]]
        instances.append({"name": name, "mesh": index[id(mesh)], "T": [float(x) for x in T.ravel()],
                          "colour": colour, "cut": name.startswith(("nut", "carrier", "retaining", "bearing", "locknut",
                                                                  "shaft_ring", "flange_bolt"))})
    tri = sum(len(asm.placed[i["name"]][0].faces) for i in instances)
    out = {"meshes": meshes, "instances": instances, "tolerance_mm": tol, "triangles": int(tri)}
    motion = _motions(asm)
    if motion is not None:
        out["animation"], body_of = motion
        for inst in instances:
            inst["motion"] = body_of[inst["name"]]
    return out


def _motions(asm: Any) -> tuple[dict[str, Any], dict[str, str]] | None:
    """The 3D view's animation of one screw revolution: per moving body the rigid motion
    M(t) (world = M(t) @ rest placement) at the keys of
    :func:`prs_geom.exports.scene.mechanism_animation` (screw, nut with its rings, carrier,
    each roller from :func:`prs_geom.analysis.kinematics.poses`), row-major float32; and the
    body each scene part moves with. None for a design the kinematics does not accept."""
    from prs_geom.analysis.kinematics import check_kinematic_sizing, poses
    from prs_geom.exports.scene import ANIMATION_PERIOD_S, animation_angles, moving_group
    from prs_geom.geometry.frames import roller_transform

    d = asm.design
    try:
        check_kinematic_sizing(d)
    except ValueError:
        return None
    angles = animation_angles()
    P = poses(d, angles)
    motions = {"screw": P.screw, "nut": P.nut, "carrier": P.carrier}
    for k in range(d.roller.count):
        motions[f"roller_{k}"] = P.roller[k] @ np.linalg.inv(roller_transform(d, k))
    body_of = {name: moving_group(asm.rigid_body(name)) for name in asm.placed}
    anim = {"period_s": ANIMATION_PERIOD_S, "keys": len(angles),
            "motions": {k: _b64(np.asarray(v, dtype=np.float32).reshape(len(angles), 16)) for k, v in motions.items()}}
    return anim, body_of







@lru_cache(maxsize=1)
def three_js() -> dict[str, str]:
    """three.js as report.html embeds it: an import map of ``data:`` URLs for ``three`` and
    its OrbitControls, the version and the licence text.

    The files are package data in ``prs_geom/exports/vendor/three``, fetched unmodified from
    the npm package by ``tools/vendor_three.py`` (which records their sha256 in
    ``MANIFEST.json``; the test suite checks them against it).
    """
    folder = resources.files("prs_geom.exports").joinpath("vendor", "three")
    manifest = json.loads(folder.joinpath("MANIFEST.json").read_text(encoding="utf-8"))

    def url(name: str) -> str:
        return "data:text/javascript;base64," + base64.b64encode(folder.joinpath(name).read_bytes()).decode("ascii")

    imports = {"three": url("three.module.min.js"),
               "three/addons/controls/OrbitControls.js": url("OrbitControls.js")}
    return {"importmap": json.dumps({"imports": imports}), "version": manifest["version"],
            "licence": folder.joinpath("LICENSE").read_text(encoding="utf-8")}


class Q(NamedTuple):
    """A table cell holding a number with its quantity: ``key`` (a report key or dotted path,
    see :mod:`prs_geom.exports.numbers`), or ``unit`` and ``precision``."""

    value: Any
    key: str | None = None
    unit: str | None = None
    precision: Any = None


class Raw(str):
    """A table cell that is already HTML (escaped, may hold :func:`num` spans)."""


def _title(value: Any) -> str:
    """The tooltip of a value: the full float64 text of each real number in it, or ''."""
    if isinstance(value, (list, tuple, np.ndarray)):
        texts = [exact(v) for v in value]
        return ", ".join(t if t is not None else str(v) for t, v in zip(texts, value)) if any(texts) else ""
    return exact(value) or ""


def num(value: Any, key: str | None = None, unit: str | None = None, precision: Any = None,
        with_unit: bool = True) -> str:
    """A number in running text (HTML): formatted by :func:`~prs_geom.exports.numbers.format_quantity`
    (with its unit unless ``with_unit`` is false), the exact value in the ``title`` tooltip."""
    text = (format_quantity if with_unit else format_cell)(value, unit, precision=precision, key=key)
    title = _title(value)
    attr = f" title='{html.escape(title, quote=True)}'" if title else ""
    return f"<span class='num'{attr}>{html.escape(text)}</span>"


def prose(s: Any) -> str:
    """Free text of a report section as HTML: escaped, ``um`` written µm, ``degC`` °C, and a
    signed zero (``-0.00``, ``+0``) without its sign."""
    out = html.escape(str(s))
    out = re.sub(r"\bum\b", "\u00b5m", out)
    out = re.sub(r"\bdegC\b", "\u00b0C", out)
    return re.sub(r"(?<![\w.])[-+](0(?:\.0+)?)(?![\d.])", r"\1", out)


#: Class of a text cell (left-aligned in report.css); a row's label cell is ``td.k``.
TEXT_CLASS = ' class="t"'


def _td(v: Any, key: str | None, first: bool) -> str:
    cls = ' class="k"' if first else ""
    if isinstance(v, Raw):
        return f"<td{cls}>{v}</td>"
    if isinstance(v, Q):
        v, key, unit, precision = v
    else:
        unit = precision = None
    if isinstance(v, str):                      # text reads from the left, numbers line up on the right
        return f"<td{cls or TEXT_CLASS}>{prose(v)}</td>"
    title = _title(v)
    attr = f" title='{html.escape(title, quote=True)}'" if title else ""
    return f"<td{cls}{attr}>{html.escape(format_cell(v, unit, precision=precision, key=key))}</td>"


def table(rows: list[list[Any]], header: list[str] | None = None, keys: list[str | None] | None = None,
          table_id: str = "") -> str:
    """An HTML table in its own horizontally scrolling box (``div.tw``): the page itself
    never scrolls sideways.

    Every number and boolean goes through :func:`~prs_geom.exports.numbers.format_cell`:
    a cell's quantity is its :class:`Q`, else the column's entry of ``keys`` (a report key
    or dotted path, whose schema annotation or unit suffix fixes unit and precision). Real
    numbers carry their exact value (``repr``) in the cell's ``title``. Text goes through
    :func:`prose` (``td.t``); :class:`Raw` cells are HTML. The first column is the row's
    label (``td.k``).
    """
    out = ["<div class='tw'>", f"<table id='{table_id}'>" if table_id else "<table>"]
    if header:
        out.append("<tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in header) + "</tr>")
    for r in rows:
        out.append("<tr>" + "".join(_td(v, keys[i] if keys and i < len(keys) else None, i == 0)
                                    for i, v in enumerate(r)) + "</tr>")
    out.append("</table></div>")
    return "".join(out)


def design_rows(d: dict[str, Any], prefix: str = "") -> list[list[Any]]:
    """Rows ``[dotted key, Q(value, "design." + dotted key)]`` of a nested design dict."""
    rows: list[list[Any]] = []
    for k, v in d.items():
        key = f"{prefix}.{k}" if prefix else k
        if isinstance(v, dict):
            rows += design_rows(v, key)
        else:
            rows.append([key, Q(list(v) if isinstance(v, tuple) else v, "design." + key)])
    return rows


def _header(title: str, unit: str) -> str:
    """A column title with its unit as printed (``um`` -> ``µm``)."""
    return f"{title} ({unit_label(unit)})" if unit else title


def page_template(name: str) -> str:
    """A page template shipped in ``prs_geom/exports/templates`` (package data): the page
    (``report.html``), its style sheet and the 3D viewer script; the harmonic report uses
    them too."""
    return resources.files("prs_geom.exports").joinpath("templates", name).read_text(encoding="utf-8")


def fill_template(template: str, values: dict[str, str]) -> str:
    """Replace every ``{{name}}`` once (values are not scanned again)."""
    return re.sub(r"\{\{(\w+)\}\}", lambda m: values[m.group(1)], template)


#: Where :func:`page_body` puts the table of contents (written by :func:`page_head`).
TOC_MARK = "<!--toc-->"


def page_head(title: str, version: str, date: str, design_sha: str, conventions: str, warnings: list[str],
              cut_label: str) -> list[str]:
    """The opening of a report page (both product lines): title, provenance (version, date,
    design hash, ``conventions``), the warnings, the script-error box, the place of the
    table of contents (:func:`page_body` fills it) and the 3D view with its cut-open
    checkbox labelled ``cut_label`` (the element ids viewer.js expects).
    ``title``, ``conventions`` and ``cut_label`` are HTML (callers escape what a user wrote)."""
    return [f"<h1>{title}</h1>",
            f"<p class='note' id='provenance'>prs_geom {html.escape(version)}; {html.escape(date)}; "
            f"design sha256 {design_sha}. {conventions}</p>",
            "<div id='warnings' class='warnings'><b>Warnings</b><ul>"
            + "".join(f"<li>{html.escape(w)}</li>" for w in warnings) + "</ul></div>"
            if warnings else "<p id='warnings' class='note'>Warnings: none.</p>",
            "<div id='errors'></div>", TOC_MARK,
            "<h2 id='assembly'>Assembly</h2><canvas id='view' width='900' height='560'></canvas>"
            "<div id='viewinfo' class='note'></div>"
            f"<label class='note'><input type='checkbox' id='cutaway' checked> {cut_label}</label>"
            "<label class='note' id='play-label' hidden><input type='checkbox' id='play'> run the mechanism "
            "(one screw revolution, repeated)</label>"]


_HEADING = re.compile(r"<h([23]) id='([^']+)'>(.*?)</h\1>", re.S)


def toc(body: str) -> str:
    """The table of contents of a page body: a link to every ``<h2 id=...>`` (and, nested
    under it, every ``<h3 id=...>``), in page order."""
    items: list[tuple[str, str, list[str]]] = []
    for level, ident, title in _HEADING.findall(body):
        link = f"<a href='#{ident}'>{re.sub(r'<[^>]+>', '', title)}</a>"
        if level == "2" or not items:
            items.append((ident, link, []))
        else:
            items[-1][2].append(f"<li>{link}</li>")
    lis = "".join(f"<li>{link}" + (f"<ul>{''.join(sub)}</ul>" if sub else "") + "</li>" for _, link, sub in items)
    return f"<nav id='toc' class='toc'><b>Contents</b><ol>{lis}</ol></nav>"


def page_body(parts: list[str]) -> str:
    """The page body from its parts (:func:`page_head` first): joined, with the table of
    contents at its mark."""
    body = "".join(parts)
    return body.replace(TOC_MARK, toc(body), 1)


def svg_element(text: str) -> str:
    """The ``<svg>`` element of an SVG file's text (without the XML prolog)."""
    return text[text.index("<svg"):]


def _checks_html(checks: dict[str, Any], contact: ContactResult | None) -> str:
    """Interference, FCL verification and per-tooth gaps, as measured."""
    out = ["<h2 id='checks'>Checks</h2>"]
    it = checks.get("interference")
    if it:
        k = "checks.interference."
        out.append(f"<p>Interference ({prose(it.get('screw', ''))} screw, pitch diameter "
                   f"{num(it.get('screw_pitch_diameter_mm'), k + 'screw_pitch_diameter_mm')}): "
                   f"<b>{'FOUND' if it['found'] else 'none'}</b> in {num(it.get('pairs_checked'))} part pairs at "
                   f"chord tolerance {num(it.get('chord_tolerance_mm'), k + 'chord_tolerance_mm')}. "
                   f"{prose(it.get('rule', ''))}</p>")
        rows = [[" - ".join(p["pair"]) if isinstance(p.get("pair"), list) else p.get("pair"),
                 p.get("volume_mm3"), p.get("mean_thickness_mm")] for p in it.get("pairs", [])]
        if rows:
            out.append(table(rows, ["pair", "overlap volume (mm³)", "mean thickness (mm)"],
                             [None, "volume_mm3", "mean_thickness_mm"]))
        ok = it.get("contact_within_tolerance") or []
        if ok:
            out.append(table([[" - ".join(p["pair"]), p["volume_mm3"], p["mean_thickness_mm"], len(p["teeth"])]
                              for p in ok], ["touching pair (within the mesh tolerance)", "overlap volume (mm³)",
                                             "mean thickness (mm)", "teeth"],
                             [None, "volume_mm3", "mean_thickness_mm", None]))
    fc = checks.get("fcl")
    if fc:
        out.append(f"<p>FCL mesh distance against the analytic contact, every tooth of every roller "
                   f"({num(fc['rollers_checked'])} rollers x {num(fc['teeth_checked'])} teeth, both sides), patches "
                   f"at {num(fc['patch_chord_tolerance_mm'] * 1e3, unit='um')} chord tolerance: largest |FCL gap - "
                   f"designed gap| {num(fc['max_abs_gap_difference_um'], 'max_abs_gap_difference_um')} (tolerance "
                   f"{num(fc['difference_tolerance_mm'] * 1e3, unit='um')}); {len(fc['warnings'])} warning(s).</p>")
        rows = []
        for side in ("screw", "nut"):
            cs = [c for c in fc["comparisons"] if c["side"] == side]
            if cs:
                fg = [c["fcl_gap_um"] for c in cs]
                dg = [c["designed_gap_um"] for c in cs]
                rows.append([side, cs[0]["flank"], len(cs), min(dg), max(dg), min(fg), max(fg),
                             max(abs(c["gap_difference_um"]) for c in cs)])
        out.append(table(rows, ["side", "roller flank", "teeth checked", "designed gap min (µm)",
                                "designed gap max (µm)", "FCL gap min (µm)", "FCL gap max (µm)",
                                "max |difference| (µm)"], [None, None, None] + ["gap_um"] * 5))
        out.append("<details><summary>every tooth (FCL and designed gap)</summary>" + table(
            [[c["side"], c["roller"], c["tooth"], c["designed_gap_um"], c["fcl_gap_um"], c["gap_difference_um"],
              c["fcl_distance_mm"], c["analytic_distance_mm"]] for c in fc["comparisons"]],
            ["side", "roller", "tooth", "designed gap (µm)", "FCL gap (µm)", "difference (µm)",
             "FCL distance (mm)", "analytic distance (mm)"],
            [None, None, None, "designed_gap_um", "fcl_gap_um", "gap_difference_um",
             "checks.fcl.comparisons.fcl_distance_mm", "checks.fcl.comparisons.analytic_distance_mm"]) + "</details>")
    if contact is not None and contact.tooth_gaps:
        g = contact.tooth_gaps
        rows = []
        for side in ("screw", "nut"):
            for flank in ("upper", "lower"):
                if side in g and flank in g[side]:
                    vals = [x for row in g[side][flank]["gap_mm"] for x in row]
                    rows.append([side, flank, min(vals) * 1e3, max(vals) * 1e3])
        if rows:
            out.append("<h3>Unloaded gaps per tooth (all rollers)</h3>" + table(
                rows, ["side", "flank", "smallest gap (µm)", "largest gap (µm)"], [None, None, "gap_um", "gap_um"]))
    return "".join(out)


#: Labels of the pitch variants of the rating section.
_RATING_VARIANTS = {"constant_pitch": "constant pitch", "equal_load": "equal-load pitch",
                    "design": "design pitch lists", "robust": "robust pitch"}


def _rating_html(r: dict[str, Any], plots_svg: dict[str, str]) -> str:
    """Ratings, life (catalogue and from the tooth loads), limits, efficiency, stiffness."""
    k = "rating."
    out = ["<h2 id='rating'>Ratings and life</h2>",
           f"<p class='note'>{prose(r['method'])}; duty: {prose(r['duty_source'])}.</p>"]
    out.append(table([
        ["basic dynamic axial load rating C_a (N)", Q(r["dynamic_load_rating_n"], k + "dynamic_load_rating_n")],
        ["basic static axial load rating C_0a (N)", Q(r["static_load_rating_n"], k + "static_load_rating_n")],
        ["equivalent (cubic-mean) load F_m (N)", Q(r["equivalent_load_n"], k + "equivalent_load_n")],
        ["equivalent speed n_m (rpm)", Q(r["equivalent_speed_rpm"], k + "equivalent_speed_rpm")],
        ["operating factor f_w", Q(r["operating_factor"], k + "operating_factor")],
        [Raw(f"reliability {num(r['reliability_pct'], k + 'reliability_pct')}: factor a_1"),
         Q(r["reliability_factor"], k + "reliability_factor")],
        ["L life, catalogue (revolutions)", Q(r["l10_revolutions"], k + "l10_revolutions")],
        ["L life, catalogue (h)", Q(r["l10_hours"], k + "l10_hours")],
        [Raw(f"required C_a for {num(r['target_life_hours'], k + 'target_life_hours')} (N)"),
         Q(r["required_dynamic_load_n"], k + "required_dynamic_load_n")],
        ["static safety C_0a / F_max", Q(r["static_safety"], k + "static_safety")]]))
    rows = [[_RATING_VARIANTS.get(name, name), v["l10_hours"], v["gain_over_constant_pitch_hours"],
             v["gain_factor_over_constant_pitch"], v["max_hertz_pressure_mpa"], v["static_safety"]]
            for name, v in r["distribution_life"].items()]
    out.append("<h3>Life from the tooth loads</h3>" + table(
        rows, ["pitch lists", "L life (h)", "gain over constant pitch (h)", "life factor over constant pitch",
               "max Hertz pressure (MPa)", "static safety (p_lim / p_max)^3"],
        [None, "l10_hours", "gain_over_constant_pitch_hours", "gain_factor_over_constant_pitch",
         "max_hertz_pressure_mpa", "static_safety"]))
    if isinstance(r.get("robust"), str):
        out.append(f"<p class='note'>Robust pitch: {prose(r['robust'])}.</p>")
    lim, eff, dn = r["limits"], r["efficiency"], r["double_nut"]
    kl, ke, kd = k + "limits.", k + "efficiency.", k + "double_nut."
    out.append("<h3>Limits, efficiency, stiffness</h3>" + table([
        [Raw(f"critical speed ({prose(lim['critical_speed_ends'])}, "
             f"{num(lim['unsupported_length_mm'], kl + 'unsupported_length_mm')}) (rpm)"),
         Q(lim["critical_speed_rpm"], kl + "critical_speed_rpm")],
        ["speed limit d n (rpm)", Q(lim["dn_speed_limit_rpm"], kl + "dn_speed_limit_rpm")],
        ["permissible speed (rpm)", Q(lim["permissible_speed_rpm"], kl + "permissible_speed_rpm")],
        [Raw(f"Euler buckling load ({prose(lim['buckling_ends'])}, "
             f"{num(lim['buckling_length_mm'], kl + 'buckling_length_mm')}) (N)"),
         Q(lim["buckling_load_n"], kl + "buckling_load_n")],
        [Raw(f"permissible buckling load (safety {num(lim['buckling_safety'], kl + 'buckling_safety')}) (N)"),
         Q(lim["permissible_buckling_load_n"], kl + "permissible_buckling_load_n")],
        [Raw(f"efficiency forward (mu {num(eff['friction_coefficient'], ke + 'friction_coefficient')})"),
         Q(eff["forward"], ke + "forward")],
        ["efficiency back-driving", Q(eff["back_driving"], ke + "back_driving")],
        [Raw(f"drive torque at {num(eff['torque_load_n'], ke + 'torque_load_n')} (N m)"),
         Q(eff["drive_torque_nm"], ke + "drive_torque_nm")],
        ["holding torque against back-driving (N m)", Q(eff["holding_torque_nm"], ke + "holding_torque_nm")],
        ["double nut preload (N)", Q(dn["preload_n"], kd + "preload_n")],
        ["double nut: preload lost at (N)", Q(dn["lift_off_load_n"], kd + "lift_off_load_n")]]))
    if "rating" in plots_svg:
        out.append("<div class='plots'>" + svg_element(plots_svg["rating"]) + "</div>")
    return "".join(out)


def _flank_text(tol: dict[str, Any]) -> Any:
    """The flank tolerance: one value, or the per-tooth range when the lists differ."""
    values = [x for v in tol["per_tooth_flank_um"].values() for x in v]
    if all(x == tol["flank_um"] for x in values):
        return Q(tol["flank_um"], "flank_um")
    return Raw(f"per tooth {num(min(values), 'flank_um', with_unit=False)} to "
               f"{num(max(values), 'flank_um', with_unit=False)}")


def _tolerance_html(t: dict[str, Any], svgs: dict[str, str]) -> str:
    """The tolerance section: error model, quantiles per load, roller share, importance, plot."""
    tol = t["tolerances"]
    out = ["<h2 id='tolerance'>Tolerances and load sharing</h2>",
           f"<p class='note'>{num(t['samples'])} Monte Carlo samples (seed {t['seed']}), all rollers side by "
           f"side; {prose(tol['distribution'])} errors; source: {prose(tol['source'])}.</p>",
           table([["flank position (µm)", _flank_text(tol)],
                  ["roller pitch diameter (µm)", Q(tol["roller_diameter_um"], "roller_diameter_um")],
                  ["screw eccentricity (µm)", Q(tol["screw_eccentricity_um"], "screw_eccentricity_um")],
                  ["nut eccentricity (µm)", Q(tol["nut_eccentricity_um"], "nut_eccentricity_um")],
                  ["base lead (µm)", Q(tol["lead_um"], "lead_um")],
                  ["temperature difference (K)", Q(tol["temperature_k"], "temperature_k")]],
                 ["error term", "tolerance T"])]
    rows = [[Raw(num(c["load_fraction"] * 100, unit="%")), c["deterministic"]["worst_ldc"], c["worst_ldc"]["median"],
             c["worst_ldc"]["p95"], c["worst_ldc"]["p99"], c["worst_ldc"]["max"],
             c["roller_load_share_max"]["p95"]] for c in t["cases"]]
    w = t["worst_ldc"]
    rows.append(["all loads", t["deterministic_worst_ldc"], w["median"], w["p95"], w["p99"], w["max"],
                 t["roller_load_share"]["max"]["p95"]])
    out.append(table(rows, ["load", "no error", "median", "p95", "p99", "max", "roller share max, p95"],
                     [None] + ["worst_ldc"] * 5 + ["roller_load_share"]))
    if t["importance"]:
        out.append("<h3>Which error drives the spread</h3>" + table(
            [[r["term"], Raw(num(r["share"] * 100, unit="%")), r["std_alone"]] for r in t["importance"]],
            ["error group", "share of the variance", "std of the worst LDC alone"], [None, None, "std_alone"]))
    if "tolerance_ldc" in svgs:
        out.append("<div class='plots'>" + svg_element(svgs["tolerance_ldc"]) + "</div>")
    return "".join(out)


def _compliance_text(model: LoadModel, fe_cache: dict[str, Any] | None) -> str:
    """One sentence naming the tooth-compliance model of a load model (plain text);
    ``fe_cache``: where its FE influence matrices came from (None: computed, not cached)."""
    details = model.details
    if compliance_model(model) == "fe" and details is not None and details.fe is not None:
        fe = details.fe
        hits = (fe_cache or {}).get("read_from_cache", {})
        src = ("read from the cache" if hits and all(hits.values()) else "computed and cached") if fe_cache \
            else "computed"
        return (f"Tooth compliance: axisymmetric finite-element influence matrices (mesh level "
                f"{format_cell(fe.mesh_level)}, {format_cell(fe.teeth)} teeth, {format_cell(fe.n_dofs)} "
                f"degrees of freedom, {src}; the screw and the roller run {format_cell(fe.extension_teeth[0])} "
                f"unloaded thread periods past the nut at each end, the nut has its real ends), coupled between "
                f"teeth and between a roller's flanks, with the FE bodies; Hertz contact as in the analytic "
                f"model.")
    return (f"Tooth compliance: Yamamoto's terms, diagonal, width convention "
            f"'{details.tooth_width if details is not None else ''}'.")


def _range(lo: Any, hi: Any, key: str) -> Raw:
    return Raw(f"{num(lo, key, with_unit=False)} to {num(hi, key, with_unit=False)}")


def _model_risk_html(loads: LoadsResult, svgs: dict[str, str], fe_cache: dict[str, Any] | None) -> str:
    """The model-risk part of the loads section: every set of pitch lists under the analytic
    model, the FE model and each documented alternative of it (worst coefficient per side at
    every load, the models described, plots)."""
    out = [f"<p class='note'>{prose(_compliance_text(loads.model, fe_cache))}</p>",
           "<h3 id='model-risk'>Model risk: the finite-element model, its alternatives and the analytic model</h3>"]
    risk = loads.model_risk
    if risk is None:
        return "".join(out) + f"<p class='note'>{prose(MODEL_RISK_NOT_COMPUTED['note'])}.</p>"
    out.append("<p class='note'>Each set of pitch lists evaluated with each compliance model: the worst "
               "load-distribution coefficient, nut-roller / roller-screw, at each load. A list designed for equal "
               "load with one model shares equally only under that model; the spread down a column is how much the "
               "answer depends on the modelling choices (largest difference of a coefficient "
               f"{num(risk.largest_model_difference, 'largest_model_difference')}). The FE matrices are ring "
               "loads: where the rollers carry unequal loads they are an approximation.</p>")
    fractions = risk.load_fractions
    for lists, made in risk.list_sets():
        rows = []
        for name in risk.models:
            cells: list[Any] = [name]
            for fr in fractions:
                nr, rs = risk.worst(lists, made, name, fr)
                cells.append(Raw(f"{num(nr, 'max_ldc', with_unit=False)} / {num(rs, 'max_ldc', with_unit=False)}"))
            rows.append(cells)
        out.append(f"<h4>{prose(lists + (f' designed with {made}' if made else ''))}</h4>")
        out.append(table(rows, ["model"] + [f"worst LDC at {format_quantity(f * 100, '%')} load" for f in fractions]))
    items = "".join(f"<li><b>{prose(k)}</b>: {prose(v)}</li>" for k, v in risk.descriptions.items())
    if items:
        out.append(f"<ul class='note'>{items}</ul>")
    shown = [svgs[f] for f in ("model_risk_ldc", "model_risk_loads") if f in svgs]
    if shown:
        out.append("<div class='plots'>" + "".join(svg_element(t) for t in shown) + "</div>")
    return "".join(out)


def _verdict(ok: Any) -> str:
    return "pass" if ok else "FAIL"


#: Row titles of the gear data (``gears.roller_gear`` / ``ring_gear``), in order.
_GEAR_ROWS = {"teeth": "teeth z", "module_mm": "module m (mm)", "pressure_angle_deg": "pressure angle (°)",
              "profile_shift": "profile shift x", "addendum_coefficient": "addendum coefficient h_a*",
              "dedendum_coefficient": "dedendum coefficient h_f*", "pitch_diameter_mm": "pitch diameter (mm)",
              "base_diameter_mm": "base diameter (mm)", "tip_diameter_mm": "tip diameter (mm)",
              "root_diameter_mm": "root diameter (mm)",
              "tooth_thickness_mm": "tooth thickness at the pitch circle (mm)",
              "backlash_thinning_mm": "backlash thinning (mm)", "span_teeth": "span measurement over k teeth",
              "span_measurement_mm": "span measurement W_k (mm)", "pin_diameter_mm": "pin (ball) diameter (mm)",
              "over_pins_mm": "size over two pins (mm)", "between_pins_mm": "size between two pins (mm)"}
#: Row titles of the pair data (``gears``), in order; other scalar keys follow with a title
#: made from the key.
_GEAR_PAIR_ROWS = {"face_width_mm": "face width (mm)", "centre_distance_mm": "centre distance (mm)",
                   "ratio": "ratio z_ring / z_g", "working_pressure_angle_deg": "working pressure angle (°)",
                   "contact_ratio": "transverse contact ratio",
                   "backlash_circumferential_mm": "backlash, circumferential (mm)",
                   "backlash_normal_mm": "backlash, normal (mm)"}


def _gears_html(g: dict[str, Any]) -> str:
    """The synchronising gears (report.json ``gears``): both gears with their shop
    measurements, the pair, every check with its value and limit, the phasing of the
    rollers' gears and the running clearance."""
    out = ["<h2 id='gears'>Synchronising gears</h2>",
           f"<p>Every gear check, the phasing and the running clearance: <b>{_verdict(g.get('passed'))}</b>.</p>"]
    if g.get("rule"):
        out.append(f"<p class='note'>Sizing: {prose(g['rule'])}</p>")
    gears = [(name, g[key]) for name, key in (("roller gear", "roller_gear"), ("ring gear (nut)", "ring_gear"))
             if isinstance(g.get(key), dict)]
    if gears:
        keys = list(_GEAR_ROWS) + [k for _, d in gears for k in d if k not in _GEAR_ROWS]
        keys = [k for i, k in enumerate(keys) if k not in keys[:i] and any(k in d for _, d in gears)]
        out.append(table([[_GEAR_ROWS.get(k, key_label(k))] + [Q(d.get(k), f"gears.{gk}.{k}") for (_, d), gk in
                                                             zip(gears, ("roller_gear", "ring_gear"))]
                          for k in keys], ["gear"] + [n for n, _ in gears], table_id="gear-data"))
    pair = [k for k in _GEAR_PAIR_ROWS if k in g] + [k for k, v in g.items() if k not in _GEAR_PAIR_ROWS and k not in
                                                     ("rule", "passed") and not isinstance(v, (dict, list, str))]
    ph, rc = g.get("phasing") or {}, g.get("running_clearance") or {}
    rows = [[_GEAR_PAIR_ROWS.get(k, key_label(k)), Q(g[k], f"gears.{k}")] for k in pair]
    rows += [[f"phasing: {key_label(k)}", Q(v, f"gears.phasing.{k}")] for k, v in ph.items()
             if not isinstance(v, (str, dict, list))]
    rows += [[f"running clearance: {key_label(k)}", Q(v, f"gears.running_clearance.{k}")] for k, v in rc.items()
             if not isinstance(v, (str, dict, list))]
    if rows:
        out.append(table(rows, ["pair", "value"], table_id="gear-pair"))
    notes = [f"Phasing: {prose(ph['rule'])}." if ph.get("rule") else "",
             f"Running clearance: {prose(rc['what'])}." if rc.get("what") else ""]
    if any(notes):
        out.append(f"<p class='note'>{' '.join(n for n in notes if n)}</p>")
    checks = g.get("checks") or []
    if checks:
        out.append("<h3 id='gear-checks'>Gear checks</h3>" + table(
            [[c.get("name", ""), Q(c.get("value"), unit=c.get("unit") or ""),
              Q(c.get("limit"), unit=c.get("unit") or ""), unit_label(c.get("unit") or "") or "—",
              _verdict(c.get("passed")), c.get("rule", "")] for c in checks],
            ["check", "value", "limit", "unit", "result", "rule"], table_id="gear-checks-table"))
    return "".join(out)


def _mechanism_html(m: dict[str, Any]) -> str:
    """Carriers, journals, retaining rings: the checks with pass/fail, the fits, the journal
    clearances measured on the meshes and the axial stack-up."""
    k = "mechanism."
    out = ["<h2 id='mechanism'>Mechanism: carriers, journals, retaining rings</h2>"]
    out.append(table([[c["name"], _verdict(c["passed"])] for c in m["checks"]], ["check", "result"]))
    ring, car = m["retaining_ring"], m["carrier"]
    out.append(table([
        ["roller journal diameter (mm)", Q(m["journal_diameter_mm"], k + "journal_diameter_mm")],
        ["carrier inner / outer diameter (mm)",
         Raw(f"{num(car['inner_diameter_mm'], unit='mm', with_unit=False)} / "
             f"{num(car['outer_diameter_mm'], unit='mm', with_unit=False)}")],
        ["carrier thickness (mm)", Q(car["thickness_mm"], k + "carrier.thickness_mm")],
        ["retaining ring", ring["designation"]],
        ["groove diameter d2 / width m / edge distance n (mm)",
         Raw(" / ".join(num(ring[f], unit="mm", with_unit=False)
                        for f in ("groove_diameter_mm", "groove_width_mm", "edge_distance_mm")))],
        ["nut end bore (mm)", Q(m["nut_end"]["bore_diameter_mm"], k + "nut_end.bore_diameter_mm")]]))
    out.append(table([[f["feature"], f["fit"], f["nominal_diameter_mm"], f["min_clearance_mm"] * 1e3,
                       f["max_clearance_mm"] * 1e3, f["modelled_clearance_mm"] * 1e3, _verdict(f["passed"])]
                      for f in m["fits"]],
                     ["fit", "ISO 286", "nominal (mm)", "min clearance (µm)", "max clearance (µm)",
                      "modelled (µm)", "result"], [None, None, "nominal_diameter_mm"] + ["clearance_um"] * 3))
    js = m["journal_clearances"]
    out.append(table([[r["roller"], r["end"], r["fcl_clearance_mm"] * 1e3, r["fit_radial_range_mm"][0] * 1e3,
                       r["fit_radial_range_mm"][1] * 1e3, _verdict(r["passed"])] for r in js],
                     ["roller", "end", "FCL radial clearance (µm)", "fit min (µm)", "fit max (µm)", "result"],
                     [None, None] + ["clearance_um"] * 3))
    st = m["stack_up"]
    out.append(table([[d["name"], d["count"], "+" if d["sense"] > 0 else "-", d["nominal_mm"],
                       d["lower_deviation_mm"], d["upper_deviation_mm"]] for d in st["chain"]],
                     ["axial stack-up", "count", "sense", "nominal (mm)", "lower dev. (mm)", "upper dev. (mm)"],
                     [None, None, None, "nominal_mm", "lower_deviation_mm", "upper_deviation_mm"]))
    out.append(f"<p class='note'>axial play of carriers and rollers between the rings: nominal "
               f"{num(st['nominal_play_mm'], 'nominal_play_mm')}, worst case {num(st['min_play_mm'], 'min_play_mm')} "
               f"to {num(st['max_play_mm'], 'max_play_mm')} ({_verdict(st['passed'])}).</p>")
    return "".join(out)


def _contact_html(contact: ContactResult) -> list[str]:
    """The contact section: the five contact points, the screw pitch diameters and the
    angle conventions."""
    c = contact_section(contact)
    sr = c["screw_roller"]
    rows = []
    for label, key, src in (("screw-roller upper, nominal", "upper_at_nominal", sr),
                            ("screw-roller lower, nominal", "lower_at_nominal", sr),
                            ("screw-roller upper, theoretical", "upper_at_theoretical", sr),
                            ("roller-nut upper", "upper", c["roller_nut"]),
                            ("roller-nut lower", "lower", c["roller_nut"])):
        p = src[key]
        rows.append([label, p["part_radius_mm"], p["part_angle_deg"], p["roller_radius_mm"],
                     p["roller_angle_deg"], p["gap_mm"]])
    k = "contact.screw_roller."
    return ["<h2 id='contact'>Contact</h2>" + table(
                rows, ["contact", "r part (mm)", "angle part (°)", "r roller (mm)", "angle roller (°)", "gap (mm)"],
                [None, "part_radius_mm", "part_angle_deg", "roller_radius_mm", "roller_angle_deg", "gap_mm"]),
            table([["nominal screw pitch diameter (mm)",
                    Q(sr["nominal_pitch_diameter_mm"], k + "nominal_pitch_diameter_mm")],
                   ["theoretical screw pitch diameter (mm)",
                    Q(sr["theoretical_pitch_diameter_mm"], k + "theoretical_pitch_diameter_mm")],
                   ["interference at nominal, axial (mm)",
                    Q(sr["interference_at_nominal_mm"], k + "interference_at_nominal_mm")]]),
            f"<p class='note'>{prose(c['conventions'])}</p>"]


def _loads_html(loads: LoadsResult, svgs: dict[str, str], fe_cache: dict[str, Any] | None) -> list[str]:
    """The load distribution section: its key values, the plots and the model risk."""
    L = loads_section(loads.distribution, fe_cache)
    shown = [svgs[f] for f in ("loads_ldc", "pitch_corrections", "off_design") if f in svgs]
    return ["<h2 id='loads'>Load distribution</h2>",
            table([["design load (N)", Q(L["design_load_N"], "loads.design_load_N")],
                   ["installation", L["installation"]],
                   ["max LDC", Q(L["max_ldc"], "loads.max_ldc")],
                   ["max LDC, constant pitch", Q(L["constant_pitch"]["max_ldc"], "loads.max_ldc")],
                   ["axial stiffness (N/µm)", Q(L["axial_stiffness_N_per_um"], "loads.axial_stiffness_N_per_um")]]),
            "<div class='plots'>" + "".join(svg_element(t) for t in shown) + "</div>",
            _model_risk_html(loads, svgs, fe_cache)]


def _parts_list_html(parts_list: list[dict[str, Any]]) -> str:
    """The parts list (report.json ``parts_list`` rows) with the total mass."""
    from prs_geom.exports.bom import COLUMNS as BOM_COLUMNS

    masses = [r["total_mass_kg"] for r in parts_list]
    total = sum(m for m in masses if m is not None)
    # a purchased part has no mass here (its supplier's catalogue has it)
    whose = " of the made parts" if any(m is None for m in masses) else ""
    return ("<h2 id='parts-list'>Parts list</h2>" + table(
        [[r[k] for k, _, _ in BOM_COLUMNS] for r in parts_list],
        [_header(t, u) for _, t, u in BOM_COLUMNS], [f"parts_list.{k}" for k, _, _ in BOM_COLUMNS])
        + f"<p class='note'>total mass{whose} {num(total, 'total_mass_kg')}; "
        "item numbers are the balloons of the assembly drawing; volumes from the meshes.</p>")


def _inspection_html(inspection: dict[str, dict[str, Any]]) -> str:
    """The inspection values of each part (report.json ``inspection``) with its method."""
    keys = ["pitch_diameter_mm", "lead_angle_deg", "gauge_diameter_mm", "measurement_mm",
            "measurement_correction_um", "numerical_check_um", "temperature_coefficient_um_per_k"]
    return ("<h2 id='inspection'>Inspection (20 °C)</h2>" + table(
        [[part, r["gauge"]] + [Q(r[k], f"inspection.{part}.{k}") for k in keys] for part, r in inspection.items()],
        ["part", "gauge"] + [key_label(k) for k in keys])
        + "".join(f"<p class='note'>{html.escape(part)}: {prose(r['method'])}</p>"
                  for part, r in inspection.items()))


def _machining_html(part: str, sheet: MachiningSheet) -> list[str]:
    """One part's machining sheet: header, starts and the per-tooth rows."""
    k = f"machining.{part}."
    ks = k + "starts."
    return [f"<h2 id='machining-{html.escape(part)}'>Machining sheet: {html.escape(part)}</h2>",
            table([[key_label(h), Q(v, k + "header." + h)] for h, v in sheet.header.items()]),
            table([[st["start"], st["angular_index_deg"], st["axial_offset_mm"], st["nominal_lead_mm"],
                    st["lead_min_mm"], st["lead_max_mm"], " ".join(map(str, st["teeth_at_theta_0"]))]
                   for st in sheet.starts],
                  ["start", "angular index (°)", "axial offset (mm)", "nominal lead (mm)",
                   "lead min (mm)", "lead max (mm)", "teeth at theta = 0"],
                  [None, ks + "angular_index_deg", ks + "axial_offset_mm", ks + "nominal_lead_mm",
                   ks + "lead_min_mm", ks + "lead_max_mm", None]),
            table([[r[c] for c, _, _ in COLUMNS] for r in sheet.rows],
                  [_header(t, u) for _, t, u in COLUMNS], [k + "rows." + c for c, _, _ in COLUMNS])]


def _mesh_checks_html(mesh_checks: list[dict[str, Any]]) -> str:
    """Each exported part mesh against its analytic surface (report.json ``checks.meshes``)."""
    return "<h2 id='mesh-checks'>Mesh checks</h2>" + table(
        [[m["part"], m["triangles"], m["watertight"], m["manifold"], m["chord_tolerance_mm"],
          m["max_deviation_mm"]] for m in mesh_checks],
        ["part", "triangles", "watertight", "manifold", "chord tol. (mm)", "max deviation (mm)"],
        [None, None, None, None, "chord_tolerance_mm", "max_deviation_mm"])


def _checks_shown(results: BuildResults) -> dict[str, Any] | None:
    """What the checks section shows: the interference and FCL checks when they ran; an empty
    section (the per-tooth gaps only) when only the mesh checks ran; None when neither did."""
    if results.checks is not None:
        return {"fcl": results.checks.fcl, "interference": results.checks.interference}
    return {} if results.meshes is not None else None


def _analysis_html(results: BuildResults, svgs: dict[str, str]) -> list[str]:
    """The sections of the analysis stages, in page order: contact to parts list."""
    parts: list[str] = []
    if results.contact is not None:
        parts += _contact_html(results.contact)
    if results.loads is not None:
        parts += _loads_html(results.loads, svgs, results.fe_cache)
    if results.rating is not None:
        parts.append(_rating_html(rating_section(results.rating), svgs))
    if results.tolerance is not None:
        parts.append(_tolerance_html(tolerance_section(results.tolerance), svgs))
    checks = _checks_shown(results)
    if checks is not None:
        parts.append(_checks_html(checks, results.contact))
    if results.gears is not None:
        parts.append(_gears_html(gears_section(results.gears)))
    if results.mechanism is not None:
        parts.append(_mechanism_html(mechanism_section(results.mechanism)))
    if results.parts_list:
        parts.append(_parts_list_html([r.as_dict() for r in results.parts_list]))
    return parts


def write_html(path: Path, results: BuildResults, plots_svg: dict[str, str] | None, date: str, version: str) -> None:
    """Write ``report.html`` from the stage results of a build.

    ``results``: each stage's result (:class:`~prs_geom.exports.report.BuildResults`; a stage
    that did not run has no section). ``plots_svg`` maps plot names (``loads_ldc``, ...) to
    their SVG text, as the plot stage rendered them; the page shows them inline. ``date`` and
    ``version`` go into the provenance line. Templates, style sheet and viewer script are
    package data (``templates/report.html``, ``report.css``, ``viewer.js``).

    Every number goes through :mod:`prs_geom.exports.numbers` (the exact value in a
    tooltip); the page opens with a table of contents and every table scrolls sideways in
    its own box.
    """
    design, svgs = results.design, plots_svg or {}
    parts = page_head(f"Planetary roller screw '{html.escape(design.name)}'", version, date, design_hash(design),
                      "Units mm, N, MPa; tooth 1 at the loaded end.", results.warnings, "cut the nut open")
    parts += _analysis_html(results, svgs)
    if results.inspection:
        parts.append(_inspection_html(inspection_section(results.inspection)))
    for part, sheet in (results.machining or {}).items():
        parts += _machining_html(part, sheet)
    parts.append("<h2 id='design'>Design</h2>" + table(design_rows(design_to_dict(design)), ["field", "value"]))
    if results.mesh_checks is not None:
        parts.append(_mesh_checks_html(results.mesh_checks))
    contact = results.contact
    scene = results.meshes.scene if results.meshes is not None else None
    if scene is None:
        scene = scene_payload(design, screw_profile=contact.screw_profile if contact else None)
    payload = json.dumps(scene).replace("</", "<\\/")
    three = three_js()
    page = fill_template(page_template("report.html"), {
        "title": html.escape(design.name), "css": page_template("report.css"), "body": page_body(parts),
        "scene": payload, "viewer": page_template("viewer.js"), "importmap": three["importmap"],
        "three_version": three["version"], "three_licence": three["licence"].replace("--", "- -")})
    # the template file ends with a newline; the page ends at </html>
    path.write_text(page.rstrip("\n"), encoding="utf-8")
