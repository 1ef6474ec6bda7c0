"""Scene exports for CAD and viewers: glTF 2.0 binary (``.glb``) and 3MF.

A :class:`Scene` is what both formats hold: distinct meshes (each in its own part frame, mm,
float64), PBR materials, and a tree of named nodes placing the meshes with rigid 4x4
transforms (mm). The rollers are one mesh placed z times. :func:`assembly_scene` builds it
from a placed :class:`~prs_geom.mesh.assembly.Assembly`.

glTF (:func:`write_glb`), per the glTF 2.0 specification:

* units are metres (glTF's unit): vertex positions and node translations are scaled by 1e-3
  when written (float32 of metres keeps about 0.06 um on a 1 m part; the rounding is reported
  by the mesh checks);
* +Y is up: one root node ``prs_geom`` turns the screw frame (axis +z) to +Y by a rotation
  of -90 deg about +X, so the screw axis reads along +Y in every viewer;
* one named node per part and per roller (the roller nodes share one mesh), PBR metallic-
  roughness materials per part, vertex normals split at sharp edges (corners whose faces
  bend by more than :data:`SHARP_EDGE_DEG` get their own vertex), indices as uint32;
* no extensions and no ``extras``: nothing a reader has to know about prs_geom.

3MF (:func:`write_3mf`), per the 3MF core specification, written with lib3mf (the 3MF
Consortium's reference library, which also validates what it writes): unit millimetre, one
named mesh object per distinct mesh, one build item per placed part carrying its transform
(the rollers are build items of one object), a base material (display colour) per part.
Object and build UUIDs are derived from the content, so the file is the same bytes from run
to run.
"""
from __future__ import annotations

import ctypes
import hashlib
import json
import locale
import math
import struct
import uuid
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from prs_geom._version import __version__
from prs_geom.model.io import atomic_path

__all__ = ["ANIMATION_PERIOD_S", "ANIMATION_STEP_DEG", "MATERIALS", "SHARP_EDGE_DEG", "Z_UP_TO_Y_UP", "Material",
           "Scene", "SceneAnimation", "SceneMesh", "SceneNode", "animation_angles", "assembly_scene", "glb_bytes",
           "mechanism_animation", "moving_group", "part_family", "quaternions", "split_normals", "write_3mf", "write_glb"]

#: Corners whose adjacent faces bend by more than this share no normal (deg).
SHARP_EDGE_DEG = 30.0
#: Screw frame (z up) to glTF (y up): rotation of -90 deg about +x, as a quaternion (x, y, z, w).
Z_UP_TO_Y_UP = (-math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5))


@dataclass(frozen=True)
class Material:
    """A PBR metallic-roughness material; ``colour`` is linear RGBA in [0, 1]."""

    name: str
    colour: tuple[float, float, float, float]
    metallic: float = 0.85
    roughness: float = 0.35

    def __post_init__(self) -> None:
        if not all(0.0 <= c <= 1.0 for c in (*self.colour, self.metallic, self.roughness)):
            raise ValueError(f"material {self.name!r}: colour, metallic and roughness must lie in [0, 1]")

    @property
    def srgb(self) -> tuple[float, float, float]:
        """The colour's red, green and blue in sRGB, each in [0, 1] (3MF and STEP colours
        are sRGB; glTF's are linear)."""
        def enc(c: float) -> float:
            return min(max(12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055, 0.0), 1.0)
        r, g, b, _ = self.colour
        return enc(r), enc(g), enc(b)

    @property
    def srgb_hex(self) -> str:
        """The colour as sRGB ``#RRGGBBAA`` (3MF display colours are sRGB)."""
        r, g, b = (int(round(255 * c)) for c in self.srgb)
        return "#%02X%02X%02X%02X" % (r, g, b, int(round(255 * self.colour[3])))


@dataclass(frozen=True, eq=False)
class SceneMesh:
    """One distinct mesh in its own frame: vertices (N, 3) mm, faces (M, 3), a material."""

    name: str
    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    material: str


