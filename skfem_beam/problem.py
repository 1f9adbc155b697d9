"""Plain, validated data objects describing a scene.

Each object checks its inputs where it is built (with :mod:`skfem_beam.checks`), so the
Python API and the command line refuse bad values the same way: an
:class:`~skfem_beam.errors.InputError` whose message names the value and what is allowed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .checks import (MAX_ELEMENTS, check_beta, check_bound, check_choice,  # noqa: F401
                     check_count, check_finite, check_nonnegative, check_positive,
                     check_ratio)
from .errors import InputError
from .timefunctions import Constant, derivative
from .spaces.ends import DEFAULT_ENDS, END_CONDITIONS, check_ends, fixed_dofs, support_nodes

Profile = Callable[[np.ndarray], np.ndarray]   # g(x), u0(x), ...: vectorised in x
TimeFunction = Callable[[np.ndarray], np.ndarray]  # a(t): vectorised in t


L_RANGE = (1e-6, 1e6)   # metres: from a micro-beam to a 1000 km line


def _constant(c: float) -> Profile:
    return lambda x: np.full(np.shape(x), c, dtype=float)


@dataclass(frozen=True)
class Material:
    """Young's modulus ``E`` (Pa) and density ``rho`` (kg/m³)."""
    E: float
    rho: float

    def __post_init__(self):
        object.__setattr__(self, "E", check_positive("E", self.E))
        object.__setattr__(self, "rho", check_positive("rho", self.rho))


@dataclass(frozen=True)
class Section:
    """Second moment of area ``I`` (m⁴) and area ``A`` (m²) of a cross-section.  ``I``
    bends the first plane (v, along y: I_z in the usual axes); ``I_w``: the second
    moment for the second plane (w, along z: I_y), None: the same as I (round sections)."""
    I: float  # noqa: E741  (the engineer's name)
    A: float
    I_w: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "I", check_positive("I", self.I))
        object.__setattr__(self, "A", check_positive("A", self.A))
        if self.I_w is not None:
            object.__setattr__(self, "I_w", check_positive("I_w", self.I_w))

    @classmethod
    def tube(cls, outer_diameter: float, wall: float) -> "Section":
        """A round tube: I = π(D⁴ − d⁴)/64, A = π(D² − d²)/4, d = D − 2·wall."""
        D = check_positive("outer_diameter", outer_diameter)
        wall = check_positive("wall", wall)
        if wall >= D / 2:
            raise InputError(f"wall={wall:g} must be less than the outer radius {D / 2:g} "
                             "(a solid rod: [section] rod = { diameter = d }, Section.rod)")
        d = D - 2 * wall
        return cls(math.pi * (D**4 - d**4) / 64, math.pi * (D**2 - d**2) / 4)

    @classmethod
    def rod(cls, diameter: float) -> "Section":
        """A solid round rod: I = πD⁴/64, A = πD²/4."""
        D = check_positive("diameter", diameter)
        return cls(math.pi * D**4 / 64, math.pi * D**2 / 4)

    @classmethod
    def rect(cls, b: float, h: float) -> "Section":
        """A b × h rectangle, h along the first plane (v): I = bh³/12, A = bh, and
        I_w = hb³/12 for bending along b (the second plane, w)."""
        b, h = check_positive("b", b), check_positive("h", h)
        return cls(b * h**3 / 12, b * h, h * b**3 / 12)


