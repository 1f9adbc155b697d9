"""The step solvers and the contact laws by name: one line each, and :func:`register`
for a step solver of the user's (then named by ``--solver``, a scene file's ``[contact]
law`` and ``PositionLevel(solver=)`` like the shipped ones, with no edit of the front end).

A step solver's parameters are its own table (``parameters``, :class:`.base.Parameter`): the
front ends read it here (:func:`parameters_of`, :func:`all_parameters`), so a law with a
parameter is set from a scene file's ``[contact]``, the command line's ``--param`` and
``PositionLevel(params=)`` without a word of theirs."""
from __future__ import annotations

import numpy as np

from ..errors import InputError
from .active_set import ActiveSet
from .base import ContactLaw, Parameter, StepData
from .daqp_solver import DAQP
from .osqp_solver import OSQP
from .penalty import Penalty
from .projection import Projection
from .restitution import Restitution
from .round_hole import RoundHole
from .round_hole_friction import RoundHoleFriction
from .sparse_qp import ClarabelSparseLaw, OSQPSparseLaw, PDASSparse, selected_unknowns

# bytes of W = A⁻¹Cᵀ (n × m) past which "auto" takes pdas-sparse where C selects unknowns
# (a fine plate over an obstacle): at 80 × 80 (W 1.3 GB) building W took 75 s and the
# active set's step 0.9 s against pdas-sparse's 0.6–0.8 s; at 60 × 60 (0.4 GB) 25 s and
# 0.12 s against 0.29 s (docs/plate.md, "Which engine at which size")
W_BUDGET = 1e9

# The step solvers: how the step's QP of exact contact at position level is solved (each
# gives the same step where it applies); a user's own joins them by register()
STEP_SOLVERS = {
    "projection": Projection,     # decoupled values (one per row of D), Lemma 4.1
    "active-set": ActiveSet,
    "osqp": OSQP,
    "daqp": DAQP,
    "round-hole": RoundHole,      # round holes (and boxes beside them), exact
    "round-hole-friction": RoundHoleFriction,   # ... with Coulomb friction, exact contact
    # x-space engines for many contacts, C a selector (the plate): no W, no D
    "pdas-sparse": PDASSparse,
    "osqp-sparse": OSQPSparseLaw,
    "clarabel-sparse": ClarabelSparseLaw,
}
# The contact laws other than exact contact, each with its parameters: normal compliance
# (one-sided springs: stiffness κ in N/m and damping c in N·s/m, one each or one per
# obstacle) and Newton's restitution (e in [0, 1], on the exact step).  They are named by
# their parameters (resolve: stiffness=, restitution=), not as solvers.  Coulomb's μ is a
# parameter of each obstacle (a hole's wall, a face), read by the exact solver that takes
# friction (StepData.friction).
LAWS = {
    "penalty": Penalty,
    "restitution": Restitution,
}


class _Names:
    """The step solvers' names as STEP_SOLVERS holds them now ("auto" first): a registered
    solver joins every list and check that holds this object, wherever it was imported."""

    def __iter__(self):
        return iter(("auto", *STEP_SOLVERS))

    def __contains__(self, name) -> bool:
        return name == "auto" or name in STEP_SOLVERS

    def __len__(self) -> int:
        return 1 + len(STEP_SOLVERS)

    def __repr__(self) -> str:
        return repr(tuple(self))


SOLVERS = _Names()


def register(name: str, law) -> None:
    """Adds the position-level law ``law`` (a :class:`ContactLaw` subclass, or any callable
    of no arguments returning a law, e.g. ``functools.partial(MyLaw, gain=0.5)`` for a
    law with parameters) under ``name``: from then on it is a solver like the shipped
    ones.  A name already taken is refused."""
    if not isinstance(name, str) or not name or name in SOLVERS or name in LAWS:
        raise InputError(f"register({name!r}): a new, non-empty name is needed (taken: "
                         f"{', '.join([*SOLVERS, *LAWS])})")
    if not callable(law):
        raise InputError(f"register({name!r}, {law!r}): a ContactLaw subclass or a callable "
                         f"returning a law is needed")
    STEP_SOLVERS[name] = law


def parameters_of(name) -> tuple[Parameter, ...]:
    """The parameter table of the step solver registered as ``name`` (none for a name
    not in STEP_SOLVERS, or a maker that is not a law class)."""
    return tuple(getattr(STEP_SOLVERS.get(name), "parameters", ())) \
        if isinstance(name, str) else ()


