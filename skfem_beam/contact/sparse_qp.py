"""Contact engines in x-space for many contacts (the plate): no W = A⁻¹Cᵀ, no D = C W.

The step QP  min ½uᵀAu − Fᵀu,  lo ≤ Cu ≤ hi  (F = A x_free) is solved for u itself.  Where
each row of C selects one unknown (the plate: w at a vertex), an active set S pins those
unknowns at their bounds b_S, and the step on S is one banded solve with

    A_S = A with the rows and columns of S replaced by the identity,
    A_S u = F − A[:, S] b_S  off S,   u_S = b_S,

whose Cholesky factor has A's band; then μ = C(A u − F) (Δt² × the nodal forces, the
scheme's multipliers: A u = A x_free + Cᵀμ).  This is exact to round-off on S; the KKT
check and the set's update are those of the primal-dual active set method (Hintermüller,
Ito & Kunisch 2003): with c = diag(A) on S's rows (so that c·gap is a force)

    lower active  if  μ_j + c_j (lo_j − u_j) > 0,   upper active  if  μ_j + c_j (hi_j − u_j) < 0,

iterated until S repeats.  The factor of the last set is kept: a step pressed on the
obstacle with an unchanged set costs one banded solve and one banded product.

Engines (registered laws, ``x_space = True``: the scheme builds neither W nor D for them
and takes u^{n+1} from the engine, contact/registry.py):

- ``pdas-sparse``: the primal-dual active set, warm-started from the last step's set;
- ``osqp-sparse``: OSQP on the Jacobi-scaled problem finds the set (factorised once per
  run, q and the bounds updated each step, warm-started), the active set method above
  finishes it exactly (it also repairs a set OSQP misread at grazing contact);
- ``clarabel-sparse``: Clarabel's interior point finds the set (a cold solve each step:
  Clarabel has no warm start), the same exact finish.

Why OSQP needs the Jacobi scaling here: the plate's unknowns mix w, slopes and the twist
u_xy, whose diagonals of A differ by 10⁷ (20 × 20: 1.1e-7 … 7.4, mean 1.7).  Scaled by the
mean diagonal (the beam's OSQP law), the twist directions have curvature ~1e-7 < OSQP's
eps_dinf = 1e-4, and OSQP reports the step QP "dual infeasible" (unbounded) at the first
contacts.  With x = s·J x̂, J = diag(A)^{-1/2}, P̂ = J A J/… has a unit diagonal.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from ..errors import InputError, SolverError
from ..linalg import Banded, band_solve
from .base import ContactLaw

MAX_SWEEPS = 100   # active-set updates of one step before it gives up (SolverError)
EPS = 1e-6         # OSQP's / Clarabel's tolerance in scaled units: enough to find the set


def selected_unknowns(C) -> np.ndarray:
    """The unknown each row of C selects (one entry 1.0 per row, distinct columns); an
    InputError for any other C (these engines need a selector)."""
    C = sp.csr_matrix(C)
    cols = C.indices
    if not (np.all(np.diff(C.indptr) == 1) and np.all(C.data == 1.0)
            and np.unique(cols).size == cols.size):
        raise InputError("the x-space contact engines need constraints that each select one "
                         "unknown (the plate's w at a vertex); use active-set, osqp or daqp")
    return cols.astype(np.int64)


def band_cholesky(band: np.ndarray) -> np.ndarray:
    """The Cholesky factor of the matrix whose upper band is ``band`` (Banded layout),
    in the layout `band_solve` takes (reciprocal diagonal).  LAPACK's dpbtrf on ONE
    thread (threadpoolctl): OpenBLAS's threads took 0.2–1.2 s at 40 × 40 on
    two busy cores against 45 ms on one (measured; a numba loop took 0.3 s)."""
    from threadpoolctl import threadpool_limits
    with threadpool_limits(1, user_api="blas"):
        chol = scipy.linalg.cholesky_banded(np.ascontiguousarray(band.T), check_finite=False)
    chol = np.ascontiguousarray(chol.T)
    chol[:, -1] = 1.0 / chol[:, -1]
    return chol


class SelectorQP:
    """The step QP with C a selector: ``finish(x, lo, hi, state)`` overwrites x (x_free on
    entry) with the exact solution from the active set ``state`` (int8: −1 lower, +1
    upper, 0 free; updated in place to the final set) and returns (μ, sweeps)."""

    def __init__(self, A, C):
        self.A = sp.csr_matrix(A, dtype=float)
        self.band = Banded(self.A)
        self.dof = selected_unknowns(C)
        self.c = self.A.diagonal()[self.dof]
        self.key, self.chol = None, None        # the last set's factor
        self.factors = 0                        # factorisations so far (a new set each)

    def factor(self, pinned: np.ndarray) -> np.ndarray:
        """The Cholesky factor (Banded layout) of A_S for the pinned unknowns, cached
        for the last set."""
        key = pinned.tobytes()
        if key == self.key:
            return self.chol
        kd = self.band.kd
        band = self.band.band.copy()                  # band[j, kd − o] = A[j − o, j]
        band[pinned, :] = 0.0                         # column j pinned
        for o in range(1, kd + 1):                    # row i pinned: A[i, i + o]
            rows = pinned[pinned + o < self.band.n]
            band[rows + o, kd - o] = 0.0
        band[pinned, kd] = 1.0
        self.key, self.chol = key, band_cholesky(band)
        self.factors += 1
        return self.chol

    def solve_on_set(self, F, lo, hi, state, u) -> np.ndarray:
        """u ← the minimiser with the set ``state`` pinned; returns μ = C(Au − F)."""
        on = state != 0
        pinned = self.dof[on]
        b = np.where(state[on] < 0, lo[on], hi[on])
        ub = np.zeros(u.size)
        ub[pinned] = b
        rhs = F - self.A @ ub
        rhs[pinned] = b
        band_solve(self.factor(pinned), rhs)
        rhs[pinned] = b                         # exactly on the bounds
        u[:] = rhs
        mu = (self.A @ u - F)[self.dof]
        mu[~on] = 0.0
        return mu

    def finish(self, x, lo, hi, state):
        F = self.A @ x
        seen = {state.tobytes()}
        for sweep in range(1, MAX_SWEEPS + 1):
            mu = self.solve_on_set(F, lo, hi, state, x)
            y = x[self.dof]
            new = np.zeros_like(state)
            new[mu + self.c * (lo - y) > 0] = -1
            new[mu + self.c * (hi - y) < 0] = 1
            if np.array_equal(new, state):
                return mu, sweep
            if new.tobytes() in seen:
                raise SolverError(f"the active set cycles after {sweep} sweeps")
            seen.add(new.tobytes())
            state[:] = new
        raise SolverError(f"no active set after {MAX_SWEEPS} sweeps")


class XSpaceSolver:
    """The Python-solver protocol of contact.base for an x-space engine: ``solve(x, y_free,
    lo, hi)`` overwrites x (x_free) with u^{n+1} and returns (μ, iterations: the engine's
    plus the exact finish's sweeps).  ``find(x, lo, hi)`` (a subclass's): the engine's
    guess of the set in ``self.state``; none here: the last step's set (pdas-sparse)."""

    def __init__(self, A, C, lo, hi):
        self.qp = SelectorQP(A, C)
        self.state = np.zeros(self.qp.dof.size, dtype=np.int8)
        self.sweeps = 0

    def find(self, x, lo, hi) -> int:
        return 0

    def solve(self, x, y_free, lo=None, hi=None):
        its = self.find(x, lo, hi)
        mu, sweeps = self.qp.finish(x, lo, hi, self.state)
        self.sweeps += sweeps
        return mu, its + sweeps

    def checkpoint(self) -> dict:
        return {"active": self.state.copy()}

    def restore(self, saved: dict) -> None:
        if "active" in saved:
            self.state[:] = saved["active"]


