"""The matrices of one step, built once per run from the system, Δt and β:

    A = M + Δt/2 B + Δt²βK  (factored, banded),   M/Δt² + βK  (the energy's),
    W = A⁻¹Cᵀ,   D = C A⁻¹ Cᵀ  (the Delassus matrix the contact laws see).

Massless rows (a redistributed mass) step in one of two ways (``massless``):

- "beta": like every row, by the β-weighted K row β u^{n+1} + (1−2β)uⁿ + βu^{n−1}
  (= Gⁿ + Cᵀλ there).  At β = 1/4 its recursion has the double root −1: the node
  oscillates step to step.
- "quasi-static": equilibrium at the new time, K u^{n+1} = f^{n+1} + Cᵀλ^{n+1} on those
  rows (no recursion, nothing to oscillate).  Written times β, the row's matrix is A's
  own row (M is zero there), so A stays M + βΔt²K, symmetric and banded; the rest of the
  row goes to the right-hand side as the explicit force of kernels.massless_force.  The
  constraint acts on massless dofs only, so the contact term is βΔt²Cᵀλ: W and D carry
  the β and the law's μ is Δt²λ^{n+1}, the nodal reaction at t_{n+1}.  Any β > 0 works:
  with nothing to recur, small β is the semi-explicit scheme (central differences on the
  dofs with mass, exact contact on the massless ones), stable below the linear limit of
  the dofs with mass (stability.kappa_h).
"""
from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import InputError
from ..linalg import Banded, band_solve
from ..spaces.redistribution import massless_rows


@dataclass
class StepOperators:
    A: sp.csr_matrix
    Ab: Banded          # A with its Cholesky factor
    Eb: Banded          # M/Δt² + βK
    Kb: Banded
    Bb: Banded | None   # damping, None when there is none
    C: sp.csr_matrix
    W: np.ndarray       # A⁻¹Cᵀ (n × m, Fortran order: W.T is C-contiguous)
    D: np.ndarray       # C A⁻¹ Cᵀ (m × m), both times β with quasi-static massless rows
    Z: np.ndarray       # the quasi-static massless rows (empty with massless="beta")


def load_norms(system, dt: float, beta: float) -> np.ndarray:
    """‖b_k‖_{N⁻¹} for each load vector b_k: a step's load g = Σ_k Gⁿ_k b_k raises
    √(½E_β) by at most Δt‖g‖_{N⁻¹} ≤ Δt Σ_k |Gⁿ_k| ‖b_k‖_{N⁻¹} (Run's a-priori bound).

    Why: the work of a step is ½gᵀδ, δ = u^{n+1} − u^{n−1}, and
    E_β = |δu|²_{M/Δt² + (β−¼)K} + |ū|²_K (δu = uⁿ − uⁿ⁻¹, ū = (uⁿ + uⁿ⁻¹)/2).  With
    S = √E_β^{n+1} + √E_βⁿ, δ = δu^{n+1} + δuⁿ = 2(ū^{n+1} − ūⁿ) gives
    |δ|²_{M/Δt² + (β−¼)K} ≤ S² and |δ|²_K ≤ 4S², so |δ|²_{M/Δt² + βK} ≤ 2S² for β ≥ 1/4:
    N = M + βΔt²K, positive definite even where M has no inertia.  A regular M keeps
    N = M (today's bound, looser: N ≥ M), so that those runs do not change."""
    if not system.loads.shape[1]:
        return np.zeros(0)
    N = system.M if massless_rows(system.M).size == 0 else system.M + beta * dt**2 * system.K
    N = N.tocsc()
    with np.errstate(over="ignore", invalid="ignore"):   # inf: Run refuses the load
        return np.sqrt(np.array([lv @ spla.spsolve(N, lv) for lv in system.loads.T]))


def step_operators(system, dt: float, beta: float, massless: str = "beta",
                   delassus: bool = True) -> StepOperators:
    """The step's operators; ``delassus=False`` (an x-space law, contact.sparse_qp): W
    and D are not built (W (n, 0), D (0, 0)); a plate builds W with one banded solve of
    all its columns (`multi_rhs_W`), the beam column by column as it always has."""
    M, K, B = system.M, system.K, system.B
    Z = massless_rows(M)
    quasi_static, massless = massless == "quasi-static", Z.size
    if massless and not quasi_static and beta < 0.25:
        # a dof without inertia steps by the β-weighted K row alone, whose recursion has
        # a root of modulus > 1 for β < 1/4 (and A = M is singular at β = 0)
        raise InputError(f"beta={beta:g} with a mass matrix that has no inertia at {massless} "
                         f"dof(s) (mass='redistributed'): their β-weighted step is unstable "
                         f"for beta < 1/4; use beta=0.5, or massless='quasi-static'")
    if massless and quasi_static and beta <= 0:
        # the quasi-static rows are written times β (module docstring): A is singular at 0
        raise InputError(f"beta={beta:g} with massless='quasi-static': its massless rows are "
                         f"written times beta, so beta must be > 0; beta=0.01 is the "
                         f"central-difference limit")
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
    # W is kept in Fortran order (W.T C-contiguous): the loop's W μ reads W's columns
    if not delassus:
        W = np.zeros((0, system.n)).T
    elif getattr(system, "meta", {}).get("kind") == "plate":
        W = multi_rhs_W(Ab, C)
    else:
        Wt = np.zeros((m, system.n))
        for j in range(m):
            col = C[j].toarray().ravel()
            band_solve(Ab.chol, col)
            Wt[j] = col
        W = Wt.T
    if quasi_static and Z.size:
        if B is not None:
            raise InputError("massless='quasi-static' with damping is not supported (the "
                             "massless rows' equilibrium would need the damping force); use "
                             "massless='beta'")
        if np.setdiff1d(C.indices, Z).size:
            raise InputError("massless='quasi-static' needs constraints that act on massless "
                             "dofs only (mass='redistributed')")
        W *= beta       # the contact term of the rows times β (see the module docstring)
    else:
        Z = np.zeros(0, dtype=np.int64)
    D = np.ascontiguousarray((C @ W).reshape(m, m)) if delassus else np.zeros((0, 0))
    return StepOperators(A=sp.csr_matrix(A), Ab=Ab, Eb=Banded(E), Kb=Banded(K),
                         Bb=Banded(B) if B is not None else None,
                         C=C, W=W, D=D, Z=Z.astype(np.int64))


SAY_W_BYTES = 100e6   # a W this large takes long enough to be announced (60 × 60: 25 s)


def multi_rhs_W(Ab: Banded, C) -> np.ndarray:
    """W = A⁻¹Cᵀ by LAPACK's banded solve of all m columns at once (one call, no CSR slice
    per column: 40 × 40 plate, 1,521 columns: 25 s column by column before); one line on
    stderr first when W passes SAY_W_BYTES."""
    n, m = C.shape[1], C.shape[0]
    if 8.0 * n * m >= SAY_W_BYTES:
        print(f"building W = A⁻¹Cᵀ for the contact law: {m} columns, {8e-9 * n * m:.2f} GB "
              f"(solver pdas-sparse builds none) …", file=sys.stderr, flush=True)
    W = np.asfortranarray(C.T.toarray())
    return np.asfortranarray(
        scipy.linalg.cho_solve_banded((Ab.lapack_band("chol"), False), W, overwrite_b=True,
                                      check_finite=False))


def csr_arrays(a):
    """(indptr, indices, data) of a sparse matrix, typed for the compiled loop."""
    a = sp.csr_matrix(a)
    return (a.indptr.astype(np.int64), a.indices.astype(np.int64), a.data.astype(float))
