"""Self-contained HTML report (``report.html``): one file, no server, no network.

Sections: design table, contact results, load-distribution plots (inline SVG), machining
tables, and an interactive 3D view of the assembly. The 3D view is a small Canvas-2D
renderer written here (orthographic projection, back-face culling, painter's sort, Lambert
shading; drag to rotate, wheel to zoom): it needs no WebGL, so it works in any browser,
headless ones included. Its mesh is a display tessellation of the assembly (coarser than
the export meshes; the tolerance is stated on the page), embedded as base64 float32/uint32
arrays, one mesh per distinct part and one transform per placed part.

When the view has drawn its first frame it sets ``data-viewer="ok"`` and
``data-triangles`` on ``<body>``; script errors are collected in ``#errors`` and
``data-errors`` (the tests read these through a headless browser).
"""
from __future__ import annotations

import base64
import html
import json
from pathlib import Path
from typing import Any

import numpy as np

from .assembly import build_assembly
from .design import PRSDesign
from .designio import design_to_dict

#: Chordal tolerance (mm) of the display mesh: coarse enough for a light page.
DISPLAY_TOLERANCE_MM = 0.1

COLOURS = {"screw": "#8a9bb0", "nut": "#c9a66b", "roller": "#7fb37f", "simplified": "#b0b0b0"}


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


def scene_payload(design: PRSDesign, tol: float = DISPLAY_TOLERANCE_MM) -> dict[str, Any]:
    asm = build_assembly(design, tol=tol)
    meshes, index, instances = [], {}, []
    for name, (mesh, T, kind) in asm.placed.items():
        if id(mesh) not in index:
            index[id(mesh)] = len(meshes)
            meshes.append({"v": _b64(np.asarray(mesh.vertices, dtype=np.float32)),
                           "f": _b64(np.asarray(mesh.faces, dtype=np.uint32))})
        colour = COLOURS["simplified"] if kind == "simplified" else COLOURS[name.split("_")[0]]
        instances.append({"name": name, "mesh": index[id(mesh)], "T": [float(x) for x in T.ravel()],
                          "colour": colour, "cut": name.startswith("nut")})
    tri = sum(len(asm.placed[i["name"]][0].faces) for i in instances)
    return {"meshes": meshes, "instances": instances, "tolerance_mm": tol, "triangles": int(tri)}