def jacobi_scaled(A, dof, lo, hi):
    """(P̂ = J A J, j = diag(J), s): x = s·J x̂ with J = diag(A)^{-1/2} and s the largest
    finite |bound|; the bounds of x̂ at the selected unknowns are bound/(s j)."""
    j = 1.0 / np.sqrt(A.diagonal())
    finite = np.abs(np.concatenate([lo[np.isfinite(lo)], hi[np.isfinite(hi)]]))
    s = float(finite.max()) if finite.size and finite.max() > 0 else 1.0
    J = sp.diags(j)
    return sp.csc_matrix(J @ A @ J), j, s


class OSQPSparse(XSpaceSolver):
    """OSQP on the Jacobi-scaled step QP (module docstring), set up once per run."""

    def __init__(self, A, C, lo, hi):
        super().__init__(A, C, lo, hi)
        import osqp
        A = self.qp.A
        P, self.j, self.s = jacobi_scaled(A, self.qp.dof, lo, hi)
        self.qmat = sp.csr_matrix(sp.diags(-self.j / self.s) @ A)   # q̂ = −J A x / s
        n, m = A.shape[0], self.qp.dof.size
        self.E = sp.csc_matrix((np.ones(m), (np.arange(m), self.qp.dof)), shape=(m, n))
        self.lo, self.hi = np.array(lo, dtype=float), np.array(hi, dtype=float)
        self._solved = osqp.SolverStatus.OSQP_SOLVED
        self.prob = osqp.OSQP()
        self.prob.setup(sp.triu(P, format="csc"), np.zeros(n), self.E, *self.scaled_bounds(),
                        verbose=False, eps_abs=EPS, eps_rel=EPS, polishing=False,
                        warm_starting=True, max_iter=100000)

    def scaled_bounds(self):
        js = self.j[self.qp.dof] * self.s
        return self.lo / js, self.hi / js

    def find(self, x, lo, hi) -> int:
        if not (np.array_equal(lo, self.lo) and np.array_equal(hi, self.hi)):
            self.lo[:], self.hi[:] = lo, hi
            lo_s, hi_s = self.scaled_bounds()
            self.prob.update(l=lo_s, u=hi_s)
        self.prob.update(q=self.qmat @ x)
        r = self.prob.solve(raise_error=False)
        if r.info.status_val != self._solved:
            raise SolverError(f"OSQP returned status '{r.info.status}' after {r.info.iter} "
                              f"iterations")
        lo_s, hi_s = self.scaled_bounds()
        z = r.x[self.qp.dof]
        self.state[:] = 0
        self.state[hi_s - z < r.y] = 1
        self.state[z - lo_s < -r.y] = -1
        return int(r.info.iter)


