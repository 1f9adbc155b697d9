"""The contact-law protocol: how one step's multipliers μ follow from its free step.

Every step the scheme computes the step without contact, x_free, and its constrained
values y_f = C x_free.  A contact law maps them to multipliers μ (Δt² × the nodal
contact forces); the step is then u^{n+1} = x_free + W μ, with W = A⁻¹Cᵀ and the
Delassus matrix D = C A⁻¹ Cᵀ, so that y^{n+1} = y_f + D μ.

A law is an object with

- ``name``: how it is found in the registry and reported (summary.json "solver");
- ``setup(step) -> params``: once per run, from the step's data (:class:`StepData`);
  refuses a scene it cannot solve (InputError) and returns the law's constants as a
  float array (``first=True``: the constants of the start step, if they differ);
- ``kernel``: a compiled law, ``compiled_law``-decorated, all with ONE signature

      kernel(D, yf, y_cur, y_prev, lo, hi, params, state, mu, active) -> iterations

  (y_cur, y_prev: the constrained values of uⁿ and uⁿ⁻¹; ``state``: int8 warm start
  kept across steps; writes ``mu`` and ``active``, the values in contact; returns
  the iterations, < 0 on failure, which the law's ``failure`` text, if it has one, explains
  in the run's error line), or ``None`` for a law solved in Python, which then
  has ``solver(step)`` returning an object with ``solve(x_free, y_free, lo, hi) ->
  (μ, its)`` (lo, hi: the step's bounds, which move with a support) and, so that its
  runs checkpoint and resume bit for bit, ``checkpoint() -> dict`` of arrays and
  ``restore(dict)`` (its warm start); the loop calls ``solve`` only on steps whose free
  values leave their bounds, unless the law sets ``free_inside = False`` (a force
  inside the bounds too);
- ``explicit`` (optional): a compiled part of the contact force known before the step,

      explicit(y_cur, y_prev, lo, hi, params, r) -> 0

  added to the step's load as Δt² Cᵀr (and to μ as Δt² r): the penalty's springs at
  uⁿ and uⁿ⁻¹, weighted (1−2β) and β like the elastic force.

Compiled laws are numba C callbacks of one signature, so the time loop is compiled
and cached once for all of them and calls the law through a pointer.
"""
from __future__ import annotations

import subprocess
import sys
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from numba import cfunc, types

from .. import aside
from ..errors import InputError

_vec = types.float64[::1]
LAW_SIGNATURE = types.int64(types.float64[:, ::1], _vec, _vec, _vec, _vec, _vec, _vec,
                            types.int8[::1], _vec, types.boolean[::1])


EXPLICIT_SIGNATURE = types.int64(_vec, _vec, _vec, _vec, _vec, _vec)


class Compiled:
    """A law's kernel, compiled (and cached on disk) the first time a run uses it, so that
    a run compiles its own law only: a cold start compiled every law at import (16 s)."""

    def __init__(self, func, signature):
        self.func, self.signature, self._cfunc, self._child = func, signature, None, None

    @property
    def cfunc(self):
        if self._cfunc is None:
            if self._child is not None:     # compiled aside: then this loads it from the cache
                try:
                    self._child.wait(timeout=600)
                except subprocess.TimeoutExpired:
                    self._child.kill()
                self._child = None
            self._cfunc = cfunc(self.signature, cache=True)(self.func)
        return self._cfunc

    def compile_aside(self) -> None:
        """Start compiling this kernel into numba's on-disk cache in a child process, while
        this process compiles the time loop (a fresh install: two independent compiles of
        ~4 s each, run side by side on two cores); `cfunc` then waits for the child and
        loads the result.  Nothing happens when it is compiled already, when it is not a
        module-level kernel another process can import, or with one core.  Should the
        child fail, `cfunc` compiles it here as before."""
        mod, name = self.func.__module__, self.func.__name__
        if self._cfunc is not None or self._child is not None or mod == "__main__" \
                or getattr(sys.modules.get(mod), name, None) is not self:
            return
        self._child = aside.start([(self, None)])


def compiled_law(func) -> Compiled:
    """``func`` as a contact-law kernel (the one signature above)."""
    return Compiled(func, LAW_SIGNATURE)


def compiled_explicit(func) -> Compiled:
    """``func`` as the explicit part of a law (the signature above)."""
    return Compiled(func, EXPLICIT_SIGNATURE)


