"""The time grid of a run and what a run returns: plain data, checked once."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..checks import check_choice, check_count, check_positive

MAX_STEPS = 10**10        # beyond this a run is a hang, not a computation
LOAD_WINDOWS = ("forward", "centered")
MASSLESS = ("beta", "quasi-static")


@dataclass(frozen=True)
class Stepping:
    """Δt and T of the run, and what is kept of it (β is the β-scheme method's:
    :class:`.methods.PositionLevel`, :class:`.methods.Penalty`).

    ``save_every``: keep every n-th state in the series; ``frames``: field frames kept
    (about); ``load_window``: fⁿ averages f over [tₙ, tₙ+Δt] ("forward", the papers'
    choice, first order) or [tₙ−Δt/2, tₙ+Δt/2] ("centered", second order);
    ``growth_limit``: the run is unstable when its energy exceeds this many times the
    a-priori bound (√E¹ + Σ‖Gⁿ‖_{N⁻¹}Δt)² (N = M, or M + βΔt²K when M has massless
    rows: see operators.load_norms); ``massless``: how dofs without inertia (a
    redistributed mass) step, "beta" (the β-weighted K row) or "quasi-static"
    (equilibrium at t_{n+1}), see scheme.operators.
    """
    dt: float
    T: float
    save_every: int = 1
    frames: int = 200
    load_window: str = "forward"
    growth_limit: float = 10.0
    massless: str = "beta"

    def __post_init__(self):
        dt, T = check_positive("dt", self.dt), check_positive("T", self.T)
        object.__setattr__(self, "dt", dt)
        object.__setattr__(self, "T", T)
        object.__setattr__(self, "save_every", check_count(
            "save_every", self.save_every, most=2**62,
            beyond="the loop counts in 64 bits (a row every more states than the run has "
                   "keeps state 0 only)"))
        object.__setattr__(self, "frames", check_count("frames", self.frames))
        object.__setattr__(self, "growth_limit", check_positive("growth_limit",
                                                                 self.growth_limit))
        check_choice("load_window", self.load_window, LOAD_WINDOWS)
        check_choice("massless", self.massless, MASSLESS)
        if self.steps < 2:
            raise InputError(f"dt={dt:g} must be less than T={T:g}: a run computes "
                             "⌈T/dt⌉ ≥ 2 steps")
        if self.steps > MAX_STEPS:
            raise InputError(f"T/dt = {self.steps:.3g} steps is more than {MAX_STEPS:.0e}: "
                             "raise dt or shorten T")

    @property
    def steps(self) -> int:
        """N = ⌈T/Δt⌉: the run computes u¹ … u^N."""
        return int(math.ceil(self.T / self.dt - 1e-9))

    @property
    def frame_every(self) -> int:
        return max(1, self.steps // self.frames)


class Named(dict):
    """A result's table by name (observed, velocity, work): a missing name says which
    there are (a bare KeyError did not)."""

    def __missing__(self, key):
        raise KeyError(f"{key!r} is not in this run's table; it holds: {', '.join(self)}")


@dataclass
class Result:
    """What a run returns, in the spirit of ``scipy.integrate.solve_ivp``.

    ``t``: saved times; ``observed[name]`` and ``velocity[name]``: observed values and
    their backward-difference velocities (uⁿ − uⁿ⁻¹)/Δt; ``energy``: ½E_β^n (the
    scheme's discrete energy, halved so that it tends to ½|u̇|² + ½a(u,u));
    ``contact_force``: nodal contact forces λ (saved × m, force per unit mass per
    length, m²/s² for the beam); ``frames_t``, ``frames_u``, ``frames_v`` (backward
    difference velocity), ``frames_force`` (λ): decimated coefficient vectors;
    ``status``: "success" or "unstable"; ``message`` says why; ``beta``: the
    β-scheme's β (None for Moreau–Jean), ``theta``: Moreau–Jean's θ (None for the
    β-scheme); ``solver``: the contact law's name; ``work``: the damping, load-input and contact work done since state 1
    (at the saved times, in the units of ``energy``): the scheme's identity
    energy − energy[0] + work["damping"] = work["input"] + work["contact"] holds to
    round-off (impacts lose energy: the contact work is ≤ 0 for exact contact);
    ``impact_events``: one row per impact (see ``Run.impact_events``).
    """
    t: np.ndarray
    observed: dict
    velocity: dict
    energy: np.ndarray
    contact_force: np.ndarray
    frames_t: np.ndarray
    frames_u: np.ndarray
    frames_v: np.ndarray
    frames_force: np.ndarray
    status: str
    message: str
    steps: int
    dt: float
    T: float
    beta: float | None
    theta: float | None
    solver: str
    wall_time_s: float
    max_nodal_violation: float
    max_penetration: float
    max_penetration_below: float
    max_penetration_above: float
    impacts: int
    contact_fraction: float
    qp_iterations: int
    work: dict = field(repr=False)
    impact_events: dict = field(repr=False)
    system: object = field(repr=False)
    springs: bool = False    # the law's obstacles are springs (contact.base.ContactLaw)

    @property
    def success(self) -> bool:
        return self.status == "success"
