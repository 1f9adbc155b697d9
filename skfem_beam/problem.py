"""Plain, validated data objects describing a scene.

Each object checks its inputs where it is built (with :mod:`skfem_beam.checks`), so the
Python API and the command line refuse bad values the same way: an
:class:`~skfem_beam.errors.InputError` whose message names the value and what is allowed.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .checks import check_beta, check_choice, check_finite, check_positive  # noqa: F401
from .errors import InputError
from .spaces.ends import DEFAULT_ENDS, END_CONDITIONS, check_ends, fixed_dofs, support_nodes

Profile = Callable[[np.ndarray], np.ndarray]   # g(x), u0(x), ...: vectorised in x
TimeFunction = Callable[[np.ndarray], np.ndarray]  # a(t): vectorised in t


def _constant(c: float) -> Profile:
    return lambda x: np.full(np.shape(x), c, dtype=float)


@dataclass(frozen=True)
class Beam:
    """Euler–Bernoulli beam u_tt + k² u_xxxx = f on [0, L] (end conditions: BeamProblem.ends).

    ``rho_S`` (kg/m, mass per unit length) is only used to report forces in newtons.
    """
    L: float
    k2: float
    rho_S: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "L", check_positive("L", self.L))
        object.__setattr__(self, "k2", check_positive("k2", self.k2))
        if self.rho_S is not None:
            object.__setattr__(self, "rho_S", check_positive("rho_S", self.rho_S))


@dataclass(frozen=True)
class Support:
    """Clamped support moving as φ(t) = amplitude · sin(omega · t)."""
    amplitude: float = 0.0
    omega: float = 0.0

    def __post_init__(self):
        check_finite("amplitude", self.amplitude)
        check_finite("omega", self.omega)

    @property
    def moves(self) -> bool:
        return self.amplitude != 0.0 and self.omega != 0.0

    def phi(self, t):
        return self.amplitude * np.sin(self.omega * np.asarray(t, dtype=float))

    def phi_dd(self, t):
        return -self.omega ** 2 * self.phi(t)


def lifting(x, L):
    """The paper's h(x) = 1 − 2s² + 4/3 s³ − 1/3 s⁴, s = x/L: h(0)=1, h'(0)=0, h(L)=0, h''(L)=0."""
    s = np.asarray(x, dtype=float) / L
    return 1 - 2 * s**2 + 4 / 3 * s**3 - s**4 / 3


@dataclass(frozen=True)
class Obstacles:
    """Obstacles g1(x) ≤ u(x) ≤ g2(x), enforced at the mesh nodes (the papers' K_h).

    ``g1``/``g2`` are numbers or vectorised functions of x; ±inf means no obstacle.
    ``breakpoints`` are abscissae the mesh must contain (ends of flat obstacles, point
    stops, kinks): a mesh without them is refused.
    """
    g1: float | Profile = -np.inf
    g2: float | Profile = np.inf
    breakpoints: tuple[float, ...] = ()

    @classmethod
    def point_stops(cls, x: float, g1: float, g2: float) -> "Obstacles":
        """Two stops at one abscissa x (the first paper's scene at x = L)."""
        g1 = check_finite("g1", g1) if np.isfinite(g1) else g1
        g2 = check_finite("g2", g2) if np.isfinite(g2) else g2

        def lower(z, x=x, g=g1):
            return np.where(np.isclose(z, x, rtol=0, atol=1e-12 * max(1.0, abs(x))), g, -np.inf)

        def upper(z, x=x, g=g2):
            return np.where(np.isclose(z, x, rtol=0, atol=1e-12 * max(1.0, abs(x))), g, np.inf)
        return cls(lower, upper, (float(x),))

    def bounds(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(g1(x), g2(x)) as float arrays, checked: no NaN, g1 < g2 everywhere."""
        x = np.asarray(x, dtype=float)
        lo = self.g1(x) if callable(self.g1) else np.full(x.shape, float(self.g1))
        hi = self.g2(x) if callable(self.g2) else np.full(x.shape, float(self.g2))
        lo = np.broadcast_to(np.asarray(lo, dtype=float), x.shape).copy()
        hi = np.broadcast_to(np.asarray(hi, dtype=float), x.shape).copy()
        for name, g in (("g1", lo), ("g2", hi)):
            if np.isnan(g).any():
                raise InputError(f"{name}(x) is NaN at x={x[np.isnan(g)][0]:g}")
        if np.isposinf(lo).any() or np.isneginf(hi).any():
            raise InputError("g1 may not be +inf and g2 may not be -inf")
        bad = lo >= hi
        if bad.any():
            i = int(np.argmax(bad))
            raise InputError(f"g1 ≥ g2 at x={x[i]:g} (g1={lo[i]:g}, g2={hi[i]:g}); "
                             "obstacles need g1 < g2")
        return lo, hi


@dataclass(frozen=True)
class Load:
    """External load f̃(x, t) = Σ_k b_k(x) a_k(t): separable terms (spatial, temporal)."""
    terms: tuple[tuple[Profile, TimeFunction], ...] = ()

    @classmethod
    def uniform(cls, a: TimeFunction) -> "Load":
        return cls(((_constant(1.0), a),))


@dataclass(frozen=True)
class InitialState:
    """u(x,0) = u0(x), u_t(x,0) = v0(x) (functions of x; None means zero).

    ``du0`` (the slope of u0) is used by the interpolants (Hermite: slopes at the nodes;
    B-spline: the tip slope); when omitted it is computed by a five-point difference.
    """
    u0: Profile | None = None
    v0: Profile | None = None
    du0: Profile | None = None


@dataclass(frozen=True)
class BeamProblem:
    """A beam scene: beam, support motion, obstacles, load and initial state, on a mesh.

    ``ends`` = (condition at x = 0, condition at x = L), each one of ``clamped``,
    ``pinned``, ``sliding``, ``free`` (see :mod:`skfem_beam.spaces.ends`); ``supports``
    are abscissae of rigid supports u(x_s) = 0, strictly inside (0, L) and at mesh nodes.
    The defaults are the papers' beam, clamped at 0 and free at L.
    """
    beam: Beam
    obstacles: Obstacles = field(default_factory=Obstacles)
    support: Support = field(default_factory=Support)
    load: Load = field(default_factory=Load)
    initial: InitialState = field(default_factory=InitialState)
    J: int = 19
    element: str = "hermite"
    nodes: np.ndarray | None = None   # x_0 = 0 < x_1 < ... < x_J = L; uniform when None
    ends: tuple[str, str] = DEFAULT_ENDS
    supports: tuple[float, ...] = ()

    def __post_init__(self):
        object.__setattr__(self, "ends", check_ends(self.ends))
        object.__setattr__(self, "supports", self._check_supports())
        if self.nodes is None:
            if isinstance(self.J, bool) or not isinstance(self.J, (int, np.integer)) or self.J < 1:
                raise InputError(f"J={self.J!r} must be a whole number ≥ 1")
            object.__setattr__(self, "nodes", np.linspace(0.0, self.beam.L, int(self.J) + 1))
        else:
            x = np.asarray(self.nodes, dtype=float)
            if x.ndim != 1 or x.size < 2 or not np.isfinite(x).all():
                raise InputError("nodes must be a finite 1-D array of at least two abscissae")
            if np.any(np.diff(x) <= 0):
                raise InputError("nodes must be strictly increasing")
            if abs(x[0]) > 1e-12 * self.beam.L or abs(x[-1] - self.beam.L) > 1e-9 * self.beam.L:
                raise InputError(f"nodes must run from 0 to L={self.beam.L:g}, "
                                 f"got [{x[0]:g}, {x[-1]:g}]")
            x[0], x[-1] = 0.0, self.beam.L
            object.__setattr__(self, "nodes", x)
            object.__setattr__(self, "J", x.size - 1)
        check_choice("element", self.element, ("hermite", "bspline"))
        for b in self.obstacles.breakpoints:
            if not 0.0 <= b <= self.beam.L:
                raise InputError(f"obstacle break point x={b:g} lies outside [0, L={self.beam.L:g}]")
            d = np.abs(self.nodes - b).min()
            if d > 1e-9 * self.beam.L:
                raise InputError(f"the mesh has no node at the obstacle break point x={b:g} "
                                 f"(nearest node {d:.3g} m away); choose J so that it is a node")
        J = self.nodes.size - 1
        value_fixed, slope_fixed = fixed_dofs(J, self.ends,
                                              support_nodes(self.nodes, self.supports))
        n_fixed = int(value_fixed.sum() + slope_fixed.sum())
        if self.element == "bspline" and J < 3 and "free" not in self.ends:
            raise InputError(f"element='bspline' with ends={self.ends!r} needs J ≥ 3 (got "
                             f"J={J}): the two end conditions would share a B-spline")
        if (2 * J + 2 if self.element == "hermite" else J + 3) <= n_fixed:
            raise InputError(f"ends={self.ends!r} and supports={self.supports!r} leave no "
                             f"degree of freedom on J={J} elements; use a finer mesh")
        free = np.flatnonzero(~value_fixed)   # nodes where u is free: obstacle rows live there
        lo, hi = self.obstacles.bounds(self.nodes[free])
        if self.supports:
            s_lo, s_hi = self.obstacles.bounds(np.asarray(self.supports, dtype=float))
            bad = (s_lo > 0) | (s_hi < 0)
            if bad.any():
                i = int(np.argmax(bad))
                raise InputError(f"the obstacles exclude u=0 at the support "
                                 f"x={self.supports[i]:g} (g1={s_lo[i]:g}, g2={s_hi[i]:g})")
        if self.support.moves:
            if self.ends[0] != "clamped" or self.ends[1] not in ("free", "pinned") \
                    or self.supports:
                raise InputError(f"a moving support needs ends=('clamped', 'free') or "
                                 f"('clamped', 'pinned') and no intermediate supports (the "
                                 f"lifting h is the clamped–free one); got ends={self.ends!r}, "
                                 f"supports={self.supports!r}")
            if (np.isfinite(lo) | np.isfinite(hi))[free < J].any():
                raise InputError("a moving support is only supported with obstacles at the "
                                 "tip x = L (where the lifting h vanishes)")

    def _check_supports(self) -> tuple[float, ...]:
        """``supports`` as sorted floats strictly inside (0, L), pairwise distinct."""
        sup = self.supports
        if isinstance(sup, (str, bytes)) or not hasattr(sup, "__iter__"):
            raise InputError(f"supports={sup!r} must be a sequence of abscissae in (0, L)")
        L = self.beam.L
        out = []
        for i, xs in enumerate(sup):
            xs = check_finite(f"supports[{i}]", xs)
            if not 0.0 <= xs <= L:
                raise InputError(f"support x={xs:g} lies outside [0, L={L:g}]")
            for end, at in ((0, 0.0), (1, L)):
                if abs(xs - at) <= 1e-9 * L:
                    e = self.ends[end]
                    hint = "already fixed there" if END_CONDITIONS[e][0] else \
                        f"use ends[{end}]={'clamped' if e == 'sliding' else 'pinned'!r} instead"
                    raise InputError(f"support x={xs:g} is at the {e} end x={at:g} ({hint}); "
                                     f"supports must lie strictly inside (0, L={L:g})")
            if any(abs(xs - o) <= 1e-9 * L for o in out):
                raise InputError(f"two supports at x={xs:g}; each support needs its own node")
            out.append(xs)
        return tuple(sorted(out))
