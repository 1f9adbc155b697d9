"""Contact solvers for one step of the scheme, all in the reduced variables y = C u.

Each step the integrator computes the unconstrained solution x_free = A⁻¹F and
y_free = C x_free.  With W = A⁻¹Cᵀ and the Delassus matrix D = C A⁻¹ Cᵀ, the step's
QP  min ½xᵀAx − Fᵀx, lo ≤ Cx ≤ hi  is equivalent to finding μ with

    y = y_free + D μ,  lo ≤ y ≤ hi,  μ_i ≥ 0 if y_i = lo_i,  μ_i ≤ 0 if y_i = hi_i,
    μ_i = 0 otherwise,

and then x = x_free + W μ; μ/Δt² are the nodal contact forces.  Solvers:

- ``projection``: D diagonal (one constrained value, Lemma 4.1): y = clip(y_free).
- ``active-set``: exact, compiled, warm-started (any m).
- ``osqp``: the general QP engine, set up once per run.
- ``daqp``: exact dual active-set QP (daqp's Model).
- ``auto``: the cheapest exact one for the scene.
"""
from __future__ import annotations

import numpy as np

from ..errors import InputError

SOLVERS = ("auto", "projection", "active-set", "osqp", "daqp")
COMPILED = {"none": 0, "projection": 1, "active-set": 2}


def choose_solver(name: str, D: np.ndarray) -> str:
    """Resolve ``auto`` and check that the named solver fits the scene."""
    if name not in SOLVERS:
        raise InputError(f"solver={name!r} is not one of: {', '.join(SOLVERS)}")
    m = D.shape[0]
    if m == 0:
        return "none"
    diagonal = np.allclose(D, np.diag(np.diag(D)), rtol=0, atol=1e-14 * np.abs(D).max())
    if name == "auto":
        return "projection" if diagonal else "active-set"
    if name == "projection" and not diagonal:
        raise InputError(f"solver='projection' needs decoupled constraints; this scene has "
                         f"{m} coupled constrained values: use active-set, osqp or daqp")
    return name


def python_solver(name: str, A, C, lo, hi, D, W, dt):
    """A per-step solver object for the engines called from Python (osqp, daqp)."""
    if name == "osqp":
        from .osqp_solver import OSQPSolver
        return OSQPSolver(A, C, lo, hi, D, W, dt)
    if name == "daqp":
        from .daqp_solver import DAQPSolver
        return DAQPSolver(A, C, lo, hi, D, W, dt)
    raise ValueError(name)
