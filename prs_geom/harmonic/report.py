"""``report.html`` of a harmonic friction drive build: one self-contained page (no server,
no network).

Sections: provenance (version, date, design hash), warnings, a 3D view of the placed
assembly (the PRS report's three.js viewer and page template, package data of
:mod:`prs_geom.exports`, used read-only), the placed position and wave generator, the speed
range, the ratio plot (inline SVG), the ratio table, the tolerance rule, the assembly and
mesh checks, and the design, after a table of contents. Every number is printed by
:mod:`prs_geom.exports.numbers` (unit- and precision-aware, as the PRS report); the exact
float (the shortest text that reads back to the same double, as in ``ratio_table.csv``)
is the ``title`` tooltip of its cell. Tables scroll sideways in their own box.

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

from prs_geom.exports.html import (Q, Raw, design_rows, fill_template, num, page_body, page_head, page_template,
                                   prose, svg_element, table, three_js)
from prs_geom.harmonic.assembly import HarmonicAssembly
from prs_geom.harmonic.model import HarmonicDesign
from prs_geom.model.io import design_hash, design_to_dict

__all__ = ["DISPLAY_TOLERANCE_MM", "CUT_PARTS", "scene_payload", "RATIO_COLUMNS", "write_report_html"]

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


RATIO_COLUMNS = [("a_mm", "a (mm)"), ("beta_deg", "beta (°)"), ("phi_deg", "phi (°)"),
                 ("contact_radius_mm", "r_c (mm)"), ("cone_radius_mm", "R_c (mm)"),
                 ("radius_difference_mm", "Delta (mm)"), ("ratio", "ratio i"),
                 ("ratio_circular_spline_fixed", "i, circular spline fixed"),
                 ("ratio_flexspline_fixed", "i, flexspline fixed"), ("it_grade", "ISO grade >= Delta")]
#: The strength table's columns (report.json ``harmonic.strength``) and titles.
STRENGTH_COLUMNS = [("name", "flexspline material"), ("youngs_modulus_mpa", "E (MPa)"),
                    ("allowed_bending_stress_mpa", "allowed stress (MPa)"),
                    ("max_radius_difference_mm", "largest Delta (mm)"), ("min_ratio", "smallest ratio"),
                    ("stress_at_min_position_mpa", "stress at positions.min_mm (MPa)"),
                    ("stress_at_max_position_mpa", "stress at positions.max_mm (MPa)"),
                    ("speed_range", "usable speed range"), ("within", "design within")]


def _placement_html(asm: dict[str, Any]) -> str:
    """The placed assembly's position and wave generator (report.json ``assembly``)."""
    wg = asm["wave_generator"]
    k, kw = "assembly.", "assembly.wave_generator."
    return (table([
        ["position a (mm)", Q(asm["position_mm"], k + "position_mm")], ["position rule", asm["position_rule"]],
        ["tilt beta on the major axis (°)", Q(asm["beta_deg"], k + "beta_deg")],
        ["radial wave amplitude at the open end (mm)", Q(asm["wave_amplitude_mm"], k + "wave_amplitude_mm")],
        ["ratio i", Q(asm["ratio"], k + "ratio")],
        ["radius difference Delta (mm)", Q(asm["radius_difference_mm"], k + "radius_difference_mm")],
        ["wave generator semi-axis x (mm)", Q(wg["semi_axis_x_mm"], kw + "semi_axis_x_mm")],
        ["wave generator semi-axis y (mm)", Q(wg["semi_axis_y_mm"], kw + "semi_axis_y_mm")],
        ["wave generator band z (mm)", Raw(f"{num(wg['z_min_mm'], kw + 'z_min_mm', with_unit=False)} to "
                                           f"{num(wg['z_max_mm'], kw + 'z_max_mm', with_unit=False)}")],
        ["triangles (export meshes)", asm["triangles"]],
    ], ["placed assembly", "value"], table_id="placement")
        + f"<p class='note'>Flexspline: {prose(asm['deformation'])}. Wave generator: {prose(wg['rule'])}.</p>")


