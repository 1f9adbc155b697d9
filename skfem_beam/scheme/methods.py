"""How a run steps in time: the integrator and its contact law as one object, as Siconos
pairs a one-step integrator with a non-smooth law.

- :class:`PositionLevel` ``(solver="auto", restitution=0.0, massless="beta", params=(),
  beta=None)``: the papers' contact-implicit β-scheme, exact contact at position level
  (the step's QP solved by ``solver``: a name of ``contact.STEP_SOLVERS`` or a law
  object), with a Newton coefficient of restitution e > 0 if asked (Paoli–Schatzman);
- :class:`Penalty` ``(stiffness, ..., beta=None)``: the same β-scheme with the obstacles as
  one-sided springs (normal compliance);
- :class:`MoreauJean` ``(theta=0.5, restitution=0.0)``: the θ-scheme with contact at
  velocity level (a Newton impact law), what Siconos and LMGC90 users run.

The β-scheme's methods carry its Newmark β, as Moreau–Jean carries its θ (None: the
method's default, the papers' 1/2 for exact contact and 1/4 for springs); Moreau–Jean has
no β.  Each owns its checks, its units and how it builds its run
(``method.build(system, stepping)``: a :class:`.run.Run` of its one-step integrator,
:class:`.beta.BetaScheme` or :class:`.moreau_jean.MoreauJeanScheme`);
:func:`.solve.solve` takes one as ``method=``.
They are importable from :mod:`skfem_beam.methods` too, where the command line's and the
scene file's words name them (``methods.make``).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar, Union

import numpy as np

from ..checks import (check_beta, check_choice, check_nonnegative, check_positive,
                      check_restitution)
from ..contact import ContactLaw, resolve
from ..contact.penalty import Penalty as PenaltyLaw
from ..errors import Deferred, InputError
from .beta import BetaScheme
from .moreau_jean import NAME as MOREAU_JEAN, MoreauJeanScheme, check_theta
from .run import Run
from .stepping import MASSLESS


def mass_scale(system) -> float:
    """What the semi-discrete equation is divided by: ρA (kg/m) for a beam whose mass per
    length is known (its equation is mass-normalised, docs/design.md §1), else 1 (a bar's
    matrices carry ρ or ρA themselves)."""
    view = system.view
    if view is not None and view.kind == "beam" and view.rho_S:
        return view.rho_S
    return 1.0


def beta_run(method, system, stepping) -> Run:
    """A run of the β-scheme with ``method``'s law, β and massless rows' stepping
    (PositionLevel's and Penalty's build)."""
    stepping = replace(stepping, massless=method.massless)
    with Deferred():               # signals wait while the kernels compile or load
        scheme = BetaScheme(system, stepping, method.law(system), method.beta)
    return Run(scheme)


def with_beta(method, beta: float | None):
    """``method`` with the β-scheme's β ``beta`` (None: as it is).  Moreau–Jean has no β:
    ``beta`` is checked and not used."""
    if beta is None:
        return method
    if isinstance(method, MoreauJean):
        check_beta(beta)
        return method
    return replace(method, beta=beta)


@dataclass(frozen=True)
class PositionLevel:
    """The β-scheme with exact contact at position level; ``massless``: how the massless
    rows of a redistributed mass step ("beta" or "quasi-static", see Stepping);
    ``params``: values of the solver's own parameters (its law's ``parameters`` table),
    a dict or (name, value) pairs; ``beta``: Newmark's β in [0, 1/2] (None: 1/2, the
    papers' for exact contact)."""
    solver: Union[str, ContactLaw] = "auto"
    restitution: float = 0.0
    massless: str = "beta"
    params: tuple = ()
    beta: float | None = None
    name: ClassVar[str] = "position"
    default_beta: ClassVar[float] = 0.5
    theta: ClassVar[None] = None

    def __post_init__(self):
        object.__setattr__(self, "restitution", check_restitution(self.restitution))
        check_choice("massless", self.massless, MASSLESS)
        object.__setattr__(self, "params", tuple(dict(self.params).items()))
        self.law(None)      # the solver's name, its parameters, restitution beside it
        object.__setattr__(self, "beta", _beta(self))

    def law(self, system) -> ContactLaw:
        return resolve(self.solver, None, self.restitution, dict(self.params))

    def build(self, system, stepping) -> Run:
        return beta_run(self, system, stepping)


