"""The words that name a method, and the only place they are dispatched.

The method classes (:class:`PositionLevel`, :class:`Penalty`, :class:`MoreauJean`: an
integrator and its contact law as one object) live with the integrators they build, in
:mod:`skfem_beam.scheme.methods`, and are importable from here.  The command line and the
scene file name a method by the words of :func:`make` (``law``, ``solver``,
``restitution``, ``stiffness``, ``massless``, ``theta``, ``beta``).
"""
from __future__ import annotations

from dataclasses import dataclass

from .checks import check_beta, check_choice, check_restitution
from .contact import SOLVERS, resolve
from .contact.registry import check_params
from .errors import InputError
from .scheme.methods import (Method, MoreauJean, Penalty, PositionLevel,  # noqa: F401
                             mass_scale, with_beta)
from .scheme.moreau_jean import NAME as MOREAU_JEAN, check_theta
from .scheme.stepping import MASSLESS

LAWS = ("position", MOREAU_JEAN, "penalty")   # the classes by name
# "contact": the first wave's word for the position-level law (the command line's --method
# contact, the bar's API, the stability map), and summary.json's "method" of a beam run
ALIASES = {"contact": "position"}
BAR_BETA = 0.25     # the bar's scheme (7.3) of the third paper: β = 1/4 whatever the law


@dataclass(frozen=True)
class Words:
    """How the front end names its words in error lines (the command line's flags or
    the scene file's keys)."""
    solver: str = "--solver "
    massless: str = "--massless "
    law: str = "--law "
    restitution: str = "--restitution "
    theta: str = "--theta "
    param: str = "--param "
    stiffness: str = "--stiffness "


FLAGS = Words()
KEYS = Words("solver=", "massless=", "law=", "restitution=", "theta=", "params: ",
             "stiffness=")   # the API's


def _name(word: str) -> str:
    return word.strip().rstrip("=")


def make(law: str = "position", solver: str = "auto", restitution: float = 0.0,
         stiffness: float | None = None, massless: str | None = None,
         words: Words = KEYS, damping: float = 0.0, params: dict | None = None) -> Method:
    """The method the words name: ``law`` one of LAWS, ``solver`` the position-level
    QP solver, ``stiffness`` and ``damping`` the penalty springs and their dashpots (N/m,
    N·s/m, see :class:`Penalty`), ``massless`` the massless rows' stepping; ``params``
    the method's own parameters: ``theta``, Moreau–Jean's θ, ``beta``, the β-scheme's β
    (position, penalty; Moreau–Jean has none: checked and not used), and the
    position-level solver's (its law's table,
    :func:`skfem_beam.contact.registry.check_params`); None: the defaults.  ``words``:
    how error lines name them (the API's keywords; the command line passes FLAGS)."""
    check_choice(_name(words.law), law, LAWS)
    params = dict(params or {})
    theta, beta = params.pop("theta", None), params.pop("beta", None)
    if params and law != "position":
        raise InputError(f"{words.param}{', '.join(params)}: parameters of a position-level "
                         f"solver; {words.law}{law} takes none")
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
        mj = MoreauJean(0.5 if theta is None else check_theta(theta, words.theta), e)
        return with_beta(mj, beta)       # no β: checked, as the other front ends' words
    if law == "penalty":     # the registry's checks: no solver, no restitution with springs
        if stiffness is None:
            raise InputError(f"{words.law}penalty needs the springs' stiffness: "
                             f"{words.stiffness}K (N/m)")
        resolve("penalty" if solver == "auto" else solver, stiffness, e)
        return Penalty(stiffness, massless=massless or "beta", damping=damping, beta=beta)
    check_choice(_name(words.solver), solver, SOLVERS)
    return PositionLevel(solver, e, massless or "beta",
                         check_params(solver, params, words.param), beta)


def law_of(word: str, name: str = "--law") -> str:
    """The law (one of LAWS) ``word`` names: a law's name or an alias of ALIASES; one line
    naming the words allowed else (``name``: the flag or key as the user wrote it)."""
    check_choice(name, word, (*LAWS, *ALIASES))
    return ALIASES.get(word, word)


def summary_word(law: str) -> str:
    """summary.json's "method" of a beam run: "penalty" for springs, "contact" for rigid
    contact at position or velocity level."""
    return "penalty" if law == "penalty" else "contact"


def split_law(word: str) -> tuple[str, str]:
    """A scene file's ``[contact] law`` names a method (one of LAWS) or a position-level
    solver (SOLVERS): the (law, solver) words of :func:`make` it stands for."""
    return (word, "auto") if word in LAWS else ("position", word)


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
    method's own (1/2 exact contact, 1/4 springs: the first two papers).  Moreau–Jean has
    no β; the one its runs record (summary.json's config) is exact contact's, 1/2."""
    if kind == "bar":
        return BAR_BETA
    return PositionLevel.default_beta if isinstance(method, MoreauJean) else method.default_beta


def recorded_beta(method: Method, given: float | None = None, kind: str = "beam") -> float:
    """The β summary.json records for a run of ``method``: the β-scheme method's own; for
    Moreau–Jean, which has none, the β its front end was given (``given``, checked) or
    :func:`default_beta`, as the runs have always recorded."""
    if isinstance(method, MoreauJean):
        return check_beta(default_beta(method, kind) if given is None else given)
    return method.beta


__all__ = ["ALIASES", "LAWS", "Method", "MoreauJean", "Penalty", "PositionLevel", "Words",
           "check_massless", "default_beta", "law_of", "make", "mass_scale", "recorded_beta", "split_law",
           "summary_word", "with_beta"]