VIEWER_JS = r"""
(function () {
  const errs = [];
  window.addEventListener('error', function (e) {
    errs.push(String(e.message));
    document.body.dataset.errors = String(errs.length);
    const el = document.getElementById('errors');
    if (el) { el.textContent = errs.join('\n'); el.style.display = 'block'; }
  });
  function decode(b64, Type) {
    const bin = atob(b64); const buf = new ArrayBuffer(bin.length); const u8 = new Uint8Array(buf);
    for (let i = 0; i < bin.length; i++) u8[i] = bin.charCodeAt(i);
    return new Type(buf);
  }
  function hex(c) { return [parseInt(c.slice(1, 3), 16), parseInt(c.slice(3, 5), 16), parseInt(c.slice(5, 7), 16)]; }
  const data = JSON.parse(document.getElementById('scene-data').textContent);
  const meshes = data.meshes.map(m => ({ v: decode(m.v, Float32Array), f: decode(m.f, Uint32Array) }));
  let nTri = 0;
  for (const inst of data.instances) nTri += meshes[inst.mesh].f.length / 3;
  const P = new Float32Array(nTri * 9), N = new Float32Array(nTri * 3), C = new Uint8Array(nTri * 3);
  const CUT = new Uint8Array(nTri);
  let t = 0; const lo = [1e9, 1e9, 1e9], hi = [-1e9, -1e9, -1e9];
  for (const inst of data.instances) {
    const m = meshes[inst.mesh], T = inst.T, col = hex(inst.colour);
    for (let k = 0; k < m.f.length; k += 3, t++) {
      const q = [];
      for (let c = 0; c < 3; c++) {
        const i = m.f[k + c] * 3, x = m.v[i], y = m.v[i + 1], z = m.v[i + 2];
        const w = [T[0] * x + T[1] * y + T[2] * z + T[3], T[4] * x + T[5] * y + T[6] * z + T[7],
                   T[8] * x + T[9] * y + T[10] * z + T[11]];
        for (let d = 0; d < 3; d++) { P[t * 9 + c * 3 + d] = w[d]; lo[d] = Math.min(lo[d], w[d]); hi[d] = Math.max(hi[d], w[d]); }
        q.push(w);
      }
      const ux = q[1][0] - q[0][0], uy = q[1][1] - q[0][1], uz = q[1][2] - q[0][2];
      const vx = q[2][0] - q[0][0], vy = q[2][1] - q[0][1], vz = q[2][2] - q[0][2];
      let nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
      const len = Math.hypot(nx, ny, nz) || 1;
      N[t * 3] = nx / len; N[t * 3 + 1] = ny / len; N[t * 3 + 2] = nz / len;
      C[t * 3] = col[0]; C[t * 3 + 1] = col[1]; C[t * 3 + 2] = col[2];
      CUT[t] = inst.cut ? 1 : 0;
    }
  }
  const centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])];
  const span = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  const canvas = document.getElementById('view'), ctx = canvas.getContext('2d');
  let yaw = 0.6, pitch = -1.2, zoom = 1.0;
  const depth = new Float32Array(nTri), order = new Uint32Array(nTri), X = new Float32Array(nTri * 6);
  function draw() {
    const W = canvas.width, H = canvas.height, s = zoom * 0.9 * Math.min(W, H) / span;
    const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
    // rotation: yaw about z, then pitch about x (view looks along -z of the rotated frame)
    const R = [cy, -sy, 0, cp * sy, cp * cy, -sp, sp * sy, sp * cy, cp];
    ctx.fillStyle = '#f4f6f8'; ctx.fillRect(0, 0, W, H);
    let n = 0;
    const cut = document.getElementById('cutaway').checked;
    for (let i = 0; i < nTri; i++) {
      const nzv = R[6] * N[i * 3] + R[7] * N[i * 3 + 1] + R[8] * N[i * 3 + 2];
      if (CUT[i] && cut) {
        // cutaway: drop the nut's half nearer to the viewer (centroid in front of the axis)
        const gx = (P[i * 9] + P[i * 9 + 3] + P[i * 9 + 6]) / 3 - centre[0];
        const gy = (P[i * 9 + 1] + P[i * 9 + 4] + P[i * 9 + 7]) / 3 - centre[1];
        if (R[6] * gx + R[7] * gy > 0) continue;
      } else if (nzv <= 0) continue;
      let zsum = 0;
      for (let c = 0; c < 3; c++) {
        const x = P[i * 9 + c * 3] - centre[0], y = P[i * 9 + c * 3 + 1] - centre[1], z = P[i * 9 + c * 3 + 2] - centre[2];
        X[i * 6 + c * 2] = W / 2 + s * (R[0] * x + R[1] * y + R[2] * z);
        X[i * 6 + c * 2 + 1] = H / 2 - s * (R[3] * x + R[4] * y + R[5] * z);
        zsum += R[6] * x + R[7] * y + R[8] * z;
      }
      depth[i] = zsum; order[n++] = i;
    }
    const vis = order.subarray(0, n);
    vis.sort((a, b) => depth[a] - depth[b]);
    for (let k = 0; k < n; k++) {
      const i = vis[k];
      const nzv = R[6] * N[i * 3] + R[7] * N[i * 3 + 1] + R[8] * N[i * 3 + 2];
      const l = 0.35 + 0.65 * Math.abs(nzv);
      const col = 'rgb(' + (C[i * 3] * l | 0) + ',' + (C[i * 3 + 1] * l | 0) + ',' + (C[i * 3 + 2] * l | 0) + ')';
      ctx.fillStyle = col; ctx.strokeStyle = col; ctx.lineWidth = 0.5;
      ctx.beginPath();
      ctx.moveTo(X[i * 6], X[i * 6 + 1]); ctx.lineTo(X[i * 6 + 2], X[i * 6 + 3]); ctx.lineTo(X[i * 6 + 4], X[i * 6 + 5]);
      ctx.closePath(); ctx.fill(); ctx.stroke();
    }
    document.getElementById('viewinfo').textContent =
      nTri + ' triangles (' + n + ' facing the viewer), display tolerance ' + data.tolerance_mm + ' mm. Drag to rotate, wheel to zoom.';
  }
  let dragging = false, lx = 0, ly = 0, pending = false;
  function later() { if (!pending) { pending = true; requestAnimationFrame(() => { pending = false; draw(); }); } }
  canvas.addEventListener('mousedown', e => { dragging = true; lx = e.clientX; ly = e.clientY; });
  window.addEventListener('mouseup', () => { dragging = false; });
  window.addEventListener('mousemove', e => {
    if (!dragging) return;
    yaw += 0.01 * (e.clientX - lx); pitch += 0.01 * (e.clientY - ly); lx = e.clientX; ly = e.clientY; later();
  });
  document.getElementById('cutaway').addEventListener('change', later);
  canvas.addEventListener('wheel', e => { e.preventDefault(); zoom *= Math.exp(-0.001 * e.deltaY); later(); }, { passive: false });
  draw();
  document.body.dataset.triangles = String(nTri);
  document.body.dataset.viewer = 'ok';
})();
"""

