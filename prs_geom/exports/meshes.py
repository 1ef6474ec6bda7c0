"""Mesh exports: binary STL per part and for the assembly, the assembly as GLB and 3MF.

* ``screw.stl``, ``roller.stl``, ``nut.stl`` and, with the mechanism parts,
  ``carrier.stl`` and ``retaining_ring.stl``: one complete part each
  (:mod:`prs_geom.mesh.parts`: the screw with its ends; the roller with its gears and
  journals; the nut with its ring gears, ends and flange), in its part frame, mm. Their
  volumes are the parts list's. The screw is the THEORETICAL one (pitch diameter from the
  contact analysis: the state the analysis certifies as free of interference);
  ``screw_nominal.stl`` holds the nominal screw (with the same ends) when asked
  (``prs-geom build --screw nominal``).
* ``assembly.stl``: every copy of every complete part placed in the screw frame, for a quick
  look. It is a multi-body file: STL has no notion of parts, so the shells arrive in one
  triangle list (CAD users take the STEP assembly, the 3MF or the per-part files).
* ``assembly.glb`` (glTF 2.0, metres, +Y up, animated): one named node per scene piece
  (a roller's gears and journals are child nodes of its thread), written by
  :mod:`prs_geom.exports.scene`; the node of a rigid body (``roller_3``, ``carrier_hi``)
  places the body exactly as the STEP assembly places that copy of its part.
* ``assembly.3mf`` (millimetres): one mesh object per complete part, one build item per copy.

STL and GLB store vertex coordinates as float32: the rounding this costs is measured and
reported (``float32_rounding_mm``, :func:`prs_geom.mesh.thread.float32_rounding`) next to the
chordal error. The STL writer fills one numpy record array (no loop over triangles); its
80-byte header names the part, the units, the frame and the design hash, and never starts
with ``solid`` (which some readers take for ASCII STL).
"""
from __future__ import annotations

from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from prs_geom.mesh.assembly import Assembly

__all__ = ["PART_FILES", "complete_scene", "stl_records", "stl_bytes", "write_stl_pieces", "write_stl", "stl_header",
           "rigid_body_pieces", "export_meshes"]

#: Binary STL record: normal, three vertices (float32 LE), attribute byte count.
_STL_RECORD = np.dtype([("normal", "<f4", (3,)), ("v", "<f4", (3, 3)), ("attr", "<u2")])


def _check_header(header: str) -> bytes:
    head = header.encode("ascii")
    if len(head) > 80 or head.lower().startswith(b"solid"):
        raise ValueError(f"STL header {header!r}: at most 80 ASCII characters, not starting with 'solid'")
    return head.ljust(80, b" ")


