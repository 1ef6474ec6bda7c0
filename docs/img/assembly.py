"""Render docs/img/assembly.png: the default actuator (nut at mid-stroke) with its end gears.

Run from the repository root: ``.venv/bin/python docs/img/assembly.py`` (needs chromium).
The picture is drawn by the project's own report viewer (three.js in headless chromium) on
the assembly at the report's display tolerance, the nut cut open, seen from the loaded end
at an angle so that the roller gears and a ring gear show; the whole screw with its ends and
bearings fits the picture (the viewer's bounding-box fit), so the stroke the threads leave
the nut on either side shows.
"""
import json
import shutil
import subprocess
import tempfile
from pathlib import Path

from PIL import Image

from prs_geom.analysis.contact import analyse_contact
from prs_geom.exports.html import fill_template, page_template, scene_payload, three_js
from prs_geom.model.design import default_design

WIDTH, HEIGHT = 900, 560


def main() -> None:
    root = Path(__file__).resolve().parents[2]
    d = default_design()
    payload = scene_payload(d, screw_profile=analyse_contact(d).screw_profile)
    payload["view"] = {"direction": [0.35, 0.45, 1.0]}
    three = three_js()
    body = ("<div id='errors'></div><canvas id='view' width='900' height='560'></canvas>"
            "<div id='viewinfo' style='display:none'></div>"
            "<input type='checkbox' id='cutaway' checked style='display:none'>")
    page = fill_template(page_template("report.html"), {
        "title": "assembly", "css": "body{margin:0;background:#f4f6f8}", "body": body,
        "scene": json.dumps(payload).replace("</", "<\\/"), "viewer": page_template("viewer.js"),
        "importmap": three["importmap"], "three_version": three["version"],
        "three_licence": three["licence"].replace("--", "- -")})
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    with tempfile.TemporaryDirectory() as tmp:
        html = Path(tmp) / "view.html"
        html.write_text(page, encoding="utf-8")
        shot = Path(tmp) / "shot.png"
        subprocess.run([chromium, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                        f"--user-data-dir={tmp}/profile", f"--window-size={WIDTH},{HEIGHT + 40}",
                        "--virtual-time-budget=20000", f"--screenshot={shot}", html.as_uri()],
                       check=True, capture_output=True, timeout=300)
        Image.open(shot).crop((0, 0, WIDTH, HEIGHT)).save(root / "docs" / "img" / "assembly.png", optimize=True)
    print("wrote docs/img/assembly.png")


if __name__ == "__main__":
    main()