@dataclass(frozen=True, eq=False)
class SceneNode:
    """A named node: an optional mesh (by name) placed by ``transform`` (4x4, mm, relative
    to the parent node), and child nodes."""

    name: str
    mesh: str | None = None
    transform: NDArray[np.float64] = field(default_factory=lambda: np.eye(4))
    children: tuple["SceneNode", ...] = ()


@dataclass(frozen=True, eq=False)
class SceneAnimation:
    """Keyframes of named nodes: at ``times_s`` (K,) each animated node's local rotation
    (K, 4) unit quaternions (x, y, z, w) and/or translation (K, 3) mm, relative to its
    parent, interpolated linearly (spherically for rotations) between keys."""

    name: str
    times_s: NDArray[np.float64]
    channels: dict[str, dict[str, NDArray[np.float64]]]


@dataclass(frozen=True, eq=False)
class Scene:
    """Meshes and materials by name, and the root nodes (screw frame, z up, mm)."""

    meshes: dict[str, SceneMesh]
    materials: dict[str, Material]
    nodes: tuple[SceneNode, ...]
    title: str = ""
    animations: tuple[SceneAnimation, ...] = ()

    def placed(self) -> list[tuple[str, SceneMesh, NDArray[np.float64]]]:
        """Every node with a mesh: (node name, mesh, world transform in mm)."""
        out = []

        def walk(node: SceneNode, parent: NDArray[np.float64]) -> None:
            T = parent @ node.transform
            if node.mesh is not None:
                out.append((node.name, self.meshes[node.mesh], T))
            for c in node.children:
                walk(c, T)

        for n in self.nodes:
            walk(n, np.eye(4))
        return out


#: Part materials (linear RGB): steel for screw and rollers, bearing bronze-tinted steel for
#: the nut, darker steel for the gears.
MATERIALS = {
    "screw": Material("screw steel", (0.42, 0.48, 0.58, 1.0)),
    "roller": Material("roller steel", (0.30, 0.50, 0.30, 1.0)),
    "nut": Material("nut steel", (0.60, 0.42, 0.20, 1.0)),
    "gear": Material("gear steel", (0.35, 0.35, 0.38, 1.0)),
    "carrier": Material("carrier steel", (0.55, 0.55, 0.60, 1.0)),
    "retaining_ring": Material("retaining ring spring steel", (0.08, 0.08, 0.09, 1.0)),
    "bearing": Material("bearing steel", (0.70, 0.71, 0.74, 1.0)),
    "locknut": Material("locknut steel", (0.20, 0.20, 0.22, 1.0)),
    "shaft_ring": Material("shaft ring spring steel", (0.08, 0.08, 0.09, 1.0)),
    "flange_bolt": Material("bolt steel, black oxide", (0.06, 0.06, 0.07, 1.0)),
    "drive_key": Material("key steel", (0.45, 0.45, 0.47, 1.0)),
}


#: The animation shows one screw revolution in this time (s), with a key every
#: :data:`ANIMATION_STEP_DEG` of screw angle (every node then turns less than 180 deg
#: between keys, so the spherical interpolation takes the intended way round).
ANIMATION_PERIOD_S = 4.0
ANIMATION_STEP_DEG = 5.0


