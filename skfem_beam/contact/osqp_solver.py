"""OSQP, the general QP engine, as a per-step contact solver.

The step QP  min ½xᵀAx − Fᵀx,  lo ≤ Cx ≤ hi  is set up ONCE per run (A, C, lo, hi are
constant); each step only updates q = −F = −A x_free and warm-starts from the last
solution.  The compiled loop calls it only when the free step leaves its bounds (μ = 0
is exact otherwise).  What makes OSQP's answer exact (docs/design.md §4 and "Known traps"):

- Scaling.  OSQP's tolerances are absolute.  Unknowns are measured in units of
  s = the largest finite |bound| and of their own diagonal of A (Jacobi: x = s·J x̂,
  J = diag(A)^{-1/2}) and the objective is divided by s², so the bounds, P̂ = JAJ (unit
  diagonal) and q̂ are O(1) and EPS means "EPS of the obstacle scale".  OSQP's own Ruiz
  scaling comes on top.  Scaled by A's mean diagonal instead, a plate's twist unknowns
  (diagonals 1e-7 of the mean) had curvature below OSQP's eps_dinf and it called the step
  QP "dual infeasible" at the first contacts (40 × 40 BFS, contact.sparse_qp).
- ADMM finds the active set, the exact finish solves on it.  ADMM runs to EPS = 1e-6
  (``status_val`` must be SOLVED); the set is read from its iterate by the rule of OSQP's
  own polishing (`guess_active`), and μ is computed exactly on it (D_WW μ_W = b_W −
  y_free,W, compiled: `active_set.exact_finish`, shared with daqp), so y = y_free + Dμ
  sits on its bounds to round-off.  Polishing itself is off: it would factorise a
  reduced KKT system every step to do the same less exactly (and OSQP 1.x then prints
  "Polishing not needed" from C whenever no constraint is active).
- A constraint whose multiplier or gap is below OSQP's accuracy (near grazing) can be
  misclassified; the exact KKT check catches it and the compiled active set,
  warm-started from OSQP's set, decides it (``self.repairs``).  A residual above
  REPAIR_TOL of the scale means OSQP's set was wrong: SolverError.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numba import njit

from ..errors import SolverError
from ..linalg import csr_product
from .active_set import bound_scale, finish_on_duals, repair
from .base import ContactLaw

EPS = 1e-6         # OSQP's eps_abs = eps_rel, in scaled units: enough to find the set
CHECK_EVERY = 10   # ADMM iterations between termination checks (OSQP's default: 25)
REPAIR_TOL = 1e4 * EPS   # a KKT residual above this (× the scale): OSQP's set is wrong


class OSQPSolver:
    """Per-run OSQP workspace; ``solve(x_free, y_free, lo, hi) -> (μ, ADMM iterations)``
    with the step's bounds (they move with a support: OSQP's l, u are updated, its
    factorisation is not); ``checkpoint()``/``restore()``: the exact finish's warm start
    (the answer's bits depend on the active set found, which is unique but at grazing
    contact; OSQP's own warm start only changes how fast it is found)."""

    def __init__(self, A, C, lo, hi, D):
        A = sp.csc_matrix(A, dtype=float)
        self.C = sp.csr_matrix(C, dtype=float)
        self.lo = np.array(lo, dtype=float)     # a copy: it follows moving bounds
        self.hi = np.array(hi, dtype=float)
        self.D = np.ascontiguousarray(D, dtype=float)
        self.s = bound_scale(self.lo, self.hi)
        J = sp.diags(1.0 / np.sqrt(A.diagonal()))
        qmat = (J @ A / -self.s).tocsr()           # q̂ = −J A x_free / s
        self.qcsr = (qmat.indptr, qmat.indices, qmat.data)
        CJ = (self.C @ J).tocsr()                  # C x = s·(C J) x̂
        self.ccsr = (CJ.indptr, CJ.indices, CJ.data)
        self.q, self.z = np.zeros(A.shape[0]), np.zeros(self.lo.size)
        self.state = np.zeros(self.lo.size, dtype=np.int8)
        self.duals = np.zeros(self.lo.size)
        self.repairs = 0
        import osqp   # here, not at import: a run that does not use it does not load it
        self._solved = osqp.SolverStatus.OSQP_SOLVED
        self.prob = osqp.OSQP()
        self.prob.setup(sp.triu(J @ A @ J, format="csc"), np.zeros(A.shape[0]),
                        CJ.tocsc(), self.lo / self.s, self.hi / self.s, verbose=False,
                        eps_abs=EPS, eps_rel=EPS, polishing=False, warm_starting=True,
                        check_termination=CHECK_EVERY, max_iter=100000)
        # the compiled workspace: osqp.OSQP.solve() wraps the same call in a namespace of
        # its 20 info fields, 7 µs a step (a third of a contact step at J = 40, measured)
        self.engine = self.prob._solver

    def solve(self, x_free, y_free, lo=None, hi=None):
        # the compiled parts before and after ADMM are one call each: a call of a compiled
        # function from Python costs ~0.5-1 µs, and OSQP runs on a third of the steps of
        # the obstacle scenes, at ~20 µs a step against the active set's 4 (issue #22: ≤ 5×)
        if lo is not None and moved(lo, hi, self.lo, self.hi):
            self.lo[:], self.hi[:] = lo, hi
            self.prob.update(l=self.lo / self.s, u=self.hi / self.s)
        csr_product(*self.qcsr, x_free, self.q)
        engine = self.engine
        engine.update_data_vec(q=self.q, l=None, u=None)
        engine.solve()
        info = engine.info
        if info.status_val != self._solved:
            raise SolverError(f"OSQP returned status '{info.status}' after {info.iter} "
                              f"iterations")
        mu = np.empty(self.lo.size)
        res = duals_and_finish(self.ccsr, engine.solution.x, engine.solution.y, self.z,
                               self.lo, self.hi, self.s, self.duals, self.D, y_free,
                               self.state, mu)
        self.repairs += repair(res, self.D, y_free, self.lo, self.hi, self.state, mu,
                               self.s, "OSQP", tol=REPAIR_TOL)
        return mu, int(info.iter)

    def checkpoint(self) -> dict:
        return {"active": self.state.copy(), **warm_state(self.engine)}

    def restore(self, saved: dict) -> None:
        if "active" in saved:
            self.state[:] = saved["active"]
        warm_again(self.engine, saved)


def warm_state(engine) -> dict:
    """OSQP's own warm start: its last x, y and its adapted ρ (without them a resumed
    run's ADMM took other iteration counts: qp_iterations 56,290 against 56,280)."""
    sol = engine.solution
    return {"x": np.array(sol.x), "y": np.array(sol.y), "rho": engine.get_settings().rho}


def warm_again(engine, saved: dict) -> None:
    """Restore :func:`warm_state` (a checkpoint written before it was kept has none)."""
    if "x" in saved:
        if float(saved["rho"]) != engine.get_settings().rho:
            engine.update_rho(float(saved["rho"]))      # refactors, as its adaptation did
        engine.warm_start(x=saved["x"], y=saved["y"])


@njit(cache=True)
def moved(lo, hi, lo_was, hi_was) -> bool:
    """The bounds differ from the last step's."""
    for i in range(lo.size):
        if lo[i] != lo_was[i] or hi[i] != hi_was[i]:
            return True
    return False


@njit(cache=True)
def duals_and_finish(ccsr, x, y, z, lo, hi, s, duals, D, yf, state, mu):
    """z ← C J x̂ (``ccsr``: C J's CSR arrays), OSQP's set by `guess_active`, μ exactly on it
    (`finish_on_duals`): its KKT residual (`active_set.repair` says what follows)."""
    csr_product(ccsr[0], ccsr[1], ccsr[2], x, z)
    guess_active(z, y, lo, hi, s, duals)
    return finish_on_duals(D, yf, lo, hi, duals, state, mu)


@njit(cache=True)
def guess_active(z, y, lo, hi, s, duals):
    """duals ← OSQP's dual y where its iterate says the bound is active, else 0: the rule
    of OSQP's own polishing (Stellato et al. 2020, §5.1): upper active when the gap to
    it is below y, lower when below −y (z = Cx̂, bounds scaled by s)."""
    for i in range(z.size):
        active = hi[i] / s - z[i] < y[i] or z[i] - lo[i] / s < -y[i]
        duals[i] = y[i] if active else 0.0


class OSQP(ContactLaw):
    """The general QP engine, called from Python each step (set up once per run)."""
    name = "osqp"

    def solver(self, step):
        return OSQPSolver(step.A, step.C, step.lo, step.hi, step.D)
