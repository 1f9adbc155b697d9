"""The plate's finite element space: mesh, element, basis, the dofs each edge's support
fixes, and the matrices K (bending), M (mass) and a load vector."""
import itertools
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from skfem import (Basis, BilinearForm, ElementQuadBFS, ElementTriArgyris, ElementTriMorley,
                   LinearForm, MeshQuad, MeshTri, asm)
from skfem.element.discrete_field import DiscreteField
from skfem.helpers import dd, ddot, trace

from ..checks import check_finite
from ..errors import InputError
from .frames import oblique_frames
from .model import MeshPlate, Plate

# the coordinate normal to each edge of the rectangle (0: x, 1: y)
NORMAL_AXIS = {"left": 0, "right": 0, "bottom": 1, "top": 1}


@dataclass
class PlateSpace:
    """What a solver needs: the matrices, which dofs are free, and at each mesh vertex its
    coordinates and the index of its deflection dof w (where contact will act).

    The dofs are ũ, skfem's u = Q ũ: Q turns the gradient and Hessian dofs of the
    vertices of oblique supported edges (Argyris) to frames where each edge condition is
    one dof (plate.frames); Q is None elsewhere (ũ = u).  K, M, fixed_dofs and free_dofs
    are ũ's; w is never turned (w_dofs are skfem's and ũ's); to_skfem and from_skfem
    convert vectors."""
    plate: Plate
    basis: Basis
    K: sparse.csr_matrix
    M: sparse.csr_matrix
    vertices: np.ndarray       # (2, number of vertices): x, y
    w_dofs: np.ndarray         # the dof of w at each vertex
    fixed_dofs: np.ndarray
    free_dofs: np.ndarray
    Q: sparse.csr_matrix | None = None     # u = Q ũ (orthogonal); None: the identity


def _apply(A, u: np.ndarray) -> np.ndarray:
    """A (sparse) times each vector along u's last axis."""
    u = np.asarray(u, dtype=float)
    flat = u.reshape(-1, u.shape[-1]).T
    return np.asarray(A @ flat).T.reshape(u.shape[:-1] + (A.shape[0],))


def to_skfem(space: PlateSpace, u: np.ndarray) -> np.ndarray:
    """skfem's dofs Q ũ of the space's dofs ũ (the last axis)."""
    return u if space.Q is None else _apply(space.Q, u)


def from_skfem(space: PlateSpace, f: np.ndarray) -> np.ndarray:
    """The space's Qᵀ f of skfem's f (the last axis): a load vector, or dofs (Q is
    orthogonal: Q⁻¹ = Qᵀ)."""
    return f if space.Q is None else _apply(space.Q.T, f)


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


def file_mesh(plate: MeshPlate) -> MeshTri:
    """The triangles of a mesh file's plate, with its named boundaries (facet indices)."""
    m = plate.mesh
    # C order: skfem transposes a Fortran-ordered one itself, saying so on stderr
    points = np.ascontiguousarray(m.points, dtype=float)
    triangles = np.ascontiguousarray(m.triangles, dtype=np.int64)
    _check_areas(points, triangles, m.source)
    _check_overlaps(points, triangles, m.source)
    mesh = MeshTri(points, triangles)
    n = mesh.p.shape[1]
    key = mesh.facets[0] * n + mesh.facets[1]          # skfem's facets: sorted pairs
    order = np.argsort(key)
    named = {}
    for name, pairs in m.boundaries.items():
        lines = np.sort(pairs, axis=0)
        want = lines[0] * n + lines[1]
        at = np.minimum(np.searchsorted(key, want, sorter=order), key.size - 1)
        found = key[order[at]] == want
        if not found.all():
            raise InputError(f"the mesh {m.source}: {np.count_nonzero(~found)} line(s) of "
                             f"boundary {name!r} are not edges of its triangles")
        named[name] = np.unique(order[at])
    return mesh.with_boundaries(named)


def _check_areas(points, triangles, source: str) -> None:
    """Refuse a triangle of no area (a repeated or collinear point): its element's
    matrices are singular, and numpy raised LinAlgError from inside skfem."""
    a, b, c = (points[:, triangles[i]] for i in range(3))
    twice = np.abs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
    size = np.ptp(points, axis=1).max() if points.size else 0.0
    flat = np.flatnonzero(twice <= 1e-12 * size * size)
    if flat.size:
        k = int(flat[0])
        raise InputError(f"the mesh {source}: triangle {k} (vertices "
                         f"{', '.join(str(int(v)) for v in triangles[:, k])}) has no area (a "
                         f"repeated or collinear point; {flat.size} such triangle(s)): a "
                         "plate's triangles need area")


