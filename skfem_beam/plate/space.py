"""The plate's finite element space: mesh, element, basis, the dofs each edge's support
fixes, and the matrices K (bending), M (mass) and a load vector."""
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from skfem import (Basis, BilinearForm, ElementQuadBFS, ElementTriArgyris, ElementTriMorley,
                   LinearForm, MeshQuad, MeshTri, asm)
from skfem.helpers import dd, ddot, trace

from .model import EDGES, Plate

# the coordinate normal to each edge of the rectangle (0: x, 1: y)
NORMAL_AXIS = {"left": 0, "right": 0, "bottom": 1, "top": 1}


@dataclass
class PlateSpace:
    """What a solver needs: the matrices, which dofs are free, and at each mesh vertex its
    coordinates and the index of its deflection dof w (where contact will act)."""
    plate: Plate
    basis: Basis
    K: sparse.csr_matrix
    M: sparse.csr_matrix
    vertices: np.ndarray       # (2, number of vertices): x, y
    w_dofs: np.ndarray         # the dof of w at each vertex
    fixed_dofs: np.ndarray
    free_dofs: np.ndarray


def rectangle_mesh(plate: Plate):
    """nx × ny rectangles for BFS, each cut in two triangles for Morley and Argyris."""
    x = np.linspace(0.0, plate.a, plate.nx + 1)
    y = np.linspace(0.0, plate.b, plate.ny + 1)
    mesh = MeshQuad.init_tensor(x, y) if plate.element == "bfs" else MeshTri.init_tensor(x, y)
    tol = 1e-9 * max(plate.a, plate.b)
    return mesh.with_boundaries({
        "left": lambda p: np.abs(p[0]) < tol,
        "right": lambda p: np.abs(p[0] - plate.a) < tol,
        "bottom": lambda p: np.abs(p[1]) < tol,
        "top": lambda p: np.abs(p[1] - plate.b) < tol,
    })


def make_element(name: str):
    return {"bfs": ElementQuadBFS, "morley": ElementTriMorley,
            "argyris": ElementTriArgyris}[name]()


def is_fixed(dofname: str, support: str, normal_axis: int) -> bool:
    """Whether a support fixes the dof ``dofname`` (u, u_x, u_xy, u_n, ...) on an edge.

    Along the edge w = 0 fixes w and all its tangential derivatives; clamping also fixes
    ∂w/∂n = 0 and so its tangential derivatives.  A dof is fixed when its derivatives
    include no normal one (simply supported), or at most one (clamped).  u_n, the
    normal derivative at an edge's midpoint (Morley, Argyris), counts as one.  Sliding
    (∂w/∂n = 0, w free: a line of symmetry) fixes those with exactly one."""
    letters = dofname.partition("_")[2]
    normal_count = sum(c in ("n", "xy"[normal_axis]) for c in letters)
    if support == "clamped":
        return normal_count <= 1
    if support == "simply_supported":
        return normal_count == 0
    if support == "sliding":
        return normal_count == 1
    return False


def fixed_dofs(basis: Basis, plate: Plate) -> np.ndarray:
    """The dofs the edges' supports fix (a corner gets the union of its two edges')."""
    fixed = []
    for edge in EDGES:
        dofs = basis.get_dofs(edge)
        for kind in (dofs.nodal, dofs.facet):
            fixed += [ix for name, ix in kind.items()
                      if is_fixed(name, plate.support(edge), NORMAL_AXIS[edge])]
    return np.unique(np.concatenate(fixed)).astype(int) if fixed else np.zeros(0, int)


def stiffness_matrix(basis: Basis, D: float, nu: float) -> sparse.csr_matrix:
    """K from the bending energy density D[(1 − ν) w,ij v,ij + ν Δw Δv]."""
    @BilinearForm
    def bending(u, v, _):
        return D * ((1.0 - nu) * ddot(dd(u), dd(v)) + nu * trace(dd(u)) * trace(dd(v)))
    return asm(bending, basis).tocsr()


def mass_matrix(basis: Basis, rho_h: float) -> sparse.csr_matrix:
    """M from the kinetic energy density ρh w v (no rotary inertia: a thin plate)."""
    @BilinearForm
    def mass(u, v, _):
        return rho_h * u * v
    return asm(mass, basis).tocsr()


def load_vector(space: PlateSpace, pressure) -> np.ndarray:
    """f from a pressure p(x, y) (Pa, positive along w): f_i = ∫ p φ_i."""
    @LinearForm
    def load(v, w):
        return pressure(w.x[0], w.x[1]) * v
    return asm(load, space.basis)


def plate_space(plate: Plate) -> PlateSpace:
    """The mesh, basis and matrices of ``plate``."""
    mesh = rectangle_mesh(plate)
    basis = Basis(mesh, make_element(plate.element))
    fixed = fixed_dofs(basis, plate)
    return PlateSpace(
        plate=plate, basis=basis,
        K=stiffness_matrix(basis, plate.D, plate.nu),
        M=mass_matrix(basis, plate.rho * plate.h),
        vertices=mesh.p.copy(),
        w_dofs=basis.nodal_dofs[0].copy(),      # every element's first nodal dof is u = w
        fixed_dofs=fixed,
        free_dofs=np.setdiff1d(np.arange(basis.N), fixed))
