"""Self-contained HTML report (``report.html``): one file, no server, no network.

Sections: design table, contact results, load-distribution plots (inline SVG), machining
tables, and an interactive 3D view of the assembly. The 3D view is three.js (WebGL with a
depth buffer, so no sorting seams; flat shading; the nut cut open by a clipping plane through
the axis facing the viewer; drag to rotate, wheel to zoom, right-drag to pan), embedded
unmodified from its npm package as ``data:`` URLs in an import map (:func:`three_js`), so
the page still fetches nothing. Its mesh is a display tessellation of the assembly (coarser
than the export meshes; the tolerance is stated on the page), embedded as base64
float32/uint32 arrays, one mesh per distinct part and one transform per placed part.

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
from typing import Any

import numpy as np

from prs_geom.analysis.contact import ContactResult
from prs_geom.analysis.loads import MODEL_RISK_NOT_COMPUTED, LoadsResult
from prs_geom.analysis.machining import COLUMNS, MachiningSheet
from prs_geom.mesh.assembly import build_assembly
from prs_geom.model.design import PRSDesign
from prs_geom.model.io import design_hash, design_to_dict

#: Chordal tolerance (mm) of the display mesh: coarse enough for a light page.
DISPLAY_TOLERANCE_MM = 0.1

COLOURS = {"screw": "#8a9bb0", "nut": "#c9a66b", "roller": "#7fb37f", "gear": "#9a9aa4", "carrier": "#b4b4c0",
           "retaining": "#2e2e33"}


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
                          "colour": colour, "cut": name.startswith(("nut", "carrier", "retaining"))})
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


def _table(rows: list[list[Any]], header: list[str] | None = None, full: bool = False) -> str:
    """An HTML table; floats to 6 significant digits, or in full (shortest round-trip repr,
    as in the CSV) when ``full``: machining values are read to 0.01 um on 40 mm positions."""
    out = ["<table>"]
    if header:
        out.append("<tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in header) + "</tr>")
    for r in rows:
        cells = []
        for i, v in enumerate(r):
            if isinstance(v, float):
                v = repr(v) if full else f"{v:.6g}"
            cls = ' class="k"' if i == 0 else ""
            cells.append(f"<td{cls}>{html.escape(str(v))}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</table>")
    return "".join(out)


def _flatten(d: dict[str, Any], prefix: str = "") -> list[list[Any]]:
    rows = []
    for k, v in d.items():
        key = f"{prefix}.{k}" if prefix else k
        if isinstance(v, dict):
            rows += _flatten(v, key)
        elif isinstance(v, list):
            rows.append([key, ", ".join(f"{x:.9g}" if isinstance(x, float) else str(x) for x in v)])
        else:
            rows.append([key, v])
    return rows


def page_template(name: str) -> str:
    """A page template shipped in ``prs_geom/exports/templates`` (package data): the page
    (``report.html``), its style sheet and the 3D viewer script; the harmonic report uses
    them too."""
    return resources.files("prs_geom.exports").joinpath("templates", name).read_text(encoding="utf-8")


def fill_template(template: str, values: dict[str, str]) -> str:
    """Replace every ``{{name}}`` once (values are not scanned again)."""
    return re.sub(r"\{\{(\w+)\}\}", lambda m: values[m.group(1)], template)


def page_head(title: str, version: str, date: str, design_sha: str, conventions: str, warnings: list[str],
              cut_label: str) -> list[str]:
    """The opening of a report page (both product lines): title, provenance (version, date,
    design hash, ``conventions``), the warnings, the script-error box and the 3D view with
    its cut-open checkbox labelled ``cut_label`` (the element ids viewer.js expects).
    ``title``, ``conventions`` and ``cut_label`` are HTML (callers escape what a user wrote)."""
    return [f"<h1>{title}</h1>",
            f"<p class='note' id='provenance'>prs_geom {html.escape(version)}; {html.escape(date)}; "
            f"design sha256 {design_sha}. {conventions}</p>",
            "<div id='warnings' class='warnings'><b>Warnings</b><ul>"
            + "".join(f"<li>{html.escape(w)}</li>" for w in warnings) + "</ul></div>"
            if warnings else "<p id='warnings' class='note'>Warnings: none.</p>",
            "<div id='errors'></div>",
            "<h2>Assembly</h2><canvas id='view' width='900' height='560'></canvas><div id='viewinfo' class='note'></div>"
            f"<label class='note'><input type='checkbox' id='cutaway' checked> {cut_label}</label>"
            "<label class='note' id='play-label' hidden><input type='checkbox' id='play'> run the mechanism "
            "(one screw revolution, repeated)</label>"]


def svg_element(text: str) -> str:
    """The ``<svg>`` element of an SVG file's text (without the XML prolog)."""
    return text[text.index("<svg"):]


