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