@dataclass(frozen=True)
class Beam:
    """Euler–Bernoulli beam ρA u_tt + (EI u'')'' = ρA f on [0, L] (end conditions:
    BeamProblem.ends), solved mass-normalised: divided by ρA_ref (docs/design.md, Units).

    ``Beam(L, k2, rho_S)``: the papers' uniform form, k2 = EI/(ρA) (m⁴/s²); ``rho_S``
    (ρA, kg/m) only converts forces to newtons and energies to joules, and is needed for
    loads given in N or N/m.  :meth:`physical` builds it from a Material and a Section;
    :meth:`stepped` a piecewise-uniform beam, whose ``segments`` are (x_end, EI, ρA) and
    whose k2, rho_S are the first segment's (the reference of the mass-normalisation).
    ``k2_w``: EI_w/(ρA), the bending stiffness of the second plane (w) of a two-plane
    scene; None: k2 (a round section); inf: a stepped beam whose segments' I_w/I differ
    (refused in two planes).
    """
    L: float
    k2: float
    rho_S: float | None = None
    segments: tuple[tuple[float, float, float], ...] = ()
    k2_w: float | None = None

    def __post_init__(self):
        L = check_positive("L", self.L)
        if not L_RANGE[0] <= L <= L_RANGE[1]:   # the cubic bases lose all accuracy outside
            raise InputError(f"L={L:g} m must lie in [{L_RANGE[0]:g}, {L_RANGE[1]:g}] m")
        object.__setattr__(self, "L", L)
        object.__setattr__(self, "k2", check_positive("k2", self.k2))
        if self.rho_S is not None:
            object.__setattr__(self, "rho_S", check_positive("rho_S", self.rho_S))
        if self.segments and (self.rho_S is None or abs(self.segments[-1][0] - self.L)
                              > 1e-12 * self.L):
            raise InputError("Beam.segments: build a stepped beam with Beam.stepped(...)")
        if self.k2_w is not None and not math.isinf(self.k2_w):
            object.__setattr__(self, "k2_w", check_positive("k2_w", self.k2_w))

    @classmethod
    def physical(cls, L: float, material: Material, section: Section) -> "Beam":
        """Uniform beam: k2 = EI/(ρA), rho_S = ρA (and k2_w = EI_w/(ρA))."""
        EI, rhoA = material.E * section.I, material.rho * section.A
        k2_w = None if section.I_w is None else material.E * section.I_w / rhoA
        return cls(L, EI / rhoA, rhoA, k2_w=k2_w)

    def plane_w(self) -> "Beam":
        """The same beam bending in the second plane: k2 → k2_w."""
        if self.k2_w is None:
            return self
        if math.isinf(self.k2_w):
            raise InputError("a stepped beam whose segments' I_y/I_z differ cannot bend in two "
                             "planes: give every segment the same ratio")
        ratio = self.k2_w / self.k2
        segs = tuple((x, EI * ratio, rhoA) for x, EI, rhoA in self.segments)
        return Beam(self.L, self.k2_w, self.rho_S, segs)

    def with_added_mass(self, added: float) -> "Beam":
        """The beam carrying ``added`` kg/m more along its whole length (the fluid inside
        and around a tube: its hydrodynamic mass): ρA → ρA + added, EI unchanged, so k2
        = EI/(ρA + added) and forces in N are (ρA + added)·λ."""
        added = check_nonnegative("[mass] added", added)
        if self.rho_S is None:
            raise InputError("[mass] added needs the beam's own mass per length: give "
                             "[material] and [section], or rho_S")
        scale = self.rho_S / (self.rho_S + added)
        k2_w = None if self.k2_w is None else self.k2_w * scale
        if self.segments:
            segs = tuple((x, EI, rhoA + added) for x, EI, rhoA in self.segments)
            return Beam(self.L, segs[0][1] / segs[0][2], segs[0][2], segs, k2_w)
        return Beam(self.L, self.k2 * scale, self.rho_S + added, k2_w=k2_w)

    @classmethod
    def stepped(cls, parts) -> "Beam":
        """Piecewise-uniform beam from ``parts`` = [(length, Material, Section), ...], left
        to right; the mesh must have a node at every step (BeamProblem refuses it otherwise)."""
        parts = list(parts)
        if not parts:
            raise InputError("Beam.stepped needs at least one (length, Material, Section)")
        segs, x = [], 0.0
        for i, part in enumerate(parts):
            if len(part) != 3 or not isinstance(part[1], Material) \
                    or not isinstance(part[2], Section):
                raise InputError(f"Beam.stepped part {i} must be (length, Material, Section)")
            x += check_positive(f"length of part {i}", part[0])
            segs.append((x, part[1].E * part[2].I, part[1].rho * part[2].A))
        ratios = {1.0 if s.I_w is None else s.I_w / s.I for _, _, s in parts}
        ratio = ratios.pop() if len(ratios) == 1 else math.inf
        EI0, rhoA0 = segs[0][1], segs[0][2]
        k2_w = None if ratio == 1.0 else ratio * EI0 / rhoA0
        if all(s[1] == EI0 and s[2] == rhoA0 for s in segs):
            return cls(x, EI0 / rhoA0, rhoA0, k2_w=k2_w)   # uniform after all
        return cls(x, EI0 / rhoA0, rhoA0, tuple(segs), k2_w)

    @property
    def EI(self) -> float | None:
        """Bending stiffness (N·m²) of the (first) segment, when ρA is known."""
        return None if self.rho_S is None else self.k2 * self.rho_S

    @property
    def steps(self) -> tuple[float, ...]:
        """Abscissae where the section or material changes (mesh nodes needed there)."""
        return tuple(s[0] for s in self.segments[:-1])

    def factors(self, x) -> tuple[np.ndarray, np.ndarray]:
        """(ρA(x)/ρA_ref, EI(x)/EI_ref): ones for a uniform beam."""
        x = np.asarray(x, dtype=float)
        if not self.segments:
            return np.ones(x.shape), np.ones(x.shape)
        seg = np.asarray(self.segments)
        i = np.clip(np.searchsorted(seg[:, 0], x, side="left"), 0, len(seg) - 1)
        return seg[i, 2] / seg[0, 2], seg[i, 1] / seg[0, 1]


