"""The bar's method, its run and its series (energies, reaction).

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

from dataclasses import dataclass, replace

import numpy as np

from .. import methods
from ..errors import InputError
from ..checks import check_count
from .problem import Bar
from .system import bar_system

# stored values ((steps + 2) × unknowns) up to which a bar run keeps every state as a
# frame, which the energy split into kinetic and strain needs
ALL_STATES_LIMIT = 4_000_000


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
               massless: str = "beta", beta: float | None = None):
    """The bar's method: a method object (:mod:`skfem_beam.methods`) or a word of
    ``methods.law_of`` with ``solver``, ``restitution`` and ``massless``; ``beta`` sets
    the β-scheme's β (None: the method object's own, or the bar's 1/4 with a word).  An
    elastic obstacle *is* the spring R = kU⁻ of stiffness ``bar.k``, whatever method steps
    it; a rigid one with the penalty method is approximated by springs of ``bar.k``."""
    if isinstance(method, str):
        law = methods.law_of(method, "method")
        method = methods.make(law, solver, restitution, bar.k if law == "penalty" else None,
                              None if massless == "beta" else massless, words=methods.KEYS,
                              params={"beta": methods.BAR_BETA if beta is None else beta})
    method = methods.with_beta(method, beta)
    if bar.obstacle != "elastic":
        return method
    if isinstance(method, methods.MoreauJean):
        raise InputError(f"law={method.name!r} enforces a rigid obstacle; the elastic "
                         "obstacle is a spring (use --law position or penalty)")
    solver, e = (method.solver, method.restitution) \
        if isinstance(method, methods.PositionLevel) else ("auto", 0.0)
    return methods.make("penalty", solver, e, bar.k, method.massless, words=methods.KEYS,
                        params={"beta": method.beta})


def bar_run(bar: Bar, dt: float, T: float, beta: float | None = 0.25, method="contact", *,
            frames: int = 200, all_states_limit: int = ALL_STATES_LIMIT, **words):
    """The bar's :class:`~skfem_beam.scheme.Run` (not yet driven), to T + Δt, with the
    method of :func:`bar_method` (``words``: its ``solver``, ``restitution``,
    ``massless``; ``beta`` the method's β, None: a method object's own).

    rigid + contact: the Signorini condition u(0) ≥ 0 (one constrained value, so the
    step is the projection of Lemma 4.1); rigid + penalty: a one-sided spring of
    stiffness ``bar.k`` stands in for the rigid obstacle (normal compliance); elastic:
    the obstacle *is* the spring R = kU⁻ (either method).  The run goes one step past
    T so that the force centred on t_N is known.  It saves every step (the reaction at
    tₙ comes from step n + 1) and keeps every state as a frame when there are at most
    ``all_states_limit`` values (the energy split needs them); else ``frames`` frames.
    """
    from ..scheme import Stepping
    method = bar_method(bar, method, beta=beta, **words)     # the check of β
    system = bar_system(bar)
    to_T = Stepping(dt, T, massless=method.massless)   # the checks of Δt, T
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
            solver: str = "auto", all_states_limit: int = ALL_STATES_LIMIT,
            massless: str = "beta") -> BarRun:
    """Integrate the bar with the shared scheme (:func:`bar_run`, driven to its end)."""
    from ..scheme import drive
    run = bar_run(bar, dt, T, beta, method, solver=solver,
                  all_states_limit=all_states_limit, massless=massless)
    drive(run)
    series = BarSeries(bar, run, T, method)
    return series.bar_run(series.rows(run, 0, series.ready(run)), run.result())
