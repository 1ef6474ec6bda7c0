"""Independent readers of the export files, shared by the tests (trimesh, manifold3d, lib3mf)."""
from __future__ import annotations

import locale
from pathlib import Path

import manifold3d
import numpy as np
import trimesh


def stl_merged(path: Path) -> trimesh.Trimesh:
    """An STL read back by trimesh, its vertices merged (STL stores a triangle soup)."""
    m = trimesh.load(path, file_type="stl", process=False)
    m.merge_vertices(merge_tex=True, merge_norm=True)
    return m


def solid(V, F) -> manifold3d.Manifold:
    """A manifold3d solid of a mesh; asserts it is one (not an empty set)."""
    m = manifold3d.Manifold(manifold3d.Mesh64(np.ascontiguousarray(V, dtype=np.float64),
                                              np.ascontiguousarray(F, dtype=np.uint64)))
    assert m.status() == manifold3d.Error.NoError and m.volume() > 0
    return m


def read_3mf(path: Path) -> dict:
    """A 3MF file read by lib3mf: unit, objects {name: (V, F)}, build items {part number: 4x4
    transform} and the object name of each item."""
    import lib3mf

    w = lib3mf.get_wrapper()
    model = w.CreateModel()
    saved = locale.setlocale(locale.LC_ALL, None)
    try:
        model.QueryReader("3mf").ReadFromFile(str(path))
    finally:
        locale.setlocale(locale.LC_ALL, saved)    # lib3mf leaves the C locale behind
    objects = {}
    it = model.GetMeshObjects()
    while it.MoveNext():
        o = it.GetCurrentMeshObject()
        V = np.array([list(p.Coordinates) for p in o.GetVertices()], dtype=np.float64)
        F = np.array([list(t.Indices) for t in o.GetTriangleIndices()], dtype=np.int64)
        objects[o.GetName()] = (V, F)
    items, item_object = {}, {}
    bi = model.GetBuildItems()
    while bi.MoveNext():
        b = bi.GetCurrent()
        f = b.GetObjectTransform().Fields
        T = np.eye(4)
        for col in range(4):
            for row in range(3):
                # lib3mf's Fields[i][j]: row i of the 4x3 matrix acting on row vectors
                T[row, col] = f[col][row]
        items[b.GetPartNumber()] = T
        item_object[b.GetPartNumber()] = b.GetObjectResource().GetName()
    return {"unit": model.GetUnit(), "mm": lib3mf.ModelUnit.MilliMeter, "objects": objects, "items": items,
            "item_object": item_object}


