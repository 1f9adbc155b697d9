"""The lowest natural frequencies and mode shapes: K φ = ω² M φ on the free dofs."""
import numpy as np
from scipy.linalg import eigh
from scipy.sparse.linalg import eigsh

from ..errors import InputError
from .space import PlateSpace, check_space, to_skfem

DENSE_UP_TO = 200   # free dofs below which a dense eigh is quicker than shift-invert


def check_mode_count(space: PlateSpace, n, name: str = "n") -> None:
    """``n`` modes can be computed (``name``: as the caller's user wrote it), else one line."""
    free = len(space.free_dofs)
    most = free if free <= DENSE_UP_TO else free - 1        # eigsh: k < n
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= most:
        why = f"the plate has {free} free dofs" + (
            ", and the sparse eigensolver finds at most one fewer modes" if most < free else "")
        raise InputError(f"{name}={n!r} must be a whole number in [1, {most}] ({why})")


def natural_frequencies(space: PlateSpace, n: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """The n lowest circular frequencies ω (rad/s), ascending, and their mode shapes
    (all of skfem's dofs, one column each, M-normalised)."""
    check_space(space, "natural_frequencies")
    free = space.free_dofs
    if not len(free):
        raise InputError("the plate has no free dofs (its edges hold them all): it has no "
                         "modes; free an edge or refine the mesh")
    check_mode_count(space, n)
    K = space.K[free][:, free]
    M = space.M[free][:, free]
    if len(free) <= DENSE_UP_TO:
        omega2, phi = eigh(K.toarray(), M.toarray(), subset_by_index=[0, n - 1])
    else:
        # shift-invert about 0 finds the eigenvalues nearest 0: the lowest ones; a fixed
        # Lanczos start, so that a run started from a mode shape has the same bits each time
        omega2, phi = eigsh(K.tocsc(), k=n, M=M.tocsc(), sigma=0.0, which="LM",
                            v0=np.ones(len(free)))
    order = np.argsort(np.abs(omega2))      # rigid modes' ω² ≈ ±1e-9: by the ω printed
    shapes = np.zeros((space.basis.N, n))
    shapes[free] = phi[:, order]
    return np.sqrt(np.abs(omega2[order])), to_skfem(space, shapes.T).T