def _ratio_table_html(rows: list[dict[str, Any]], k: str) -> str:
    """The ratio table: the contact state, the signed ratios and the ISO grade per position."""
    return ("<h3 id='ratio-table-title'>Ratio table</h3><p class='note'>Signed ratios: generator speed over "
                 "output speed, negative when the output turns against the generator. ISO grade: the finest ISO 286 "
                 "grade whose tolerance at the contact diameter is at least the radius difference (the source: "
                 "0.0519 mm about IT8, 0.0120 mm about IT5); '&gt; IT13': coarser than the table.</p>" + table(
        [[("> IT13" if row[c] is None else row[c]) if c == "it_grade" else row[c] for c, _ in RATIO_COLUMNS]
         for row in rows], [h for _, h in RATIO_COLUMNS],
        [k + "table." + c if c != "it_grade" else None for c, _ in RATIO_COLUMNS], table_id="ratio-table"))


#: The drive table's columns (report.json ``harmonic.table``) and titles.
DRIVE_COLUMNS = [("a_mm", "a (mm)"), ("ratio_all_stages", "ratio, all stages"), ("adjusting_turns", "adjusting turns"),
                 ("ratio_change_per_degree", "ratio change per degree of adjusting input"),
                 ("output_torque_nm", "output torque (N m)"), ("input_torque_nm", "generator torque (N m)"),
                 ("contact_pressure_mpa", "Hertz pressure (MPa)"),
                 ("circumferential_semi_axis_mm", "contact semi-axis round (mm)"), ("hertz_valid", "Hertz holds")]


#: Columns the drive table adds for a planetary wave generator.
PLANETARY_COLUMNS = [("generator_ratio", "generator stage ratio"), ("total_ratio", "total ratio (product)"),
                     ("total_ratio_coupled", "total ratio (flexspline turning)")]


def _drive_html(drive: dict[str, Any], rows: list[dict[str, Any]], k: str) -> str:
    """The drive section: fixed member and signed ratios, pressing and torque, contact
    pressure and where Hertz holds, the adjusting mechanism; a table along the travel."""
    valid = drive["hertz_valid_up_to_mm"]
    text = (f"The {drive['fixed_member'].replace('_', ' ')} is fixed; the {drive['output'].replace('_', ' ')} is "
            f"the output, ratio {num(drive['ratio_at_min_position'], k + 'drive.ratio_at_min_position')} to "
            f"{num(drive['ratio_at_max_position'], k + 'drive.ratio_at_max_position')} (negative: it turns against "
            f"the generator). The pressing device's {num(drive['pressing_force_n'], k + 'drive.pressing_force_n')} "
            f"press the cone with {num(drive['normal_force_n'], k + 'drive.normal_force_n')} "
            f"({num(drive['normal_force_factor'], k + 'drive.normal_force_factor')} times, 1 / sin alpha); with "
            f"friction {num(drive['friction_coefficient'], k + 'drive.friction_coefficient')} and slip safety "
            f"{num(drive['slip_safety_factor'], k + 'drive.slip_safety_factor')} the output carries "
            f"{num(drive['output_torque_nm'], k + 'drive.output_torque_nm', unit='N m')}. The arc on the cone "
            "nearly conforms round the circumference: Hertz's quadratic gap holds while the contact's semi-axis "
            "there is under a tenth of the contact radius, "
            + (f"up to a = {num(valid, k + 'drive.hertz_valid_up_to_mm')}" if valid is not None else "nowhere here")
            + "; beyond, the pressures are an upper estimate and the contact a band. Adjusting: "
            f"{prose(drive['adjusting_mechanism'])}, {num(drive['adjusting_travel_per_turn_mm'], k + 'drive.adjusting_travel_per_turn_mm')} "
            f"per turn, {num(drive['adjusting_turns'], k + 'drive.adjusting_turns')} turns over the travel. "
            f"Efficiency: {prose(drive['efficiency'])}.")
    cols = DRIVE_COLUMNS + (PLANETARY_COLUMNS if rows and "generator_ratio" in rows[0] else [])
    return ("<h2 id='drive'>Drive: direction, torque, adjusting</h2><p class='note'>" + text + "</p>"
            + table([[r[c] for c, _ in cols] for r in rows], [h for _, h in cols],
                    [k + "table." + c if c != "hertz_valid" else None for c, _ in cols],
                    table_id="drive-table"))


