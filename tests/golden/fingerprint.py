"""Golden outputs: what a build must keep when code is restructured.

A *fingerprint* of an output folder holds

* ``report``: report.json with the wall-clock fields removed (``timings_s`` and every
  ``time_s``), compared number by number to 1e-12 relative;
* ``files``: the SHA-256 of every exported file's bytes, less what is not content:
  DXF creation/update dates and GUIDs, the XLSX (a zip with dates inside) is replaced by its
  cell values, the manifest (which holds the write time) is left out. Builds run with
  SOURCE_DATE_EPOCH fixed, so the drawing title blocks carry the same date.

Regenerate the goldens (after a change that alters outputs on purpose, in its own commit
with the reason) with::

    .venv/bin/python tests/golden/regenerate.py
"""
from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
DATA = HERE / "data"
EXAMPLES = HERE.parent.parent / "examples"
#: Designs with goldens: None is the built-in default design.
DESIGNS = {"default": None, "standard": "standard.toml", "graded-pitch": "graded-pitch.toml",
           "harmonic": "harmonic.toml"}
#: Files not compared byte for byte (see module docstring).
SKIP = {".prs-geom-manifest.json", "report.json"}
_DXF_VOLATILE = re.compile(rb"\n\$(TDCREATE|TDUPDATE|TDUCREATE|TDUUPDATE|TDINDWG|TDUSRTIMER|FINGERPRINTGUID|"
                           rb"VERSIONGUID)\r?\n *\d+\r?\n[^\r\n]*")


#: ezdxf's "written by" stamp: version @ ISO time.
_DXF_STAMP = re.compile(rb"\n[0-9.]+ @ \d{4}-\d\d-\d\dT[^\r\n]*")


def _strip_times(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {k: _strip_times(v) for k, v in obj.items() if k not in ("timings_s", "time_s")}
    if isinstance(obj, list):
        return [_strip_times(v) for v in obj]
    return obj


def _xlsx_cells(path: Path) -> bytes:
    from openpyxl import load_workbook

    wb = load_workbook(path, read_only=True)
    rows = {ws.title: [list(r) for r in ws.iter_rows(values_only=True)] for ws in wb.worksheets}
    return json.dumps(rows, default=repr, sort_keys=True).encode()


def file_digest(path: Path) -> str:
    raw = path.read_bytes()
    if path.suffix == ".dxf":
        raw = _DXF_STAMP.sub(b"", _DXF_VOLATILE.sub(b"", raw))
    elif path.suffix == ".xlsx":
        raw = _xlsx_cells(path)
    return hashlib.sha256(raw).hexdigest()


def fingerprint(folder: Path) -> dict[str, Any]:
    report = json.loads((folder / "report.json").read_text(encoding="utf-8"))
    files = {p.relative_to(folder).as_posix(): file_digest(p) for p in sorted(folder.rglob("*"))
             if p.is_file() and p.name not in SKIP}
    return {"report": _strip_times(report), "files": files}


def compare_numbers(a: Any, b: Any, path: str = "report", rtol: float = 1e-12, atol: float = 1e-13) -> list[str]:
    """Differences between two JSON values; numbers to ``rtol`` relative or ``atol``
    absolute: a quantity that is zero up to rounding (a contact overlap of -7e-16 mm, a
    sliding speed of 1e-36 mm/s) takes its last bits from the BLAS and numpy build, and
    1e-13 (mm, um, N, ...) is far below every resolution the project states."""
    if isinstance(a, dict) and isinstance(b, dict):
        out = [f"{path}: key {k!r} only in the golden" for k in a.keys() - b.keys()]
        out += [f"{path}: key {k!r} only in the new report" for k in b.keys() - a.keys()]
        for k in a.keys() & b.keys():
            out += compare_numbers(a[k], b[k], f"{path}.{k}", rtol, atol)
        return out
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: length {len(a)} != {len(b)}"]
        out = []
        for i, (x, y) in enumerate(zip(a, b)):
            out += compare_numbers(x, y, f"{path}[{i}]", rtol, atol)
        return out
    num = (int, float)
    if isinstance(a, num) and isinstance(b, num) and not isinstance(a, bool) and not isinstance(b, bool):
        if a == b or abs(a - b) <= max(rtol * max(abs(a), abs(b)), atol):
            return []
        return [f"{path}: {a!r} != {b!r}"]
    return [] if a == b else [f"{path}: {a!r} != {b!r}"]


def build_fingerprint(key: str, out: Path) -> dict[str, Any]:
    from prs_geom.model.design import default_design
    from prs_geom.pipeline import build
    from prs_geom.pipeline import load_any_design as load_design

    import os

    design = default_design() if DESIGNS[key] is None else load_design(EXAMPLES / DESIGNS[key])
    # the drawings print a date in their title blocks: a fixed one (2026-01-01) for the goldens
    saved = os.environ.get("SOURCE_DATE_EPOCH")
    os.environ["SOURCE_DATE_EPOCH"] = "1767225600"
    try:
        build(design, out, memory_budget=8 * 2 ** 30)
    finally:
        if saved is None:
            del os.environ["SOURCE_DATE_EPOCH"]
        else:
            os.environ["SOURCE_DATE_EPOCH"] = saved
    return fingerprint(out)
