"""The impacting bar of Do, Raupp & Feijoo: a (visco)elastic bar, obstacle at x = 0.

    ρ u_tt = (a u_x + b u_xt)_x + f   on (0, L),   σ(L) = 0,
    σ = a u_x + b u_xt,   R = −σ(0) the obstacle's reaction on the bar,

    rigid obstacle:   U = u(0, t) ≥ 0,  R ≥ 0,  R·U = 0       (paper (2.10))
    elastic obstacle: R = k U⁻                                 (paper (2.8))

Units: everything is per unit cross-section area.  The semi-discrete equation is the
paper's (2.9) with the density kept:

    ρ M₁ ü + b S u̇ + a S u = f·(1, φ_i) + e₀ R,     (M₁ = (φ_i, φ_j), S = (φ_i', φ_j'))

so M carries ρ, every term is a force, f is a body force per unit volume (N/m³ for a
bar of unit cross-section; with ρ = 1 it equals the paper's f) and the spring
stiffness enters the shared scheme as κ = k itself, with no division by ρ.

The rigid obstacle is one more constrained value for the shared contact-implicit
scheme (``solve(system, …)``); the elastic obstacle is the same scheme with
``stiffness=k``: the one-sided spring is weighted like the elastic force,
β R(U^{n+1}) + (1−2β) R(Uⁿ) + β R(U^{n−1}), and the step's piecewise-linear monotone
equation in U^{n+1} is solved exactly by a semi-smooth Newton step
(:mod:`skfem_beam.contact.penalty`; ≤ 2 iterations for one value).

Why not the paper's splitting kU⁻ = (k/2)(|U| − U), (k/2)U β-weighted and (k/2)|Uⁿ|
explicit ((7.3)(iv)): in contact the halves add up to the linear spring
k[(β/2)U^{n+1} + (1−β)Uⁿ + (β/2)U^{n−1}], i.e. weighted with β/2 < 1/4, which is only
conditionally stable for a stiff spring (Δt < 2/√(ω²(1−2β)), ω² = k/m₀, m₀ the
contact node's mass), and the explicit half keeps any discrete energy from being
conserved.  The implicit law has no step limit for β ≥ 1/4, and the energy
E_β + ½k(β(δU⁻)² + U⁻ⁿU⁻ⁿ⁻¹) is conserved to round-off while the spring stays
compressed or idle (measured: 5e-12), changing only on the steps where it switches.

The paper's exponential shift z = e^{−λt}u is not used: it serves the proof (a
Gronwall argument) and the paper saw no difference between λ = 0 and 0.25; with the
implicit spring the scheme is stable without it, and it would make the energy the
scheme conserves a weighted one.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from .. import methods
from ..errors import InputError
from ..checks import check_choice, check_count, check_finite, check_nonnegative, check_positive
from ..semidiscrete import SceneView, SemiDiscrete
from ..spaces.lagrange import MASSES, LagrangeSpace

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
        lines = open(path, encoding="utf-8").read().splitlines()
    except OSError as e:
        raise InputError(f"{flag} {path}: cannot read it ({e.strerror or e})") from None
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
    far_end: str = "free"    # 'free' | 'clamped': the end without the obstacle
    obstacle_at: object = "left"   # 'left' (x = 0) | 'right' (x = L), or 0 | L
    A: float | None = None   # cross-section (m²); None: per unit cross-section

    def __post_init__(self):
        for name in ("a", "rho", "L"):
            object.__setattr__(self, name, check_positive(name, getattr(self, name)))
        object.__setattr__(self, "b", check_nonnegative("b", self.b))
        object.__setattr__(self, "f", check_finite("f", self.f))
        object.__setattr__(self, "N", check_count("N", self.N))
        check_choice("obstacle", self.obstacle, OBSTACLES)
        check_choice("mass", self.mass, MASSES)
        check_choice("far_end", self.far_end, FAR_ENDS)
        object.__setattr__(self, "obstacle_at", _side(self.obstacle_at, self.L))
        if self.A is not None:
            object.__setattr__(self, "A", check_positive("A", self.A))
        k = check_nonnegative("k", self.k)
        if k == 0 and self.obstacle == "elastic":
            raise InputError("k=0 must be > 0 for an elastic obstacle")
        object.__setattr__(self, "k", k)
        x = np.linspace(0.0, self.L, self.N + 1)
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


def bar_system(bar: Bar) -> SemiDiscrete:
    """P1 semi-discretisation of the bar: M = ρA·M_mass, K = aA·S, B = bA·S (A = 1 per
    unit cross-section), a clamped far end's node dropped, one constrained value at
    the obstacle: u(0) ≥ 0 or u(L) ≤ 0.

    The constraint row is there for both obstacles: the rigid one enforces it, the
    elastic one is a spring on the same value (``Penalty(bar.k)``).
    """
    left = bar.obstacle_at == "left"
    fixed = () if bar.far_end == "free" else ((bar.N,) if left else (0,))
    space = LagrangeSpace(np.linspace(0.0, bar.L, bar.N + 1), bar.mass, fixed)
    n, A = space.n, bar.section
    nodal = space.C.toarray()
    e0, eL = nodal[0], nodal[-1]
    loads = A * space.load_vector(lambda x: np.ones_like(x))[:, None] if bar.f != 0 \
        else np.zeros((n, 0))
    load_time = [lambda t, f=bar.f: np.full(np.shape(t), f)] if bar.f != 0 else []
    u0, v0 = (np.full(n, p) if isinstance(p, float) else space.interpolate(p)
              for p in (bar.u0, bar.v0))
    system = SemiDiscrete(
        M=(bar.rho * A * space.M).tocsr(), K=(bar.a * A * space.S).tocsr(),
        B=(bar.b * A * space.S).tocsr() if bar.b > 0 else None,
        C=sp.csr_matrix((e0 if left else eL)[None, :]),
        lo=np.array([0.0 if left else -np.inf]), hi=np.array([np.inf if left else 0.0]),
        x_contact=np.array([0.0 if left else bar.L]),
        loads=loads, load_time=load_time, u0=u0, v0=v0,
        # mean_u = (1/L)∫u dx: the centre of mass, and the load's potential −fAL·mean_u
        observe={"u0": e0, "uL": eL, "mean_u": space.load_vector(np.ones_like) / bar.L},
        space=space,
        meta={"kind": "bar", "L": bar.L, "a": bar.a, "b": bar.b, "rho": bar.rho,
              "obstacle": bar.obstacle, "k": bar.k, "N": bar.N, "mass": bar.mass,
              "far_end": bar.far_end, "obstacle_at": bar.obstacle_at, "A": bar.A},
        view=SceneView("bar", bar.L))
    if bar.mass == "redistributed":      # no inertia at the contact node (modified mass)
        from ..spaces.redistribution import redistributed
        system = redistributed(system)
    return system




def spring_step_ratio(bar: Bar, dt: float) -> float:
    """ω₀Δt, ω₀ = √(k/m₀): the contact node (mass m₀ = M₀₀) on the spring.  Well above 1
    the β-weighted one-sided spring mis-times each impact on the node and can gain
    energy there (measured: ×36 over Example 2 with k = 1e8, Δt = 1e-3)."""
    share = {"consistent": 1 / 3, "lumped": 1 / 2, "average": 5 / 12}.get(bar.mass, 0.0)
    if share == 0.0:      # a massless contact node has no impact to mis-time
        return 0.0
    m0 = bar.rho * bar.section * bar.h * share
    return math.sqrt(bar.k / m0) * dt


@dataclass
class BarRun:
    """A bar run, as series at the step times tₙ (n = 0, 1, … to T).

    ``force`` is the obstacle reaction R at tₙ: the force of the step centred on tₙ
    (for the spring, its β-weighted value β R^{n+1} + (1−2β) Rⁿ + β R^{n−1}).  The
    start step (u¹ from a Taylor step, placed inside the obstacle) records no force,
    so ``force[0]`` is the spring force at u⁰ for a spring and NaN for the rigid
    obstacle.  Energies: ``kinetic`` ½|δu/Δt|²_M, ``strain`` ½(βδuᵀKδu + uⁿᵀKuⁿ⁻¹)
    (the two halves of the scheme's conserved E_β), ``obstacle`` the spring's
    ½k(β(δU⁻)² + Uⁿ⁻U^{n−1,−}) (the same quadratic form while it is compressed),
    ``energy`` their sum; ``load_potential`` −fAL·ū (ū the mean displacement), so that
    ``energy + load_potential`` is what an elastic bar conserves.  The split needs every
    state: for very long runs (more than ``all_states_limit`` stored values) only
    ``energy`` is given and the split is NaN.
    """
    bar: Bar
    method: str
    t: np.ndarray
    u0: np.ndarray
    uL: np.ndarray
    force: np.ndarray
    kinetic: np.ndarray
    strain: np.ndarray
    obstacle: np.ndarray
    energy: np.ndarray
    load_potential: np.ndarray
    result: object   # the integrator's Result (run to T + Δt, see run_bar)
    every: int = 1   # the series keep every ``every``-th step

    @property
    def gap(self) -> np.ndarray:
        """U(tₙ): u(0, tₙ) for the obstacle at x = 0, −u(L, tₙ) for the one at x = L."""
        return self.u0 if self.bar.obstacle_at == "left" else -self.uL

    @property
    def penetration(self) -> float:
        """max(−U(tₙ)) ≥ 0 over the run (the spring's compression for a spring)."""
        return float(max(0.0, -np.min(self.gap)))

    @property
    def wall_time_s(self) -> float:
        return self.result.wall_time_s


def steps_to(T: float, dt: float) -> int:
    """⌈T/Δt⌉: the steps of a bar run to T (T and Δt checked by the run's Stepping)."""
    return int(np.ceil(T / dt - 1e-9))


def bar_method(bar: Bar, method="contact", solver="auto", restitution: float = 0.0,
               massless: str = "beta"):
    """The bar's method: a method object (:mod:`skfem_beam.methods`) or a word of
    ``methods.law_of`` with ``solver``, ``restitution`` and ``massless``.  An elastic
    obstacle *is* the spring R = kU⁻ of stiffness ``bar.k``, whatever method steps it; a
    rigid one with the penalty method is approximated by springs of ``bar.k``."""
    if isinstance(method, str):
        law = methods.law_of(method, "method")
        method = methods.make(law, solver, restitution, bar.k if law == "penalty" else None,
                              None if massless == "beta" else massless, words=methods.KEYS)
    if bar.obstacle != "elastic":
        return method
    if isinstance(method, methods.MoreauJean):
        raise InputError(f"law={method.name!r} enforces a rigid obstacle; the elastic "
                         "obstacle is a spring (use --law position or penalty)")
    solver, e = (method.solver, method.restitution) \
        if isinstance(method, methods.PositionLevel) else ("auto", 0.0)
    return methods.make("penalty", solver, e, bar.k, method.massless, words=methods.KEYS)


def bar_run(bar: Bar, dt: float, T: float, beta: float = 0.25, method="contact", *,
            frames: int = 200, all_states_limit: int = 4_000_000, **words):
    """The bar's :class:`~skfem_beam.scheme.Run` (not yet driven), to T + Δt, with the
    method of :func:`bar_method` (``words``: its ``solver``, ``restitution``,
    ``massless``).

    rigid + contact: the Signorini condition u(0) ≥ 0 (one constrained value, so the
    step is the projection of Lemma 4.1); rigid + penalty: a one-sided spring of
    stiffness ``bar.k`` stands in for the rigid obstacle (normal compliance); elastic:
    the obstacle *is* the spring R = kU⁻ (either method).  The run goes one step past
    T so that the force centred on t_N is known.  It saves every step (the reaction at
    tₙ comes from step n + 1) and keeps every state as a frame when there are at most
    ``all_states_limit`` values (the energy split needs them); else ``frames`` frames.
    """
    from ..scheme import Stepping
    method = bar_method(bar, method, **words)
    system = bar_system(bar)
    to_T = Stepping(dt, T, beta, massless=method.massless)   # the checks of Δt, T, β
    n_steps = to_T.steps
    every_state = (n_steps + 2) * system.n <= all_states_limit
    stepping = replace(to_T, T=n_steps * dt + dt, frames=n_steps + 1 if every_state else frames)
    if isinstance(method, methods.MoreauJean):   # its energy is its own: no β split
        stepping = replace(stepping, frames=frames)
    return method.build(system, stepping)


def _spring(bar: Bar, method) -> bool:
    return bar.obstacle == "elastic" or getattr(method, "name", method) == "penalty"


class BarSeries:
    """The bar's series at tₙ (n = 0, every, 2·every, … ≤ N), computed from its run's
    saved buffers as the run goes (``columns``, the timeseries.csv contract), or all at
    once (:meth:`bar_run`).  ``exact``: a :class:`skfem_beam.reference.BarExact` whose
    values are written beside the computed ones, or None."""

    def __init__(self, bar: Bar, run, T: float, method: str = "contact", every: int = 1,
                 exact=None):
        self.bar, self.method, self.exact = bar, method, exact
        self.every = check_count("save_every", every)
        self.n_steps = steps_to(T, run.dt)
        self.spring = _spring(bar, method)
        s = run.system
        self.names = list(s.observe)
        self.sign = bar.gap_sign                 # U = sign·(C u), R = sign·λ
        self.end = "u0" if bar.obstacle_at == "left" else "uL"
        Um0 = max(-self.sign * float((s.C @ s.u0)[0]), 0.0)
        self.obstacle0 = 0.5 * bar.k * (Um0 * Um0) if self.spring else 0.0
        self.energy0 = 0.5 * s.v0 @ (s.M @ s.v0) + 0.5 * s.u0 @ (s.K @ s.u0) + self.obstacle0

    def ready(self, run) -> int:
        """Rows whose values are final: the reaction at tₙ needs state n + 1."""
        return min(run.n + 1 if run.done else run.n, self.n_steps + 1)

    def rows(self, run, k0: int, k1: int) -> dict:
        """Every series (BarRun's names) at the states n in [k0, k1) kept by ``every``."""
        n = np.arange(k0, k1)
        n = n[n % self.every == 0]
        bar, dt, beta, s = self.bar, run.dt, run.beta, run.system
        obs = {k: run.obs[n, i] for i, k in enumerate(self.names)}
        u0, first = obs["u0"], n == 0
        force = np.full(n.size, np.nan)
        known = (n >= 1) & (n + 1 <= run.n)      # force at tₙ = the force of step n → n+1
        force[known] = self.sign * run.lam[n[known] + 1, 0]
        Um = np.maximum(-self.sign * obs[self.end], 0.0)
        if self.spring:
            force[first] = bar.k * Um[first]
            Um_prev = np.maximum(-self.sign * run.obs[np.maximum(n - 1, 0),
                                                      self.names.index(self.end)], 0.0)
            Um_prev[first] = Um[first]         # at t = 0: ½k(U⁻)² of the data
            obstacle = 0.5 * bar.k * (beta * (Um - Um_prev) ** 2 + Um * Um_prev)
        else:
            obstacle = np.zeros(n.size)
        kinetic = np.full(n.size, np.nan)
        strain = np.full(n.size, np.nan)
        if run.frame_every == 1 and beta is not None:   # every state kept: the β split
            U, P = run.fr[n], run.fr[np.maximum(n - 1, 0)]
            d = U - P
            Md, Kd = (s.M @ d.T).T, (s.K @ d.T).T
            kinetic = 0.5 * np.einsum("ij,ij->i", d, Md) / dt**2
            strain = 0.5 * (beta * np.einsum("ij,ij->i", d, Kd)
                            + np.einsum("ij,ij->i", U, (s.K @ P.T).T))
            kinetic[first] = 0.5 * s.v0 @ (s.M @ s.v0)     # t = 0: the data themselves
            strain[first] = 0.5 * s.u0 @ (s.K @ s.u0)
            energy = kinetic + strain + obstacle
        else:
            energy = run.energy[n] + obstacle
            energy[first] = self.energy0
        return {"t": n * dt, "u0": u0, "uL": obs["uL"], "force": force, "kinetic": kinetic,
                "strain": strain, "obstacle": obstacle, "energy": energy,
                "load_potential": -bar.f * bar.section * bar.L * obs["mean_u"]}

    def columns(self, run, k0: int, k1: int) -> dict:
        """The timeseries.csv columns of the rows in [k0, k1)."""
        r = self.rows(run, k0, k1)
        cols = {"t": r["t"], "u_0": r["u0"], "u_L": r["uL"], "contact_force": r["force"],
                "energy": r["energy"], "energy_kinetic": r["kinetic"],
                "energy_strain": r["strain"], "energy_obstacle": r["obstacle"]}
        if self.bar.f != 0:
            cols["load_potential"] = r["load_potential"]
        ex = self.exact
        if ex is not None:
            t = r["t"]
            cols.update(u_0_exact=ex.u(0.0, t), u_L_exact=ex.u(self.bar.L, t),
                        contact_force_exact=ex.contact_force(t))
            if self.bar.f == 0:   # an elastic bar with f = 0 conserves its energy
                cols["energy_exact"] = np.full(t.size, self.energy0)
        return cols

    def bar_run(self, rows: dict, result) -> BarRun:
        """A :class:`BarRun` of ``rows`` (from :meth:`rows`, or the columns of
        :meth:`columns`)."""
        get = {"u0": "u_0", "uL": "u_L", "force": "contact_force", "kinetic": "energy_kinetic",
               "strain": "energy_strain", "obstacle": "energy_obstacle"}
        col = {k: rows[k] if k in rows else rows[get[k]] for k in get}
        potential = rows.get("load_potential", np.zeros(rows["t"].size))
        return BarRun(self.bar, self.method, rows["t"], col["u0"], col["uL"], col["force"],
                      col["kinetic"], col["strain"], col["obstacle"], rows["energy"], potential,
                      result, self.every)


def run_bar(bar: Bar, dt: float, T: float, beta: float = 0.25, method: str = "contact",
            solver: str = "auto", all_states_limit: int = 4_000_000,
            massless: str = "beta") -> BarRun:
    """Integrate the bar with the shared scheme (:func:`bar_run`, driven to its end)."""
    from ..scheme import drive
    run = bar_run(bar, dt, T, beta, method, solver=solver,
                  all_states_limit=all_states_limit, massless=massless)
    drive(run)
    series = BarSeries(bar, run, T, method)
    return series.bar_run(series.rows(run, 0, series.ready(run)), run.result())


def l2_time(e: np.ndarray, dt: float) -> float:
    """Discrete L²(0, T) norm √(Δt Σₙ eₙ²) (samples that are NaN, e.g. force[0], skipped)."""
    e = np.asarray(e, dtype=float)
    return float(np.sqrt(dt * np.sum(e[np.isfinite(e)] ** 2)))


def errors(run: BarRun, exact) -> dict:
    """L²-in-time errors of u(0,·), u(L,·) and the reaction R against ``exact``
    (a :class:`skfem_beam.reference.BarExact`), and the largest pointwise ones."""
    t, dt = run.t, run.result.dt * run.every
    e = {"u0": run.u0 - exact.u(0.0, t), "uL": run.uL - exact.u(run.bar.L, t),
         "force": run.force - exact.contact_force(t)}
    out = {f"l2_{k}": l2_time(v, dt) for k, v in e.items()}
    out.update({f"max_{k}": float(np.nanmax(np.abs(v))) for k, v in e.items()})
    return out


def contact_periods(t: np.ndarray, force: np.ndarray, merge: float = 0.0
                    ) -> list[tuple[float, float]]:
    """Maximal runs of steps with a positive reaction, as (first, last) times; runs
    separated by less than ``merge`` seconds count as one (the chatter of a grazing
    separation)."""
    on = np.nan_to_num(force, nan=0.0) > 0
    on[0] = on[0] or (on.size > 1 and on[1])      # the start step of an impact at t = 0
    edges = np.flatnonzero(np.diff(np.concatenate([[0], on.astype(int), [0]])))
    periods: list[tuple[float, float]] = []
    for a, b in zip(edges[::2], edges[1::2]):
        if periods and t[a] - periods[-1][1] < merge:
            periods[-1] = (periods[-1][0], float(t[b - 1]))
        else:
            periods.append((float(t[a]), float(t[b - 1])))
    return periods


def energy_report(run: BarRun) -> dict:
    """Energy before the first contact and just after it ends (E + load potential).

    The exact elastic bar (b = 0) conserves it, so ``loss`` is the scheme's own.  Runs
    of contact less than a tenth of a wave transit L/c apart count as one period.
    """
    E = run.energy + run.load_potential
    bar = run.bar
    periods = contact_periods(run.t, run.force, merge=0.1 * bar.L / bar.c)
    out = {"energy_initial": float(E[0]), "energy_final": float(E[-1]),
           "contact_periods": periods}
    if periods:
        i0 = int(np.searchsorted(run.t, periods[0][0]))
        i1 = int(np.searchsorted(run.t, periods[0][1])) + 1
        before = float(E[max(i0 - 1, 0)])
        out["energy_before_contact"] = before
        if i1 < E.size:
            after = float(E[i1])
            out.update(energy_after_contact=after, energy_loss=before - after,
                       energy_loss_relative=(before - after) / abs(before) if before else None)
    return out