def _strength_html(strength: list[dict[str, Any]], k: str) -> str:
    """The flexspline-strength section: the thin-ring stress rule and one row per material."""
    return ("<h2 id='strength'>Flexspline strength</h2><p class='note'>The generator ovalises the flexspline "
            "by the radius difference; the thin wall then bends with sigma = 3 E t Delta / (2 r0^2) (thin-ring "
            "theory). The allowed stress sets the largest Delta and the smallest ratio. Materials and where "
            "their numbers come from: " + "; ".join(prose(f"{m['name']}: {m['source']}") for m in strength)
            + ".</p>" + table([[m[c] for c, _ in STRENGTH_COLUMNS] for m in strength],
                              [h for _, h in STRENGTH_COLUMNS],
                              [k + "strength." + c if c not in ("name", "within") else None
                               for c, _ in STRENGTH_COLUMNS], table_id="strength-table"))


def _checks_html(report: dict[str, Any]) -> str:
    checks = report.get("checks") or {}
    out = ["<h2 id='checks'>Checks</h2>"]
    c = checks.get("assembly")
    if c:
        it = c["interference"]
        k = "checks.assembly."
        out.append(f"<p>Placed assembly at a = {num(c['position_mm'], k + 'position_mm')}, chord tolerance "
                   f"{num(c['chord_tolerance_mm'], k + 'chord_tolerance_mm')}. Interference: "
                   f"<b>{'FOUND' if it['found'] else 'none'}</b> (rule: {prose(it['rule'])}). Exact clearances are "
                   f"of the analytic parts in each meridian section; mesh values of the exported meshes.</p>")
        out.append(table([
            ["model contact point x (mm)", Q(c["contact_point_mm"]["x"], k + "contact_point_mm.x", "mm")],
            ["model contact point r (mm)", Q(c["contact_point_mm"]["r"], k + "contact_point_mm.r", "mm")],
            ["mesh gap to the cone on the major axis (mm)", Q(c["contact_gap_mm"], k + "contact_gap_mm")],
            ["mesh distance from the model contact point (mm)", Q(c["contact_offset_mm"], k + "contact_offset_mm")],
            ["exact arc-cone clearance, minor axis (mm)",
             Q(c["arc_cone_clearance_minor_axis_mm"], k + "arc_cone_clearance_minor_axis_mm")],
            ["exact arc-cone clearance, minimum over theta (mm)",
             Q(c["arc_cone_clearance_min_mm"], k + "arc_cone_clearance_min_mm")],
            ["exact wave generator clearance, min (mm)",
             Q(c["wave_generator_clearance_min_mm"], k + "wave_generator_clearance_min_mm")],
            ["exact wave generator clearance, max (mm)",
             Q(c["wave_generator_clearance_max_mm"], k + "wave_generator_clearance_max_mm")],
            ["ratio measured on the meshes", Q(c["measured_ratio"]["ratio"], k + "measured_ratio.ratio")],
            ["ratio of the model", Q(c["measured_ratio"]["model_ratio"], k + "measured_ratio.model_ratio")],
            ["measured / model - 1" + ("" if c["measured_ratio"]["resolved"] else
                                       " (Delta below 100 chord tolerances: not resolved by the meshes)"),
             Q(c["measured_ratio"]["relative_difference"], k + "measured_ratio.relative_difference")],
        ], ["check", "value"], table_id="assembly-checks"))
        out.append(table([[" - ".join(p["pair"]), p["volume_mm3"], p["mean_thickness_mm"], p["status"]]
                          for p in it["pairs"]],
                         ["part pair", "overlap volume (mm³)", "mean thickness (mm)", "status"],
                         [None, "volume_mm3", "mean_thickness_mm", None], table_id="interference"))
    rows = [[m["part"], m["triangles"], m["watertight"], m["volume_mm3"], m["chord_tolerance_mm"],
             m["max_deviation_mm"]] for m in checks.get("meshes") or []]
    rows += [[f"{m['part']} (placed)", m["triangles"], m["watertight"], m["volume_mm3"], m["chord_tolerance_mm"],
              m["max_deviation_mm"]] for m in (report.get("assembly") or {}).get("meshes", [])]
    if rows:
        out.append("<h3 id='meshes'>Mesh checks</h3>" + table(
            rows, ["part", "triangles", "watertight", "volume (mm³)", "chord tol. (mm)", "max deviation (mm)"],
            [None, None, None, "volume_mm3", "chord_tolerance_mm", "max_deviation_mm"], table_id="mesh-checks"))
    return "".join(out)


