"""Rebuild every golden design and write its fingerprint to tests/golden/data/<name>.json.

Run from the repository root: ``.venv/bin/python tests/golden/regenerate.py [NAME ...]``.
Commit the result on its own, saying why the outputs changed.
"""
from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from fingerprint import DATA, DESIGNS, build_fingerprint  # noqa: E402


def main(names: list[str]) -> None:
    DATA.mkdir(exist_ok=True)
    for key in names or list(DESIGNS):
        with tempfile.TemporaryDirectory() as tmp:
            fp = build_fingerprint(key, Path(tmp) / key)
        (DATA / f"{key}.json").write_text(json.dumps(fp, indent=1, sort_keys=True) + "\n", encoding="utf-8")
        print(f"wrote {DATA / (key + '.json')}: {len(fp['files'])} files")


if __name__ == "__main__":
    main(sys.argv[1:])
