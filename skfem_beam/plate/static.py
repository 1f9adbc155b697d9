"""The static deflection under a load: K w = f on the free dofs, w = 0 on the fixed."""
import numpy as np
from scipy.sparse.linalg import spsolve

from ..checks import check_finite
from ..errors import InputError
from .space import PlateSpace, check_space, from_skfem, to_skfem


def static_deflection(space: PlateSpace, f: np.ndarray) -> np.ndarray:
    """All the dofs' values (w, its derivatives) under the load vector f (all dofs:
    :func:`~skfem_beam.plate.space.load_vector`)."""
    check_space(space, "static_deflection")
    free = space.free_dofs
    f = np.asarray(f, dtype=float)
    if f.shape != (space.basis.N,):
        raise InputError(f"f has shape {f.shape}: a load vector over all {space.basis.N} "
                         "dofs is needed (load_vector(space, p))")
    if not np.isfinite(f).all():
        raise InputError("f is not finite: the load vector has NaN or infinite entries")
    if not f.any():         # no load: flat, whatever the supports
        return np.zeros(space.basis.N)
    if rigid_motions(space):
        raise InputError("a static deflection needs edges that hold the plate: its free "
                         "and sliding edges leave it free to move as a rigid body (w = a + "
                         "bx + cy), so K w = f has no solution; clamp or simply support an "
                         "edge, or start from rest")
    u = np.zeros(space.basis.N)
    u[free] = spsolve(space.K[free][:, free].tocsc(), from_skfem(space, f)[free])
    return to_skfem(space, u)


def rigid_motions(space: PlateSpace) -> int:
    """How many independent rigid motions w = a + bx + cy the supports leave the plate
    (0: K is positive definite on the free dofs): for each part of the mesh (cells joined
    by a vertex; a mesh file may hold two plates, one of them unsupported), the rank that
    its fixed dofs' values of 1, x/L and y/L (:func:`rigid_dofs`, in the space's dofs)
    leave out of 3."""
    R, part = from_skfem(space, rigid_dofs(space).T).T, dof_parts(space)
    fixed = np.zeros(space.basis.N, dtype=bool)
    fixed[space.fixed_dofs] = True
    free = 0
    for p in range(part.max() + 1):
        held = R[fixed & (part == p)]
        s = np.linalg.svd(held, compute_uv=False) if held.size else np.zeros(1)
        free += 3 - (int(np.sum(s > 1e-9 * s[0])) if s[0] > 0 else 0)
    return free


def dof_parts(space: PlateSpace) -> np.ndarray:
    """Each dof's part of the mesh (0, 1, ...: the connected components of its cells,
    joined by their vertices)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    t = space.basis.mesh.t
    nv, nc = space.basis.mesh.p.shape[1], t.shape[1]
    cells = coo_matrix((np.ones(t.size), (np.repeat(np.arange(nc), t.shape[0]),
                                          t.T.ravel())), shape=(nc, nv)).tocsr()
    _, cell_part = connected_components(cells @ cells.T, directed=False)
    part = np.zeros(space.basis.N, dtype=np.int64)
    part[space.basis.element_dofs] = cell_part[None, :]
    return part


def rigid_dofs(space: PlateSpace) -> np.ndarray:
    """The dofs of w = 1, x/L, y/L (N × 3, L the plate's size) by the dofs' names: u the
    value, u_x and u_y the slopes, the second derivatives 0, u_n at an edge's midpoint
    the slope along a normal of the edge, up to skfem's sign for it (a row's sign does
    not change the rank rigid_motions takes).  skfem's own L² projection of them is off
    by 1e-9 to 1e-6 (the dofs' scales differ), too much to tell a zero by."""
    basis, L = space.basis, space.plate.size
    mesh, names = basis.mesh, basis.elem.dofnames
    R = np.zeros((basis.N, 3))
    x, y = mesh.p
    rows = {"u": (np.ones_like(x), x / L, y / L), "u_x": (0.0, 1.0 / L, 0.0),
            "u_y": (0.0, 0.0, 1.0 / L)}
    for k in range(basis.elem.nodal_dofs):
        if names[k] in rows:
            R[basis.nodal_dofs[k]] = np.column_stack(np.broadcast_arrays(*rows[names[k]]))
    if basis.elem.facet_dofs:
        t = mesh.p[:, mesh.facets[1]] - mesh.p[:, mesh.facets[0]]
        n = np.array([t[1], -t[0]]) / np.hypot(t[0], t[1])
        R[basis.facet_dofs[0], 1:] = n.T / L
    return R


def deflection_at_vertex(space: PlateSpace, u: np.ndarray, x: float, y: float) -> float:
    """w at the mesh vertex (x, y); a point that is not a vertex is an InputError."""
    check_space(space, "deflection_at_vertex")
    if np.shape(u) != (space.basis.N,):
        raise InputError(f"u has shape {np.shape(u)}: all {space.basis.N} dofs are needed "
                         "(full_dofs(system, u) gives them from a system's unknowns)")
    x, y = check_finite("x", x), check_finite("y", y)
    distance = np.hypot(space.vertices[0] - x, space.vertices[1] - y)
    nearest = int(np.argmin(distance))
    if distance[nearest] > 1e-9 * space.plate.size:
        raise InputError(f"({x:g}, {y:g}) is not a vertex of the plate's mesh; the nearest "
                         f"is ({space.vertices[0, nearest]:g}, {space.vertices[1, nearest]:g})")
    return float(u[space.w_dofs[nearest]])