def stl_records(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> bytes:
    """The triangle records of a binary STL (no header, no count); facet normals from the
    float64 vertices. Rows are independent, so records of consecutive pieces concatenate to
    the records of the whole."""
    V = np.asarray(vertices, dtype=np.float64)
    F = np.asarray(faces, dtype=np.int64)
    tri = V[F]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    rec = np.zeros(len(F), dtype=_STL_RECORD)
    rec["normal"] = n
    rec["v"] = tri
    return rec.tobytes()


def stl_bytes(vertices: NDArray[np.float64], faces: NDArray[np.int64], header: str = "") -> bytes:
    """Binary STL of a triangle mesh; facet normals from the float64 vertices.

    ``header`` (ASCII, at most 80 characters, padded with spaces) must not start with
    ``solid``.
    """
    head = _check_header(header)
    return head + np.uint32(len(faces)).tobytes() + stl_records(vertices, faces)


def write_stl_pieces(pieces: Iterable[tuple[NDArray[np.float64], NDArray[np.int64]]], path: Path,
                     header: str = "") -> int:
    """Write one binary STL from (vertices, faces) pieces, one piece in memory at a time (the
    assembly of a long design has millions of triangles); the same bytes as
    :func:`stl_bytes` of the concatenated pieces. Returns the triangle count."""
    head = _check_header(header)
    count = 0
    with open(path, "wb") as fh:
        fh.write(head + b"\0\0\0\0")
        for V, F in pieces:
            fh.write(stl_records(V, F))
            count += len(F)
        fh.seek(80)
        fh.write(np.uint32(count).tobytes())
    return count


def write_stl(mesh, path: Path, header: str = "") -> None:
    """Write a mesh (anything with ``vertices`` and ``faces``) as binary STL."""
    Path(path).write_bytes(stl_bytes(mesh.vertices, mesh.faces, header))


def stl_header(part: str, design_hash: str, frame: str = "part frame") -> str:
    return f"prs_geom {part}; units mm; {frame}; design sha256 {design_hash}"[:80]


def rigid_body_pieces(asm: Assembly) -> Iterator[tuple[NDArray[np.float64], NDArray[np.int64]]]:
    """Vertices and faces of every copy of every complete part of the assembly
    (:meth:`Assembly.complete_parts`), placed in the screw frame: the parts of each rigid
    body united, so that faces touching face to face share no edges and every edge of the
    file bounds exactly two triangles."""
    for part in asm.complete_parts().values():
        for k in range(part.count):
            yield part.placed_vertices(k), part.faces


#: The made parts with a file of their own, and how the file list describes them.
PART_FILES = {
    "screw": "theoretical-pitch-diameter screw, complete (thread, run-outs, ends)",
    "roller": "roller, complete (thread, end gears, journals)",
    "nut": "nut, complete (thread, ring gears, ends, flange)",
    "carrier": "carrier (one of two)",
    "retaining_ring": "retaining ring (one of two)",
}


def complete_scene(asm: Assembly, title: str = "") -> "Any":
    """A flat :class:`~prs_geom.exports.scene.Scene` of the complete parts: one mesh per
    part (its own frame), one node per copy named after its rigid body, placed by the
    copy's transform."""
    from prs_geom.exports.scene import MATERIALS, Scene, SceneMesh, SceneNode, part_family

    meshes, nodes = {}, []
    for part in asm.complete_parts().values():
        meshes[part.name] = SceneMesh(part.name, part.vertices, part.faces, part_family(part.name))
        nodes += [SceneNode(body, part.name, part.transforms[k]) for k, body in enumerate(part.instances)]
    mats = {k: v for k, v in MATERIALS.items() if k in {m.material for m in meshes.values()}}
    return Scene(meshes, mats, tuple(nodes), title)


def export_meshes(asm: Assembly, out: Path, design_hash: str, nominal_screw=None) -> dict[str, str]:
    """Write the mesh files listed in the module docstring; returns {file name: description}.

    ``nominal_screw``: the nominal screw thread's mesh (anything with ``vertices`` and
    ``faces``), written with the screw's ends as ``screw_nominal.stl`` when given.
    """
    from prs_geom.exports.scene import assembly_scene, write_3mf, write_glb
    from prs_geom.mesh.parts import union_pieces

    files = {}
    complete = asm.complete_parts()
    for name, what in PART_FILES.items():
        if name in complete:
            part = complete[name]
            write_stl_pieces([(part.vertices, part.faces)], out / f"{name}.stl", stl_header(name, design_hash))
            files[f"{name}.stl"] = f"{what}, part frame, binary STL (mm)"
    if nominal_screw is not None:
        screw = complete["screw"]
        pieces = [(nominal_screw, np.eye(4))] + [(asm.placed[n][0], asm.placed[n][1]) for n in screw.pieces[1:]]
        V, F, _ = union_pieces(pieces)
        write_stl_pieces([(V, F)], out / "screw_nominal.stl", stl_header("nominal screw", design_hash))
        files["screw_nominal.stl"] = "nominal screw, complete (not the analysed state), part frame, binary STL (mm)"
    write_stl_pieces(rigid_body_pieces(asm), out / "assembly.stl",
                     stl_header("assembly, multi-body", design_hash, "screw frame"))
    files["assembly.stl"] = ("the assembly in the screw frame, every complete part placed; multi-body "
                             "binary STL (mm), for viewing")
    scene = assembly_scene(asm, asm.design.name, animate=True)
    write_glb(scene, out / "assembly.glb")
    files["assembly.glb"] = "glTF 2.0 binary: one named node per part piece and roller, metres, +Y up, PBR materials"
    write_3mf(complete_scene(asm, asm.design.name), out / "assembly.3mf")
    files["assembly.3mf"] = "3MF: one object per complete part, one build item per placed copy (mm)"
    return files