def _check_overlaps(points, triangles, source: str) -> None:
    """Refuse triangles that overlap across an edge: an edge of three or more triangles
    (a triangle listed twice, say), or of two on the same side of it.  Their stiffness
    and mass were assembled twice, silently (a disk's first frequency 102.06 → 102.78 Hz
    for three repeated triangles).  Overlaps that share no edge are not looked for."""
    t = triangles.shape[1]
    _, first, again = np.unique(np.sort(triangles, axis=0), axis=1, return_index=True,
                                return_inverse=True)
    repeat = np.flatnonzero(first[again.ravel()] != np.arange(t))
    if repeat.size:
        k = int(repeat[0])
        raise InputError(f"the mesh {source}: triangle {k} repeats triangle "
                         f"{int(first[again.ravel()[k]])} ({repeat.size} repeated); a plate's "
                         "triangles are listed once")
    edges = np.sort(np.hstack([triangles[[0, 1]], triangles[[1, 2]], triangles[[2, 0]]]),
                    axis=0)
    owner = np.tile(np.arange(t), 3)
    opposite = np.hstack([triangles[2], triangles[0], triangles[1]])
    order = np.lexsort(edges)
    edges, owner, opposite = edges[:, order], owner[order], opposite[order]
    same = np.all(edges[:, 1:] == edges[:, :-1], axis=0)
    third = np.flatnonzero(same[1:] & same[:-1])
    if third.size:
        i = int(third[0])
        three = ", ".join(str(int(k)) for k in owner[i:i + 3])
        raise InputError(f"the mesh {source}: triangles {three} share the edge "
                         f"({int(edges[0, i])}, {int(edges[1, i])}): overlapping or repeated "
                         "triangles; a plate's triangles meet two at an edge")
    pair = np.flatnonzero(same)
    a, b = points[:, edges[0, pair]], points[:, edges[1, pair]]

    def side(c):
        return np.sign((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
    folded = np.flatnonzero(side(points[:, opposite[pair]])
                            == side(points[:, opposite[pair + 1]]))
    if folded.size:
        i = int(pair[folded[0]])
        raise InputError(f"the mesh {source}: triangles {int(owner[i])} and "
                         f"{int(owner[i + 1])} overlap (both on one side of their edge "
                         f"({int(edges[0, i])}, {int(edges[1, i])})); a plate's triangles "
                         "meet two at an edge, one on each side")


def plate_mesh(plate):
    """The skfem mesh of ``plate``, its boundaries named (the rectangle's left, right,
    bottom, top; a mesh file's own names)."""
    return file_mesh(plate) if isinstance(plate, MeshPlate) else rectangle_mesh(plate)


class MonomialsOnce:
    """scikit-fem's ``ElementGlobal.gbasis`` with each monomial of the power basis evaluated
    once per set of points, not once per basis function: skfem builds basis function i as
    Σ_k V[:, k, i] p_k(x) and evaluates every p_k (x^a y^b and its derivatives, up to the
    Hessian) again for each i: 21 × 21 × 7 evaluations for Argyris, 0.5 s of a Basis on the
    shipped disk's 216 triangles, 0.04 s once.  The same sums in the same order: the basis
    is skfem's to the bit (tests/test_plate.py)."""

    _points = None      # (mapping, X, tind) → the power basis at those points

    def gbasis(self, mapping, X, i, tind=None):
        if tind is None:
            tind = np.arange(mapping.mesh.t.shape[1])
        if self.V is None:
            self._pbasis_init(self.maxdeg, self.dim, self.derivatives, self.tensorial_basis)
            self.V = np.linalg.inv(self._eval_dofs(mapping.mesh))
        key = (X.tobytes(), tind.tobytes())
        if self._points is None or self._points[0] is not mapping or self._points[1] != key:
            x = mapping.F(X, tind=tind)         # (the mapping kept: its id stays its own)
            self._points = (mapping, key, x[0].shape,
                            {diff: [p(*x) for p in ps] for diff, ps in self._pbasis.items()})
        _, _, shape, P = self._points
        V = self.V[tind]
        U = [np.zeros((self.dim,) * k + shape) for k in range(self.derivatives + 1)]
        for k in range(self.derivatives + 1):
            diffs = list(itertools.product(range(self.dim), repeat=k))
            for itr in range(len(self._pbasis[()])):
                for diff in diffs:
                    U[k][diff] += V[:, itr, i][:, None] * P[diff][itr]
        higher = {f"grad{k + 3}": U[k + 3] for k in range(self.derivatives - 2)}
        return (DiscreteField(value=U[0], grad=U[1], hess=U[2], **higher),)


class BFS(MonomialsOnce, ElementQuadBFS):
    pass


class Morley(MonomialsOnce, ElementTriMorley):
    pass


class Argyris(MonomialsOnce, ElementTriArgyris):
    pass


def make_element(name: str):
    return {"bfs": BFS, "morley": Morley, "argyris": Argyris}[name]()


def is_fixed(dofname: str, support: str, normal_axis: int | None) -> bool:
    """Whether a support fixes the dof ``dofname`` (u, u_x, u_xy, u_n, ...) on an edge
    whose normal is along x (``normal_axis`` 0), y (1) or neither (None: an oblique edge
    of a mesh file's plate, below).

    Along the edge w = 0 fixes w and all its tangential derivatives; clamping also fixes
    ∂w/∂n = 0 and so its tangential derivatives.  A dof is fixed when its derivatives
    include no normal one (simply supported), or at most one (clamped).  u_n, the
    normal derivative at an edge's midpoint (Morley, Argyris), counts as one.  Sliding
    (∂w/∂n = 0, w free: a line of symmetry) fixes those with exactly one.

    On an oblique edge the tangential and normal derivatives mix x and y, so only what
    is a dof there is fixed here: w (simply supported, clamped), w_x and w_y (clamped:
    the whole gradient is 0) and u_n (clamped, sliding); Argyris's vertex gradient and
    Hessian there then get the edge's full conditions in frames of their own
    (plate.frames.oblique_frames, which replaces this choice of w_x, w_y)."""
    letters = dofname.partition("_")[2]
    if normal_axis is None:
        return {"clamped": letters in ("", "x", "y", "n"), "simply_supported": letters == "",
                "sliding": letters == "n"}.get(support, False)
    normal_count = sum(c in ("n", "xy"[normal_axis]) for c in letters)
    if support == "clamped":
        return normal_count <= 1
    if support == "simply_supported":
        return normal_count == 0
    if support == "sliding":
        return normal_count == 1
    return False


def facet_axes(mesh, facets: np.ndarray) -> np.ndarray:
    """The normal axis of each facet: 0 (along x: a facet parallel to y), 1 (along y),
    -1 (oblique)."""
    d = mesh.p[:, mesh.facets[1, facets]] - mesh.p[:, mesh.facets[0, facets]]
    tol = 1e-9 * np.hypot(d[0], d[1])
    return np.where(np.abs(d[0]) <= tol, 0, np.where(np.abs(d[1]) <= tol, 1, -1))


def support_groups(basis: Basis, plate):
    """(facets, support, normal axis or None) of each supported boundary: the
    rectangle's edges whole (their axis, :data:`NORMAL_AXIS`), a mesh file's boundaries
    split by their facets' directions (:func:`facet_axes`)."""
    mesh = basis.mesh
    for name in plate.boundary_names:
        facets = mesh.boundaries[name]
        if name in NORMAL_AXIS and isinstance(plate, Plate):
            yield facets, plate.support(name), NORMAL_AXIS[name]
            continue
        axes = facet_axes(mesh, facets)
        for axis in (0, 1, -1):
            if np.any(axes == axis):
                yield facets[axes == axis], plate.support(name), None if axis < 0 else axis


def fixed_dofs(basis: Basis, plate) -> np.ndarray:
    """The dofs the edges' supports fix (a corner gets the union of its two edges')."""
    fixed = []
    for facets, support, axis in support_groups(basis, plate):
        dofs = basis.get_dofs(facets)
        for kind in (dofs.nodal, dofs.facet):
            fixed += [ix for name, ix in kind.items() if is_fixed(name, support, axis)]
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


def values_at(g, x, y, what: str, bounds: bool = False) -> np.ndarray:
    """g (a number or a vectorised function of x, y) at the points (x, y); a function
    that raises, returns a value per point of another shape or something not a number,
    or a value that is NaN (infinite, unless ``bounds``: an obstacle's ±inf is one-sided)
    is one line naming ``what``."""
    try:
        v = g(x, y) if callable(g) else g
        v = np.broadcast_to(np.asarray(v, dtype=float), np.shape(x)).copy()
    except InputError:
        raise
    except Exception as e:      # noqa: BLE001  (the user's function, whatever it raised)
        raise InputError(f"{what}: its function of x, y at the {np.size(x)} points must "
                         f"return one number per point (a vectorised function); it gave "
                         f"{type(e).__name__}: {e}") from None
    bad = (np.isnan(v) if bounds else ~np.isfinite(v)).ravel()
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(f"{what} is {v.ravel()[i]} at ({np.ravel(x)[i]:g}, "
                         f"{np.ravel(y)[i]:g}): it must be a finite number there")
    return v


def check_space(space, what: str) -> None:
    """One line when ``space`` is not a plate's (a beam's system, a Plate itself)."""
    if not isinstance(space, PlateSpace):
        raise InputError(f"{what} needs the plate's space, plate_space(plate), not "
                         f"{type(space).__name__}")


def load_vector(space: PlateSpace, pressure) -> np.ndarray:
    """f from a pressure p(x, y) (Pa, positive along w; a number: uniform): f_i = ∫ p φ_i."""
    check_space(space, "load_vector")
    p = pressure if callable(pressure) else \
        (lambda x, y, c=check_finite("load_vector p", pressure): c + 0.0 * x)

    @LinearForm
    def load(v, w):
        return values_at(p, w.x[0], w.x[1], "load_vector p") * v
    return asm(load, space.basis)


FAR = 10.0      # mesh sizes from the origin past which the Argyris basis is refused


def check_near_origin(mesh, element: str) -> None:
    """One line for an Argyris mesh farther than FAR of its sizes from the origin: its
    shape functions are skfem's global monomials in x, y, which lose digits there (a clamped
    disk of 1 m: ω₁ 0.7 % off at 30 m, 33 % at 50 m, then refused as singular)."""
    if element != "argyris":
        return
    size = float(np.ptp(mesh.p, axis=1).max())
    far = float(np.abs(mesh.p).max())
    if far > FAR * size:
        raise InputError(f"the plate's mesh lies up to {far:.3g} m from the origin, "
                         f"{far / size:.3g} times its size ({size:.3g} m): the argyris "
                         "element's global monomials in x, y lose digits there; move its "
                         f"points within {FAR:g} sizes of the origin")


def plate_space(plate) -> PlateSpace:
    """The mesh, basis and matrices of ``plate`` (a :class:`Plate` or a
    :class:`MeshPlate`)."""
    if not isinstance(plate, (Plate, MeshPlate)):
        raise InputError(f"plate_space needs a Plate or a MeshPlate, not {plate!r}")
    mesh = plate_mesh(plate)
    check_near_origin(mesh, plate.element)
    try:
        basis = Basis(mesh, make_element(plate.element))
    except np.linalg.LinAlgError:   # skfem's global monomials on a tiny cell: a traceback
        size = float(np.min(np.ptp(mesh.p[:, mesh.t], axis=1).max(axis=0)))
        raise InputError(f"the {plate.element} element's matrices (global monomials in x, "
                         f"y) are singular on this mesh: a cell too small (smallest "
                         f"{size:.3g} m across) or too flat for them; coarsen the mesh or "
                         "mend its slivers") from None
    fixed, Q = oblique_frames(basis, support_groups(basis, plate), fixed_dofs(basis, plate))
    K = stiffness_matrix(basis, plate.D, plate.nu)
    M = mass_matrix(basis, plate.rho * plate.h)
    if Q is not None:                   # (only then: the others' K and M keep their bits)
        K, M = (Q.T @ K @ Q).tocsr(), (Q.T @ M @ Q).tocsr()
    return PlateSpace(
        plate=plate, basis=basis, K=K, M=M,
        vertices=mesh.p.copy(),
        w_dofs=basis.nodal_dofs[0].copy(),      # every element's first nodal dof is u = w
        fixed_dofs=fixed,
        free_dofs=np.setdiff1d(np.arange(basis.N), fixed), Q=Q)
