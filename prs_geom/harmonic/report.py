"""``report.html`` of a harmonic friction drive build: one self-contained page (no server,
no network).

Sections: provenance (version, date, design hash), warnings, a 3D view of the placed
assembly (the PRS report's three.js viewer and page template, package data of
:mod:`prs_geom.exports`, used read-only), the placed position and wave generator, the speed
range, the ratio plot (inline SVG), the full ratio table (every float at full precision:
the shortest text that reads back to the same double, as in ``ratio_table.csv``), the
tolerance rule, the assembly and mesh checks, and the design.

The viewer reads a JSON ``scene-data`` block: one mesh per part at the display tolerance
(base64 float32 vertices, uint32 faces, part frame, mm) and one instance per part with its
4x4 placement (row-major, mm), colour and whether the view cuts it open. The circular spline
and the flexspline are cut, so the flexspline and the wave generator inside show. When the
view has drawn it sets ``data-viewer="ok"`` on ``<body>``.
"""
from __future__ import annotations

import base64
import html
import json
from pathlib import Path
from typing import Any

import numpy as np

from prs_geom.exports.html import fill_template, page_head, page_template, svg_element, three_js
from prs_geom.harmonic.assembly import HarmonicAssembly
from prs_geom.harmonic.model import HarmonicDesign
from prs_geom.model.io import design_hash, design_to_dict

#: Chord tolerance (mm) of the page's display meshes: light enough for a browser.
DISPLAY_TOLERANCE_MM = 0.1
#: Parts the 3D view cuts open by the plane through the axis facing the viewer.
CUT_PARTS = ("circular_spline", "flexspline")


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


def scene_payload(asm: HarmonicAssembly, colours: dict[str, str]) -> dict[str, Any]:
    """The viewer's data for a placed assembly; ``colours``: part -> ``#rrggbb``."""
    meshes, instances = [], []
    for i, (name, (mesh, T)) in enumerate(asm.parts.items()):
        meshes.append({"v": _b64(np.asarray(mesh.vertices, dtype=np.float32)),
                       "f": _b64(np.asarray(mesh.faces, dtype=np.uint32))})
        instances.append({"name": name, "mesh": i, "T": [float(x) for x in np.asarray(T).ravel()],
                          "colour": colours[name], "cut": name in CUT_PARTS})
    tri = sum(len(m.faces) for m, _ in asm.parts.values())
    return {"meshes": meshes, "instances": instances, "tolerance_mm": asm.tolerance_mm, "triangles": int(tri)}


def _cell(v: Any, full: bool) -> str:
    if isinstance(v, bool) or v is None:
        return "" if v is None else str(v).lower()
    if isinstance(v, float):
        return repr(v) if full else f"{v:.6g}"
    return str(v)


#: Class of a table's first column (left-aligned, monospace in report.css).
KEY_CLASS = ' class="k"'