def quaternions(R: NDArray[np.float64]) -> NDArray[np.float64]:
    """Unit quaternions (x, y, z, w) of rotation matrices ``R`` (..., 3, 3).

    Shepperd's method: the largest of 4 w^2, 4 x^2, 4 y^2, 4 z^2 (from the diagonal) is taken
    by its square root and the other three from sums and differences of the off-diagonal
    terms, so no component comes from the square root of a difference that rounding left
    near zero (that would give 1e-8 where the exact value is 0)."""
    R = np.asarray(R, dtype=np.float64)
    d0, d1, d2 = R[..., 0, 0], R[..., 1, 1], R[..., 2, 2]
    cand = np.stack([1.0 + d0 - d1 - d2, 1.0 - d0 + d1 - d2, 1.0 - d0 - d1 + d2, 1.0 + d0 + d1 + d2], -1)
    pick = np.argmax(cand, axis=-1)
    big = 0.5 * np.sqrt(np.take_along_axis(cand, pick[..., None], -1)[..., 0])
    f = 0.25 / big
    s21, s02, s10 = R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]
    a01, a02, a12 = R[..., 0, 1] + R[..., 1, 0], R[..., 0, 2] + R[..., 2, 0], R[..., 1, 2] + R[..., 2, 1]
    q = np.select([pick[..., None] == 0, pick[..., None] == 1, pick[..., None] == 2],
                  [np.stack([big, f * a01, f * a02, f * s21], -1),
                   np.stack([f * a01, big, f * a12, f * s02], -1),
                   np.stack([f * a02, f * a12, big, f * s10], -1)],
                  np.stack([f * s21, f * s02, f * s10, big], -1))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def _continuous(q: NDArray[np.float64]) -> NDArray[np.float64]:
    """Key quaternions (K, 4) with signs chosen so that consecutive keys have a positive dot
    product (q and -q are the same rotation; interpolation goes the short way between them)."""
    q = q.copy()
    for i in range(1, len(q)):        # K ~ 73 keys: a sequential sign walk, not a hot path
        if np.dot(q[i], q[i - 1]) < 0.0:
            q[i] = -q[i]
    return q


def part_family(name: str) -> str:
    """The material key (:data:`MATERIALS`) of a scene part or a complete part: its family
    (screw, roller, gear, bearing, ...)."""
    for family in ("retaining_ring", "shaft_ring", "flange_bolt", "drive_key"):
        if name.startswith(family):
            return family
    return "gear" if "gear" in name else name.split("_")[0]


def _scene_meshes(asm: Any) -> tuple[dict[str, SceneMesh], dict[int, str]]:
    """One SceneMesh per distinct mesh of the assembly, named after its first placement
    without the roller index; and the name of each mesh by id."""
    meshes: dict[str, SceneMesh] = {}
    by_id: dict[int, str] = {}
    for name, (mesh, _, _) in asm.placed.items():
        if id(mesh) not in by_id:
            base = name if not name.startswith("roller_") else "roller" + name[len("roller_") + 1:].lstrip("0123456789")
            key = base if base not in meshes else f"{base}_{len(meshes)}"
            by_id[id(mesh)] = key
            meshes[key] = SceneMesh(key, np.asarray(mesh.vertices, dtype=np.float64),
                                    np.asarray(mesh.faces, dtype=np.int64), part_family(name))
    return meshes, by_id


def assembly_scene(asm: Any, title: str = "", animate: bool = False) -> Scene:
    """The scene of a placed assembly: one mesh per distinct part mesh, one node per placed
    part, materials by part family.

    Without ``animate`` the nodes are flat, in ``asm.placed`` order. With it (a design the
    kinematics accepts, :func:`prs_geom.analysis.kinematics.check_kinematic_sizing`) the
    nodes follow the running mechanism, and the scene carries the animation
    ``screw revolution`` (:func:`mechanism_animation`):

    * ``screw``: turns about the axis; children: an actuator's screw ends, bearings,
      locknut, shaft ring and drive key (:func:`moving_group`);
    * ``nut_assembly`` (no mesh): travels along the axis; children: the nut, its ring gears,
      ends and (an actuator's) flange and flange bolts, the retaining rings;
    * ``carrier`` (no mesh): travels with the nut and turns at the carrier speed; children:
      the carriers and the rollers ``roller_<k>``, each spinning about its own axis, with
      its gears and journals as children.

    Every node's rest transform places its part exactly where the flat scene does.
    """
    meshes, by_id = _scene_meshes(asm)
    used = {m.material for m in meshes.values()}
    mats = {k: v for k, v in MATERIALS.items() if k in used}
    if animate:
        from prs_geom.analysis.kinematics import check_kinematic_sizing

        try:
            check_kinematic_sizing(asm.design)
        except ValueError:
            animate = False
    if not animate:
        nodes = [SceneNode(name, by_id[id(mesh)], np.asarray(T, dtype=np.float64))
                 for name, (mesh, T, kind) in asm.placed.items()]
        return Scene(meshes, mats, tuple(nodes), title)
    I = np.eye(4)
    groups: dict[str, list[str]] = {}
    for name in asm.placed:
        groups.setdefault(asm.rigid_body(name), []).append(name)

    def leaf(name: str, parent_T: NDArray[np.float64]) -> SceneNode:
        mesh, T, _ = asm.placed[name]
        return SceneNode(name, by_id[id(mesh)], np.linalg.solve(parent_T, np.asarray(T, dtype=np.float64)))

    nut_children, carrier_children, screw_names = [], [], []
    for body, names in groups.items():
        group = moving_group(body)
        if group == "screw":
            screw_names.extend(n for n in names if n != "screw")
        elif group == "nut":
            nut_children.extend(leaf(n, I) for n in names)
        elif group == "carrier":
            carrier_children.extend(leaf(n, I) for n in names)
        else:   # a roller: its thread node carries the body's other parts as children
            mesh, T, _ = asm.placed[body]
            T = np.asarray(T, dtype=np.float64)
            carrier_children.append(SceneNode(body, by_id[id(mesh)], T,
                                              tuple(leaf(n, T) for n in names if n != body)))
    # the screw's node turns; what turns with it (an actuator's screw ends, bearings, locknut
    # and shaft ring) hangs below it
    mesh, T, _ = asm.placed["screw"]
    T = np.asarray(T, dtype=np.float64)
    nodes = (SceneNode("screw", by_id[id(mesh)], T, tuple(leaf(n, T) for n in screw_names)),
             SceneNode("nut_assembly", None, I, tuple(nut_children)),
             SceneNode("carrier", None, I, tuple(carrier_children)))
    return Scene(meshes, mats, nodes, title, (mechanism_animation(asm.design),))