@compiled_explicit
def no_explicit(y_cur, y_prev, lo, hi, params, r):
    return 0


@dataclass(frozen=True)
class Parameter:
    """A law's parameter, as every front end names it: ``[contact] <name> = value`` in a
    scene file, ``--param <name>=value`` on the command line, ``PositionLevel(solver,
    params={name: value})`` from Python.  The law's constructor takes it by ``name``; its
    value must be a finite number in [``low``, ``high``] (``unit``: as the docs and the
    error line write it)."""
    name: str
    help: str
    unit: str = ""
    low: float = -np.inf
    high: float = np.inf

    def check(self, value, written: str) -> float:
        """``value`` as a float, or one line naming it (``written``: the key or flag as the
        user wrote it, e.g. ``[contact] gain = ``) and the range allowed."""
        ok = isinstance(value, (int, float, np.number)) and not isinstance(value, bool) \
            and np.isfinite(value) and self.low <= value <= self.high
        if not ok:
            unit = f" ({self.unit})" if self.unit else ""
            raise InputError(f"{written}{value!r}: {self.name}{unit} must be a number in "
                             f"[{self.low:g}, {self.high:g}]")
        return float(value)


@dataclass(frozen=True)
class StepData:
    """What a law sees of the scheme, once per run."""
    A: sp.csr_matrix      # the step matrix M + Δt/2 B + Δt²βK
    C: sp.csr_matrix      # constrained values y = C u
    D: np.ndarray         # Delassus matrix C A⁻¹ Cᵀ (m × m)
    lo: np.ndarray        # bounds of y (±inf: none)
    hi: np.ndarray
    dt: float
    beta: float
    disks: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    #                     (q, 2) row pairs (v, w) of round holes: |y_p − c| ≤ r with c, r
    #                     those of the pair's box [lo, hi] (contact.round_hole)
    lands: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    #                     (q, 3) per disk: (lands, half width, angle) of a broached hole
    #                     (contact.lands), (0, 0, 0) a round one; (0, 3): all round
    friction: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #                     Coulomb's μ per row (a round hole's first row, a face's row;
    #                     none: (0,))
    obstacle: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    #                     (m, 2) per row the obstacle (Obstacles.parts index; one
    #                     obstacle: 0) giving its lo and its hi, −1 none; (0, 2): unknown
    tangents: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    #                     (k, 2) a face with friction's row and its tangent row (bounds ±∞)

    @property
    def decoupled(self) -> bool:
        """D diagonal: each constrained value is its own one-dimensional problem."""
        D = self.D
        return bool(np.allclose(D, np.diag(np.diag(D)), rtol=0,
                                atol=1e-14 * np.abs(D).max(initial=0.0)))


class ContactLaw:
    """Base of the laws (see the module docstring); a law sets ``name`` and ``kernel``
    and overrides what it needs."""
    name = "law"
    kernel = None
    explicit = None
    free_inside = True   # μ = 0 whenever y_free lies within [lo, hi] (a Python law's
    #                      solver is then not called: every position-level law)
    round_holes = False  # takes StepData.disks (round holes); the others refuse them
    springs = False      # the obstacles are springs: a penetration is a support's
    #                      deflection (physics), not a numerical error
    friction = False     # takes Coulomb friction (StepData.friction); the others refuse it
    x_space = False      # solves for uⁿ⁺¹ itself (contact.sparse_qp): the scheme builds
    #                      neither W nor D for it
    parameters: tuple = ()   # its Parameter table: what the front ends let a user set

    def setup(self, step: StepData, first: bool = False) -> np.ndarray:
        return np.zeros(0)

    def kernels_for(self, step: StepData) -> tuple:
        """The compiled kernels `setup` will pick for ``step``, read from its rows alone
        (its A and D are not built yet: None), so that a fresh install compiles them aside
        while the step operators are built; () where that needs D (the default)."""
        return ()

    def solver(self, step: StepData):
        raise NotImplementedError(f"the {self.name} law has no Python solver")

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name!r})"


@compiled_law
def no_contact_kernel(D, yf, y_cur, y_prev, lo, hi, params, state, mu, active):
    return 0


class NoContact(ContactLaw):
    """No constrained value (m = 0); also the loop's law for steps whose μ was set by a
    law solved in Python."""
    name = "none"
    kernel = no_contact_kernel
