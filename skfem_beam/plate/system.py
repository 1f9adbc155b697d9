"""The plate's semi-discrete system for the one time scheme (:func:`skfem_beam.scheme.solve`):

    M ẅ + K w = Σ_k a_k(t) b_k + Cᵀλ,   g1 ≤ C w ≤ g2 at the constrained vertices

in physical units (SI): M = ρh(w, v) in kg, K the bending form in N/m, b_k = ∫ p_k φ in N
(p_k a pressure in Pa), λ the nodal contact forces in N, energies in J.  Only the free
dofs are kept, ordered by their location along the plate's longer side, then its shorter
side (``grid_order``): the banded Cholesky of the scheme then has half bandwidth about
4(n_short + 2) for BFS (87 at 20 × 20, 167 at 40 × 40; docs/plate.md, Dynamics).
``system.meta["dofs"]`` maps the system's unknowns back to the space's dof numbers, and
:func:`full_dofs` to skfem's dofs (through the space's Q where an oblique edge turns a
vertex's dofs: plate.frames).  A row of C is the deflection dof w at one vertex: contact is exact
there, as at the beam's nodes.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

from ..checks import check_bound, check_finite
from ..errors import InputError
from ..system import SemiDiscrete
from .space import PlateSpace, check_space, from_skfem, load_vector, to_skfem, values_at
from .region import cells_in, region_load
from .static import static_deflection


def one(t):
    """a(t) = 1, vectorised."""
    return np.ones(np.shape(t))


def _inside(region, x, y, tol: float) -> np.ndarray:
    """Whether (x, y) lies in the rectangle region = (x0, x1, y0, y1) (None: everywhere)."""
    if region is None:
        return np.ones(np.shape(x), dtype=bool)
    x0, x1, y0, y1 = region
    return (x >= x0 - tol) & (x <= x1 + tol) & (y >= y0 - tol) & (y <= y1 + tol)


def checked_region(what: str, region, space, area: bool, written=None):
    """``region`` = (x0, x1, y0, y1) (m) on the plate's bounding box, x0 ≤ x1 and y0 ≤ y1
    (``area``: both strict, a load's; else one side may be zero, a line of vertices, but
    not both: a point is ``points``), or None; else one line naming it and the order.  It
    must hold what it acts on: a load's (``area``) some of the plate, an obstacle's a
    vertex.  ``written``: the region as a scene
    file writes it, [x0, y0, x1, y1], ``what`` its key."""
    if region is None:
        return None
    plate = space.plate
    if written is None:
        label, order = f"{what} region={region!r}", \
            "(x0, x1, y0, y1) in m (a scene file writes [x0, y0, x1, y1])"
    else:
        label, order = f"{what} = {written!r}", "[x0, y0, x1, y1] in m"
    try:
        x0, x1, y0, y1 = (check_finite("region", v) for v in region)
    except (TypeError, ValueError, InputError):
        raise InputError(f"{label} must be four numbers {order}") from None
    bx0, bx1, by0, by1 = plate.box
    tol = 1e-9 * plate.size
    sides = (x1 - x0, y1 - y0)
    if min(sides) < 0 or (max(sides) == 0 if not area else min(sides) == 0):
        need = "x0 < x1 and y0 < y1" if area else "x0 ≤ x1 and y0 ≤ y1, not one point"
        raise InputError(f"{label} needs {need}: {order}")
    if x0 < bx0 - tol or y0 < by0 - tol or x1 > bx1 + tol or y1 > by1 + tol:
        raise InputError(f"{label} is off {plate.outline()}: {order}")
    region = x0, x1, y0, y1
    if area and not region_holds_plate(space, region):
        raise InputError(f"{label} holds none of the plate (a mesh's notch or hole): a "
                         "pressure there would load nothing")
    if not area and not region_vertices(space, region).any():
        raise InputError(f"{label} holds no vertex of the mesh")
    return region


def region_vertices(space, region) -> np.ndarray:
    """Whether each vertex lies in ``region`` (checked, (x0, x1, y0, y1); None: all)."""
    x, y = space.vertices
    return _inside(region, x, y, 1e-9 * space.plate.size)


def region_holds_plate(space, region) -> bool:
    """Whether some of the plate lies in ``region`` (checked): some cell, whole or in
    part (plate.region): a pressure there loads it."""
    whole, cut = cells_in(space.basis.mesh, region, 1e-9 * space.plate.size)
    return bool(whole.size or cut)


@dataclass(frozen=True)
class PlateObstacle:
    """g1(x, y) ≤ w ≤ g2(x, y) (numbers or vectorised functions of x, y; ±inf: one-sided)
    at the vertices of ``region`` = (x0, x1, y0, y1) (None: the whole plate), of ``disk`` =
    (xc, yc, r) (those within r of the centre), or, with ``points`` = ((x, y), ...), at
    those vertices only (point stops)."""
    g1: float | Callable = -np.inf
    g2: float | Callable = np.inf
    region: tuple[float, float, float, float] | None = None
    points: tuple[tuple[float, float], ...] | None = None
    disk: tuple[float, float, float] | None = None

    def __post_init__(self):
        for name in ("g1", "g2"):
            check_bound(f"PlateObstacle {name}", getattr(self, name), "x, y")
        if self.points is not None:
            object.__setattr__(self, "points", _points("PlateObstacle points", self.points))
            if not self.points:      # an empty list is no vertex, not the whole plate
                raise InputError("PlateObstacle points=() names no vertex: give ((x, y), ...) "
                                 "or leave points out for the whole plate or a region")
        if not bounds_act(self.g1, self.g2):
            raise InputError("PlateObstacle needs g1 and/or g2 (m): with neither it would "
                             "never act")
        if sum(v is not None for v in (self.points, self.region, self.disk)) > 1:
            raise InputError("PlateObstacle: give one of region, disk, points")
        if self.disk is not None:
            d = np.asarray(self.disk, dtype=float).ravel()
            if d.size != 3 or not np.isfinite(d).all() or d[2] <= 0:
                raise InputError(f"PlateObstacle disk={self.disk!r} must be (xc, yc, r) (m), "
                                 "r > 0")
            object.__setattr__(self, "disk", tuple(float(v) for v in d))

    def bounds(self, space: PlateSpace) -> tuple[np.ndarray, np.ndarray]:
        """(g1, g2) at every vertex of the mesh, ±inf where this obstacle does not act."""
        x, y = space.vertices
        if self.points:
            where = np.zeros(x.size, dtype=bool)
            where[[vertex_index(space, px, py) for px, py in self.points]] = True
        elif self.disk is not None:
            where = disk_vertices(space, self.disk)
            if not where.any():
                raise InputError("PlateObstacle disk=({:g}, {:g}, {:g}) holds no vertex of "
                                 "the mesh".format(*self.disk))
        else:
            region = checked_region("PlateObstacle", self.region, space, area=False)
            where = region_vertices(space, region)
        lo, hi = np.full(x.size, -np.inf), np.full(x.size, np.inf)
        # g where it acts only: a table need not cover the plate
        lo[where] = values_at(self.g1, x[where], y[where], "PlateObstacle g1", bounds=True)
        hi[where] = values_at(self.g2, x[where], y[where], "PlateObstacle g2", bounds=True)
        return lo, hi


@dataclass(frozen=True)
class Pressure:
    """A pressure p(x, y)·a(t) (Pa, positive along w) over ``region`` = (x0, x1, y0, y1)
    (None: the whole plate; a region whose sides cut cells is integrated exactly over
    each cell's part in it: plate.region)."""
    p: float | Callable = 0.0
    time: Callable = one
    region: tuple[float, float, float, float] | None = None

    def __post_init__(self):
        _number_or_function("Pressure p", self.p, "Pa", "x, y")
        _check_time("Pressure", self.time)

    def vector(self, space: PlateSpace) -> np.ndarray:
        """b = ∫ p·1_region φ (N), all dofs."""
        tol = 1e-9 * space.plate.size
        region = checked_region("Pressure", self.region, space, area=True)

        def p(x, y):
            return values_at(self.p, x, y, "Pressure p")
        b = None if region is None else region_load(space.basis, p, region, tol)
        return load_vector(space, lambda x, y: p(x, y) * _inside(region, x, y, tol)) \
            if b is None else b


@dataclass(frozen=True)
class PointForce:
    """A force P·a(t) (N, positive along w) at the mesh vertex (x, y): on the w dof there,
    whose virtual work is P·w(x, y), exactly (a point that is not a vertex is refused,
    naming the nearest)."""
    x: float
    y: float
    P: float = 0.0
    time: Callable = one

    def __post_init__(self):
        check_finite("PointForce P", self.P)
        _check_time("PointForce", self.time)

    def vector(self, space: PlateSpace) -> np.ndarray:
        """b = P e_w at the vertex (N), all dofs."""
        b = np.zeros(space.basis.N)
        b[self.dof(space)] = float(self.P)
        return b

    def dof(self, space: PlateSpace) -> int:
        """The w dof of its vertex; one line when it is no vertex, or one the edges hold
        at w = 0 (the force would go into the support and move nothing)."""
        dof = int(space.w_dofs[vertex_index(space, self.x, self.y)])
        if dof in space.fixed_dofs:
            raise InputError(f"({self.x:g}, {self.y:g}) is a vertex the edges hold at w = 0: "
                             "a force there goes into the support and moves nothing")
        return dof


def _check_time(what: str, time) -> None:
    """a(t) a vectorised, finite function of t (the scheme calls it on arrays of times)."""
    if not callable(time):
        raise InputError(f"{what} time={time!r} must be a function of t")
    t = np.array([0.0, 1e-3])
    try:
        a = np.asarray(time(t), dtype=float)
    except Exception as e:          # noqa: BLE001  (the user's function)
        a = e
    if not isinstance(a, np.ndarray) or a.shape != t.shape:
        got = f"shape {a.shape}" if isinstance(a, np.ndarray) else repr(a)
        raise InputError(f"{what} time must be vectorised: a(t) of an array of times "
                         f"returns one number per time (e.g. lambda t: np.sin(50 * t)); "
                         f"for t = [0, 0.001] it gave {got}")
    if not np.isfinite(a).all():
        raise InputError(f"{what} time gives {a} at t = [0, 0.001]: a(t) must be finite")


@dataclass(frozen=True)
class PlateInitial:
    """The start: w⁰ = the static deflection under ``static`` (a :class:`Pressure` whose
    time function is ignored; None: w⁰ = 0), or the ``mode``-th mode shape scaled to
    ``amplitude`` (m, its largest absolute w at a vertex); ẇ⁰ = ``v0`` (m/s, a number or a
    function of x, y), L²-projected on the free dofs as the beam's v0 is."""
    static: Pressure | None = None
    v0: float | Callable = 0.0
    mode: int = 0
    amplitude: float = 0.0

    def __post_init__(self):
        if self.static is not None and not isinstance(self.static, Pressure):
            raise InputError(f"PlateInitial static={self.static!r} must be a Pressure (the "
                             "load whose static deflection starts the run) or None")
        _number_or_function("PlateInitial v0", self.v0, "m/s", "x, y")
        if isinstance(self.mode, bool) or not isinstance(self.mode, int) or self.mode < 0:
            raise InputError(f"PlateInitial mode={self.mode!r} must be a whole number ≥ 1 "
                             "(0: none)")
        check_finite("PlateInitial amplitude", self.amplitude)
        if self.mode and (self.static is not None or self.amplitude == 0.0):
            raise InputError("PlateInitial mode starts from a mode shape: give its "
                             "amplitude (m, ≠ 0) and no static load")
        if self.amplitude != 0.0 and not self.mode:      # else dropped: the plate flat
            raise InputError(f"PlateInitial amplitude={self.amplitude!r} is a mode shape's: "
                             "give the mode too (mode = k ≥ 1)")


def bounds_act(g1, g2) -> bool:
    """Whether an obstacle's g1, g2 (numbers or functions) bound w at all (not −inf, inf)."""
    return any(callable(g) or np.isfinite(g) for g in (g1, g2))


def _points(what: str, points) -> tuple:
    """``points`` as ((x, y), ...) of floats, else one line naming them."""
    try:
        return tuple((float(x), float(y)) for x, y in points)
    except (TypeError, ValueError):
        raise InputError(f"{what}={points!r} must be vertices ((x, y), ...) in m") from None


def _number_or_function(name: str, value, unit: str, of: str) -> None:
    """A finite number or a function (of ``of``), else one line naming it."""
    if callable(value):
        return
    try:
        check_finite(name, value)
    except InputError:
        raise InputError(f"{name}={value!r} must be a finite number ({unit}) or a function "
                         f"of {of}") from None


def disk_vertices(space: PlateSpace, disk) -> np.ndarray:
    """Which vertices lie within r of the centre of ``disk`` = (xc, yc, r)."""
    xc, yc, r = disk
    x, y = space.vertices
    return np.hypot(x - xc, y - yc) <= r + 1e-9 * space.plate.size


def vertex_index(space: PlateSpace, x: float, y: float) -> int:
    """The mesh vertex at (x, y); a point that is not a vertex is an InputError."""
    x, y = check_finite("vertex x", x), check_finite("vertex y", y)
    distance = np.hypot(space.vertices[0] - x, space.vertices[1] - y)
    nearest = int(np.argmin(distance))
    if distance[nearest] > 1e-9 * space.plate.size:
        # the nearest written in full (repr): a user pastes it back, and its %g form, six
        # digits, may be no vertex either (1/3 on a grid of thirds)
        vx, vy = (float(v) for v in space.vertices[:, nearest])
        raise InputError(f"({x:g}, {y:g}) is not a vertex of the plate's mesh; the nearest "
                         f"is ({vx!r}, {vy!r})")
    return nearest


def grid_order(space: PlateSpace) -> np.ndarray:
    """The free dofs sorted by their location (skfem's doflocs) along the longer side,
    then the shorter side, then dof number: a narrow band for any of the elements."""
    free = space.free_dofs
    loc = space.basis.doflocs[:, free]
    long_axis = 0 if space.plate.a >= space.plate.b else 1
    return free[np.lexsort((free, loc[1 - long_axis], loc[long_axis]))]


def half_bandwidth(A) -> int:
    """max |i − j| over the nonzeros of A."""
    coo = sp.coo_matrix(A)
    return int(np.abs(coo.col - coo.row).max()) if coo.nnz else 0


def full_dofs(system: SemiDiscrete, u: np.ndarray) -> np.ndarray:
    """The system's coefficients (last axis) as all of skfem's dofs (fixed ones 0; the
    space's Q applied, plate.frames): for :func:`~skfem_beam.plate.deflection_at_vertex`,
    plotting, skfem's tools."""
    if not isinstance(system, SemiDiscrete) or system.meta.get("kind") != "plate":
        raise InputError(f"full_dofs needs a plate's system, plate_system(...), not "
                         f"{type(system).__name__}")
    u = np.asarray(u, dtype=float)
    if u.shape[-1:] != system.meta["dofs"].shape:
        raise InputError(f"u has shape {u.shape}: its last axis must be the system's "
                         f"{system.meta['dofs'].size} unknowns")
    full = np.zeros(u.shape[:-1] + (system.meta["space"].basis.N,))
    full[..., system.meta["dofs"]] = u
    return to_skfem(system.meta["space"], full)


def _of(k: int) -> str:
    """" of obstacles[k]", the obstacle that set a bound (none: an infinite one)."""
    return f" of obstacles[{k}]" if k >= 0 else ""


def _contact_rows(space, obstacles, position):
    """(vertices, lo, hi) of the constrained vertices: the highest g1 and the lowest g2
    of the obstacles at each vertex whose w is free and bounded."""
    nv = space.vertices.shape[1]
    lo, hi = np.full(nv, -np.inf), np.full(nv, np.inf)
    lo_of, hi_of = np.full(nv, -1), np.full(nv, -1)     # the obstacle giving each bound
    held = position[space.w_dofs] < 0       # w fixed to 0 by a support
    for k, obstacle in enumerate(obstacles):
        g1, g2 = obstacle.bounds(space)
        acts = np.isfinite(g1) | np.isfinite(g2)
        # as a beam's: it ran with no contact (one that conflicts with w = 0: below)
        if acts.any() and held[acts].all() and not np.any((g1 > 0) | (g2 < 0)):
            raise InputError(f"obstacles[{k}] acts only at vertices its plate's supports "
                             "hold at w = 0: it would never act")
        lo_of[(g1 > lo) | np.isnan(g1)] = k
        hi_of[(g2 < hi) | np.isnan(g2)] = k
        lo, hi = np.maximum(lo, g1), np.minimum(hi, g2)
    if np.isnan(lo).any() or np.isnan(hi).any() or np.any(lo >= hi):
        i = int(np.argmax(np.isnan(lo) | np.isnan(hi) | (lo >= hi)))
        raise InputError(f"obstacles at vertex ({space.vertices[0, i]:g}, "
                         f"{space.vertices[1, i]:g}) need g1 < g2 (g1={lo[i]:g}"
                         f"{_of(lo_of[i])}, g2={hi[i]:g}{_of(hi_of[i])})")
    if np.any(held & ((lo > 0) | (hi < 0))):
        i = int(np.argmax(held & ((lo > 0) | (hi < 0))))
        which = _of(lo_of[i]) if lo[i] > 0 else _of(hi_of[i])
        raise InputError(f"vertex ({space.vertices[0, i]:g}, {space.vertices[1, i]:g}) is "
                         f"held at w = 0 by its support, outside [{lo[i]:g}, {hi[i]:g}] "
                         f"(g{1 if lo[i] > 0 else 2}{which})")
    rows = np.flatnonzero(~held & (np.isfinite(lo) | np.isfinite(hi)))
    return rows, lo[rows], hi[rows]


def _initial(space, initial: PlateInitial, dofs: np.ndarray, M: sp.csr_matrix):
    """(u0, v0) on the system's unknowns."""
    u0 = np.zeros(dofs.size)
    if initial.static is not None:
        u0 = from_skfem(space, static_deflection(space, initial.static.vector(space)))[dofs]
    if initial.mode:
        from .modes import natural_frequencies
        shape = natural_frequencies(space, initial.mode)[1][:, initial.mode - 1]
        w = shape[space.w_dofs]      # a mode's sign is the solver's: its peak made +
        shape = shape * (initial.amplitude / w[np.argmax(np.abs(w))])
        u0 = from_skfem(space, shape)[dofs]
    v0 = np.zeros(dofs.size)
    if not (np.isscalar(initial.v0) and initial.v0 == 0.0):
        rho_h = space.plate.rho * space.plate.h      # M carries ρh: (ρh v0, φ) on the right
        b = from_skfem(space, load_vector(space, lambda x, y: rho_h * values_at(
            initial.v0, x, y, "PlateInitial v0")))[dofs]
        v0 = spsolve(M.tocsc(), b)
    return u0, v0


def _observers(space, points, position) -> dict[str, np.ndarray]:
    """{"w(x,y)": the row reading w at that vertex}; default: the vertex nearest the
    centre."""
    if points is None:
        x, y = space.vertices
        c = int(np.argmin(np.hypot(x - space.plate.centre[0], y - space.plate.centre[1])))
        points = [(float(x[c]), float(y[c]))]
    rows, seen = {}, {}
    for k, (px, py) in enumerate(points):
        vertex = vertex_index(space, px, py)
        first = seen.setdefault(vertex, k)
        if first != k:                      # one row per name: a second one crashed a run
            raise InputError(f"plate_system observe[{k}] = ({px:g}, {py:g}) is the vertex of "
                             f"observe[{first}]: give each vertex once")
        j = position[space.w_dofs[vertex]]
        row = np.zeros(space.free_dofs.size)
        if j >= 0:                          # a held vertex reads 0
            row[j] = 1.0
        rows[f"w({px:g},{py:g})"] = row
    return rows


def _check_parts(space, obstacles, loads, initial) -> None:
    """The arguments' kinds, each refused in one line saying what goes there."""
    check_space(space, "plate_system")
    for name, items, kind in (("obstacles", obstacles, (PlateObstacle,)),
                              ("loads", loads, (Pressure, PointForce))):
        if isinstance(items, (*kind, str)) or not hasattr(items, "__iter__") \
                or not all(isinstance(i, kind) for i in items):
            raise InputError(f"{name}= must be a list of "
                             f"{' or '.join(k.__name__ for k in kind)} (got {items!r})")
    if initial is not None and not isinstance(initial, PlateInitial):
        raise InputError(f"initial={initial!r} must be a PlateInitial or None")


def plate_system(space: PlateSpace, obstacles=(), loads=(), initial: PlateInitial | None = None,
                 observe=None, damping=None) -> SemiDiscrete:
    """The plate's :class:`~skfem_beam.system.SemiDiscrete` (physical units, see the
    module docstring): ``obstacles`` a sequence of :class:`PlateObstacle`, ``loads`` of
    :class:`Pressure`, ``initial`` a :class:`PlateInitial` (None: at rest, flat),
    ``observe`` the vertices (x, y) whose w is observed (None: the one nearest the
    centre), ``damping`` a :class:`~skfem_beam.problem.Damping` (Rayleigh αM + α_K K in the
    plate's M and K, and/or every mode at ζ; None: none).  ``meta``: "dofs" (the space's dof of each unknown), "contact_vertices",
    "y_contact" (x_contact holds the x of each constrained vertex)."""
    from ..semidiscrete import damping_matrix       # as a beam's (Rayleigh and modal)
    _check_parts(space, obstacles, loads, initial)
    if observe is not None:
        observe = _points("plate_system observe", observe)
    dofs = grid_order(space)
    position = np.full(space.basis.N, -1)
    position[dofs] = np.arange(dofs.size)
    M = space.M[dofs][:, dofs].tocsr()
    K = space.K[dofs][:, dofs].tocsr()
    vertices, lo, hi = _contact_rows(space, obstacles, position)
    cols = position[space.w_dofs[vertices]]
    C = sp.csr_matrix((np.ones(cols.size), (np.arange(cols.size), cols)),
                      shape=(cols.size, dofs.size))
    b = [from_skfem(space, load.vector(space))[dofs] for load in loads]
    u0, v0 = _initial(space, initial or PlateInitial(), dofs, M)
    y0 = C @ u0
    tol = 1e-12 * max(1.0, np.abs(u0).max(initial=0.0))
    if np.any((y0 < lo - tol) | (y0 > hi + tol)):
        i = int(np.argmax((y0 < lo - tol) | (y0 > hi + tol)))
        x, y = space.vertices[:, vertices[i]]
        raise InputError(f"the initial deflection violates the obstacles at ({x:g}, {y:g}): "
                         f"w0={y0[i]:.10g} not in [{lo[i]:.10g}, {hi[i]:.10g}]")
    return SemiDiscrete(
        M=M, K=K, C=C, lo=lo, hi=hi, x_contact=space.vertices[0, vertices].copy(),
        B=damping_matrix(damping, M, K),
        loads=np.column_stack(b) if b else np.zeros((dofs.size, 0)),
        load_time=[load.time for load in loads], u0=u0, v0=v0,
        observe=_observers(space, observe, position), space=space,
        meta={"kind": "plate", "plate": space.plate, "space": space, "dofs": dofs,
              "contact_vertices": vertices, "y_contact": space.vertices[1, vertices].copy()})