def khronos_issues(glb: Path, tmp_path: Path) -> dict:
    """The Khronos glTF validator's ``issues`` for a GLB file (npm ``gltf-validator`` on node,
    at ``PRS_GLTF_VALIDATOR`` or ``.ci/node``). Skips the test where node or the validator is
    missing, except in CI, which installs both (.ci/run)."""
    import json
    import os
    import shutil
    import subprocess

    import pytest

    node = shutil.which("node")
    validator = Path(os.environ.get("PRS_GLTF_VALIDATOR", Path(__file__).resolve().parent.parent / ".ci" / "node"
                                    / "node_modules" / "gltf-validator"))
    if node is None or not (validator / "package.json").exists():
        if os.environ.get("CI"):
            raise RuntimeError(f"CI must install node and gltf-validator at {validator} (see .ci/run)")
        pytest.skip(f"node or gltf-validator not installed at {validator} "
                    "(npm install --prefix .ci/node gltf-validator)")
    script = tmp_path / "validate.js"
    script.write_text(
        "const v = require(process.argv[2]); const fs = require('fs');\n"
        "v.validateBytes(new Uint8Array(fs.readFileSync(process.argv[3]))).then(r => {\n"
        "  console.log(JSON.stringify(r.issues)); }).catch(e => { console.error(e); process.exit(3); });\n")
    r = subprocess.run([node, str(script), str(validator), str(glb)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def assert_xlsx_cell(got, want) -> None:
    """A machining-sheet cell read back from the XLSX against the value written: booleans as
    yes/no, floats to the ~16 significant digits XLSX numbers carry (Excel shows 15)."""
    import pytest

    if isinstance(want, bool):
        assert got == ("yes" if want else "no")
    elif isinstance(want, float):
        assert got == pytest.approx(want, rel=1e-15, abs=1e-300)
    else:
        assert got == want


def glb_node_transforms(path: Path) -> dict[str, np.ndarray]:
    """World transform (4x4, mm, screw frame z up) of every named node of a GLB written by
    prs_geom, read from the glTF JSON chunk: each node's local TRS or matrix composed down
    the tree below the root node ``prs_geom`` (whose z-up to y-up turn is left out), metres
    scaled to mm."""
    import json
    import struct

    from scipy.spatial.transform import Rotation

    data = Path(path).read_bytes()
    length, kind = struct.unpack_from("<I4s", data, 12)
    doc = json.loads(data[20:20 + length])
    nodes = doc["nodes"]

    def local(node: dict) -> np.ndarray:
        if "matrix" in node:
            T = np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T
        else:
            T = np.eye(4)
            if "rotation" in node:
                T[:3, :3] = Rotation.from_quat(node["rotation"]).as_matrix()
            if "scale" in node:
                T[:3, :3] = T[:3, :3] * np.array(node["scale"])
            if "translation" in node:
                T[:3, 3] = node["translation"]
        T[:3, 3] *= 1000.0
        return T

    out: dict[str, np.ndarray] = {}

    def walk(i: int, parent: np.ndarray) -> None:
        T = parent @ local(nodes[i])
        out[nodes[i].get("name", "")] = T
        for c in nodes[i].get("children", []):
            walk(c, T)

    root = doc["scenes"][doc.get("scene", 0)]["nodes"]
    for r in root:
        for c in nodes[r].get("children", []):     # below the root's z-up to y-up turn
            walk(c, np.eye(4))
    return out


def dxf_text_boxes(doc, layout) -> list[tuple[str, np.ndarray, float]]:
    """The text boxes of a DXF layout read by ezdxf, each (label, corners (4, 2) in the
    layout's coordinates, text height): TEXT and MTEXT entities, and the measurement texts a
    DIMENSION renders (its virtual entities). ezdxf sizes them with the style's font (the
    drawings pin DejaVu Sans): a TEXT from the outline of its glyph box
    (``ezdxf.disassemble``), an MTEXT from ``ezdxf.tools.text_size.mtext_size`` at its
    attachment point and direction."""
    import math

    from ezdxf import disassemble
    from ezdxf.tools import text_size

    def box(e):
        if e.dxftype() == "TEXT":
            corners = np.array([(v.x, v.y) for v in disassemble.make_primitive(e).vertices()][:4])
            return (corners, e.dxf.height) if len(corners) == 4 else None
        size = text_size.mtext_size(e)
        w, h = size.total_width, size.total_height
        attach = int(e.dxf.get("attachment_point", 1)) - 1
        x0 = -0.5 * (attach % 3) * w
        top = (0.0, 0.5 * h, h)[attach // 3]
        local = np.array([[x0, top - h], [x0 + w, top - h], [x0 + w, top], [x0, top]])
        d = e.dxf.get("text_direction", None)
        a = math.atan2(d[1], d[0]) if d is not None else math.radians(e.dxf.get("rotation", 0.0))
        R = np.array([[math.cos(a), math.sin(a)], [-math.sin(a), math.cos(a)]])
        return local @ R + np.array([e.dxf.insert.x, e.dxf.insert.y]), e.dxf.char_height

    out = []
    for e in layout:
        kind = e.dxftype()
        found = list(e.virtual_entities()) if kind == "DIMENSION" else [e] if kind in ("TEXT", "MTEXT") else []
        for v in found:
            if v.dxftype() not in ("TEXT", "MTEXT"):
                continue
            text = v.plain_text() if v.dxftype() == "MTEXT" else v.dxf.text
            got = box(v)
            if got is not None and text.strip():
                out.append((f"{kind} {text!r}", *got))
    return out


def boxes_overlap(a: np.ndarray, b: np.ndarray, margin: float) -> bool:
    """True when the convex quadrilaterals ``a`` and ``b`` (4, 2), each grown by ``margin`` on
    every side, overlap: no edge normal of either separates them (separating axis test)."""
    for quad in (a, b):
        edges = np.roll(quad, -1, axis=0) - quad
        for n in np.column_stack([-edges[:, 1], edges[:, 0]]):
            n = n / np.linalg.norm(n)
            pa, pb = a @ n, b @ n
            if pa.max() + margin <= pb.min() - margin or pb.max() + margin <= pa.min() - margin:
                return False
    return True
