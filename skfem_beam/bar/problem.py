"""The impacting bar of Do, Raupp & Feijoo: a (visco)elastic bar, obstacle at x = 0.

    ρ u_tt = (a u_x + b u_xt)_x + f   on (0, L),   σ(L) = 0,
    σ = a u_x + b u_xt,   R = −σ(0) the obstacle's reaction on the bar,

    rigid obstacle:   U = u(0, t) ≥ 0,  R ≥ 0,  R·U = 0       (paper (2.10))
    elastic obstacle: R = k U⁻                                 (paper (2.8))

The bar scene (:class:`Bar`: plain validated data) and its profiles (numbers, functions
of x or tables of (x, value) pairs: :class:`Table`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..checks import (MAX_ELEMENTS, check_choice, check_count, check_finite,
                      check_nonnegative, check_positive)
from ..spaces.lagrange import ELEMENTS, MASSES

OBSTACLES = ("rigid", "elastic")
FAR_ENDS = ("free", "clamped")
SIDES = ("left", "right")


@dataclass(frozen=True)
class Table:
    """A profile given as (x, value) pairs, x increasing: linear interpolation between
    them.  It must cover the bar [0, L] (checked by :class:`Bar`)."""
    x: tuple
    value: tuple

    def __call__(self, x):
        return np.interp(np.asarray(x, dtype=float), self.x, self.value)

    @classmethod
    def of(cls, name: str, pairs) -> "Table":
        try:
            xy = np.asarray(pairs, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"{name}={pairs!r} is neither a number, a function of x nor "
                             f"(x, value) pairs") from None
        if xy.ndim != 2 or xy.shape[1] != 2 or xy.shape[0] < 2:
            raise InputError(f"{name}: a table needs at least two (x, value) pairs, "
                             f"got an array of shape {xy.shape}")
        if not np.isfinite(xy).all():
            raise InputError(f"{name}: the table has a value that is not a finite number")
        step = np.diff(xy[:, 0])
        if (step <= 0).any():
            i = int(np.argmax(step <= 0))
            raise InputError(f"{name}: the table's x must increase, but x={xy[i, 0]:g} is "
                             f"followed by x={xy[i + 1, 0]:g}")
        return cls(tuple(xy[:, 0].tolist()), tuple(xy[:, 1].tolist()))


def _profile(name: str, value):
    """A uniform value (float), a :class:`Table`, or a function of x, as given."""
    if isinstance(value, Table) or (callable(value) and not isinstance(value, type)):
        return value
    if np.ndim(value) == 0:
        return check_finite(name, value)
    return Table.of(name, value)


def profile_values(value, x: np.ndarray) -> np.ndarray:
    """The profile ``value`` (a number, a Table or a function) at the abscissae ``x``."""
    if isinstance(value, float):
        return np.full(x.shape, value)
    return np.broadcast_to(np.asarray(value(x), dtype=float), x.shape).copy()


def read_profile(path: str, flag: str) -> Table:
    """A profile from a CSV file of x,value rows (a header line and # comments allowed)."""
    try:
        with open(path, encoding="utf-8-sig") as fh:       # a byte-order mark is no header
            lines = fh.read().splitlines()
    except OSError as e:
        raise InputError(f"{flag} {path}: cannot read it ({e.strerror or e})") from None
    except UnicodeDecodeError:
        raise InputError(f"{flag} {path}: not a UTF-8 text file (a CSV of numbers)") from None
    pairs = []
    for i, line in enumerate(lines, 1):
        cells = [c.strip() for c in line.split("#")[0].split(",")]
        if cells == [""]:
            continue
        try:
            if len(cells) != 2:
                raise ValueError
            pairs.append((float(cells[0]), float(cells[1])))
        except ValueError:
            if pairs or i > 1:       # only the first line may be a header
                raise InputError(f"{flag} {path}: line {i} {line.strip()!r} is not two "
                                 f"numbers x,value") from None
    return Table.of(f"{flag} {path}", pairs)


def describe(value):
    """A profile for summary.json: the number, the table's pairs, or 'function'."""
    if isinstance(value, float):
        return value
    if isinstance(value, Table):
        return {"x": list(value.x), "value": list(value.value)}
    return "function of x"


@dataclass(frozen=True)
class Bar:
    """The bar scene.  Defaults: the paper's Example 1 (k = 100, v0 = −1, N = 100).

    ``u0``, ``v0``: the initial displacement and velocity, each a number (uniform), a
    function of x, or a table of (x, value) pairs (linear interpolation); the scheme
    starts from their nodal values.  A uniform u0 > 0 is a gap to the obstacle at x = 0
    (the bar then flies freely for u0/|v0| before it hits).

    ``obstacle_at``: the end the obstacle sits at, "left" (x = 0: u(0) ≥ 0) or "right"
    (x = L: u(L) ≤ 0); the numbers 0 and L are accepted too.  The gap is U = u(0) or
    U = −u(L), so the law reads the same at either end (U ≥ 0, R ≥ 0, RU = 0, or
    R = kU⁻) and R ≥ 0 is the obstacle's push on the bar.  ``far_end``: the other end,
    "free" (σ = 0) or "clamped" (u = 0; u0 must vanish there).

    ``A``: the cross-section (m²).  None (default) is the paper's per-unit-section form:
    forces in Pa, energies in J/m², the spring k in Pa/m.  With A the matrices carry it
    (ρA, EA, bA, fA): forces are in N, energies in J, and k is a spring in N/m.
    ``mass`` is the mass matrix; the default ``average`` is the one that meets the
    accuracy targets (see :mod:`skfem_beam.spaces.lagrange` and docs/design.md §6).
    ``element``: P1 (the paper's) or P2 (twice the unknowns; with β = 0.09 the rod's
    error at Δt/h = 0.4 is half P1's best: docs/methods.md, "The rod's accuracy study").
    """
    a: float = 1.0           # Young's modulus E (Pa)
    b: float = 0.0           # Kelvin–Voigt viscosity (Pa·s)
    rho: float = 1.0         # density (kg/m³)
    L: float = 1.0           # length (m)
    f: float = 0.0           # uniform body force (N/m³); Example 2: −1
    v0: object = -1.0        # initial velocity (m/s): number, function or table; < 0 moves left
    u0: object = 0.0         # initial displacement (m): number, function or table
    obstacle: str = "rigid"  # 'rigid' (Signorini) or 'elastic' (spring R = k U⁻)
    k: float = 100.0         # spring stiffness of the elastic obstacle (Pa/m; N/m with A)
    N: int = 100             # number of elements
    mass: str = "average"    # 'consistent' | 'lumped' | 'average'
    element: str = "p1"      # 'p1' | 'p2' (Lagrange elements of degree 1 or 2)
    far_end: str = "free"    # 'free' | 'clamped': the end without the obstacle
    obstacle_at: object = "left"   # 'left' (x = 0) | 'right' (x = L), or 0 | L
    A: float | None = None   # cross-section (m²); None: per unit cross-section

    def __post_init__(self):
        for name in ("a", "rho", "L"):
            object.__setattr__(self, name, check_positive(name, getattr(self, name)))
        object.__setattr__(self, "b", check_nonnegative("b", self.b))
        object.__setattr__(self, "f", check_finite("f", self.f))
        object.__setattr__(self, "N", check_count("N", self.N, most=MAX_ELEMENTS))
        check_choice("obstacle", self.obstacle, OBSTACLES)
        check_choice("mass", self.mass, MASSES)
        check_choice("element", self.element, tuple(ELEMENTS))
        check_choice("far_end", self.far_end, FAR_ENDS)
        object.__setattr__(self, "obstacle_at", _side(self.obstacle_at, self.L))
        if self.A is not None:
            object.__setattr__(self, "A", check_positive("A", self.A))
        k = check_nonnegative("k", self.k)
        if k == 0 and self.obstacle == "elastic":
            raise InputError("k=0 must be > 0 for an elastic obstacle")
        object.__setattr__(self, "k", k)
        # every node of the element's dofs, the P2 midpoints too (a profile NaN there only
        # was found by the first step, as "the initial state ... too large")
        per = 1 + ELEMENTS[self.element]().interior_dofs
        x = np.linspace(0.0, self.L, per * self.N + 1)
        for name in ("v0", "u0"):
            value = _profile(name, getattr(self, name))
            object.__setattr__(self, name, value)
            _check_values(name, value, x, self.L)
        u = profile_values(self.u0, x)
        end, far = (0, -1) if self.obstacle_at == "left" else (-1, 0)
        where = ("(0,0)", "x=0") if end == 0 else ("(L,0)", "x=L")
        if self.obstacle == "rigid" and self.gap_sign * u[end] < 0:
            value = f"u{where[0]}=u0={self.u0:g}" if isinstance(self.u0, float) \
                else f"u{where[0]}={u[end]:g}"
            raise InputError(f"the initial state violates the rigid obstacle at {where[1]}: "
                             f"{value} {'<' if end == 0 else '>'} 0")
        if self.far_end == "clamped" and abs(u[far]) > 1e-12 * max(1.0, np.abs(u).max()):
            raise InputError(f"u0={u[far]:g} at the clamped end x={x[far]:g} must be 0")

    @property
    def c(self) -> float:
        """Wave speed √(a/ρ)."""
        return math.sqrt(self.a / self.rho)

    @property
    def E(self) -> float:
        """Young's modulus (the paper's a)."""
        return self.a

    @property
    def h(self) -> float:
        return self.L / self.N

    @property
    def section(self) -> float:
        """The factor of the matrices and loads: A, or 1 per unit cross-section."""
        return 1.0 if self.A is None else self.A

    @property
    def gap_sign(self) -> float:
        """U = gap_sign·u at the obstacle's end: +1 at x = 0, −1 at x = L."""
        return 1.0 if self.obstacle_at == "left" else -1.0


def _side(value, L: float) -> str:
    if isinstance(value, str):
        return check_choice("obstacle_at", value, SIDES)
    x = check_finite("obstacle_at", value)
    if x == 0.0:
        return "left"
    if abs(x - L) <= 1e-12 * L:
        return "right"
    raise InputError(f"obstacle_at={x:g} must be 'left', 'right', 0 or L={L:g} "
                     f"(the obstacle sits at an end)")


def _check_values(name: str, value, x: np.ndarray, L: float) -> None:
    """A profile covers [0, L] (tables) and is finite at the nodes (functions)."""
    if isinstance(value, Table) and (value.x[0] > 1e-12 * L or value.x[-1] < L * (1 - 1e-12)):
        raise InputError(f"{name}: the table covers [{value.x[0]:g}, {value.x[-1]:g}], "
                         f"not the whole bar [0, {L:g}]")
    if isinstance(value, float):
        return
    try:
        u = profile_values(value, x)
    except Exception as e:   # a user function that fails on an array of abscissae
        raise InputError(f"{name}: the function failed at the nodes ({type(e).__name__}: "
                         f"{e}); it must take an array of x") from None
    bad = ~np.isfinite(u)
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(f"{name}(x={x[i]:g})={u[i]} must be a finite number")