def moving_group(body: str) -> str:
    """What a rigid body (:meth:`~prs_geom.mesh.assembly.Assembly.rigid_body`) moves with in
    the running mechanism: "screw" (the screw, and an actuator's bearings, locknut, shaft
    ring and drive key: the locknut, the ring and the key turn with it, and a bearing's
    envelope is a body of revolution, so turning it with the screw shows what standing still
    would), "nut" (the nut, the retaining rings in its grooves and the flange bolts),
    "carrier" (both carriers) or, for a roller, the roller itself."""
    if body.startswith(("bearing_", "locknut", "shaft_ring", "drive_key")):
        return "screw"
    if body == "nut" or body.startswith(("retaining_ring", "flange_bolt")):
        return "nut"
    return "carrier" if body.startswith("carrier") else body


def animation_angles(step_deg: float = ANIMATION_STEP_DEG) -> NDArray[np.float64]:
    """Screw angles (rad) of the animation keys: one revolution, a key every ``step_deg``,
    both ends included."""
    n = int(round(360.0 / step_deg))
    return 2.0 * math.pi * np.arange(n + 1) / n


def mechanism_animation(design: Any, period_s: float = ANIMATION_PERIOD_S,
                        step_deg: float = ANIMATION_STEP_DEG) -> SceneAnimation:
    """One screw revolution of the running mechanism as node keyframes, from the poses of
    :func:`prs_geom.analysis.kinematics.poses` (screw rotation, nut and carrier travel,
    carrier rotation, each roller's pose in the carrier); node names as in
    :func:`assembly_scene`."""
    from prs_geom.analysis.kinematics import poses

    angles = animation_angles(step_deg)
    P = poses(design, angles)
    ch: dict[str, dict[str, NDArray[np.float64]]] = {
        "screw": {"rotation": _continuous(quaternions(P.screw[:, :3, :3]))},
        "nut_assembly": {"translation": np.array(P.nut[:, :3, 3])},
        "carrier": {"rotation": _continuous(quaternions(P.carrier[:, :3, :3])),
                    "translation": np.array(P.carrier[:, :3, 3])},
    }
    for k in range(design.roller.count):
        T = P.roller_in_carrier[k]
        ch[f"roller_{k}"] = {"rotation": _continuous(quaternions(T[:, :3, :3])), "translation": np.array(T[:, :3, 3])}
    return SceneAnimation("screw revolution", period_s * angles / (2.0 * math.pi), ch)