def _table(rows: list[list[Any]], header: list[str] | None = None, full: bool = False,
           table_id: str = "") -> str:
    """An HTML table; floats to 6 significant digits, or in full (``repr``: reads back to
    the same double) when ``full``."""
    out = [f"<table id='{table_id}'>" if table_id else "<table>"]
    if header:
        out.append("<tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in header) + "</tr>")
    for r in rows:
        cells = [f"<td{KEY_CLASS if i == 0 else ''}>{html.escape(_cell(v, full))}</td>" for i, v in enumerate(r)]
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</table>")
    return "".join(out)


def _flatten(d: dict[str, Any], prefix: str = "") -> list[list[Any]]:
    rows: list[list[Any]] = []
    for k, v in d.items():
        key = f"{prefix}.{k}" if prefix else k
        if isinstance(v, dict):
            rows += _flatten(v, key)
        elif isinstance(v, (list, tuple)):
            rows.append([key, ", ".join(repr(x) if isinstance(x, float) else str(x) for x in v)])
        else:
            rows.append([key, v])
    return rows


RATIO_COLUMNS = [("a_mm", "a (mm)"), ("beta_deg", "beta (deg)"), ("phi_deg", "phi (deg)"),
                 ("contact_radius_mm", "r_c (mm)"), ("cone_radius_mm", "R_c (mm)"),
                 ("radius_difference_mm", "Delta (mm)"), ("ratio", "ratio i")]


def _checks_html(report: dict[str, Any]) -> str:
    checks = report.get("checks") or {}
    out = ["<h2 id='checks'>Checks</h2>"]
    c = checks.get("assembly")
    if c:
        it = c["interference"]
        out.append(f"<p>Placed assembly at a = {c['position_mm']:g} mm, chord tolerance "
                   f"{c['chord_tolerance_mm']:g} mm. Interference: <b>{'FOUND' if it['found'] else 'none'}</b> "
                   f"(rule: {html.escape(it['rule'])}). Exact clearances are of the analytic parts in each "
                   f"meridian section; mesh values of the exported meshes.</p>")
        out.append(_table([
            ["model contact point x (mm)", c["contact_point_mm"]["x"]],
            ["model contact point r (mm)", c["contact_point_mm"]["r"]],
            ["mesh gap to the cone on the major axis (mm)", c["contact_gap_mm"]],
            ["mesh distance from the model contact point (mm)", c["contact_offset_mm"]],
            ["exact arc-cone clearance, minor axis (mm)", c["arc_cone_clearance_minor_axis_mm"]],
            ["exact arc-cone clearance, minimum over theta (mm)", c["arc_cone_clearance_min_mm"]],
            ["exact wave generator clearance, min (mm)", c["wave_generator_clearance_min_mm"]],
            ["exact wave generator clearance, max (mm)", c["wave_generator_clearance_max_mm"]],
        ], ["check", "value"], full=True, table_id="assembly-checks"))
        out.append(_table([[" - ".join(p["pair"]), p["volume_mm3"], p["mean_thickness_mm"], p["status"]]
                           for p in it["pairs"]],
                          ["part pair", "overlap volume (mm3)", "mean thickness (mm)", "status"], full=True,
                          table_id="interference"))
    rows = [[m["part"], m["triangles"], m["watertight"], m["volume_mm3"], m["chord_tolerance_mm"],
             m["max_deviation_mm"]] for m in checks.get("meshes") or []]
    rows += [[f"{m['part']} (placed)", m["triangles"], m["watertight"], m["volume_mm3"], m["chord_tolerance_mm"],
              m["max_deviation_mm"]] for m in (report.get("assembly") or {}).get("meshes", [])]
    if rows:
        out.append("<h3>Mesh checks</h3>" + _table(
            rows, ["part", "triangles", "watertight", "volume (mm3)", "chord tol. (mm)", "max deviation (mm)"],
            table_id="mesh-checks"))
    return "".join(out)


def write_report_html(path: Path, design: HarmonicDesign, report: dict[str, Any], view: HarmonicAssembly,
                      colours: dict[str, str], ratio_svg: str, date: str, version: str) -> None:
    """Write ``report.html``.

    Parameters
    ----------
    path : Path
        File to write.
    design : HarmonicDesign
    report : dict
        The build report: ``harmonic`` (:func:`~prs_geom.harmonic.model.harmonic_report`),
        ``checks`` (``meshes``, ``assembly``), ``assembly`` and ``warnings``.
    view : HarmonicAssembly
        The placed assembly at the display tolerance (the 3D view).
    colours : dict
        Part -> ``#rrggbb`` display colour.
    ratio_svg : str
        Text of the ratio plot's SVG file.
    date, version : str
        Build date and prs_geom version (provenance).
    """
    rep = report["harmonic"]
    asm = report.get("assembly") or {}
    warnings = report.get("warnings") or []
    parts = page_head(f"Harmonic friction drive '{html.escape(design.name)}'", version, date, design_hash(design),
                      "Units mm, degrees; axial positions from the flexspline bottom; x along the wave "
                      "generator's major axis.", warnings, "cut the circular spline and the flexspline open")
    if asm:
        wg = asm["wave_generator"]
        parts.append(_table([
            ["position a (mm)", asm["position_mm"]], ["position rule", asm["position_rule"]],
            ["tilt beta on the major axis (deg)", asm["beta_deg"]],
            ["radial wave amplitude at the open end (mm)", asm["wave_amplitude_mm"]], ["ratio i", asm["ratio"]],
            ["radius difference Delta (mm)", asm["radius_difference_mm"]],
            ["wave generator semi-axis x (mm)", wg["semi_axis_x_mm"]],
            ["wave generator semi-axis y (mm)", wg["semi_axis_y_mm"]],
            ["wave generator band z (mm)", f"{wg['z_min_mm']!r} .. {wg['z_max_mm']!r}"],
            ["triangles (export meshes)", asm["triangles"]],
        ], ["placed assembly", "value"], full=True, table_id="placement"))
        parts.append(f"<p class='note'>Flexspline: {html.escape(asm['deformation'])}. Wave generator: "
                     f"{html.escape(wg['rule'])}.</p>")
    parts.append("<h2 id='ratio'>Ratio</h2>" + _table([
        ["cone half-angle alpha (deg)", rep["alpha_deg"]], ["a0 (mm)", rep["a0_mm"]],
        ["infinite-ratio position (mm)", rep["infinite_ratio_position_mm"]],
        ["ratio at positions.min_mm", rep["ratio_min"]], ["ratio at positions.max_mm", rep["ratio_max"]],
        ["speed range", rep["speed_range"]]], ["quantity", "value"], full=True, table_id="speed-range"))
    parts.append("<div class='plots'>" + svg_element(ratio_svg) + "</div>")
    parts.append("<h3>Ratio table</h3>" + _table([[row[k] for k, _ in RATIO_COLUMNS] for row in rep["table"]],
                                                 [h for _, h in RATIO_COLUMNS], full=True, table_id="ratio-table"))
    parts.append("<h2 id='tolerance'>Tolerance</h2><p class='note'>Radius error e that keeps the ratio within the "
                 "relative error at the given ratio (e = error x Delta / 2), the centred diameter band T = 4 e and "
                 "the coarsest ISO 286-1 grade meeting it on the bore diameter 2 b2 (none: finer than IT1).</p>"
                 + _table([[t["max_ratio"], t["ratio_error"], t["radius_difference_mm"], t["radius_tolerance_um"],
                            t["diameter_band_um"], t["bore_diameter_mm"],
                            "none" if t["it_grade"] is None else f"IT{t['it_grade']}", t["ratio_change_per_um"]]
                           for t in rep["tolerance"]],
                          ["ratio", "relative error", "Delta (mm)", "radius tol. e (um)", "diameter band T (um)",
                           "bore diameter (mm)", "ISO grade", "ratio change per um"], full=True,
                          table_id="tolerance-table"))
    parts.append(_checks_html(report))
    parts.append("<h2>Design</h2>" + _table(_flatten(design_to_dict(design)), ["field", "value"], full=True,
                                            table_id="design"))
    parts.append(f"<p class='note'>Model assumptions: {html.escape(rep['assumptions'])} "
                 f"(docs/theory/harmonic.md).</p>")
    payload = json.dumps(scene_payload(view, colours)).replace("</", "<\\/")
    three = three_js()
    page = fill_template(page_template("report.html"), {
        "title": html.escape(design.name), "css": page_template("report.css"), "body": "".join(parts),
        "scene": payload, "viewer": page_template("viewer.js"), "importmap": three["importmap"],
        "three_version": three["version"], "three_licence": three["licence"].replace("--", "- -")})
    path.write_text(page.rstrip("\n"), encoding="utf-8")
