"""Fetch three.js from the npm registry into ``prs_geom/exports/vendor/three`` (or check it).

report.html embeds three.js (MIT, https://threejs.org) for its WebGL 3D view, so that the page
needs no network. The files are taken unmodified from the published npm package at the pinned
version below, next to the package's own LICENSE; ``MANIFEST.json`` records the tarball, npm's
integrity hash and the sha256 of every file taken. Nothing here is edited by hand.

Usage::

    python tools/vendor_three.py          # (re)fetch with `npm pack` and write the files
    python tools/vendor_three.py --check  # fetch again and verify the vendored bytes

Needs ``npm`` on PATH and access to registry.npmjs.org.
"""
from __future__ import annotations

import argparse
import base64
import hashlib
import json
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

PACKAGE = "three"
VERSION = "0.170.0"
#: files taken from the tarball (its paths below ``package/``) -> name in the vendor folder
FILES = {"build/three.module.min.js": "three.module.min.js",
         "examples/jsm/controls/OrbitControls.js": "OrbitControls.js",
         "LICENSE": "LICENSE"}
VENDOR = Path(__file__).resolve().parent.parent / "prs_geom" / "exports" / "vendor" / "three"


def fetch(workdir: Path) -> tuple[dict[str, bytes], dict[str, str]]:
    """The pinned tarball's files (by vendor name) and its npm metadata."""
    out = subprocess.run(["npm", "pack", f"{PACKAGE}@{VERSION}", "--json", "--pack-destination", str(workdir)],
                         capture_output=True, text=True, cwd=workdir)
    if out.returncode != 0:
        raise SystemExit(f"npm pack {PACKAGE}@{VERSION} failed:\n{out.stderr.strip()}")
    meta = json.loads(out.stdout)[0]
    tgz = workdir / meta["filename"]
    algo, digest = meta["integrity"].split("-", 1)
    if base64.b64encode(hashlib.new(algo, tgz.read_bytes()).digest()).decode() != digest:
        raise SystemExit(f"{tgz.name}: integrity {meta['integrity']} does not match the download")
    with tarfile.open(tgz) as tar:
        files = {name: tar.extractfile(f"package/{src}").read() for src, name in FILES.items()}
    return files, {"integrity": meta["integrity"], "tarball": meta["filename"]}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="verify the vendored files against npm")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        files, meta = fetch(Path(tmp))
    if args.check:
        bad = [n for n, b in files.items() if (VENDOR / n).read_bytes() != b]
        print("vendored three.js differs from npm: " + ", ".join(bad) if bad else
              f"vendored three.js {VERSION} equals the npm package ({meta['integrity']})")
        return 1 if bad else 0
    VENDOR.mkdir(parents=True, exist_ok=True)
    for name, data in files.items():
        (VENDOR / name).write_bytes(data)
    manifest = {"package": PACKAGE, "version": VERSION, "source": f"npm registry, {meta['tarball']}",
                "integrity": meta["integrity"], "licence": "MIT (LICENSE, unmodified from the package)",
                "files": {name: {"from": f"package/{src}", "sha256": hashlib.sha256(files[name]).hexdigest()}
                          for src, name in FILES.items()}}
    (VENDOR / "MANIFEST.json").write_text(json.dumps(manifest, indent=2) + "\n", encoding="utf-8")
    print(f"wrote {', '.join(files)} and MANIFEST.json to {VENDOR}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