# --------------------------------------------------------------------------- normals
def split_normals(vertices: NDArray[np.float64], faces: NDArray[np.int64],
                  sharp_deg: float = SHARP_EDGE_DEG) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """Vertices, unit normals and faces with the vertices split at sharp edges.

    The corners of a vertex are grouped by the faces around it that are joined across
    smooth edges (the two faces of an edge bend by at most ``sharp_deg``); each group is one
    output vertex with the corner-angle-weighted mean normal of its faces. Smooth surfaces (the
    helicoid at the chord tolerance) stay smooth; crests, roots and end faces stay crisp.
    Linear in the number of faces (connected components of a sparse corner graph).
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    V = np.asarray(vertices, dtype=np.float64)
    F = np.asarray(faces, dtype=np.int64)
    nf = len(F)
    fn = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])   # |fn| = 2 x area
    unit = fn / np.maximum(np.linalg.norm(fn, axis=1, keepdims=True), 1e-300)
    # half-edges: face f, local corners i -> (i + 1) % 3
    loc_a = np.tile([0, 1, 2], nf)
    loc_b = np.tile([1, 2, 0], nf)
    face = np.repeat(np.arange(nf), 3)
    va, vb = F[face, loc_a], F[face, loc_b]
    key = np.minimum(va, vb) * (len(V) + 1) + np.maximum(va, vb)
    order = np.argsort(key, kind="stable")
    ks = key[order]
    # the two half-edges of a manifold edge are neighbours after sorting
    twin = np.flatnonzero(ks[:-1] == ks[1:])
    h1, h2 = order[twin], order[twin + 1]
    smooth = np.einsum("ij,ij->i", unit[face[h1]], unit[face[h2]]) >= math.cos(math.radians(sharp_deg))
    h1, h2 = h1[smooth], h2[smooth]
    # corner ids 3 f + i; half-edge h1 = (a -> b) in f1 and h2 = (b -> a) in f2 (consistent
    # winding): join corner of a in f1 with corner of a in f2, and b likewise
    c1a, c1b = 3 * face[h1] + loc_a[h1], 3 * face[h1] + loc_b[h1]
    c2a, c2b = 3 * face[h2] + loc_b[h2], 3 * face[h2] + loc_a[h2]
    rows = np.concatenate([c1a, c1b])
    cols = np.concatenate([c2a, c2b])
    graph = coo_matrix((np.ones(len(rows), np.int8), (rows, cols)), shape=(3 * nf, 3 * nf))
    _, group = connected_components(graph, directed=False)
    # groups never span two vertices (joined corners share their vertex); renumber densely
    uniq, inverse = np.unique(group, return_inverse=True)
    # corner-angle weights: independent of how a surface was cut into triangles
    e1 = V[np.roll(F, -1, axis=1)] - V[F]
    e2 = V[np.roll(F, 1, axis=1)] - V[F]
    cosang = np.einsum("fij,fij->fi", e1, e2) / np.maximum(
        np.linalg.norm(e1, axis=2) * np.linalg.norm(e2, axis=2), 1e-300)
    angle = np.arccos(np.clip(cosang, -1.0, 1.0)).ravel()
    acc = np.zeros((len(uniq), 3))
    np.add.at(acc, inverse, unit[np.arange(3 * nf) // 3] * angle[:, None])
    normals = acc / np.maximum(np.linalg.norm(acc, axis=1, keepdims=True), 1e-300)
    first = np.empty(len(uniq), np.int64)
    first[inverse[::-1]] = np.arange(3 * nf)[::-1]
    out_v = V[F.ravel()[first]]
    return out_v, normals, inverse.reshape(-1, 3)


# --------------------------------------------------------------------------- glTF
def _decomposed(T: NDArray[np.float64], scale: float) -> dict[str, list[float]]:
    """A rigid 4x4 (mm) as glTF translation (scaled to metres) and rotation quaternion."""
    R = T[:3, :3]
    if not np.allclose(R @ R.T, np.eye(3), atol=1e-9) or np.linalg.det(R) <= 0:
        raise ValueError("scene transforms must be rigid rotations with translation")
    w = math.sqrt(max(0.0, 1.0 + R[0, 0] + R[1, 1] + R[2, 2])) / 2.0
    x = math.copysign(math.sqrt(max(0.0, 1.0 + R[0, 0] - R[1, 1] - R[2, 2])) / 2.0, R[2, 1] - R[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1.0 - R[0, 0] + R[1, 1] - R[2, 2])) / 2.0, R[0, 2] - R[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1.0 - R[0, 0] - R[1, 1] + R[2, 2])) / 2.0, R[1, 0] - R[0, 1])
    q = np.array([x, y, z, w])
    q /= np.linalg.norm(q)
    out: dict[str, list[float]] = {}
    t = T[:3, 3] * scale
    if np.any(t != 0.0):
        out["translation"] = [float(v) for v in t]
    if not np.allclose(q, [0, 0, 0, 1], atol=0, rtol=0):
        out["rotation"] = [float(v) for v in q]
    return out


#: glTF constants: bufferView targets, accessor component types, primitive mode.
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963
_FLOAT, _UNSIGNED_INT = 5126, 5125
_TRIANGLES = 4


class _GlbBuffer:
    """The binary chunk of a .glb being filled: bytes, buffer views and accessors, each
    view starting on a 4-byte boundary."""

    def __init__(self) -> None:
        self.blob = bytearray()
        self.views: list[dict[str, Any]] = []
        self.accessors: list[dict[str, Any]] = []

    def view(self, data: bytes, target: int | None) -> int:
        """Append ``data`` as a buffer view (``target`` None for data that are not vertex
        data, e.g. keyframes); its index."""
        while len(self.blob) % 4:
            self.blob.append(0)
        view: dict[str, Any] = {"buffer": 0, "byteOffset": len(self.blob), "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self.views.append(view)
        self.blob.extend(data)
        return len(self.views) - 1

    def accessor(self, entry: dict[str, Any]) -> int:
        self.accessors.append(entry)
        return len(self.accessors) - 1


def _gl_materials(scene: Scene) -> list[dict[str, Any]]:
    return [{"name": m.name, "pbrMetallicRoughness": {
        "baseColorFactor": list(m.colour), "metallicFactor": m.metallic, "roughnessFactor": m.roughness}}
        for m in scene.materials.values()]


def _gl_meshes(scene: Scene, buf: _GlbBuffer, sharp_deg: float, scale: float) -> tuple[list[dict[str, Any]],
                                                                                      dict[str, int]]:
    """One glTF mesh per scene mesh (positions scaled to metres as float32, split normals,
    uint32 indices) and the glTF index of each by name."""
    materials = list(scene.materials)
    gl_meshes, mesh_index = [], {}
    for key, sm in scene.meshes.items():
        V, N, F = split_normals(sm.vertices, sm.faces, sharp_deg)
        pos = (V * scale).astype(np.float32)
        nrm = N.astype(np.float32)
        idx = F.astype(np.uint32)
        position = buf.accessor({"bufferView": buf.view(pos.tobytes(), _ARRAY_BUFFER), "componentType": _FLOAT,
                                 "count": len(pos), "type": "VEC3", "min": [float(v) for v in pos.min(0)],
                                 "max": [float(v) for v in pos.max(0)]})
        normal = buf.accessor({"bufferView": buf.view(nrm.tobytes(), _ARRAY_BUFFER), "componentType": _FLOAT,
                               "count": len(nrm), "type": "VEC3"})
        indices = buf.accessor({"bufferView": buf.view(idx.tobytes(), _ELEMENT_ARRAY_BUFFER),
                                "componentType": _UNSIGNED_INT, "count": idx.size, "type": "SCALAR"})
        gl_meshes.append({"name": key, "primitives": [{"attributes": {"POSITION": position, "NORMAL": normal},
                                                        "indices": indices, "mode": _TRIANGLES,
                                                        "material": materials.index(sm.material)}]})
        mesh_index[key] = len(gl_meshes) - 1
    return gl_meshes, mesh_index


def _gl_nodes(scene: Scene, mesh_index: dict[str, int], scale: float) -> list[dict[str, Any]]:
    """The glTF nodes: the root ``prs_geom`` (z up to y up), then the scene's nodes depth
    first, each before its children."""
    gl_nodes: list[dict[str, Any]] = [{"name": "prs_geom", "rotation": list(Z_UP_TO_Y_UP), "children": []}]

    def add_node(node: SceneNode) -> int:
        entry: dict[str, Any] = {"name": node.name, **_decomposed(node.transform, scale)}
        if node.mesh is not None:
            entry["mesh"] = mesh_index[node.mesh]
        gl_nodes.append(entry)
        i = len(gl_nodes) - 1
        if node.children:
            entry["children"] = [add_node(c) for c in node.children]
        return i

    gl_nodes[0]["children"] = [add_node(n) for n in scene.nodes]
    return gl_nodes


def _gl_animation(anim: SceneAnimation, buf: _GlbBuffer, node_index: dict[str, int], scale: float) -> dict[str, Any]:
    """One glTF animation: a sampler per animated node and path, linear keys (translations
    scaled to metres), the key times shared."""
    def add_keys(values: NDArray[np.float64], kind: str, bounds: bool = False) -> int:
        data = np.ascontiguousarray(values, dtype=np.float32)
        entry: dict[str, Any] = {"bufferView": buf.view(data.tobytes(), None), "componentType": _FLOAT,
                                 "count": len(data), "type": kind}
        if bounds:
            entry.update(min=[float(data.min())], max=[float(data.max())])
        return buf.accessor(entry)

    times = add_keys(anim.times_s, "SCALAR", bounds=True)
    samplers, channels = [], []
    for node, paths in anim.channels.items():
        for path, values in paths.items():
            out = add_keys(values * scale if path == "translation" else values,
                           "VEC3" if path == "translation" else "VEC4")
            samplers.append({"input": times, "output": out, "interpolation": "LINEAR"})
            channels.append({"sampler": len(samplers) - 1, "target": {"node": node_index[node], "path": path}})
    return {"name": anim.name, "samplers": samplers, "channels": channels}


def _glb_chunks(doc: dict[str, Any], blob: bytearray) -> list[bytes | memoryview]:
    """The .glb file in pieces: 12-byte header, the JSON chunk (space-padded) and the BIN
    chunk (zero-padded), each a multiple of 4 bytes. The binary chunk is a view of ``blob``,
    not a copy: the default assembly's is 12 MB."""
    js = json.dumps(doc, separators=(",", ":")).encode("utf-8")
    js += b" " * (-len(js) % 4)
    blob.extend(b"\0" * (-len(blob) % 4))
    total = 12 + 8 + len(js) + 8 + len(blob)
    return [struct.pack("<4sII", b"glTF", 2, total), struct.pack("<I4s", len(js), b"JSON"), js,
            struct.pack("<I4s", len(blob), b"BIN\0"), memoryview(blob)]


