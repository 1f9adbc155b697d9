"""How a run steps in time: the integrator and its contact law as one object, as Siconos
pairs a one-step integrator with a non-smooth law.

- :class:`PositionLevel` ``(solver="auto", restitution=0.0, massless="beta")``: the
  papers' contact-implicit β-scheme, exact contact at position level (the step's QP
  solved by ``solver``: a name of ``contact.LAWS`` or a law object), with a Newton
  coefficient of restitution e > 0 if asked (Paoli–Schatzman);
- :class:`Penalty` ``(stiffness)``: the same β-scheme with the obstacles as one-sided
  springs (normal compliance);
- :class:`MoreauJean` ``(theta=0.5, restitution=0.0)``: the θ-scheme with contact at
  velocity level (a Newton impact law), what Siconos and LMGC90 users run.

Each owns its default β (the papers: 1/2 for exact contact, 1/4 for springs), its checks,
its units and how it builds its run (``method.build(system, stepping)``).  The command
line and the scene file name a method by the words of :func:`make` (``law``,
``solver``, ``restitution``, ``stiffness``, ``massless``); this module is the only place
those words are dispatched.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar, Union

from .checks import check_choice, check_nonnegative, check_positive, check_restitution
from .contact import SOLVERS, ContactLaw, resolve
from .contact.penalty import Penalty as PenaltyLaw
from .contact.restitution import Restitution
from .errors import InputError
from .scheme.moreau_jean import NAME as MOREAU_JEAN
from .scheme.stepping import MASSLESS

LAWS = ("position", MOREAU_JEAN, "penalty")   # the classes by name
BAR_BETA = 0.25     # the bar's scheme (7.3) of the third paper: β = 1/4 whatever the law


def mass_scale(system) -> float:
    """What the semi-discrete equation is divided by: ρA (kg/m) for a beam whose mass per
    length is known (its equation is mass-normalised, docs/design.md §1), else 1 (a bar's
    matrices carry ρ or ρA themselves)."""
    view = system.view
    if view is not None and view.kind == "beam" and view.rho_S:
        return view.rho_S
    return 1.0


@dataclass(frozen=True)
class PositionLevel:
    """The β-scheme with exact contact at position level; ``massless``: how the massless
    rows of a redistributed mass step ("beta" or "quasi-static", see Stepping)."""
    solver: Union[str, ContactLaw] = "auto"
    restitution: float = 0.0
    massless: str = "beta"
    name: ClassVar[str] = "position"
    default_beta: ClassVar[float] = 0.5
    theta: ClassVar[None] = None

    def __post_init__(self):
        object.__setattr__(self, "restitution", check_restitution(self.restitution))
        check_choice("massless", self.massless, MASSLESS)
        self.law(None)      # the solver's name and its combination with restitution

    def law(self, system) -> ContactLaw:
        return resolve(self.solver, None, self.restitution)

    def build(self, system, stepping):
        from .scheme import Run
        return Run(system, replace(stepping, massless=self.massless), self.law(system))


@dataclass(frozen=True)
class Penalty:
    """The β-scheme with one-sided springs of ``stiffness`` at the obstacles: N/m for a
    beam whose mass per length is known and for a bar with a cross-section, Pa/m for a bar
    per unit cross-section; ``equation_units``: the number is already in the units of the
    semi-discrete equation (per unit mass for a beam), as ``solve(stiffness=)`` takes it.
    ``damping``: a dashpot beside each spring (Kelvin–Voigt, N·s/m in the same units as
    ``stiffness``), the supports' own damping; ``implicit``: the whole spring force at
    t_{n+1} (contact.penalty: the regularisation whose limit is the exact step)."""
    stiffness: float
    equation_units: bool = False
    massless: str = "beta"
    damping: float = 0.0
    implicit: bool = False
    name: ClassVar[str] = "penalty"
    default_beta: ClassVar[float] = 0.25
    theta: ClassVar[None] = None

    def __post_init__(self):
        object.__setattr__(self, "stiffness", check_positive("stiffness", self.stiffness))
        object.__setattr__(self, "damping", check_nonnegative("damping", self.damping))
        check_choice("massless", self.massless, MASSLESS)

    def law(self, system) -> ContactLaw:
        scale = 1.0 if self.equation_units or system is None else mass_scale(system)
        return PenaltyLaw(self.stiffness / scale, self.damping / scale,  # the one conversion
                          self.implicit)

    def build(self, system, stepping):
        from .scheme import Run     # the quasi-static massless rows refuse springs there
        return Run(system, replace(stepping, massless=self.massless), self.law(system))


@dataclass(frozen=True)
class MoreauJean:
    """Moreau–Jean: θ ∈ [1/2, 1], Newton restitution e ∈ [0, 1] (see
    :mod:`skfem_beam.scheme.moreau_jean`); the Stepping's β is not used."""
    theta: float = 0.5
    restitution: float = 0.0
    name: ClassVar[str] = MOREAU_JEAN
    default_beta: ClassVar[float] = 0.5
    massless: ClassVar[str] = "beta"

    def __post_init__(self):
        from .scheme.moreau_jean import check_theta    # θ's range is the θ-scheme's
        object.__setattr__(self, "theta", check_theta(self.theta))
        object.__setattr__(self, "restitution", check_restitution(self.restitution))

    def build(self, system, stepping):
        from .scheme.moreau_jean import MoreauJean as MoreauJeanRun
        return MoreauJeanRun(system, stepping, self.theta, self.restitution)


