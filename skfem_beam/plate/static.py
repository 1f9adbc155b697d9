"""The static deflection under a load: K w = f on the free dofs, w = 0 on the fixed."""
import numpy as np
from scipy.sparse.linalg import spsolve

from ..errors import InputError
from .space import PlateSpace


def static_deflection(space: PlateSpace, f: np.ndarray) -> np.ndarray:
    """All the dofs' values (w, its derivatives) under the load vector f (all dofs:
    :func:`~skfem_beam.plate.space.load_vector`)."""
    free = space.free_dofs
    f = np.asarray(f, dtype=float)
    if f.shape != (space.basis.N,):
        raise InputError(f"f has shape {f.shape}: a load vector over all {space.basis.N} "
                         "dofs is needed (load_vector(space, p))")
    u = np.zeros(space.basis.N)
    u[free] = spsolve(space.K[free][:, free].tocsc(), f[free])
    return u


def deflection_at_vertex(space: PlateSpace, u: np.ndarray, x: float, y: float) -> float:
    """w at the mesh vertex (x, y); a point that is not a vertex is an InputError."""
    distance = np.hypot(space.vertices[0] - x, space.vertices[1] - y)
    nearest = int(np.argmin(distance))
    if distance[nearest] > 1e-9 * space.plate.size:
        raise InputError(f"({x:g}, {y:g}) is not a vertex of the plate's mesh; the nearest "
                         f"is ({space.vertices[0, nearest]:g}, {space.vertices[1, nearest]:g})")
    return float(u[space.w_dofs[nearest]])