CSS = """
body { font-family: system-ui, sans-serif; margin: 1.5em; color: #1d2733; max-width: 1300px; }
h1 { font-size: 1.5em; } h2 { font-size: 1.2em; margin-top: 1.6em; border-bottom: 1px solid #ccd; }
table { border-collapse: collapse; font-size: 0.82em; margin: 0.4em 0; }
td, th { border: 1px solid #ccd; padding: 2px 6px; text-align: right; }
th { background: #e8eef5; } td.k { text-align: left; font-family: monospace; }
#view { border: 1px solid #99a; background: #f4f6f8; cursor: grab; }
#errors { display: none; color: #a00; white-space: pre; }
.plots svg { max-width: 100%; height: auto; }
.note { color: #556; font-size: 0.85em; }
.warnings { border: 2px solid #c80; background: #fff6e0; padding: 0.3em 0.8em; margin: 0.6em 0; }
"""


def _table(rows: list[list[Any]], header: list[str] | None = None) -> str:
    out = ["<table>"]
    if header:
        out.append("<tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in header) + "</tr>")
    for r in rows:
        cells = []
        for i, v in enumerate(r):
            if isinstance(v, float):
                v = f"{v:.6g}"
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


def _svg(path: Path) -> str:
    text = path.read_text(encoding="utf-8")
    return text[text.index("<svg"):]


def write_html(design: PRSDesign, report: dict[str, Any], out: Path, path: Path) -> None:
    """Write ``report.html`` from the report dict and the plot files already in ``out``."""
    from .machining import COLUMNS

    parts = [f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
             f"<title>prs_geom report: {html.escape(design.name)}</title><style>{CSS}</style></head><body>",
             f"<h1>Planetary roller screw '{html.escape(design.name)}'</h1>",
             f"<p class='note'>prs_geom {html.escape(report['prs_geom_version'])}. Units mm, N, MPa; "
             f"tooth 1 at the loaded end.</p>",
             "<div id='warnings' class='warnings'><b>Warnings</b><ul>"
             + "".join(f"<li>{html.escape(w)}</li>" for w in report["warnings"]) + "</ul></div>"
             if report["warnings"] else "<p id='warnings' class='note'>Warnings: none.</p>",
             "<div id='errors'></div>",
             "<h2>Assembly</h2><canvas id='view' width='900' height='560'></canvas><div id='viewinfo' class='note'></div>"
             "<label class='note'><input type='checkbox' id='cutaway' checked> cut the nut open</label>"]
    c = report.get("contact") or {}
    if c:
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
    L = report.get("loads") or {}
    if L:
        parts.append("<h2>Load distribution</h2>")
        parts.append(_table([["design load (N)", L["design_load_N"]], ["installation", L["installation"]],
                             ["max LDC", L["max_ldc"]], ["max LDC, constant pitch", L["constant_pitch"]["max_ldc"]],
                             ["axial stiffness (N/um)", L["axial_stiffness_N_per_um"]]]))
        plots = [f for f in ("loads_ldc.svg", "pitch_corrections.svg", "off_design.svg") if (out / f).exists()]
        parts.append("<div class='plots'>" + "".join(_svg(out / f) for f in plots) + "</div>")
    M = report.get("machining") or {}
    for part, sheet in M.items():
        parts.append(f"<h2>Machining sheet: {html.escape(part)}</h2>")
        parts.append(_table([[k, v] for k, v in sheet["header"].items()]))
        parts.append(_table([[r[k] if r[k] is not None else "" for k, _, _ in COLUMNS] for r in sheet["rows"]],
                            [f"{t} ({u})" if u else t for _, t, u in COLUMNS]))
    parts.append("<h2>Design</h2>" + _table(_flatten(design_to_dict(design)), ["field", "value"]))
    checks = report.get("checks", {})
    if "meshes" in checks:
        parts.append("<h2>Mesh checks</h2>" + _table(
            [[m["part"], m["triangles"], m["watertight"], m["manifold"], m["chord_tolerance_mm"],
              m["max_deviation_mm"]] for m in checks["meshes"]],
            ["part", "triangles", "watertight", "manifold", "chord tol. (mm)", "max deviation (mm)"]))
    payload = json.dumps(scene_payload(design)).replace("</", "<\\/")
    parts.append(f"<script type='application/json' id='scene-data'>{payload}</script>")
    parts.append(f"<script>{VIEWER_JS}</script></body></html>")
    path.write_text("".join(parts), encoding="utf-8")