LIFTINGS = ("auto", "paper", "static")


@dataclass(frozen=True)
class Support:
    """A support whose transverse displacement is prescribed as φ(t).

    ``amplitude``, ``omega``: φ = amplitude · sin(omega · t) (the papers' default); or
    ``motion``: any time function of :mod:`skfem_beam.timefunctions` (Sine, SumOfSines,
    Table, ...; a plain callable gets φ', φ'' by finite differences).  ``at``: where it
    moves: x = 0 or x = L (a clamped or pinned end) or an intermediate support's x.
    ``lifting``: "paper" (the first paper's h: clamped end at x = 0, free or pinned end at
    L, uniform beam, no intermediate supports), "static" (h solves the discrete static
    problem with u = 1 at the moving support, docs/design.md §1), or "auto" (the paper's
    h where it applies, static elsewhere).  ``direction``: in a two-plane scene, the unit
    vector (dy, dz) the support moves along (default the first plane).
    """
    amplitude: float = 0.0
    omega: float = 0.0
    motion: TimeFunction | None = None
    at: float = 0.0
    lifting: str = "auto"
    direction: tuple[float, float] = (1.0, 0.0)

    def __post_init__(self):
        check_finite("amplitude", self.amplitude)
        check_finite("omega", self.omega)
        object.__setattr__(self, "at", check_finite("at", self.at))
        check_choice("lifting", self.lifting, LIFTINGS)
        object.__setattr__(self, "direction", check_direction("direction", self.direction))
        if self.motion is not None:
            if not callable(self.motion):
                raise InputError(f"motion={self.motion!r} must be a function of t")
            if self.amplitude != 0.0 or self.omega != 0.0:
                raise InputError("give either amplitude/omega (a sine) or motion, not both")

    @property
    def moves(self) -> bool:
        return self.motion is not None or (self.amplitude != 0.0 and self.omega != 0.0)

    def phi(self, t):
        if self.motion is not None:
            return np.asarray(self.motion(np.asarray(t, dtype=float)), dtype=float)
        return self.amplitude * np.sin(self.omega * np.asarray(t, dtype=float))

    def phi_d(self, t):
        if self.motion is not None:
            return np.asarray(derivative(self.motion, 1)(np.asarray(t, dtype=float)))
        return self.amplitude * self.omega * np.cos(self.omega * np.asarray(t, dtype=float))

    def phi_dd(self, t):
        if self.motion is not None:
            return np.asarray(derivative(self.motion, 2)(np.asarray(t, dtype=float)))
        return -self.omega ** 2 * self.phi(t)


def check_direction(name: str, d) -> tuple[float, float]:
    """A unit vector [dy, dz] in the cross-section (normalised here; (0, 0) refused)."""
    if isinstance(d, (str, bytes)) or not hasattr(d, "__len__") or len(d) != 2:
        raise InputError(f"{name}={d!r} must be a pair [dy, dz]")
    dy, dz = check_finite(f"{name}[0]", d[0]), check_finite(f"{name}[1]", d[1])
    norm = math.hypot(dy, dz)
    if norm == 0:
        raise InputError(f"{name}=[0, 0] has no direction")
    return (1.0, 0.0) if (dy, dz) == (1.0, 0.0) else (dy / norm, dz / norm)


def lifting(x, L):
    """The paper's h(x) = 1 − 2s² + 4/3 s³ − 1/3 s⁴, s = x/L: h(0)=1, h'(0)=0, h(L)=0, h''(L)=0."""
    s = np.asarray(x, dtype=float) / L
    return 1 - 2 * s**2 + 4 / 3 * s**3 - s**4 / 3


def lifting_d(x, L):
    """h'(x) of :func:`lifting`: (−4s + 4s² − 4/3 s³)/L."""
    s = np.asarray(x, dtype=float) / L
    return (-4 * s + 4 * s**2 - 4 / 3 * s**3) / L


def lifting_dd(x, L):
    """h''(x) of :func:`lifting`: −4(1 − s)²/L²."""
    s = np.asarray(x, dtype=float) / L
    return -4 * (1 - s) ** 2 / L**2