def _checks_html(checks: dict[str, Any], contact: ContactResult | None) -> str:
    """Interference, FCL verification and per-tooth gaps, as measured."""
    out = ["<h2 id='checks'>Checks</h2>"]
    it = checks.get("interference")
    if it:
        out.append(f"<p>Interference ({html.escape(str(it.get('screw', '')))} screw, pitch diameter "
                   f"{it.get('screw_pitch_diameter_mm', '')} mm): <b>{'FOUND' if it['found'] else 'none'}</b> "
                   f"in {it.get('pairs_checked', '')} part pairs at chord tolerance {it.get('chord_tolerance_mm')} mm. "
                   f"{html.escape(str(it.get('rule', '')))}</p>")
        rows = [[" - ".join(p["pair"]) if isinstance(p.get("pair"), list) else p.get("pair"),
                 p.get("volume_mm3"), p.get("mean_thickness_mm")] for p in it.get("pairs", [])]
        if rows:
            out.append(_table(rows, ["pair", "overlap volume (mm3)", "mean thickness (mm)"], full=True))
        ok = it.get("contact_within_tolerance") or []
        if ok:
            out.append(_table([[" - ".join(p["pair"]), p["volume_mm3"], p["mean_thickness_mm"], len(p["teeth"])]
                               for p in ok], ["touching pair (within the mesh tolerance)", "overlap volume (mm3)",
                                              "mean thickness (mm)", "teeth"], full=True))
    fc = checks.get("fcl")
    if fc:
        out.append(f"<p>FCL mesh distance against the analytic contact, every tooth of every roller "
                   f"({fc['rollers_checked']} rollers x {fc['teeth_checked']} teeth, both sides), patches at "
                   f"{fc['patch_chord_tolerance_mm'] * 1e3:g} um chord tolerance: largest |FCL gap - designed "
                   f"gap| {fc['max_abs_gap_difference_um']:.4f} um (tolerance "
                   f"{fc['difference_tolerance_mm'] * 1e3:.4f} um); {len(fc['warnings'])} warning(s).</p>")
        rows = []
        for side in ("screw", "nut"):
            cs = [c for c in fc["comparisons"] if c["side"] == side]
            if cs:
                fg = [c["fcl_gap_um"] for c in cs]
                dg = [c["designed_gap_um"] for c in cs]
                rows.append([side, cs[0]["flank"], len(cs), min(dg), max(dg), min(fg), max(fg),
                             max(abs(c["gap_difference_um"]) for c in cs)])
        out.append(_table(rows, ["side", "roller flank", "teeth checked", "designed gap min (um)",
                                 "designed gap max (um)", "FCL gap min (um)", "FCL gap max (um)",
                                 "max |difference| (um)"], full=True))
        out.append("<details><summary>every tooth (FCL and designed gap)</summary>" + _table(
            [[c["side"], c["roller"], c["tooth"], c["designed_gap_um"], c["fcl_gap_um"], c["gap_difference_um"],
              c["fcl_distance_mm"], c["analytic_distance_mm"]] for c in fc["comparisons"]],
            ["side", "roller", "tooth", "designed gap (um)", "FCL gap (um)", "difference (um)",
             "FCL distance (mm)", "analytic distance (mm)"], full=True) + "</details>")
    if contact is not None and contact.tooth_gaps:
        g = contact.tooth_gaps
        rows = []
        for side in ("screw", "nut"):
            for flank in ("upper", "lower"):
                if side in g and flank in g[side]:
                    vals = [x for row in g[side][flank]["gap_mm"] for x in row]
                    rows.append([side, flank, min(vals) * 1e3, max(vals) * 1e3])
        if rows:
            out.append("<h3>Unloaded gaps per tooth (all rollers)</h3>" + _table(
                rows, ["side", "flank", "smallest gap (um)", "largest gap (um)"], full=True))
    return "".join(out)


#: Labels of the pitch variants of the rating section.
_RATING_VARIANTS = {"constant_pitch": "constant pitch", "equal_load": "equal-load pitch",
                    "design": "design pitch lists", "robust": "robust pitch"}


