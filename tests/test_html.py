"""report.html in a real headless browser (issue 6), and as people read it (issue 28): no
sideways scrolling, numbers through prs_geom.exports.numbers, a table of contents, the gears."""
import html
import json
import os
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from prs_geom.exports.numbers import format_cell
from prs_geom.model.design import MeshSettings, PRSDesign, Roller
from prs_geom.pipeline import build

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
if CHROMIUM is None and os.environ.get("CI"):
    raise RuntimeError("CI must have Debian's chromium installed (see .ci/run)")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="chromium not installed (apt-get install chromium)")

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync"]


@pytest.fixture(scope="module")
def report_html(tmp_path_factory):
    out = tmp_path_factory.mktemp("h") / "out"
    build(PRSDesign(name="html", roller=Roller(count=6), mesh=MeshSettings(chord_tolerance_mm=0.02)), out)
    return out / "report.html"


def chromium(args, tmp_path, budget_ms=20000):
    """Run headless chromium for ``budget_ms`` of virtual time. A running animation draws
    a frame every 1/60 s of that time in software GL, so the play test keeps it short."""
    prof = tmp_path / "profile"
    return subprocess.run([CHROMIUM, *FLAGS, f"--virtual-time-budget={budget_ms}",
                           f"--user-data-dir={prof}", *args],
                          capture_output=True, text=True, timeout=180)


def test_report_is_self_contained(report_html):
    import re
    text = report_html.read_text()
    # nothing is fetched: no src/href to another file or host, no external script or style
    assert not re.search(r"""(src|href)\s*=\s*["'](https?:|//|/|\.\.?/)""", text)
    assert "<link" not in text and "@import" not in text and "<script src" not in text
    assert text.count("<svg") == 4 and "scene-data" in text   # loads, pitch, off-design, rating


