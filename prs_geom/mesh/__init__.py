"""Triangle meshes of the parts and their placed assembly (trimesh, manifold3d).

Owns the thread mesher that builds every vertex on the analytic surface and measures its
deviation (:mod:`~prs_geom.mesh.thread`), the assembly of one mesh per part with placed
roller copies (:mod:`~prs_geom.mesh.assembly`), the carriers, journals, retaining rings and
nut ends (:mod:`~prs_geom.mesh.mechanism`), an actuator's screw ends, nut flange and purchased
parts' envelopes (:mod:`~prs_geom.mesh.actuator`), the part volumes of the rigid bodies
(:mod:`~prs_geom.mesh.volumes`) and the memory guard that estimates a mesh
job before it starts (:mod:`~prs_geom.mesh.budget`).
"""

__all__: list[str] = []