def _rating_html(r: dict[str, Any], plots_svg: dict[str, str]) -> str:
    """Ratings, life (catalogue and from the tooth loads), limits, efficiency, stiffness."""
    out = ["<h2 id='rating'>Ratings and life</h2>",
           f"<p class='note'>{html.escape(r['method'])}; duty: {html.escape(r['duty_source'])}.</p>"]
    out.append(_table([
        ["basic dynamic axial load rating C_a (N)", r["dynamic_load_rating_n"]],
        ["basic static axial load rating C_0a (N)", r["static_load_rating_n"]],
        ["equivalent (cubic-mean) load F_m (N)", r["equivalent_load_n"]],
        ["equivalent speed n_m (rpm)", r["equivalent_speed_rpm"]],
        ["operating factor f_w", r["operating_factor"]],
        [f"reliability {r['reliability_pct']:g} %: factor a_1", r["reliability_factor"]],
        ["L life, catalogue (revolutions)", r["l10_revolutions"]],
        ["L life, catalogue (h)", r["l10_hours"]],
        [f"required C_a for {r['target_life_hours']:g} h (N)", r["required_dynamic_load_n"]],
        ["static safety C_0a / F_max", r["static_safety"]]]))
    rows = [[_RATING_VARIANTS.get(k, k), v["l10_hours"], v["gain_over_constant_pitch_hours"],
             v["gain_factor_over_constant_pitch"], v["max_hertz_pressure_mpa"], v["static_safety"]]
            for k, v in r["distribution_life"].items()]
    out.append("<h3>Life from the tooth loads</h3>" + _table(
        rows, ["pitch lists", "L life (h)", "gain over constant pitch (h)", "life factor over constant pitch",
               "max Hertz pressure (MPa)", "static safety (p_lim / p_max)^3"]))
    if isinstance(r.get("robust"), str):
        out.append(f"<p class='note'>Robust pitch: {html.escape(r['robust'])}.</p>")
    lim, eff, dn = r["limits"], r["efficiency"], r["double_nut"]
    out.append("<h3>Limits, efficiency, stiffness</h3>" + _table([
        [f"critical speed ({lim['critical_speed_ends']}, {lim['unsupported_length_mm']:g} mm) (rpm)",
         lim["critical_speed_rpm"]],
        ["speed limit d n (rpm)", lim["dn_speed_limit_rpm"]],
        ["permissible speed (rpm)", lim["permissible_speed_rpm"]],
        [f"Euler buckling load ({lim['buckling_ends']}) (N)", lim["buckling_load_n"]],
        [f"permissible buckling load (safety {lim['buckling_safety']:g}) (N)", lim["permissible_buckling_load_n"]],
        [f"efficiency forward (mu {eff['friction_coefficient']:g})", eff["forward"]],
        ["efficiency back-driving", eff["back_driving"]],
        [f"drive torque at {eff['torque_load_n']:g} N (N m)", eff["drive_torque_nm"]],
        ["holding torque against back-driving (N m)", eff["holding_torque_nm"]],
        ["double nut preload (N)", dn["preload_n"]],
        ["double nut: preload lost at (N)", dn["lift_off_load_n"]]]))
    if "rating" in plots_svg:
        out.append("<div class='plots'>" + svg_element(plots_svg["rating"]) + "</div>")
    return "".join(out)


def _flank_text(tol: dict[str, Any]) -> Any:
    """The flank tolerance: one value, or the per-tooth range when the lists differ."""
    values = [x for v in tol["per_tooth_flank_um"].values() for x in v]
    if all(x == tol["flank_um"] for x in values):
        return tol["flank_um"]
    return f"per tooth {min(values):g} to {max(values):g}"


