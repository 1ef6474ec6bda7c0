"""Axisymmetric linear elasticity with quadratic triangles (scikit-fem).

Pure math, no I/O. Frame and units: r radial, z axial (mm); displacements u = (u_r, u_z)
(mm); Young's modulus E (MPa = N/mm^2); forces N. A load "per ring" is the total force of
the ring around the axis: every integral carries the 2 pi r of the circumference, so the
energy is the true three-dimensional one and the work of a ring load of total axial force
F through an axial rigid shift U is F U.

The bilinear form (written here, not taken from a library)
----------------------------------------------------------
With the strains of a torsion-free axisymmetric field

    eps_rr = du_r/dr,  eps_zz = du_z/dz,  eps_tt = u_r / r  (hoop),
    eps_rz = (du_r/dz + du_z/dr) / 2,

and the Lame constants lambda = E nu / ((1 + nu)(1 - 2 nu)), mu = E / (2 (1 + nu)):

    a(u, v) = integral over the section of
              [lambda tr eps(u) tr eps(v) + 2 mu eps(u) : eps(v)] 2 pi r dr dz,

eps : eps including the hoop term eps_tt(u) eps_tt(v) and 2 eps_rz(u) eps_rz(v). The hoop
term is the one a plane-strain form lacks; it is checked against Lame's thick-walled
cylinder and a solid cylinder under axial load in tests/test_fe.py. On the axis (r = 0)
u_r = 0 is imposed (a solid's radial displacement vanishes there, and the hoop energy
u_r^2 / r would otherwise be unbounded).

Elements: ElementTriP2 for both components on affine triangles; element integrals with a
quadrature of order 4 (exact for the polynomial part, the 1/r hoop terms converge with the
mesh), facet integrals of order 6 (exact for a quadratic band weight x P2 test function x r).
Linear systems: the free-free block of the stiffness is factorised once (SuperLU) and
every ring load is one back substitution, so an influence matrix costs one factorisation.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import csc_matrix
from scipy.sparse.linalg import splu
from skfem import Basis, BilinearForm, ElementTriP2, ElementVector, FacetBasis, Functional, LinearForm, MeshTri

from prs_geom.analysis.fe.mesh import TriangleMesh

__all__ = ["lame_constants", "axisymmetric_stiffness", "AxisymmetricModel"]

#: Quadrature orders (see the module docstring).
ELEMENT_INTORDER = 4
FACET_INTORDER = 6
#: Threads of the stiffness assembly (the project's machines and CI have two cores).
ASSEMBLY_THREADS = 2


def lame_constants(E: float, nu: float) -> tuple[float, float]:
    """(lambda, mu) in MPa from Young's modulus E (MPa) and Poisson's ratio nu."""
    return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), E / (2.0 * (1.0 + nu))


def _strains(w_grad: NDArray, w_val: NDArray, r: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """(eps_rr, eps_zz, eps_tt, eps_rz) from the gradient [i][j] = d u_i / d x_j of (u_r, u_z)."""
    return w_grad[0][0], w_grad[1][1], w_val[0] / r, 0.5 * (w_grad[0][1] + w_grad[1][0])


def axisymmetric_stiffness(E: float, nu: float) -> BilinearForm:
    """The axisymmetric elasticity form a(u, v) of the module docstring (N mm)."""
    lam, mu = lame_constants(E, nu)

    @BilinearForm(nthreads=ASSEMBLY_THREADS)
    def form(u, v, w):
        r = w.x[0]
        urr, uzz, utt, urz = _strains(u.grad, u, r)
        vrr, vzz, vtt, vrz = _strains(v.grad, v, r)
        tr_u = urr + uzz + utt
        tr_v = vrr + vzz + vtt
        dens = lam * tr_u * tr_v + 2.0 * mu * (urr * vrr + uzz * vzz + utt * vtt + 2.0 * urz * vrz)
        return dens * 2.0 * math.pi * r

    return form


@dataclass(frozen=True)
class AxisymmetricModel:
    """A meshed axisymmetric body of one isotropic material, assembled and ready to load: the
    stiffness is assembled and the free block factorised on construction.

    Parameters
    ----------
    mesh : TriangleMesh
        The meridian section (r, z), mm.
    youngs_modulus_mpa : float
        E (MPa).
    poisson_ratio : float
        nu, in (-1, 0.5).
    fixed : tuple of (str, int)
        Supports as (node-set name, component): component 0 holds u_r = 0, 1 holds u_z = 0
        on every node and mid-side node of the set's boundary edges. The node set
        ``"axis"`` (if the mesh has one) always gets u_r = 0.
    """

    mesh: TriangleMesh
    youngs_modulus_mpa: float
    poisson_ratio: float
    fixed: tuple[tuple[str, int], ...] = ()
    skmesh: MeshTri = field(init=False, repr=False, compare=False)
    basis: Basis = field(init=False, repr=False, compare=False)
    free: NDArray = field(init=False, repr=False, compare=False)
    _lu: object = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        E, nu = float(self.youngs_modulus_mpa), float(self.poisson_ratio)
        if not (math.isfinite(E) and E > 0):
            raise ValueError("Young's modulus must be positive (MPa)")
        if not -1.0 < nu < 0.5:
            raise ValueError("Poisson's ratio must lie in (-1, 0.5)")
        m = MeshTri(self.mesh.points, self.mesh.triangles, sort_t=False, validate=False)
        basis = Basis(m, ElementVector(ElementTriP2()), intorder=ELEMENT_INTORDER)
        K = axisymmetric_stiffness(E, nu).assemble(basis)
        constrained = []
        fixed = list(self.fixed)
        if "axis" in self.mesh.node_sets:
            fixed.append(("axis", 0))
        for name, comp in fixed:
            if comp not in (0, 1):
                raise ValueError("a support component is 0 (u_r) or 1 (u_z)")
            constrained.append(self._dofs_on(m, basis, name, comp))
        mask = np.ones(basis.N, dtype=bool)
        if constrained:
            mask[np.concatenate(constrained)] = False
        free = np.flatnonzero(mask)
        Kff = csc_matrix(K[free][:, free])
        # the symmetric minimum-degree ordering keeps the fill of a 2D stiffness small
        lu = splu(Kff, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                  options={"SymmetricMode": True})
        object.__setattr__(self, "skmesh", m)
        object.__setattr__(self, "basis", basis)
        object.__setattr__(self, "free", free)
        object.__setattr__(self, "_lu", lu)

    # -- node sets, facets and dofs --------------------------------------------
    def facets_of(self, name: str) -> NDArray:
        """Boundary facets (edges) with both end nodes in the node set ``name``."""
        return self._facets_on(self.skmesh, name)

    def _facets_on(self, m: MeshTri, name: str) -> NDArray:
        nodes = self.mesh.node_sets[name]
        inset = np.zeros(m.p.shape[1], dtype=bool)
        inset[nodes] = True
        bf = m.boundary_facets()
        f = m.facets[:, bf]
        return bf[inset[f[0]] & inset[f[1]]]

    def _dofs_on(self, m: MeshTri, basis: Basis, name: str, comp: int) -> NDArray:
        nodes = self.mesh.node_sets[name]
        facets = self._facets_on(m, name)
        return np.concatenate([basis.nodal_dofs[comp, nodes], basis.facet_dofs[comp, facets]])

    def dofs_of(self, facets: NDArray, comp: int | None = None) -> NDArray:
        """Degrees of freedom (vertex and mid-side) of boundary facets, both components or
        one (0: u_r, 1: u_z)."""
        f = self.skmesh.facets[:, facets]
        comps = (0, 1) if comp is None else (comp,)
        return np.unique(np.concatenate([np.concatenate([self.basis.nodal_dofs[c, f.ravel()],
                                                         self.basis.facet_dofs[c, facets]]) for c in comps]))

    @property
    def n_dofs(self) -> int:
        """Number of degrees of freedom (both components, constrained ones included)."""
        return int(self.basis.N)

    # -- loads -----------------------------------------------------------------
    def facet_load(self, facets: NDArray, traction: Callable[[NDArray], tuple[NDArray, NDArray]]) -> NDArray:
        """Load vector of a ring traction on boundary facets, N.

        ``traction(x)`` returns (t_r, t_z) (MPa) at points x = (r, z) (arrays of the facet
        quadrature points); the vector is integral t . v 2 pi r ds.
        """
        fb = FacetBasis(self.skmesh, self.basis.elem, facets=facets, intorder=FACET_INTORDER)

        @LinearForm
        def load(v, w):
            tr, tz = traction(w.x)
            return (tr * v[0] + tz * v[1]) * 2.0 * math.pi * w.x[0]

        return load.assemble(fb)

    def facet_integral(self, facets: NDArray, density: Callable[[NDArray], NDArray]) -> float:
        """integral of density(x) 2 pi r ds over the facets (density per unit area)."""
        fb = FacetBasis(self.skmesh, self.basis.elem, facets=facets, intorder=FACET_INTORDER)

        @Functional
        def total(w):
            return density(w.x) * 2.0 * math.pi * w.x[0]

        return float(total.assemble(fb))

    # -- solution --------------------------------------------------------------
    def solve(self, loads: NDArray) -> NDArray:
        """Displacements (N_dofs,) or (N_dofs, m) for load vectors of the same shape, mm;
        supported dofs are zero."""
        loads = np.asarray(loads, dtype=np.float64)
        out = np.zeros_like(loads)
        rhs = loads[self.free]
        if rhs.ndim == 1:
            out[self.free] = self._lu.solve(rhs)
        else:
            # column by column: SuperLU's multi-column solve is several times slower here
            for j in range(rhs.shape[1]):
                out[self.free, j] = self._lu.solve(np.ascontiguousarray(rhs[:, j]))
        return out

    def nodal_displacement(self, u: NDArray) -> NDArray:
        """(2, N_nodes) displacements (u_r, u_z) at the mesh vertices of a solution u."""
        return u[self.basis.nodal_dofs]

    def energy(self, u: NDArray) -> float:
        """Strain energy 1/2 u.K u (N mm) of a displacement vector (assembles K again)."""
        K = axisymmetric_stiffness(self.youngs_modulus_mpa, self.poisson_ratio).assemble(self.basis)
        return 0.5 * float(u @ (K @ u))