def write_report_html(path: Path, design: HarmonicDesign, report: dict[str, Any], view: HarmonicAssembly,
                      colours: dict[str, str], ratio_svg: str, date: str, version: str, drive_svg: str = "") -> None:
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
    drive_svg : str
        Text of the drive plot's SVG file (the arrangement sketch, stress and torque curves;
        empty: left out).
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
        parts.append(_placement_html(asm))
    k = "harmonic."
    parts.append("<h2 id='ratio'>Ratio</h2>" + table([
        ["cone half-angle alpha (°)", Q(rep["alpha_deg"], k + "alpha_deg")], ["a0 (mm)", Q(rep["a0_mm"], k + "a0_mm")],
        ["infinite-ratio position (mm)", Q(rep["infinite_ratio_position_mm"], k + "infinite_ratio_position_mm")],
        ["ratio at positions.min_mm", Q(rep["ratio_min"], k + "ratio_min")],
        ["ratio at positions.max_mm", Q(rep["ratio_max"], k + "ratio_max")],
        ["speed range", Q(rep["speed_range"], k + "speed_range")]], ["quantity", "value"], table_id="speed-range"))
    parts.append("<div class='plots'>" + svg_element(ratio_svg) + "</div>")
    parts.append(_ratio_table_html(rep["table"], k))
    parts.append(_strength_html(rep["strength"], k))
    parts.append(_drive_html(rep["drive"], rep["table"], k))
    if drive_svg:
        parts.append("<div class='plots'>" + svg_element(drive_svg) + "</div>")
    tol_keys = ["max_ratio", "ratio_error", "radius_difference_mm", "radius_tolerance_um", "diameter_band_um",
                "bore_diameter_mm", None, "ratio_change_per_um"]
    parts.append("<h2 id='tolerance'>Tolerance</h2><p class='note'>Radius error e that keeps the ratio within the "
                 "relative error at the given ratio (e = error x Delta / 2), the centred diameter band T = 4 e and "
                 "the coarsest ISO 286-1 grade meeting it on the bore diameter 2 b2 (none: finer than IT01).</p>"
                 + table([[t["max_ratio"], t["ratio_error"], t["radius_difference_mm"], t["radius_tolerance_um"],
                           t["diameter_band_um"], t["bore_diameter_mm"],
                           "none" if t["it_grade"] is None else t["it_grade"], t["ratio_change_per_um"]]
                          for t in rep["tolerance"]],
                         ["ratio", "relative error", "Delta (mm)", "radius tol. e (µm)", "diameter band T (µm)",
                          "bore diameter (mm)", "ISO grade", "ratio change per µm"],
                         [k + "tolerance." + c if c else None for c in tol_keys], table_id="tolerance-table"))
    parts.append(_checks_html(report))
    parts.append("<h2 id='design'>Design</h2>" + table(design_rows(design_to_dict(design)), ["field", "value"],
                                                       table_id="design"))
    parts.append(f"<p class='note'>Model assumptions: {prose(rep['assumptions'])} "
                 f"(docs/theory/harmonic.md).</p>")
    payload = json.dumps(scene_payload(view, colours)).replace("</", "<\\/")
    three = three_js()
    page = fill_template(page_template("report.html"), {
        "title": html.escape(design.name), "css": page_template("report.css"), "body": page_body(parts),
        "scene": payload, "viewer": page_template("viewer.js"), "importmap": three["importmap"],
        "three_version": three["version"], "three_licence": three["licence"].replace("--", "- -")})
    path.write_text(page.rstrip("\n"), encoding="utf-8")