def _tolerance_html(t: dict[str, Any], svgs: dict[str, str]) -> str:
    """The tolerance section: error model, quantiles per load, roller share, importance, plot."""
    tol = t["tolerances"]
    out = ["<h2 id='tolerance'>Tolerances and load sharing</h2>",
           f"<p class='note'>{t['samples']} Monte Carlo samples (seed {t['seed']}), all rollers side by "
           f"side; {html.escape(tol['distribution'])} errors; source: {html.escape(tol['source'])}.</p>",
           _table([["flank position (um)", _flank_text(tol)], ["roller pitch diameter (um)", tol["roller_diameter_um"]],
                   ["screw eccentricity (um)", tol["screw_eccentricity_um"]],
                   ["nut eccentricity (um)", tol["nut_eccentricity_um"]], ["base lead (um)", tol["lead_um"]],
                   ["temperature difference (K)", tol["temperature_k"]]], ["error term", "tolerance T"])]
    rows = [[f"{c['load_fraction'] * 100:g} %", c["deterministic"]["worst_ldc"], c["worst_ldc"]["median"],
             c["worst_ldc"]["p95"], c["worst_ldc"]["p99"], c["worst_ldc"]["max"],
             c["roller_load_share_max"]["p95"]] for c in t["cases"]]
    w = t["worst_ldc"]
    rows.append(["all loads", t["deterministic_worst_ldc"], w["median"], w["p95"], w["p99"], w["max"],
                 t["roller_load_share"]["max"]["p95"]])
    out.append(_table(rows, ["load", "no error", "median", "p95", "p99", "max", "roller share max, p95"]))
    if t["importance"]:
        out.append("<h3>Which error drives the spread</h3>" + _table(
            [[r["term"], f"{r['share'] * 100:.1f} %", r["std_alone"]] for r in t["importance"]],
            ["error group", "share of the variance", "std of the worst LDC alone"]))
    if "tolerance_ldc" in svgs:
        out.append("<div class='plots'>" + svg_element(svgs["tolerance_ldc"]) + "</div>")
    return "".join(out)


def _compliance_text(comp: dict[str, Any]) -> str:
    """One sentence naming the tooth-compliance model of a loads section."""
    details = comp.get("details", {})
    if comp.get("model") == "fe":
        fe = details["fe"]
        cache = fe.get("cache", {})
        hits = cache.get("read_from_cache", {})
        src = ("read from the cache" if hits and all(hits.values()) else "computed and cached") if cache else "computed"
        return (f"Tooth compliance: axisymmetric finite-element influence matrices (mesh level {fe['mesh_level']}, "
                f"{fe['teeth']} teeth, {fe['n_dofs']:,} degrees of freedom, {src}), coupled between teeth and "
                f"between a roller's flanks; Hertz contact and 1D bodies as in the analytic model.")
    return (f"Tooth compliance: Yamamoto's terms, diagonal, width convention "
            f"'{html.escape(str(details.get('tooth_width', '')))}'.")


def _model_risk_html(loads: LoadsResult, svgs: dict[str, str]) -> str:
    """The model-risk part of the loads section: every set of pitch lists under every
    compliance model (table at the design load, worst over the loads, plots)."""
    out = [f"<p class='note'>{html.escape(_compliance_text(loads.report()['compliances']))}</p>",
           "<h3 id='model-risk'>Model risk: analytic against finite-element compliance</h3>"]
    risk = loads.model_risk
    if risk is None:
        return "".join(out) + f"<p class='note'>{html.escape(MODEL_RISK_NOT_COMPUTED['note'])}.</p>"
    out.append("<p class='note'>Each set of pitch lists evaluated with each compliance model. A list designed "
               "for equal load with one model shares equally only under that model; the spread between the rows "
               f"is how much the answer depends on the model (largest difference of a coefficient "
               f"{risk.largest_model_difference:.4f}).</p>")
    rows = []
    for c in risk.cases:
        if c.load_fraction != 1.0:
            continue
        others = [o for o in risk.cases if (o.pitch_lists, o.designed_with, o.evaluated_with)
                  == (c.pitch_lists, c.designed_with, c.evaluated_with)]
        worst = max(max(float(o.ldc_nut_roller.max()), float(o.ldc_roller_screw.max())) for o in others)
        rows.append([c.pitch_lists + (f" (designed with {c.designed_with})" if c.designed_with else ""),
                     c.evaluated_with, f"{c.ldc_nut_roller.min():.4f} - {c.ldc_nut_roller.max():.4f}",
                     f"{c.ldc_roller_screw.min():.4f} - {c.ldc_roller_screw.max():.4f}", f"{worst:.4f}"])
    out.append(_table(rows, ["pitch lists", "evaluated with", "nut-roller LDC at design load",
                             "roller-screw LDC at design load",
                             "worst LDC over " + ", ".join(f"{f * 100:g} %" for f in risk.load_fractions)]))
    shown = [svgs[f] for f in ("model_risk_ldc", "model_risk_loads") if f in svgs]
    if shown:
        out.append("<div class='plots'>" + "".join(svg_element(t) for t in shown) + "</div>")
    return "".join(out)