def all_parameters() -> dict[str, Parameter]:
    """Every registered step solver's parameters by name (the keys a scene file's
    [contact] may hold besides its own)."""
    return {p.name: p for name in STEP_SOLVERS for p in parameters_of(name)}


def check_params(name, params: dict, written: str = "--param ") -> dict:
    """``params`` checked against the table of the law ``name``: one line for a
    parameter it does not have or a value out of its range (``written``: how the front
    end writes a parameter, e.g. ``[contact] ``)."""
    table = {p.name: p for p in parameters_of(name)}
    for key in params:
        if key not in table:
            has = ", ".join(table) if table else "none"
            raise InputError(f"{written}{key}: not a parameter of the {name!r} law (its "
                             f"parameters: {has})")
    return {key: table[key].check(value, f"{written}{key} = ")
            for key, value in params.items()}


def resolve(law: str | ContactLaw = "auto", stiffness: float | None = None,
            restitution: float = 0.0, params: dict | None = None) -> ContactLaw:
    """A law object from a name in LAWS, ``"auto"`` (decided at setup: the cheapest exact
    law for the scene) or a law object of the user's; ``stiffness`` means penalty,
    ``restitution`` e > 0 the position-level scheme with Newton restitution; ``params``:
    values of the named law's parameters (its table)."""
    if params:      # check_params refuses them for a law without that table
        checked = check_params(law, params, "params: ")
        return resolve(STEP_SOLVERS[law](**checked), stiffness, restitution)
    e = Restitution(restitution).e
    if e > 0:
        if law not in ("auto", "restitution") or stiffness is not None:
            other = f"stiffness={stiffness:g} (springs)" if stiffness is not None \
                else f"solver={law!r}"
            raise InputError(f"restitution={e:g} is a law of its own (exact contact with a "
                             f"coefficient of restitution): it cannot be combined with {other}")
        return Restitution(e)
    if stiffness is not None:
        if law not in ("auto", "penalty"):
            raise InputError(f"solver={law!r} cannot be combined with stiffness= (the penalty "
                             f"law): pass one of them")
        return Penalty(stiffness)
    if isinstance(law, ContactLaw):
        return law
    if law == "auto":
        return Auto()
    if law in LAWS:          # a law is named by its parameter, not as a step solver
        needs = {"penalty": "stiffness= (the spring stiffness 1/ε)",
                 "restitution": "restitution= (the coefficient e)"}[law]
        raise InputError(f"solver={law!r} needs {needs}")
    if law not in STEP_SOLVERS:
        raise InputError(f"solver={law!r} is not one of: {', '.join(SOLVERS)}")
    made = STEP_SOLVERS[law]()
    if not isinstance(made, ContactLaw):
        raise InputError(f"solver={law!r}: its registered maker returned {made!r}, not a "
                         f"ContactLaw")
    return made


class Auto(ContactLaw):
    """The exact law with Coulomb friction at position level when a round hole or a face
    has μ > 0; else the exact round-hole law where there are round holes, projection when
    the constraints are decoupled, the exact active set when not; pdas-sparse, before W
    and D are built, where W would pass W_BUDGET bytes (`before_operators`)."""
    name = "auto"

    @staticmethod
    def before_operators(n: int, C) -> ContactLaw | None:
        """pdas-sparse where W = A⁻¹Cᵀ would pass W_BUDGET bytes and each row of C selects
        one unknown; else None (`choose` decides, once W and D are built)."""
        if 8.0 * n * C.shape[0] <= W_BUDGET:
            return None
        try:
            selected_unknowns(C)
        except InputError:
            return None
        return PDASSparse()

    @staticmethod
    def choose(step: StepData) -> ContactLaw:
        return Auto._holes(step) or (Projection() if step.decoupled else ActiveSet())

    @staticmethod
    def _holes(step: StepData) -> ContactLaw | None:
        """The law for round holes or friction, read from the step's rows; None without."""
        fric = np.asarray(step.friction, dtype=float)
        if fric.size and np.any(fric > 0):
            return RoundHoleFriction()
        return RoundHole() if step.disks.size else None

    def kernels_for(self, step):
        law = self._holes(step)       # else projection or active set: D decides
        return law.kernels_for(step) if law is not None else ()
