"""Complete parts (prs_geom.mesh.parts): the union of a rigid body's pieces, its copies, and
the files and volumes made from them."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh

from prs_geom.mesh.assembly import build_assembly
from prs_geom.mesh.parts import complete_parts, part_name, union_pieces
from prs_geom.mesh.thread import to_manifold
from prs_geom.model.design import default_design


@pytest.fixture(scope="module")
def asm():
    return build_assembly(default_design())


def test_part_names_drop_the_copy_suffix():
    assert [part_name(b) for b in ("roller_12", "carrier_hi", "retaining_ring_lo", "bearing_fixed_1", "nut",
                                   "shaft_ring", "screw")] == [
        "roller", "carrier", "retaining_ring", "bearing_fixed", "nut", "shaft_ring", "screw"]


def test_every_complete_part_is_one_closed_shell_with_its_copies(asm):
    parts = complete_parts(asm)
    d = asm.design
    assert list(parts)[:3] == ["screw", "nut", "roller"]
    assert parts["roller"].instances == tuple(f"roller_{k}" for k in range(d.roller.count))
    assert parts["carrier"].instances == ("carrier_lo", "carrier_hi")
    assert parts["bearing_fixed"].count == 2 and parts["bearing_fixed"].purchased
    for part in parts.values():
        closed, shells = part.edge_check()
        assert closed and shells == 1, part.name
        # trimesh, an independent reader of the same arrays, agrees
        m = trimesh.Trimesh(part.vertices, part.faces, process=False)
        assert m.is_watertight and m.volume == pytest.approx(part.volume_mm3, rel=1e-12)
    # copy k placed by its transform is the piece the assembly placed under that name
    roller = parts["roller"]
    for k in (0, d.roller.count - 1):
        placed = asm.placed_mesh(f"roller_{k}")
        ref = np.asarray(asm.placed["roller_0"][0].vertices)
        T = roller.transforms[k]
        assert np.allclose(ref @ T[:3, :3].T + T[:3, 3], placed.vertices, atol=1e-9)


@pytest.mark.parametrize("defect", ["none", "flipped face", "duplicate face", "missing face", "two boxes"])
def test_edge_check_against_trimesh_on_closed_and_broken_meshes(defect):
    """edge_check's closure against trimesh's independent is_watertight and
    is_winding_consistent, on a closed box and on the box with each kind of defect."""
    from prs_geom.mesh.parts import CompletePart

    box = trimesh.creation.box()
    V, F = np.asarray(box.vertices), np.asarray(box.faces)
    if defect == "flipped face":
        F = np.concatenate([F[:1, ::-1], F[1:]])
    elif defect == "duplicate face":
        F = np.concatenate([F, F[:1]])
    elif defect == "missing face":
        F = F[1:]
    elif defect == "two boxes":
        V, F = np.concatenate([V, V + 3.0]), np.concatenate([F, F + len(V)])
    part = CompletePart("box", V, F, 1.0, ("box",), ("box",), np.eye(4)[None])
    m = trimesh.Trimesh(V, F, process=False)
    closed, shells = part.edge_check()
    assert closed == (m.is_watertight and m.is_winding_consistent) == (defect in ("none", "two boxes"))
    assert shells == (2 if defect == "two boxes" else 1)


def test_a_complete_part_is_the_union_of_its_pieces(asm):
    """The union's volume against a second formulation: the sum of the pieces' volumes less
    every pairwise overlap (no three pieces share a region by the layout), plus the datum
    slot the gear or nut end closes (a void the union fills)."""
    parts = complete_parts(asm)
    for name in ("roller", "nut", "screw"):
        part = parts[name]
        pieces = [asm.placed[p] for p in part.pieces]
        T0inv = np.linalg.inv(pieces[0][1])
        solids = []
        for mesh, T, _ in pieces:
            s = to_manifold(mesh.vertices, mesh.faces)
            R = T0inv @ T
            solids.append(s if np.allclose(R, np.eye(4)) else s.transform(np.ascontiguousarray(R[:3, :4])))
        total = sum(s.volume() for s in solids)
        for i in range(len(solids)):
            for j in range(i + 1, len(solids)):
                total -= (solids[i] ^ solids[j]).volume()
        assert part.volume_mm3 == pytest.approx(total + part.filled_voids_mm3, rel=1e-9), name
    # the roller's and the nut's datum slots lie under a gear / a nut end: filled, and of the
    # slot's size (DatumMark.volume)
    for name in ("roller", "nut"):
        mark = asm.parts[name].datum_mark
        assert parts[name].filled_voids_mm3 == pytest.approx(mark.volume, rel=1e-6)
    assert parts["screw"].filled_voids_mm3 == 0.0


def test_copies_of_one_part_share_one_mesh_placed_by_a_translation(asm):
    from prs_geom.geometry.mechanism import layout

    lay = layout(asm.design)
    carrier = complete_parts(asm)["carrier"]
    for k, end in enumerate(lay.ends):
        zs = carrier.placed_vertices(k)[:, 2]
        assert (zs.min(), zs.max()) == pytest.approx(end.carrier, abs=1e-12)


def test_union_pieces_drops_a_closed_void():
    box = trimesh.creation.box((2.0, 2.0, 2.0))
    hole = trimesh.creation.box((1.0, 1.0, 1.0))
    hole.invert()
    V, F, void = union_pieces([(box, np.eye(4))])
    assert void == 0.0 and len(F) == len(box.faces)
    shell = trimesh.util.concatenate([box, hole])
    V, F, void = union_pieces([(shell, np.eye(4)), (trimesh.creation.box((0.5, 0.5, 4.0)), np.eye(4))])
    assert void == pytest.approx(1.0 - 0.25, rel=1e-12)
    assert trimesh.Trimesh(V, F).volume == pytest.approx(8.0 + 2 * 0.25, rel=1e-12)


def test_part_files_and_the_parts_list_give_one_volume(tmp_path, asm):
    """Each per-part STL read back (trimesh) has the parts list's volume of that part (within
    the STL's float32 rounding)."""
    from prs_geom.exports.bom import parts_list
    from prs_geom.exports.meshes import PART_FILES, export_meshes
    from prs_geom.mesh.volumes import part_volumes

    export_meshes(asm, tmp_path, "0" * 64)
    rows = {row.part.replace(" ", "_"): row for row in parts_list(asm.design, part_volumes(asm))}
    for name in PART_FILES:
        m = trimesh.load(tmp_path / f"{name}.stl")
        assert m.is_watertight and m.body_count == 1
        assert m.volume == pytest.approx(rows[name].volume_mm3, rel=2e-7), name