def _mechanism_html(m: dict[str, Any]) -> str:
    """Carriers, journals, retaining rings: the checks with pass/fail, the fits, the journal
    clearances measured on the meshes and the axial stack-up."""
    def verdict(ok: bool) -> str:
        return "pass" if ok else "FAIL"

    out = ["<h2 id='mechanism'>Mechanism: carriers, journals, retaining rings</h2>"]
    out.append(_table([[c["name"], verdict(c["passed"])] for c in m["checks"]], ["check", "result"]))
    ring = m["retaining_ring"]
    out.append(_table([["roller journal diameter (mm)", m["journal_diameter_mm"]],
                       ["carrier inner / outer diameter (mm)",
                        f"{m['carrier']['inner_diameter_mm']:.4f} / {m['carrier']['outer_diameter_mm']:.4f}"],
                       ["carrier thickness (mm)", m["carrier"]["thickness_mm"]],
                       ["retaining ring", ring["designation"]],
                       ["groove diameter d2 / width m / edge distance n (mm)",
                        f"{ring['groove_diameter_mm']:g} / {ring['groove_width_mm']:g} / {ring['edge_distance_mm']:g}"],
                       ["nut end bore (mm)", m["nut_end"]["bore_diameter_mm"]]]))
    out.append(_table([[f["feature"], f["fit"], f["nominal_diameter_mm"], f["min_clearance_mm"] * 1e3,
                        f["max_clearance_mm"] * 1e3, f["modelled_clearance_mm"] * 1e3, verdict(f["passed"])]
                       for f in m["fits"]],
                      ["fit", "ISO 286", "nominal (mm)", "min clearance (um)", "max clearance (um)",
                       "modelled (um)", "result"]))
    js = m["journal_clearances"]
    out.append(_table([[r["roller"], r["end"], r["fcl_clearance_mm"] * 1e3, r["fit_radial_range_mm"][0] * 1e3,
                        r["fit_radial_range_mm"][1] * 1e3, verdict(r["passed"])] for r in js],
                      ["roller", "end", "FCL radial clearance (um)", "fit min (um)", "fit max (um)", "result"],
                      full=True))
    st = m["stack_up"]
    out.append(_table([[d["name"], d["count"], "+" if d["sense"] > 0 else "-", d["nominal_mm"],
                        d["lower_deviation_mm"], d["upper_deviation_mm"]] for d in st["chain"]],
                      ["axial stack-up", "count", "sense", "nominal (mm)", "lower dev. (mm)", "upper dev. (mm)"]))
    out.append(f"<p class='note'>axial play of carriers and rollers between the rings: nominal "
               f"{st['nominal_play_mm']:.4f} mm, worst case {st['min_play_mm']:.4f} to {st['max_play_mm']:.4f} mm "
               f"({verdict(st['passed'])}).</p>")
    return "".join(out)


