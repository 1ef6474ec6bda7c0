"""The drawn section of each complete part (prs_geom.geometry.part_sections) against the
complete part's mesh (prs_geom.mesh.parts): the same end faces and, cell by cell along the
axis, the same outer and inner radii (the threads and gears at their crests and tips)."""
import numpy as np
import pytest

from prs_geom.analysis.contact import analyse_contact
from prs_geom.geometry.mechanism import NUT_END_RELIEF_MM
from prs_geom.geometry.part_sections import merged_cells, outline_polygons, part_section
from prs_geom.mesh.assembly import build_assembly
from prs_geom.mesh.parts import complete_parts
from prs_geom.model.design import default_design

TOL = 0.05      # chord tolerance of the meshes (mm): coarse, for speed


@pytest.fixture(scope="module")
def parts():
    d = default_design()
    contact = analyse_contact(d)
    asm = build_assembly(d, tol=TOL, screw_profile=contact.screw_profile)
    return d, contact, complete_parts(asm)


@pytest.mark.parametrize("part", ["screw", "roller", "nut"])
def test_section_is_the_complete_parts_mesh(parts, part):
    """Per cell of the section (a z span of constant radii), the complete part's mesh cut by
    the plane through the cell's middle (trimesh) reaches the drawn outer radius and, for the
    nut, the drawn inner one, within the chord tolerance (the nut's outside within its ends'
    0.1 mm meshing relief, which the drawing does not show: a meshing device, not a step to
    machine); the end faces are the mesh's z extent."""
    import trimesh

    d, contact, cp = parts
    sec = part_section(d, part, contact.screw_profile if part == "screw" else None)
    mesh = trimesh.Trimesh(cp[part].vertices, cp[part].faces, process=False)
    z0, z1 = sec.z_span
    assert mesh.bounds[0][2] == pytest.approx(z0, abs=1e-6) and mesh.bounds[1][2] == pytest.approx(z1, abs=1e-6)
    checked = 0
    for a, b, spans in merged_cells(sec.zones):
        cut = mesh.section(plane_origin=[0.0, 0.0, 0.5 * (a + b)], plane_normal=[0.0, 0.0, 1.0])
        r = np.hypot(cut.vertices[:, 0], cut.vertices[:, 1])
        relief = NUT_END_RELIEF_MM if part == "nut" else 0.0
        assert r.max() == pytest.approx(spans[-1][1], abs=TOL + relief + 1e-6), (part, a, b)
        if part == "nut":
            assert r.min() == pytest.approx(spans[0][0], abs=TOL + 1e-6), (part, a, b)
        checked += 1
    assert checked >= {"screw": 8, "roller": 3, "nut": 8}[part]


def test_outline_polygons_close_and_cover_the_cells():
    """The upper-half outline of a solid part runs along the axis and round its steps; its
    area is the sum of the cells' (r1 - r0) (z1 - z0)."""
    d = default_design()
    for part in ("screw", "roller", "nut"):
        sec = part_section(d, part)
        (poly,) = outline_polygons(sec.zones)
        x, y = np.array(poly).T
        area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
        cells = sum((b - a) * (r1 - r0) for a, b, spans in merged_cells(sec.zones) for r0, r1 in spans)
        assert area == pytest.approx(cells, rel=1e-12)