def _glb_file(scene: Scene, sharp_deg: float) -> list[bytes | memoryview]:
    """The scene as a glTF 2.0 binary, in pieces (:func:`_glb_chunks`)."""
    scale = 1e-3                                   # mm -> m
    buf = _GlbBuffer()
    gl_meshes, mesh_index = _gl_meshes(scene, buf, sharp_deg, scale)
    gl_nodes = _gl_nodes(scene, mesh_index, scale)
    node_index = {n["name"]: i for i, n in enumerate(gl_nodes)}
    gl_animations = [_gl_animation(anim, buf, node_index, scale) for anim in scene.animations]
    doc = {"asset": {"version": "2.0", "generator": f"prs_geom {__version__}"},
           "scene": 0, "scenes": [{"name": scene.title or "prs_geom assembly", "nodes": [0]}],
           "nodes": gl_nodes, "meshes": gl_meshes, "materials": _gl_materials(scene),
           "accessors": buf.accessors, "bufferViews": buf.views, "buffers": [{"byteLength": len(buf.blob)}]}
    if gl_animations:
        doc["animations"] = gl_animations
    return _glb_chunks(doc, buf.blob)


def glb_bytes(scene: Scene, sharp_deg: float = SHARP_EDGE_DEG) -> bytes:
    """The scene as a glTF 2.0 binary (see the module docstring for the conventions)."""
    return b"".join(_glb_file(scene, sharp_deg))