def test_report_loads_without_errors_and_viewer_draws(report_html, tmp_path):
    r = chromium(["--dump-dom", report_html.as_uri()], tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    body = r.stdout[r.stdout.index("<body"):r.stdout.index(">", r.stdout.index("<body")) + 1]
    assert 'data-viewer="ok"' in body
    assert "data-errors" not in body
    assert "data-triangles" in body
    # drawn by WebGL with a depth buffer (per-pixel occlusion: no painter's-sort streaks)
    assert 'data-renderer="webgl2"' in body
    depth_bits = int(body.split('data-depth-bits="')[1].split('"')[0])
    assert depth_bits >= 16


def test_3d_view_is_not_blank(report_html, tmp_path):
    from PIL import Image
    shot = tmp_path / "shot.png"
    r = chromium(["--window-size=1000,800", f"--screenshot={shot}", report_html.as_uri()], tmp_path)
    assert r.returncode == 0 and shot.exists(), r.stderr[-2000:]
    img = np.asarray(Image.open(shot).convert("RGB")).astype(float)
    # the canvas (900 x 560 at the top of the page, after the title): sample its middle
    region = img[250:650, 150:850]
    background = np.array([0xF4, 0xF6, 0xF8], float)
    differs = np.abs(region - background).sum(axis=2) > 30
    # the parts cover a good share of the view: the actuator (283 mm long, 76 mm across at
    # the flange) lies along the canvas and spans most of its width
    assert differs.mean() > 0.12
    columns = np.flatnonzero(differs.any(axis=0))
    assert columns[-1] - columns[0] > 0.6 * region.shape[1]
    assert region.std() > 20             # shaded, not one flat colour
    # the part colours are there: green rollers
    green = (region[:, :, 1] > region[:, :, 0] + 15) & (region[:, :, 1] > region[:, :, 2] + 15)
    assert green.mean() > 0.02


@pytest.mark.parametrize("size", ["700,900", "1600,1000"])
def test_3d_view_fits_the_window_without_clipping(report_html, tmp_path, size):
    """In a real browser at two window sizes: the canvas follows the page width, no part pixel
    touches the canvas border (nothing clipped), the parts cover a fair share of the view, and a
    screenshot shows the view and the tables below it (not blank)."""
    import re

    from PIL import Image
    r = chromium([f"--window-size={size}", "--dump-dom", report_html.as_uri()], tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    body = r.stdout[r.stdout.index("<body"):r.stdout.index(">", r.stdout.index("<body")) + 1]
    attrs = dict(re.findall(r'data-([a-z-]+)="([^"]*)"', body))
    assert attrs["edge-pixels"] == "0", attrs
    w, h = map(int, attrs["canvas"].split("x"))
    assert w <= min(900, int(size.split(",")[0])) and abs(h - round(w * 560 / 900)) <= 1
    assert float(attrs["coverage"]) > 0.08
    shot = tmp_path / "shot.png"
    r = chromium([f"--window-size={size}", f"--screenshot={shot}", report_html.as_uri()], tmp_path)
    assert r.returncode == 0 and shot.exists()
    img = np.asarray(Image.open(shot).convert("RGB")).astype(float)
    green = (img[:, :, 1] > img[:, :, 0] + 15) & (img[:, :, 1] > img[:, :, 2] + 15)
    assert green.mean() > 0.005                                     # the rollers are in the shot


def test_three_js_is_embedded_unmodified_with_its_licence(report_html):
    """The vendored three.js files are the bytes MANIFEST.json recorded from the npm package
    (sha256), the page embeds exactly those bytes, and carries the MIT licence text."""
    import base64
    import hashlib
    import json
    import re
    from importlib import resources

    folder = resources.files("prs_geom.exports").joinpath("vendor", "three")
    manifest = json.loads(folder.joinpath("MANIFEST.json").read_text())
    assert manifest["package"] == "three" and manifest["integrity"].startswith("sha512-")
    for name, entry in manifest["files"].items():
        assert hashlib.sha256(folder.joinpath(name).read_bytes()).hexdigest() == entry["sha256"], name
    text = report_html.read_text()
    imports = json.loads(re.search(r"<script type='importmap'>(.*?)</script>", text, re.S).group(1))["imports"]
    embedded = base64.b64decode(imports["three"].split(",", 1)[1])
    assert embedded == folder.joinpath("three.module.min.js").read_bytes()
    assert "Permission is hereby granted, free of charge" in text and manifest["version"] in text


@pytest.mark.skipif(shutil.which("npm") is None, reason="npm not installed")
def test_vendored_three_js_equals_the_npm_package():
    """tools/vendor_three.py --check fetches the pinned tarball again (npm verifies its
    integrity) and compares every vendored file byte for byte."""
    import sys
    from pathlib import Path

    tool = Path(__file__).parent.parent / "tools" / "vendor_three.py"
    r = subprocess.run([sys.executable, str(tool), "--check"], capture_output=True, text=True, timeout=300)
    if r.returncode != 0 and ("ENOTFOUND" in r.stderr or "EAI_AGAIN" in r.stderr or "ECONNREFUSED" in r.stderr):
        pytest.skip("the npm registry is not reachable: " + r.stderr.strip().splitlines()[-1])
    assert r.returncode == 0, r.stdout + r.stderr
    assert "equals the npm package" in r.stdout


#: Injected before </body> for the play test: count 12 animation frames, note the distinct
#: keys drawn, then stop the mechanism. A page that keeps animating never lets headless
#: Chromium's virtual time run out, and --dump-dom then waits for the process timeout.
STOP_PLAY = """<script>
window.addEventListener('load', function () {
  // written on every frame, so a slow (loaded) machine still leaves the count it reached;
  // stops the animation once three keys were seen (or after 240 frames) so the page idles
  let frames = 0; const keys = new Set();
  function count() {
    const k = document.body.dataset.animationKey;
    if (k !== undefined) keys.add(k);
    document.body.dataset.keysSeen = String(keys.size);
    if (keys.size < 3 && ++frames < 240) { requestAnimationFrame(count); return; }
    document.getElementById('play').checked = false;
  }
  requestAnimationFrame(count);
});
</script>"""


def test_view_runs_the_mechanism(report_html, tmp_path):
    """report.html#play runs the animation: the viewer steps through the keys of the
    screw revolution without a script error (a copy of the page with :data:`STOP_PLAY`)."""
    text = report_html.read_text(encoding="utf-8")
    i = text.rindex("</body>")
    page = tmp_path / "play" / "report.html"
    page.parent.mkdir()
    page.write_text(text[:i] + STOP_PLAY + text[i:], encoding="utf-8")
    r = chromium(["--dump-dom", page.as_uri() + "#play"], tmp_path, budget_ms=10000)
    assert r.returncode == 0, r.stderr[-2000:]
    body = r.stdout[r.stdout.index("<body"):r.stdout.index(">", r.stdout.index("<body")) + 1]
    assert 'data-viewer="ok"' in body and "data-errors" not in body
    key = int(body.split('data-animation-key="')[1].split('"')[0])
    assert 0 < key <= 72
    # a 4 s revolution of 72 keys gives a new key every 1/18 s: three within a few frames
    assert int(body.split('data-keys-seen="')[1].split('"')[0]) >= 3


def test_view_motions_are_the_kinematics(report_html):
    """The page's motion of each body, applied to a part's rest placement, is the pose of
    prs_geom.analysis.kinematics at every key (float32)."""
    import base64
    import json
    import math

    import numpy as np

    from prs_geom.analysis.kinematics import poses
    from prs_geom.geometry.frames import roller_transform

    text = report_html.read_text()
    start = text.index("id='scene-data'")
    payload = json.loads(text[text.index(">", start) + 1:text.index("</script>", start)].replace("<\\/", "</"))
    anim = payload["animation"]
    d = PRSDesign(name="html", roller=Roller(count=6), mesh=MeshSettings(chord_tolerance_mm=0.02))
    angles = 2 * math.pi * np.arange(anim["keys"]) / (anim["keys"] - 1)
    P = poses(d, angles)
    M = {k: np.frombuffer(base64.b64decode(v), np.float32).reshape(-1, 4, 4) for k, v in anim["motions"].items()}
    inst = {i["name"]: i for i in payload["instances"]}
    assert inst["retaining_ring_lo"]["motion"] == "nut" and inst["roller_2_journal_hi"]["motion"] == "roller_2"
    np.testing.assert_allclose(M["screw"], P.screw, atol=1e-6)
    np.testing.assert_allclose(M["nut"], P.nut, atol=1e-5)
    for k in range(6):
        world = M[f"roller_{k}"].astype(np.float64) @ roller_transform(d, k)
        np.testing.assert_allclose(world, P.roller[k], atol=2e-5)


# --------------------------------------------------------------------------- report.html for people (issue 28)
#: a number of more than 10 significant digits in visible text (digit groups joined by U+202F)
LONG_NUMBER = re.compile(r"(?<![\w.])\d[\d\u202f]*(?:\.\d+)?")
PYTHON_WORDS = re.compile(r"\b(None|True|False|nan|NaN)\b")
#: a negative zero as text: -0, -0.000
NEGATIVE_ZERO = re.compile(r"(?<![\w.\d])-0(?:\.0+)?(?![\d.])")

#: Injected before </body>: once the page has loaded (and the viewer started), open every
#: <details>, then write the layout facts and the visible text into a JSON script element
#: that --dump-dom prints.
PROBE = """<script>
window.addEventListener('load', function () { setTimeout(function () {
  document.querySelectorAll('details').forEach(function (d) { d.open = true; });
  const de = document.documentElement, boxes = document.querySelectorAll('.tw');
  let scrolling = 0;
  boxes.forEach(function (b) { if (b.scrollWidth > b.clientWidth) scrolling += 1; });
  const facts = {scrollWidth: de.scrollWidth, innerWidth: window.innerWidth, text: document.body.innerText,
                 boxes: boxes.length, scrollingBoxes: scrolling, tables: document.querySelectorAll('table').length};
  const s = document.createElement('script');
  s.type = 'application/json'; s.id = 'probe-facts';
  s.textContent = JSON.stringify(facts).replace(/</g, '\\\\u003c');
  document.body.appendChild(s);
}, 300); });
</script>"""


def page_facts(page: Path, tmp_path: Path, width: int = 1280) -> dict:
    """Layout and visible text of ``page`` in headless Chromium at a ``width`` px wide window
    (a copy of the page with :data:`PROBE` added; the page itself is not changed)."""
    text = page.read_text(encoding="utf-8")
    i = text.rindex("</body>")
    probe = tmp_path / "probe" / "report.html"
    probe.parent.mkdir(exist_ok=True)
    probe.write_text(text[:i] + PROBE + text[i:], encoding="utf-8")
    r = chromium([f"--window-size={width},900", "--dump-dom", probe.as_uri()], tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    m = re.search(r'<script type="application/json" id="probe-facts">(.*?)</script>', r.stdout, re.S)
    assert m, r.stdout[-2000:]
    return json.loads(m.group(1))


class _Page(HTMLParser):
    """The parts of a report page the tests read: ids (outside the inline SVG plots, whose
    matplotlib ids repeat from plot to plot), TOC links, h2 ids, and the cells (``td``) with
    their text and title."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.ids, self.toc, self.h2, self.cells, self.tables_in_box = [], [], [], [], []
        self._stack, self._cell, self._nav, self._svg = [], None, False, 0

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self._svg += tag == "svg"
        if "id" in a and not self._svg:
            self.ids.append(a["id"])
        if tag == "nav" and a.get("id") == "toc":
            self._nav = True
        if tag == "a" and self._nav:
            self.toc.append(a.get("href", ""))
        if tag == "h2":
            self.h2.append(a.get("id"))
        if tag == "table":
            self.tables_in_box.append(bool(self._stack) and self._stack[-1] == ("div", "tw"))
        if tag == "td":
            self._cell = [a.get("title"), ""]
        if tag in ("div", "table", "nav", "td", "tr", "details"):
            self._stack.append((tag, a.get("class")))

    def handle_endtag(self, tag):
        self._svg -= tag == "svg"
        if tag == "nav":
            self._nav = False
        if tag == "td" and self._cell is not None:
            self.cells.append(tuple(self._cell))
            self._cell = None
        if tag in ("div", "table", "nav", "td", "tr", "details") and self._stack:
            self._stack.pop()

    def handle_data(self, data):
        if self._cell is not None:
            self._cell[1] += data


def parse_page(page: Path) -> _Page:
    p = _Page()
    text = page.read_text(encoding="utf-8")
    p.feed(text[:text.index("<script type='application/json' id='scene-data'>")])
    return p


@pytest.fixture(scope="module")
def default_page(default_build):
    """The default design's report.html and report.json (the run's shared build)."""
    return default_build.out / "report.html", default_build.report


@pytest.fixture(scope="module")
def graded_page(graded_build):
    return graded_build.out / "report.html", graded_build.report


@pytest.fixture(scope="module")
def harmonic_page(harmonic_build):
    return harmonic_build.out / "report.html", harmonic_build.report


@pytest.mark.parametrize("which", ["default_page", "graded_page", "harmonic_page"])
def test_page_fits_1280_px_and_reads_like_a_report(which, request, tmp_path):
    """At 1280 px the page never scrolls sideways (wide tables scroll in their own box), and
    its visible text (every <details> opened) holds no Python literal (None, True, False,
    nan), no negative zero, no 'um' for µm, and no number of more than 10 significant
    digits."""
    page, _ = request.getfixturevalue(which)
    facts = page_facts(page, tmp_path)
    assert facts["scrollWidth"] <= facts["innerWidth"], facts["scrollWidth"]
    assert facts["boxes"] == facts["tables"] > 5
    text = facts["text"]
    assert len(text) > 5000
    assert not PYTHON_WORDS.findall(text), PYTHON_WORDS.findall(text)[:10]
    assert not NEGATIVE_ZERO.findall(text), [text[max(0, m.start() - 60):m.end() + 10]
                                             for m in NEGATIVE_ZERO.finditer(text)][:5]
    long = [n for n in LONG_NUMBER.findall(text) if len(n.replace("\u202f", "").replace(".", "").lstrip("0")) > 10]
    assert not long, long[:10]
    tables = parse_page(page)
    assert tables.cells and all(tables.tables_in_box)
    assert not [c for c in tables.cells if re.search(r"\bum\b", c[1])]


def test_wide_tables_scroll_inside_their_box(default_page, tmp_path):
    """At a narrow window the machining tables are wider than the page: they scroll in
    their own box and the page still does not."""
    page, _ = default_page
    facts = page_facts(page, tmp_path, width=700)
    assert facts["scrollWidth"] <= facts["innerWidth"]
    assert facts["scrollingBoxes"] >= 2


def test_table_of_contents_links_every_section(default_page):
    """The page opens with a table of contents; every link points to an id on the page, and
    every section (h2) has an id that the contents link to."""
    page, rep = default_page
    p = parse_page(page)
    text = page.read_text(encoding="utf-8")
    assert text.index("id='toc'") < text.index("id='assembly'") < text.index("<canvas")
    assert len(p.ids) == len(set(p.ids)), [i for i in p.ids if p.ids.count(i) > 1]
    targets = [h[1:] for h in p.toc]
    assert all(h.startswith("#") for h in p.toc) and set(targets) <= set(p.ids)
    assert None not in p.h2 and set(p.h2) <= set(targets)
    for section in ("assembly", "contact", "loads", "rating", "checks", "gears", "mechanism", "parts-list",
                    "inspection", "machining-roller", "machining-nut", "design", "mesh-checks"):
        assert section in targets, section


def _table_cells(page: Path, table_id: str) -> list[list[tuple[str | None, str]]]:
    text = page.read_text(encoding="utf-8")
    body = re.search(rf"<table id='{table_id}'>(.*?)</table>", text, re.S).group(1)
    rows = []
    for tr in re.findall(r"<tr>(.*?)</tr>", body, re.S):
        cells = re.findall(r"<td([^>]*)>(.*?)</td>", tr, re.S)
        if cells:
            rows.append([((re.findall(r"title='([^']*)'", a) or [None])[0], html.unescape(c)) for a, c in cells])
    return rows


def test_gear_section_shows_the_gears_of_report_json(default_page):
    """The gear section holds report.json's gears: both gears' data, the pair, phasing and
    running clearance, and every check with its verdict, formatted, exact values in the
    tooltips."""
    page, rep = default_page
    g = rep["gears"]
    data = {r[0][1]: r[1:] for r in _table_cells(page, "gear-data")}
    assert data["teeth z"] == [(None, str(g["roller_gear"]["teeth"])), (None, str(g["ring_gear"]["teeth"]))]
    assert [c[1] for c in data["module m (mm)"]] == ["0.4000", "0.4000"]
    assert data["addendum coefficient h_a*"][0] == (repr(g["roller_gear"]["addendum_coefficient"]), "0.7500")
    base = g["roller_gear"]["base_diameter_mm"]
    assert data["base diameter (mm)"][0] == (repr(base), format_cell(base, key="base_diameter_mm")) \
        == (repr(base), "7.5175")
    assert data["size over two pins (mm)"][1][1] == data["size between two pins (mm)"][0][1] == "\u2014"
    pair = {r[0][1]: r[1] for r in _table_cells(page, "gear-pair")}
    assert pair["transverse contact ratio"] == (repr(g["contact_ratio"]), "1.574")
    assert pair["ratio z_ring / z_g"][1] == "5.000"
    assert pair["backlash, normal (mm)"][1] == format_cell(g["backlash_normal_mm"], "mm") == "0.0376"
    assert pair["phasing: consistent"][1] == "yes" and pair["running clearance: overlap"][1] == "no"
    assert pair["phasing: max residual (°)"][1] == "0.0000"        # 5e-14 deg of float noise
    checks = {r[0][1]: r for r in _table_cells(page, "gear-checks-table")}
    assert set(checks) == {c["name"] for c in g["checks"]}
    for c in g["checks"]:
        row = checks[c["name"]]
        assert row[1] == (repr(float(c["value"])), format_cell(c["value"], c["unit"]))
        assert row[4][1] == ("pass" if c["passed"] else "FAIL")
    assert checks["trochoid_interference"][1][1] == "0.009425" and checks["trochoid_interference"][3][1] == "rad"


def test_tooltips_carry_the_exact_values(default_page):
    """A cell shows the rounded number and its title the exact float64 (repr); every
    titled cell reads back to its title within the printed precision."""
    page, rep = default_page
    d = rep["contact"]["screw_roller"]["theoretical_pitch_diameter_mm"]
    assert f"<td title='{d!r}'>23.8679</td>" in page.read_text(encoding="utf-8")
    assert repr(d) == "23.867870054925227"
    p = parse_page(page)
    titled = [(t, c) for t, c in p.cells if t]
    assert len(titled) > 1000
    for title, cell in titled:
        x = float(title.split(", ")[0])
        shown = cell.split(", ")[0].replace("\u202f", "")
        if "×" in shown or not re.fullmatch(r"-?\d+(\.\d+)?", shown):
            continue
        step = 10.0 ** -len(shown.partition(".")[2])
        assert abs(float(shown) - x) <= 0.5 * step * (1 + 1e-9) + 1e-9, (title, cell)


def test_graded_machining_sheet_shows_the_pitch_corrections(graded_page):
    """On a graded design the per-tooth pitch differences (0.02 µm per tooth) stay visible:
    pitches and positions to 0.001 µm, shifts in µm."""
    page, rep = graded_page
    text = page.read_text(encoding="utf-8")
    row = rep["machining"]["roller"]["rows"][2]
    shown = format_cell(row["designed_pitch_mm"], key="designed_pitch_mm")
    assert f"<td title='{row['designed_pitch_mm']!r}'>{shown}</td>" in text
    pitches = rep["pitch"]["equal_load"]["roller_mm"]
    shown = {format_cell(p, key="pitch.equal_load.roller_mm") for p in pitches}
    assert len(shown) == len(set(pitches)) > 10                     # no two pitches print alike
    assert "designed pitch to next tooth (mm)" in text and "axial shift to produce = designed - base (µm)" in text