@dataclass(frozen=True)
class Penalty:
    """The β-scheme with one-sided springs of ``stiffness`` at the obstacles: N/m for a
    beam whose mass per length is known and for a bar with a cross-section, Pa/m for a bar
    per unit cross-section; ``equation_units``: the number is already in the units of the
    semi-discrete equation (per unit mass for a beam).
    ``damping``: a dashpot beside each spring (Kelvin–Voigt, N·s/m in the same units as
    ``stiffness``), the supports' own damping; ``implicit``: the whole spring force at
    t_{n+1} (contact.penalty: the regularisation whose limit is the exact step).
    ``stiffness`` and ``damping`` are one number, or a tuple of one per obstacle (in the
    order of ``Obstacles.parts``: a scene file's [[obstacles]]) for a one-plane beam.
    ``beta``: Newmark's β in [0, 1/2] (None: 1/4, the papers' for springs)."""
    stiffness: float | tuple[float, ...]
    equation_units: bool = False
    massless: str = "beta"
    damping: float | tuple[float, ...] = 0.0
    implicit: bool = False
    beta: float | None = None
    name: ClassVar[str] = "penalty"
    default_beta: ClassVar[float] = 0.25
    theta: ClassVar[None] = None

    def __post_init__(self):
        object.__setattr__(self, "stiffness", _one_or_each("stiffness", self.stiffness,
                                                           check_positive))
        object.__setattr__(self, "damping", _one_or_each("damping", self.damping,
                                                         check_nonnegative))
        check_choice("massless", self.massless, MASSLESS)
        object.__setattr__(self, "beta", _beta(self))

    def law(self, system) -> ContactLaw:
        view = None if system is None else system.view
        if not self.equation_units and view is not None and view.kind == "beam" \
                and not view.rho_S:     # N/m of a beam known by k² alone: it was taken
            raise InputError(          # per unit mass, silently (8.4× softer, measured)
                f"Penalty stiffness={self.stiffness} is in N/m, which needs the beam's mass "
                "per length ρS (this beam gives k² only): give it rho_S (Beam(L, k2, "
                "rho_S) or Beam.physical), or the stiffness per unit mass with "
                "equation_units=True")
        scale = 1.0 if self.equation_units or system is None else mass_scale(system)
        k, c = np.asarray(self.stiffness), np.asarray(self.damping)
        problem = None if system is None else system.meta.get("problem")
        if problem is not None and problem.planes == 1:     # one per obstacle: all of them
            count = len(problem.obstacles.parts) or 1
            for name, v in (("stiffness", k), ("damping", c)):
                if v.size > 1 and v.size != count:
                    raise InputError(f"Penalty {name}: {v.size} values for {count} "
                                     "obstacle(s): give one per obstacle, in their order, "
                                     "or one for all")
        return PenaltyLaw(k / scale, c / scale, self.implicit)     # the one conversion

    def build(self, system, stepping) -> Run:   # the quasi-static massless rows refuse springs
        return beta_run(self, system, stepping)


def _beta(method) -> float:
    """The β-scheme method's β, checked (None: the method's default)."""
    return check_beta(method.default_beta if method.beta is None else method.beta)


def _one_or_each(name: str, value, check):
    """A number (checked by ``check``), or a tuple of one per obstacle, each checked."""
    if np.ndim(value) == 0:
        return check(name, value)
    values = tuple(np.asarray(value, dtype=float).ravel().tolist())
    if not values:
        raise InputError(f"{name}: give one number or one per obstacle")
    return tuple(check(f"{name}[{i}]", v) for i, v in enumerate(values))


@dataclass(frozen=True)
class MoreauJean:
    """Moreau–Jean: θ ∈ [1/2, 1], Newton restitution e ∈ [0, 1] (see
    :mod:`.moreau_jean`); it has θ where the β-scheme has β, and no β."""
    theta: float = 0.5
    restitution: float = 0.0
    name: ClassVar[str] = MOREAU_JEAN
    massless: ClassVar[str] = "beta"

    def __post_init__(self):
        object.__setattr__(self, "theta", check_theta(self.theta))
        object.__setattr__(self, "restitution", check_restitution(self.restitution))

    def build(self, system, stepping) -> Run:
        with Deferred():           # signals wait while the kernels compile or load
            scheme = MoreauJeanScheme(system, stepping, self.theta, self.restitution)
        return Run(scheme)


Method = Union[PositionLevel, Penalty, MoreauJean]


__all__ = ["Method", "MoreauJean", "Penalty", "PositionLevel", "mass_scale", "with_beta"]