class ClarabelSparse(XSpaceSolver):
    """Clarabel's interior point on the Jacobi-scaled step QP: the finite bounds as
    nonnegative slacks, the data updated each step (its factorisation's symbolic part
    kept), no warm start (an interior point has none)."""

    def __init__(self, A, C, lo, hi):
        super().__init__(A, C, lo, hi)
        import clarabel
        A = self.qp.A
        P, self.j, self.s = jacobi_scaled(A, self.qp.dof, lo, hi)
        self.qmat = sp.csr_matrix(sp.diags(-self.j / self.s) @ A)
        n, m = A.shape[0], self.qp.dof.size
        self.up, self.dn = np.flatnonzero(np.isfinite(hi)), np.flatnonzero(np.isfinite(lo))
        rows = np.concatenate([self.up, self.dn])
        sign = np.concatenate([np.ones(self.up.size), -np.ones(self.dn.size)])
        G = sp.csc_matrix((sign, (np.arange(rows.size), self.qp.dof[rows])),
                          shape=(rows.size, n))
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        settings.presolve_enable = False     # (data updates need the rows kept)
        settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = EPS
        self.solver = clarabel.DefaultSolver(sp.triu(P, format="csc"), np.zeros(n), G,
                                             self.rhs(lo, hi), [clarabel.NonnegativeConeT(
                                                 rows.size)], settings)
        self._solved = clarabel.SolverStatus.Solved

    def rhs(self, lo, hi) -> np.ndarray:
        js = self.j[self.qp.dof] * self.s
        return np.concatenate([hi[self.up] / js[self.up], -lo[self.dn] / js[self.dn]])

    def find(self, x, lo, hi) -> int:
        self.solver.update(q=self.qmat @ x, b=self.rhs(lo, hi))
        r = self.solver.solve()
        if r.status != self._solved:
            raise SolverError(f"Clarabel returned status {r.status} after {r.iterations} "
                              f"iterations")
        z, slack = np.asarray(r.z), np.asarray(r.s)
        active = z > slack
        self.state[:] = 0
        self.state[self.up[active[:self.up.size]]] = 1
        self.state[self.dn[active[self.up.size:]]] = -1
        return int(r.iterations)


class XSpaceLaw(ContactLaw):
    """A law solved in Python in x-space (module docstring): the scheme builds neither W
    nor D for it, and its solver writes u^{n+1}."""
    x_space = True
    engine = XSpaceSolver

    def solver(self, step):
        return self.engine(step.A, step.C, step.lo, step.hi)


class PDASSparse(XSpaceLaw):
    """The primal-dual active set in x-space, warm-started from the last step's set."""
    name = "pdas-sparse"


class OSQPSparseLaw(XSpaceLaw):
    """OSQP (Jacobi-scaled) finds the set, the active set method finishes it exactly."""
    name = "osqp-sparse"
    engine = OSQPSparse


class ClarabelSparseLaw(XSpaceLaw):
    """Clarabel finds the set, the active set method finishes it exactly."""
    name = "clarabel-sparse"
    engine = ClarabelSparse
