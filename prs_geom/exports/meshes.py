"""Mesh exports: binary STL per part and for the assembly, GLB scene with named parts.

STL and GLB store vertex coordinates as float32: the rounding this costs is measured and
reported (``float32_rounding_mm``, :func:`prs_geom.mesh.float32_rounding`) next to the
chordal error.
"""
from __future__ import annotations

from pathlib import Path

import trimesh

from prs_geom.mesh.assembly import Assembly


def write_stl(mesh: trimesh.Trimesh, path: Path) -> None:
    path.write_bytes(trimesh.exchange.stl.export_stl(mesh))


def export_meshes(asm: Assembly, out: Path) -> dict[str, str]:
    """Write ``screw.stl``, ``roller.stl`` (part frame), ``nut.stl``, ``assembly.stl``
    (every scene part placed) and ``assembly.glb`` (scene, one named node per part).
    Returns {file name: description}."""
    files = {}
    for name in ("screw", "roller", "nut"):
        write_stl(asm.parts[name].to_trimesh(), out / f"{name}.stl")
        files[f"{name}.stl"] = f"{name} thread, part frame, binary STL (mm)"
    write_stl(asm.combined(), out / "assembly.stl")
    files["assembly.stl"] = "all parts placed in the screw frame, binary STL (mm)"
    (out / "assembly.glb").write_bytes(trimesh.exchange.gltf.export_glb(asm.scene()))
    files["assembly.glb"] = "scene with one named node per part (glTF binary; units mm)"
    return files
