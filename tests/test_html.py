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
    assert text.count("<svg") == 3 and "scene-data" in text


def test_report_loads_without_errors_and_viewer_draws(report_html, tmp_path):
    r = chromium(["--dump-dom", report_html.as_uri()], tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    body = r.stdout[r.stdout.index("<body"):r.stdout.index(">", r.stdout.index("<body")) + 1]
    assert 'data-viewer="ok"' in body
    assert "data-errors" not in body
    assert "data-triangles" in body


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