@dataclass(frozen=True)
class Obstacles:
    """Obstacles g1(x) ≤ u(x) ≤ g2(x), enforced at the mesh nodes (the papers' K_h).

    ``g1``/``g2`` are numbers or vectorised functions of x; ±inf means no obstacle.
    ``breakpoints`` are abscissae the mesh must contain (ends of flat obstacles, point
    stops, kinks): a mesh without them is refused.  ``carried``: the obstacle moves
    with the moving support (False: fixed to the ground); see docs/design.md §1 for the
    bounds this gives in the lifted variable.  :meth:`stops`, :meth:`span` and
    :meth:`combine` build several obstacles (e.g. baffle clearances) as one.
    """
    g1: float | Profile = -np.inf
    g2: float | Profile = np.inf
    breakpoints: tuple[float, ...] = ()
    carried: bool = False
    parts: tuple["Obstacles", ...] = ()
    name: str = ""      # its key path in a scene file (obstacles.1), for its refusals

    def __post_init__(self):
        if not isinstance(self.carried, (bool, np.bool_)):
            raise InputError(f"carried={self.carried!r} must be True or False")
        for name in ("g1", "g2"):
            check_bound(name, getattr(self, name), "x")

    @classmethod
    def stops(cls, x, g1, g2, carried: bool = False, name: str = "") -> "Obstacles":
        """Point stops g1[i] ≤ u(x[i]) ≤ g2[i] (numbers apply to every x; ±inf: one-sided)."""
        xs = np.atleast_1d(np.asarray(x, dtype=float))
        if xs.size == 0:
            raise InputError("Obstacles.stops needs one x or more (x=[] holds no stop)")
        for key, g in (("g1", g1), ("g2", g2)):    # complex: a TypeError, or cast silently
            for v in np.atleast_1d(np.asarray(g, dtype=object)).ravel():
                check_bound(key, v, "x")
        lo = np.broadcast_to(np.asarray(g1, dtype=float), xs.shape)
        hi = np.broadcast_to(np.asarray(g2, dtype=float), xs.shape)
        parts = [cls.point_stops(check_finite(f"x[{i}]", xi), lo[i], hi[i], carried, name)
                 for i, xi in enumerate(xs)]
        return parts[0] if len(parts) == 1 else cls.combine(*parts)

    @classmethod
    def span(cls, a: float, b: float, g1=-np.inf, g2=np.inf, carried: bool = False,
             name: str = "") -> "Obstacles":
        """A profile g1(x) ≤ u ≤ g2(x) over [a, b] (numbers or functions of x), none elsewhere."""
        a, b = check_finite("a", a), check_finite("b", b)
        if b <= a:
            raise InputError(f"span [a={a:g}, b={b:g}] needs a < b")
        check_bound("g1", g1, "x")
        check_bound("g2", g2, "x")

        # a node within the mesh check's tolerance of an end is that end (one a rounding
        # below a was left free)
        tol = 1e-9 * max(1.0, abs(a), abs(b))

        def within(g, outside):         # g is evaluated where the span acts only
            def bound(x):
                x = np.asarray(x, dtype=float)
                out = np.full(x.shape, outside)
                inside = (x >= a - tol) & (x <= b + tol)
                out[inside] = g(x[inside]) if callable(g) else float(g)
                return out
            return bound
        return cls(within(g1, -np.inf), within(g2, np.inf), (a, b), carried, name=name)

    @classmethod
    def combine(cls, *obstacles: "Obstacles") -> "Obstacles":
        """All of ``obstacles`` at once: the highest g1 and the lowest g2 at each x."""
        parts = tuple(q for o in obstacles for q in (o.parts or (o,)))
        if not parts or not all(isinstance(o, Obstacles) for o in parts):
            raise InputError("Obstacles.combine needs one or more Obstacles")

        def g1(x):
            return np.max([o.bounds(x)[0] for o in parts], axis=0)

        def g2(x):
            return np.min([o.bounds(x)[1] for o in parts], axis=0)
        br = tuple(sorted({b for o in parts for b in o.breakpoints}))
        return cls(g1, g2, br, any(o.carried for o in parts), parts)

    def carried_at(self, x: np.ndarray) -> np.ndarray:
        """Whether the obstacle at each x moves with the support (one line if a carried and
        a fixed obstacle both act at one x: their bounds would move differently)."""
        x = np.asarray(x, dtype=float)
        if not self.parts:
            return np.full(x.shape, bool(self.carried))
        on = [(np.isfinite(lo) | np.isfinite(hi), o.carried)
              for o in self.parts for lo, hi in [o.bounds(x)]]
        carried = np.any([f & c for f, c in on], axis=0)
        fixed = np.any([f & (not c) for f, c in on], axis=0)
        both = carried & fixed
        if both.any():
            raise InputError(f"a carried and a fixed obstacle both act at x={x[both][0]:g}; "
                             "each node's obstacles must all be carried or all fixed")
        return carried

    @classmethod
    def point_stops(cls, x: float, g1: float, g2: float, carried: bool = False,
                    name: str = "") -> "Obstacles":
        """Two stops at one abscissa x (the first paper's scene at x = L)."""
        for key, g in (("g1", g1), ("g2", g2)):
            if callable(g):
                raise InputError(f"point stops: {key} must be a number (m; ±inf: no bound)")
            check_bound(key, g, "x")
        g1, g2 = float(g1), float(g2)
        if not g1 < g2:         # where it is built, not at beam_system
            raise InputError(f"{_named(name)}g1 ≥ g2 at x={x:g} (g1={g1:g}, g2={g2:g}); "
                             "obstacles need g1 < g2")

        def lower(z, x=x, g=g1):
            return np.where(np.isclose(z, x, rtol=0, atol=1e-12 * max(1.0, abs(x))), g, -np.inf)

        def upper(z, x=x, g=g2):
            return np.where(np.isclose(z, x, rtol=0, atol=1e-12 * max(1.0, abs(x))), g, np.inf)
        return cls(lower, upper, (float(x),), carried, name=name)

    def owners(self, x: np.ndarray) -> np.ndarray:
        """(len(x), 2): per x the index in ``parts`` of the obstacle whose g1 is the bound
        g1(x) (the highest; ties: the first listed) and of the one whose g2 is g2(x) (the
        lowest), −1 where the bound is infinite; one obstacle (no parts): 0."""
        x = np.asarray(x, dtype=float).ravel()
        parts = self.parts or (self,)
        out = np.full((x.size, 2), -1, np.int64)
        if not x.size:
            return out
        bounds = [o.bounds(x) for o in parts]
        for side, best in ((0, np.argmax), (1, np.argmin)):
            g = np.array([b[side] for b in bounds])
            i = best(g, axis=0)              # the first of equal bounds
            out[:, side] = np.where(np.isfinite(g[i, np.arange(x.size)]), i, -1)
        return out

    def bounds(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(g1(x), g2(x)) as float arrays, checked: no NaN, g1 < g2 everywhere."""
        x = np.asarray(x, dtype=float)
        lo = self.g1(x) if callable(self.g1) else np.full(x.shape, float(self.g1))
        hi = self.g2(x) if callable(self.g2) else np.full(x.shape, float(self.g2))
        lo = np.broadcast_to(np.asarray(lo, dtype=float), x.shape).copy()
        hi = np.broadcast_to(np.asarray(hi, dtype=float), x.shape).copy()
        for key, g in (("g1", lo), ("g2", hi)):
            if np.isnan(g).any():
                raise InputError(f"{_named(self.name)}{key}(x) is NaN at "
                                 f"x={x[np.isnan(g)][0]:g}")
        if np.isposinf(lo).any() or np.isneginf(hi).any():
            raise InputError("g1 may not be +inf and g2 may not be -inf")
        bad = lo >= hi
        if bad.any():
            i = int(np.argmax(bad))
            raise InputError(self._crossing(x[i], lo[i], hi[i]))
        return lo, hi

    def _crossing(self, x: float, g1: float, g2: float) -> str:
        """The refusal of g1 ≥ g2 at x, naming the obstacles whose bounds they are."""
        names = (self.name, self.name)
        if self.parts:
            i, j = self.owners(np.array([x]))[0]
            names = (self.parts[i].name, self.parts[j].name)
        if all(names) and names[0] != names[1]:
            return (f"{names[0]}'s g1={g1:g} ≥ {names[1]}'s g2={g2:g} at x={x:g}; "
                    "obstacles need g1 < g2")
        return (f"{_named(names[0] or names[1])}g1 ≥ g2 at x={x:g} (g1={g1:g}, g2={g2:g}); "
                "obstacles need g1 < g2")


def _named(name: str) -> str:
    """A refusal's prefix naming its obstacle's key path, if it has one."""
    return f"{name}: " if name else ""


@dataclass(frozen=True)
class Load:
    """External load, sum of separable terms profile(x) · a(t).

    ``terms``: per unit mass (m/s², the papers' f̃ of the mass-normalised equation);
    ``forces``: distributed forces in N/m; ``points``: (x, a) point forces a(t) in N;
    ``g``: gravity (m/s², acting as −g·ρA(x) on u).  ``forces`` and ``points`` need the
    beam's ρA (``Beam.physical``, ``Beam.stepped`` or ``rho_S``).  Loads add with ``+``.
    """
    terms: tuple[tuple[Profile, TimeFunction], ...] = ()
    forces: tuple[tuple[Profile, TimeFunction], ...] = ()
    points: tuple[tuple[float, TimeFunction], ...] = ()
    g: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "g", check_finite("g", self.g))
        for i, (x, a) in enumerate(self.points):
            check_finite(f"points[{i}] x", x)
            if not callable(a):
                raise InputError(f"points[{i}]: the force {a!r} must be a function of t")
        for name in ("terms", "forces"):
            for i, (b, a) in enumerate(getattr(self, name)):
                if not (callable(b) and callable(a)):
                    raise InputError(f"{name}[{i}] must be (profile(x), function of t)")

    @classmethod
    def uniform(cls, a: TimeFunction) -> "Load":
        return cls(((_constant(1.0), a),))

    @classmethod
    def distributed(cls, q, time: TimeFunction | None = None) -> "Load":
        """q(x)·time(t) in N/m (q a number or a function of x; time defaults to 1)."""
        b = q if callable(q) else _constant(check_finite("q", q))
        return cls(forces=((b, time or Constant(1.0)),))

    @classmethod
    def point(cls, x: float, P: float, time: TimeFunction | None = None) -> "Load":
        """A point force P·time(t) in N at x (time defaults to 1)."""
        P = check_finite("P", P)
        a = time or Constant(1.0)
        return cls(points=((check_finite("x", x), lambda t: P * np.asarray(a(t))),))

    @classmethod
    def gravity(cls, g: float = 9.81) -> "Load":
        """Self-weight: −g ρA(x) on u (u measured upwards)."""
        return cls(g=g)

    def __add__(self, other: "Load") -> "Load":
        return Load(self.terms + other.terms, self.forces + other.forces,
                    self.points + other.points, self.g + other.g)

    def scaled(self, factor: float) -> "Load":
        """The load times ``factor`` (one plane's share of a direction; 0: no load)."""
        from .timefunctions import Scaled
        if factor == 1.0:
            return self
        if factor == 0.0:
            return Load()
        return Load(tuple((b, Scaled(a, factor)) for b, a in self.terms),
                    tuple((b, Scaled(a, factor)) for b, a in self.forces),
                    tuple((x, Scaled(a, factor)) for x, a in self.points), self.g * factor)


@dataclass(frozen=True)
class Damping:
    """Rayleigh damping B = alpha·M + alpha_K·K (alpha in 1/s, alpha_K in s), plus modal
    damping: the ratio ``modal`` = ζ in every mode (B += M Φ diag(2ζω) Φᵀ M, Φ the
    mass-normalised modes; a dense B, as every mode couples every node).

    The Rayleigh ratio at ω is ζ(ω) = alpha/(2ω) + alpha_K·ω/2; :meth:`ratio` gives the
    pair with ζ at two frequencies.
    """
    alpha: float = 0.0
    alpha_K: float = 0.0
    modal: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "alpha", check_nonnegative("alpha", self.alpha))
        object.__setattr__(self, "alpha_K", check_nonnegative("alpha_K", self.alpha_K))
        object.__setattr__(self, "modal", check_ratio("modal", self.modal))

    @classmethod
    def ratio(cls, zeta: float, f1: float, f2: float) -> "Damping":
        """ζ(2πf1) = ζ(2πf2) = zeta (f in Hz, f1 ≠ f2); between them ζ is a little lower."""
        zeta = check_ratio("zeta", zeta)
        w1, w2 = 2 * math.pi * check_positive("f1", f1), 2 * math.pi * check_positive("f2", f2)
        if f1 == f2:
            raise InputError(f"f1={f1:g} and f2={f2:g} must differ (two frequencies fix "
                             "alpha and alpha_K)")
        # [1/(2ω1) ω1/2; 1/(2ω2) ω2/2] (alpha, alpha_K) = (ζ, ζ)
        return cls(2 * zeta * w1 * w2 / (w1 + w2), 2 * zeta / (w1 + w2))

    @property
    def none(self) -> bool:
        return self.alpha == 0.0 and self.alpha_K == 0.0 and self.modal == 0.0


@dataclass(frozen=True)
class InitialState:
    """u(x,0) = u0(x), u_t(x,0) = v0(x) (functions of x; None means zero).

    ``du0`` (the slope of u0) is used by the interpolants (Hermite: slopes at the nodes;
    B-spline: the tip slope); when omitted it is computed by a five-point difference.
    By default u0, v0 are the lifted u = ũ − hφ (the papers'); ``fixed_frame=True`` reads
    them as the physical ũ, ũ_t (e.g. zero: at rest in the fixed frame).
    """
    u0: Profile | None = None
    v0: Profile | None = None
    du0: Profile | None = None
    fixed_frame: bool = False

    def __post_init__(self):
        for name in ("u0", "v0", "du0"):
            f = getattr(self, name)
            if f is not None and not callable(f):
                raise InputError(f"InitialState {name}={f!r} must be a function of x (None: "
                                 "zero); values at the nodes: wrap them, e.g. lambda x: "
                                 "np.interp(x, nodes, values)")


@dataclass(frozen=True)
class Plane:
    """The second bending plane's load and initial state (``BeamProblem.second``, two
    planes); ``initial`` None: at rest, in the frame the first plane's initial state says."""
    load: Load = field(default_factory=Load)
    initial: InitialState | None = None


@dataclass(frozen=True)
class BeamProblem:
    """A beam scene: beam, support motion, obstacles, load and initial state, on a mesh.

    ``ends`` = (condition at x = 0, condition at x = L), each one of ``clamped``,
    ``pinned``, ``sliding``, ``free`` (see :mod:`skfem_beam.spaces.ends`); ``supports``
    are abscissae of rigid supports u(x_s) = 0, strictly inside (0, L) and at mesh nodes.
    The defaults are the papers' beam, clamped at 0 and free at L.

    ``planes``: 1 (the papers' transverse u) or 2 (displacements v, w in two bending
    planes, the second with the beam's ``k2_w``): then ``load`` and ``initial`` are the
    first plane's and ``second`` (:class:`Plane`) the second's load and initial state
    (:meth:`plane` gives plane k's), ``obstacles`` (flat, g1 ≤ v ≤ g2) act in the first,
    the support moves along ``support.direction``, and ``holes``
    (:class:`~skfem_beam.holes.HoleAt`) bound (v, w) at their nodes.
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
    damping: Damping = field(default_factory=Damping)
    planes: int = 1
    holes: tuple = ()
    second: Plane = field(default_factory=Plane)

    def __post_init__(self):
        self._check_kinds()
        object.__setattr__(self, "ends", check_ends(self.ends))
        self._check_planes()
        object.__setattr__(self, "supports", self._check_supports())
        if self.nodes is None:
            check_count("J", self.J, most=MAX_ELEMENTS)
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
        self._check_break_nodes()
        self._check_load()
        if self.planes == 2:
            self._check_load(self.second.load)
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
        self._check_acting(value_fixed)
        if self.supports:
            s_lo, s_hi = self.obstacles.bounds(np.asarray(self.supports, dtype=float))
            bad = (s_lo > 0) | (s_hi < 0)
            if bad.any():
                i = int(np.argmax(bad))
                raise InputError(f"the obstacles exclude u=0 at the support "
                                 f"x={self.supports[i]:g} (g1={s_lo[i]:g}, g2={s_hi[i]:g})")
        if self.support.moves:
            self._check_moving_support()
        self.obstacles.carried_at(self.nodes[free])   # carried and fixed may not meet

    def _check_break_nodes(self) -> None:
        """Every obstacle's break point and the beam's steps are nodes of the mesh."""
        for b in (*self.obstacles.breakpoints, *self.hole_breakpoints):
            if not 0.0 <= b <= self.beam.L:
                raise InputError(f"obstacle break point x={b:g} lies outside [0, L={self.beam.L:g}]")
            d = np.abs(self.nodes - b).min()
            if d > 1e-9 * self.beam.L:
                owner = [o.name for o in (*(self.obstacles.parts or (self.obstacles,)),
                                          *self.holes) if b in o.breakpoints and o.name]
                raise InputError(f"{_named(owner[0] if owner else '')}the mesh has no node at "
                                 f"the obstacle break point x={b:g} (nearest node {d:.3g} m "
                                 "away); choose J so that it is a node")
        for b in self.beam.steps:
            d = np.abs(self.nodes - b).min()
            if d > 1e-9 * self.beam.L:
                raise InputError(f"the mesh has no node at the beam's step x={b:g} (nearest "
                                 f"node {d:.3g} m away); choose J or nodes so that it is one")

    def _check_acting(self, held: np.ndarray) -> None:
        """Refuse an obstacle that bounds only nodes an end or a support holds (u = 0
        there: it would never act, and the run would say nothing)."""
        for i, part in enumerate(self.obstacles.parts or (self.obstacles,)):
            lo, hi = part.bounds(self.nodes)
            bounds = np.isfinite(lo) | np.isfinite(hi)
            if bounds.any() and not bounds[~held].any():
                x = self.nodes[np.argmax(bounds)]
                raise InputError(f"obstacle {i} bounds u only at x={x:g}, where "
                                 f"{'an end' if x in (0.0, self.beam.L) else 'a support'} "
                                 "holds the beam: it would never act (move it, or free that "
                                 "end)")

    def _check_kinds(self) -> None:
        """The parts' kinds, each refused in one line saying what goes there."""
        for name, kind, example in (("beam", Beam, "Beam(L, k2=...)"),
                                    ("obstacles", Obstacles, "Obstacles(g1=-0.01, g2=0.01)"),
                                    ("initial", InitialState, "InitialState(u0=...)")):
            value = getattr(self, name)
            if not isinstance(value, kind):
                raise InputError(f"BeamProblem {name}= is a {type(value).__name__}: it takes "
                                 f"{example}")

    def _check_planes(self) -> None:
        if self.planes not in (1, 2) or isinstance(self.planes, bool):
            raise InputError(f"planes={self.planes!r} must be 1 or 2 (bending planes)")
        if self.planes == 1:
            given = [name for name, bad in (
                ("holes", bool(self.holes)),
                ("a second plane's load or initial state", self.second != Plane()),
                ("a support direction", self.support.direction != (1.0, 0.0))) if bad]
            if given:
                raise InputError(f"{', '.join(given)} need planes = 2 (the beam bends in one "
                                 "plane here)")
            return
        self.beam.plane_w()          # a stepped beam must bend alike in both planes
        sec = self.second
        if not (isinstance(sec, Plane) and isinstance(sec.load, Load) and
                isinstance(sec.initial, (InitialState, type(None)))):
            raise InputError(f"second={sec!r} must be a Plane(load=Load(...), "
                             "initial=InitialState(...) or None)")
        if self.element not in ("hermite", "bspline"):
            raise InputError(f"element={self.element!r}: two planes take hermite or bspline")
        from .holes import HoleAt
        object.__setattr__(self, "holes", tuple(self.holes))
        for h in self.holes:
            if not isinstance(h, HoleAt):
                raise InputError(f"holes must be HoleAt objects, got {h!r}")
            for b in h.breakpoints:
                if not 0.0 <= b <= self.beam.L:
                    raise InputError(f"hole at x={b:g} lies outside [0, L={self.beam.L:g}]")

    def plane(self, k: int) -> tuple[Load, InitialState]:
        """Plane k's (load, initial state): k = 0 ``load``, ``initial``; k = 1 ``second``'s
        (its initial None: at rest, in the frame ``initial.fixed_frame`` says)."""
        if k == 0:
            return self.load, self.initial
        if k != 1 or self.planes != 2:
            raise InputError(f"plane {k!r}: this problem has planes 0..{self.planes - 1}")
        ini = self.second.initial
        return self.second.load, (InitialState(fixed_frame=self.initial.fixed_frame)
                                  if ini is None else ini)

    @property
    def hole_breakpoints(self) -> tuple[float, ...]:
        return tuple(b for h in self.holes for b in h.breakpoints)

    @property
    def lifting(self) -> str:
        """"paper", "static", or "none" (the support does not move): docs/design.md §1."""
        sup = self.support
        if not sup.moves:
            return "none"
        if sup.lifting == "auto":
            return "paper" if self._paper_lifting_applies() else "static"
        return sup.lifting

    def _paper_lifting_applies(self) -> bool:
        return (self.support.at == 0.0 and self.ends[0] == "clamped"
                and self.ends[1] in ("free", "pinned") and not self.supports
                and not self.beam.segments)

    def _check_moving_support(self) -> None:
        """The moving support must be a clamped/pinned end or an intermediate support."""
        at, L = self.support.at, self.beam.L
        end = 0 if abs(at) <= 1e-9 * L else 1 if abs(at - L) <= 1e-9 * L else None
        if end is not None:
            e = self.ends[end]
            if not END_CONDITIONS[e][0]:
                raise InputError(f"the support moving at x={at:g} is a {e} end, whose "
                                 "displacement is free; only clamped or pinned ends and "
                                 "intermediate supports can move")
        elif not any(abs(at - xs) <= 1e-9 * L for xs in self.supports):
            raise InputError(f"the moving support at={at:g} is neither an end (0 or "
                             f"L={L:g}) nor one of supports={self.supports!r}")
        if self.support.lifting == "paper" and not self._paper_lifting_applies():
            raise InputError(f"lifting='paper' needs the clamped end x=0 moving, a free or "
                             f"pinned end at L, a uniform beam and no intermediate "
                             f"supports (got at={at:g}, ends={self.ends!r}); use 'static'")

    def _check_load(self, ld: Load | None = None) -> None:
        ld, L = ld or self.load, self.beam.L
        if (ld.forces or ld.points) and self.beam.rho_S is None:
            raise InputError("forces in N or N/m need the beam's mass per length: build it "
                             "with Beam.physical(...) or give rho_S")
        for x, _ in ld.points:
            if not 0.0 <= x <= L:
                raise InputError(f"point force at x={x:g} lies outside [0, L={L:g}]")

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
                raise InputError(f"supports[{i}] x={xs:g} must lie on the beam [0, L={L:g}]")
            for end, at in ((0, 0.0), (1, L)):
                if abs(xs - at) <= 1e-9 * L:
                    e = self.ends[end]
                    fix = "clamped" if e == "sliding" else "pinned"
                    hint = "already fixed there" if END_CONDITIONS[e][0] else \
                        f"use ends.{('left', 'right')[end]}={fix!r} instead"
                    raise InputError(f"supports[{i}] x={xs:g} is at the {e} end x={at:g} "
                                     f"({hint}); supports must lie strictly inside (0, "
                                     f"L={L:g})")
            if any(abs(xs - o) <= 1e-9 * L for o in out):
                raise InputError(f"supports[{i}] x={xs:g}: two supports at x={xs:g}; each "
                                 "support needs its own node")
            out.append(xs)
        return tuple(sorted(out))
