"""report.html in a real headless browser (issue 6)."""
import os
import shutil
import subprocess

import numpy as np
import pytest

from prs_geom.model.design import MeshSettings, PRSDesign, Roller
from prs_geom.pipeline import build

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
if CHROMIUM is None and os.environ.get("CI"):
    raise RuntimeError("CI must have Debian's chromium installed (see .ci/run)")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="chromium not installed (apt-get install chromium)")

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--virtual-time-budget=20000"]


@pytest.fixture(scope="module")
def report_html(tmp_path_factory):
    out = tmp_path_factory.mktemp("h") / "out"
    build(PRSDesign(name="html", roller=Roller(count=6), mesh=MeshSettings(chord_tolerance_mm=0.02)), out)
    return out / "report.html"


def chromium(args, tmp_path):
    prof = tmp_path / "profile"
    return subprocess.run([CHROMIUM, *FLAGS, f"--user-data-dir={prof}", *args],
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
    assert differs.mean() > 0.2          # the parts cover a good share of the view
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


def test_view_runs_the_mechanism(report_html, tmp_path):
    """report.html#play runs the animation: the viewer steps through the keys of the
    screw revolution without a script error."""
    r = chromium(["--dump-dom", report_html.as_uri() + "#play"], tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    body = r.stdout[r.stdout.index("<body"):r.stdout.index(">", r.stdout.index("<body")) + 1]
    assert 'data-viewer="ok"' in body and "data-errors" not in body
    key = int(body.split('data-animation-key="')[1].split('"')[0])
    assert 0 <= key <= 72


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
