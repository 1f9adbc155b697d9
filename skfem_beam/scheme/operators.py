"""The matrices of one step, built once per run from the system, Δt and β:

    A = M + Δt/2 B + Δt²βK  (factored, banded),   M/Δt² + βK  (the energy's),
    W = A⁻¹Cᵀ,   D = C A⁻¹ Cᵀ  (the Delassus matrix the contact laws see).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import InputError
from ..linalg import Banded, band_solve


@dataclass
class StepOperators:
    A: sp.csr_matrix
    Ab: Banded          # A with its Cholesky factor
    Eb: Banded          # M/Δt² + βK
    Kb: Banded
    Bb: np.ndarray      # damping rows, (0, 1) when there is none
    C: sp.csr_matrix
    W: np.ndarray       # A⁻¹Cᵀ (n × m)
    D: np.ndarray       # C A⁻¹ Cᵀ (m × m)


def step_operators(system, dt: float, beta: float) -> StepOperators:
    M, K, B = system.M, system.K, system.B
    massless = int((abs(M).sum(axis=1) == 0).sum())
    if massless and beta < 0.25:
        # a dof without inertia steps by the β-weighted K row alone, whose recursion has
        # a root of modulus > 1 for β < 1/4 (and A = M is singular at β = 0)
        raise InputError(f"beta={beta:g} with a mass matrix that has no inertia at {massless} "
                         f"dof(s) (mass='redistributed'): their quasi-static step is unstable "
                         f"for beta < 1/4; use beta=0.5")
    try:
        with np.errstate(over="raise", invalid="raise"):
            A = M + dt**2 * beta * K + (0.5 * dt * B if B is not None else 0)
            E = M / dt**2 + beta * K
            _ = dt**3 * K   # used by the start step
        if not all(np.isfinite(a.data).all() for a in (M, K, A, E)):
            raise FloatingPointError("non-finite entries")
        Ab = Banded(A, factor=True)
    except (OverflowError, FloatingPointError, ValueError, np.linalg.LinAlgError) as e:
        raise InputError(f"dt={dt:g} with this system's M and K gives step matrices outside "
                         f"floating-point range ({e}): check the scales of k2, L, dt") from None
    C = system.C.tocsr()
    m = C.shape[0]
    W = np.zeros((system.n, m))
    for j in range(m):
        col = C[j].toarray().ravel()
        band_solve(Ab.chol, col)
        W[:, j] = col
    D = np.ascontiguousarray((C @ W).reshape(m, m))
    return StepOperators(A=sp.csr_matrix(A), Ab=Ab, Eb=Banded(E), Kb=Banded(K),
                         Bb=Banded(B).rows if B is not None else np.zeros((0, 1)),
                         C=C, W=W, D=D)


def csr_arrays(a):
    """(indptr, indices, data) of a sparse matrix, typed for the compiled loop."""
    a = sp.csr_matrix(a)
    return (a.indptr.astype(np.int64), a.indices.astype(np.int64), a.data.astype(float))