Method = Union[PositionLevel, Penalty, MoreauJean]


@dataclass(frozen=True)
class Words:
    """How the front end names its words in error lines (the command line's flags or
    the scene file's keys)."""
    solver: str = "--solver "
    massless: str = "--massless "
    law: str = "--law "
    restitution: str = "--restitution "
    theta: str = "--theta "


FLAGS = Words()
KEYS = Words("solver=", "massless=", "law=", "restitution=", "theta=")   # the Python API's


def _name(word: str) -> str:
    return word.strip().rstrip("=")


def make(law: str = "position", solver: str = "auto", restitution: float = 0.0,
         stiffness: float | None = None, massless: str | None = None,
         words: Words = FLAGS, damping: float = 0.0, theta: float | None = None) -> Method:
    """The method the words name: ``law`` one of LAWS, ``solver`` the position-level
    QP solver, ``stiffness`` and ``damping`` the penalty springs and their dashpots (N/m,
    N·s/m, see :class:`Penalty`), ``massless`` the massless rows' stepping, ``theta``
    Moreau–Jean's θ (None: the defaults)."""
    check_choice(_name(words.law), law, LAWS)
    e = check_restitution(restitution, words.restitution)
    if theta is not None and law != MOREAU_JEAN:
        raise InputError(f"{words.theta}{theta} is Moreau–Jean's θ ({words.law}{MOREAU_JEAN}); "
                         f"{words.law}{law} is a β-scheme: set its β instead")
    if law == MOREAU_JEAN:
        if solver != "auto":
            raise InputError(f"{words.law}{law} solves its own impulse problem: "
                             f"{words.solver}{solver} does not apply")
        if massless is not None:
            raise InputError(f"{words.massless}{massless} applies to the β-scheme "
                             f"({words.law}position); {words.law}{law} does not take it")
        from .scheme.moreau_jean import check_theta
        return MoreauJean(0.5 if theta is None else check_theta(theta, words.theta), e)
    if law == "penalty":     # the registry's checks: no solver, no restitution with springs
        resolve("penalty" if solver == "auto" else solver, stiffness, e)
        return Penalty(stiffness, massless=massless or "beta", damping=damping)
    check_choice(_name(words.solver), solver, SOLVERS)
    return PositionLevel(solver, e, massless or "beta")


def check_massless(massless: str | None, mass: str, name: str = "--massless") -> None:
    """``massless`` (None: not given) is one of MASSLESS, and only for a redistributed
    mass: the others have no massless rows.  ``name``: the flag or key as the user wrote
    it."""
    if massless is None:
        return
    check_choice(name, massless, MASSLESS)
    if mass != "redistributed":
        raise InputError(f"{name} {massless!r} applies to a redistributed mass only (the "
                         f"mass is {mass!r}: it has no massless rows)")


def default_beta(method: Method, kind: str = "beam") -> float:
    """β when none is given: the bar's scheme takes 1/4 (the third paper), a beam the
    method's own (1/2 exact contact, 1/4 springs: the first two papers)."""
    return BAR_BETA if kind == "bar" else method.default_beta


def of(method: Method | str | None, stiffness: float | None = None,
       restitution: float = 0.0) -> Method:
    """A method from :func:`skfem_beam.scheme.solve`'s arguments: a method object, or a
    position-level solver's name / law object with ``stiffness`` (equation units) and
    ``restitution`` as ``contact.resolve`` takes them."""
    if isinstance(method, (PositionLevel, Penalty, MoreauJean)):
        return method
    law = resolve("auto" if method is None else method, stiffness, restitution)
    if isinstance(law, PenaltyLaw):
        return Penalty(law.stiffness, equation_units=True)
    if isinstance(law, Restitution):
        return PositionLevel("auto", law.e)
    return PositionLevel(law if isinstance(method, ContactLaw) else (method or "auto"))


__all__ = ["LAWS", "Method", "MoreauJean", "Penalty", "PositionLevel", "Words", "check_massless",
           "default_beta", "make", "mass_scale", "of"]