def write_glb(scene: Scene, path: Path | str) -> None:
    """Write the scene as ``.glb`` (:func:`glb_bytes`, the same bytes), atomically
    (:func:`prs_geom.model.io.atomic_path`), piece by piece: never the whole file in memory
    twice."""
    chunks = _glb_file(scene, SHARP_EDGE_DEG)
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        for chunk in chunks:
            fh.write(chunk)


# --------------------------------------------------------------------------- 3MF
def _uuid(*parts: str) -> str:
    """A UUID derived from ``parts`` (SHA-256), so that the 3MF file is the same bytes from run to run."""
    return str(uuid.UUID(hashlib.sha256("\0".join(parts).encode()).hexdigest()[:32]))


def write_3mf(scene: Scene, path: Path | str) -> None:
    """Write the scene as 3MF with lib3mf (unit millimetre; see the module docstring),
    atomically (:func:`prs_geom.model.io.atomic_path`): ``path`` is never half-written and no
    temporary file is left behind."""
    import lib3mf

    wrapper = lib3mf.get_wrapper()
    model = wrapper.CreateModel()
    model.SetUnit(lib3mf.ModelUnit.MilliMeter)
    group = model.AddBaseMaterialGroup()
    prop = {}
    for key, m in scene.materials.items():
        r, g, b, a = (int(h, 16) for h in (m.srgb_hex[1:3], m.srgb_hex[3:5], m.srgb_hex[5:7], m.srgb_hex[7:9]))
        prop[key] = group.AddMaterial(m.name, wrapper.RGBAToColor(r, g, b, a))
    objects = {}
    for key, sm in scene.meshes.items():
        obj = model.AddMeshObject()
        obj.SetName(key)
        V = np.ascontiguousarray(sm.vertices, dtype=np.float32)
        F = np.ascontiguousarray(sm.faces, dtype=np.uint32)
        # one call with the whole arrays (lib3mf's Python wrapper would box every vertex)
        vbuf = (lib3mf.Position * len(V)).from_buffer_copy(V.tobytes())
        fbuf = (lib3mf.Triangle * len(F)).from_buffer_copy(F.tobytes())
        wrapper.checkError(obj, wrapper.lib.lib3mf_meshobject_setgeometry(
            obj._handle, ctypes.c_uint64(len(V)), vbuf, ctypes.c_uint64(len(F)), fbuf))
        obj.SetObjectLevelProperty(group.GetResourceID(), prop[sm.material])
        obj.SetUUID(_uuid("object", key, hashlib.sha256(V.tobytes() + F.tobytes()).hexdigest()))
        objects[key] = obj
    for name, sm, T in scene.placed():
        t = lib3mf.Transform()
        for col in range(4):
            for row in range(3):
                # lib3mf's Fields[i][j]: row i of the 4x3 matrix acting on row vectors
                t.Fields[col][row] = float(T[row, col])
        item = model.AddBuildItem(objects[sm.name], t)
        item.SetUUID(_uuid("item", name))
        item.SetPartNumber(name)
    model.SetBuildUUID(_uuid("build", scene.title, *[n for n, _, _ in scene.placed()]))
    meta = model.GetMetaDataGroup()
    meta.AddMetaData("", "Title", scene.title or "prs_geom assembly", "string", True)
    meta.AddMetaData("", "Application", f"prs_geom {__version__}", "string", True)
    with atomic_path(path) as tmp:
        _write_model(model, tmp)


def _write_model(model: Any, path: Path) -> None:
    """lib3mf's 3MF writer on ``model``, to ``path``, coordinates to 9 decimals."""
    writer = model.QueryWriter("3mf")
    writer.SetDecimalPrecision(9)
    with _locale_kept():
        writer.WriteToFile(str(path))


@contextmanager
def _locale_kept():
    """Restore the process locale after lib3mf, whose writer and reader set it to "C" for
    every category and leave it so: Python's default text encoding would turn to ASCII
    for the rest of the process."""
    saved = locale.setlocale(locale.LC_ALL, None)
    try:
        yield
    finally:
        locale.setlocale(locale.LC_ALL, saved)
