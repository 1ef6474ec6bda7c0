"""Mesh exports: binary STL per part and for the assembly, the assembly as GLB and 3MF.

* ``screw.stl``, ``roller.stl``, ``nut.stl``: one part each, in its part frame, mm. The
  screw is the THEORETICAL one (pitch diameter from the contact analysis: the state the
  analysis certifies as free of interference); ``screw_nominal.stl`` holds the nominal screw
  when asked (``prs-geom build --screw nominal``).
* ``assembly.stl``: the assembly in the screw frame, for a quick look; the parts of each
  rigid body (the nut and its ring gears, each roller and its gears) united by
  :func:`rigid_body_pieces`, so that faces touching face to face share no edges and every
  edge of the file bounds exactly two triangles. It is a multi-body file: STL has no notion
  of parts, so the shells arrive in one triangle list (CAD users take the GLB, 3MF or
  per-part STLs).
* ``assembly.glb`` (glTF 2.0, metres, +Y up) and ``assembly.3mf`` (millimetres), written by
  :mod:`prs_geom.exports.scene`: one named node / build item per part and per roller.

STL and GLB store vertex coordinates as float32: the rounding this costs is measured and
reported (``float32_rounding_mm``, :func:`prs_geom.mesh.thread.float32_rounding`) next to the
chordal error. The STL writer fills one numpy record array (no loop over triangles); its
80-byte header names the part, the units, the frame and the design hash, and never starts
with ``solid`` (which some readers take for ASCII STL).
"""
from __future__ import annotations

from collections.abc import Iterable, Iterator
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from prs_geom.mesh.assembly import Assembly

__all__ = ["stl_records", "stl_bytes", "write_stl_pieces", "write_stl", "stl_header", "rigid_body_pieces",
           "export_meshes"]

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
    """Vertices and faces of each rigid body of the assembly, placed in the screw frame, in
    the order of ``asm.placed``, with the parts of each rigid body united (manifold3d,
    float64): a roller and its gears, the nut and its ring gears touch at end faces, whose
    coincident vertices would otherwise make edges used by four faces (manifold3d may keep
    face-touching parts as separate shells, but their boundaries no longer coincide). Bodies whose parts share one frame
    (every roller) are united once and placed by transform."""
    from prs_geom.mesh.thread import from_manifold, to_manifold

    bodies: dict[str, list[tuple[object, NDArray[np.float64]]]] = {}
    for name, (mesh, T, _) in asm.placed.items():
        bodies.setdefault(asm.rigid_body(name), []).append((mesh, T))
    united: dict[tuple[int, ...], tuple[NDArray[np.float64], NDArray[np.int64]]] = {}
    for body, parts in bodies.items():
        T = parts[0][1]
        same_frame = all(np.array_equal(Tp, T) for _, Tp in parts)
        key = tuple(id(m) for m, _ in parts) if same_frame else (id(parts),)
        if key not in united:
            if len(parts) == 1:
                united[key] = (np.asarray(parts[0][0].vertices, dtype=np.float64), np.asarray(parts[0][0].faces))
            else:
                solid = None
                for m, Tp in parts:
                    piece = to_manifold(m.vertices, m.faces)
                    if not same_frame:
                        piece = piece.transform(np.ascontiguousarray(Tp[:3, :4]))
                    solid = piece if solid is None else solid + piece
                united[key] = from_manifold(solid)
        V, F = united[key]
        if same_frame:
            V = V @ T[:3, :3].T + T[:3, 3]
        yield V, F


def export_meshes(asm: Assembly, out: Path, design_hash: str, nominal_screw=None) -> dict[str, str]:
    """Write the mesh files listed in the module docstring; returns {file name: description}.

    ``nominal_screw``: the nominal screw's mesh (anything with ``vertices`` and ``faces``),
    written as ``screw_nominal.stl`` when given.
    """
    from prs_geom.exports.scene import assembly_scene, write_3mf, write_glb

    files = {}
    for name in ("screw", "roller", "nut"):
        write_stl(asm.parts[name], out / f"{name}.stl", stl_header(name, design_hash))
        what = "theoretical-pitch-diameter screw" if name == "screw" else name
        files[f"{name}.stl"] = f"{what} thread, part frame, binary STL (mm)"
    for name, label in (("carrier", "carrier"), ("retaining_ring", "retaining ring")):
        if f"{name}_lo" in asm.placed:
            # one piece in its own frame: the lower copy moved so that its lower face is z = 0
            mesh = asm.placed[f"{name}_lo"][0]
            V = np.asarray(mesh.vertices, dtype=np.float64).copy()
            V[:, 2] -= V[:, 2].min()
            write_stl_pieces([(V, np.asarray(mesh.faces))], out / f"{name}.stl", stl_header(name, design_hash))
            files[f"{name}.stl"] = f"{label} (one of two), part frame (z = 0 at its face toward the nut end), binary STL (mm)"
    if nominal_screw is not None:
        write_stl(nominal_screw, out / "screw_nominal.stl", stl_header("nominal screw", design_hash))
        files["screw_nominal.stl"] = "nominal screw thread (not the analysed state), part frame, binary STL (mm)"
    write_stl_pieces(rigid_body_pieces(asm), out / "assembly.stl",
                     stl_header("assembly, multi-body", design_hash, "screw frame"))
    files["assembly.stl"] = ("the assembly in the screw frame, parts of each rigid body united; multi-body "
                             "binary STL (mm), for viewing")
    scene = assembly_scene(asm, asm.design.name, animate=True)
    write_glb(scene, out / "assembly.glb")
    files["assembly.glb"] = "glTF 2.0 binary: one named node per part and roller, metres, +Y up, PBR materials"
    write_3mf(scene, out / "assembly.3mf")
    files["assembly.3mf"] = "3MF: one object per distinct part, one build item per placed part (mm)"
    return files