def write_html(path: Path, design: PRSDesign, version: str, warnings: list[str],
               contact: ContactResult | None = None, loads: LoadsResult | None = None,
               plots_svg: dict[str, str] | None = None, machining: dict[str, MachiningSheet] | None = None,
               mesh_checks: list[dict[str, Any]] | None = None,
               tolerance: dict[str, Any] | None = None, checks: dict[str, Any] | None = None,
               inspection: dict[str, Any] | None = None, date: str = "",
               rating: dict[str, Any] | None = None, mechanism: dict[str, Any] | None = None,
               parts_list: list[dict[str, Any]] | None = None) -> None:
    """Write ``report.html`` from the stage results of a build.

    ``plots_svg`` maps plot names (``loads_ldc``, ...) to their SVG text, as the plot stage
    rendered them; the page shows them inline. Templates, style sheet and viewer script are
    package data (``templates/report.html``, ``report.css``, ``viewer.js``).
    """
    parts = page_head(f"Planetary roller screw '{html.escape(design.name)}'", version, date, design_hash(design),
                      "Units mm, N, MPa; tooth 1 at the loaded end.", warnings, "cut the nut open")
    if contact is not None:
        c = contact.report()
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
        parts.append("<h2>Contact</h2>" + _table(rows, ["contact", "r part (mm)", "angle part (deg)",
                                                         "r roller (mm)", "angle roller (deg)", "gap (mm)"]))
        parts.append(_table([["nominal screw pitch diameter (mm)", sr["nominal_pitch_diameter_mm"]],
                             ["theoretical screw pitch diameter (mm)", sr["theoretical_pitch_diameter_mm"]],
                             ["interference at nominal, axial (mm)", sr["interference_at_nominal_mm"]]]))
        parts.append(f"<p class='note'>{html.escape(c['conventions'])}</p>")
    if loads is not None:
        L = loads.report()
        parts.append("<h2>Load distribution</h2>")
        parts.append(_table([["design load (N)", L["design_load_N"]], ["installation", L["installation"]],
                             ["max LDC", L["max_ldc"]], ["max LDC, constant pitch", L["constant_pitch"]["max_ldc"]],
                             ["axial stiffness (N/um)", L["axial_stiffness_N_per_um"]]]))
        shown = [plots_svg[f] for f in ("loads_ldc", "pitch_corrections", "off_design") if f in (plots_svg or {})]
        parts.append("<div class='plots'>" + "".join(svg_element(t) for t in shown) + "</div>")
        parts.append(_model_risk_html(loads, plots_svg or {}))
    if rating is not None:
        parts.append(_rating_html(rating, plots_svg or {}))
    if tolerance is not None:
        parts.append(_tolerance_html(tolerance, plots_svg or {}))
    if checks:
        parts.append(_checks_html(checks, contact))
    if mechanism:
        parts.append(_mechanism_html(mechanism))
    if parts_list:
        from prs_geom.exports.bom import COLUMNS as BOM_COLUMNS

        parts.append("<h2 id='parts-list'>Parts list</h2>" + _table(
            [[r[k] for k, _, _ in BOM_COLUMNS] for r in parts_list],
            [f"{t} ({u})" if u else t for _, t, u in BOM_COLUMNS], full=True)
            + f"<p class='note'>total mass {sum(r['total_mass_kg'] for r in parts_list):.4f} kg; "
            "item numbers are the balloons of the assembly drawing; volumes from the meshes.</p>")
    if inspection:
        keys = ["gauge", "pitch_diameter_mm", "lead_angle_deg", "gauge_diameter_mm", "measurement_mm",
                "measurement_correction_um", "numerical_check_um", "temperature_coefficient_um_per_k"]
        parts.append("<h2 id='inspection'>Inspection (20 degC)</h2>" + _table(
            [[part] + [r[k] for k in keys] for part, r in inspection.items()], ["part"] + keys, full=True)
            + "".join(f"<p class='note'>{html.escape(part)}: {html.escape(r['method'])}</p>"
                      for part, r in inspection.items()))
    for part, sheet in (machining or {}).items():
        parts.append(f"<h2>Machining sheet: {html.escape(part)}</h2>")
        parts.append(_table([[k, v] for k, v in sheet.header.items()]))
        parts.append(_table([[st["start"], st["angular_index_deg"], st["axial_offset_mm"], st["nominal_lead_mm"],
                              st["lead_min_mm"], st["lead_max_mm"], " ".join(map(str, st["teeth_at_theta_0"]))]
                             for st in sheet.starts],
                            ["start", "angular index (deg)", "axial offset (mm)", "nominal lead (mm)",
                             "lead min (mm)", "lead max (mm)", "teeth at theta = 0"], full=True))
        parts.append(_table([[r[k] if r[k] is not None else "" for k, _, _ in COLUMNS] for r in sheet.rows],
                            [f"{t} ({u})" if u else t for _, t, u in COLUMNS], full=True))
    parts.append("<h2>Design</h2>" + _table(_flatten(design_to_dict(design)), ["field", "value"]))
    if mesh_checks is not None:
        parts.append("<h2>Mesh checks</h2>" + _table(
            [[m["part"], m["triangles"], m["watertight"], m["manifold"], m["chord_tolerance_mm"],
              m["max_deviation_mm"]] for m in mesh_checks],
            ["part", "triangles", "watertight", "manifold", "chord tol. (mm)", "max deviation (mm)"]))
    payload = json.dumps(scene_payload(design, screw_profile=contact.screw_profile if contact else None)
                         ).replace("</", "<\\/")
    three = three_js()
    page = fill_template(page_template("report.html"), {
        "title": html.escape(design.name), "css": page_template("report.css"), "body": "".join(parts),
        "scene": payload, "viewer": page_template("viewer.js"), "importmap": three["importmap"],
        "three_version": three["version"], "three_licence": three["licence"].replace("--", "- -")})
    # the template file ends with a newline; the page has always ended at </html>
    path.write_text(page.rstrip("\n"), encoding="utf-8")
