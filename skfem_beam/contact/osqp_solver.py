"""OSQP, the general QP engine, as a per-step contact solver.

The step QP  min ½xᵀAx − Fᵀx,  lo ≤ Cx ≤ hi  is set up ONCE per run (A, C, lo, hi are
constant); each step only updates q = −F = −A x_free and warm-starts from the last
solution.  What makes OSQP's answer trustworthy here (see docs/design.md, "Known traps"):

- Scaling.  OSQP's tolerances are absolute.  Unknowns are measured in units of
  s = the largest finite |bound| (x = s·x̂) and the objective is divided by s²·ā
  (ā = mean diagonal of A), so the bounds, P and q are O(1) and eps = 1e-10 means
  "1e-10 of the obstacle scale".  OSQP's own Ruiz scaling comes on top.
- Polishing on; ``status_val`` and ``status_polish`` are checked every step.
- Exact finish (`active_set.exact_finish`, shared with daqp).  ADMM is only accurate
  to eps; polishing identifies the active set.  μ is then recomputed exactly on that
  set (D_WW μ_W = b_W − y_free,W, compiled), so y = y_free + Dμ sits on its bounds to
  round-off.  A constraint whose multiplier or gap is below OSQP's accuracy (grazing
  contact) can be misclassified; the exact KKT check catches it and the compiled
  active-set method, warm-started from OSQP's set, decides it (counted in
  ``self.repairs``).  A set wrong by more than grazing (KKT residual > 1e-6 of the
  scale) is a failure: SolverError.
- OSQP 1.x prints "Polishing not needed ..." whenever no constraint is active, even
  with verbose=False.  Its Python module routes C-level printing through
  PySys_WriteStdout, i.e. Python's ``sys.stdout`` (redirecting file descriptor 1
  does nothing); ``sys.stdout`` is swapped for a null sink around solve(), which
  costs ~0.3 µs (measured; the GIL is held throughout, so no other thread prints
  meanwhile).
"""
from __future__ import annotations

import sys

import numpy as np
import scipy.sparse as sp

from ..errors import SolverError
from .active_set import bound_scale, exact_finish
from .base import ContactLaw

EPS = 1e-10          # OSQP's eps_abs = eps_rel, in scaled units
_POLISH_OK = (1, 2)  # OSQP_POLISH_SUCCESS, OSQP_POLISH_NO_ACTIVE_SET_FOUND


class _NullWriter:
    def write(self, text):
        return len(text)

    def flush(self):
        pass


_NULL = _NullWriter()


class OSQPSolver:
    """Per-run OSQP workspace; ``solve(x_free, y_free, lo, hi) -> (μ, ADMM iterations)``
    with the step's bounds (they move with a support: OSQP's l, u are updated, its
    factorisation is not); ``checkpoint()``/``restore()``: the exact finish's warm start
    (the answer's bits depend on the active set found, which is unique but at grazing
    contact; OSQP's own warm start only changes how fast it is found)."""

    def __init__(self, A, C, lo, hi, D):
        A = sp.csc_matrix(A, dtype=float)
        C = sp.csc_matrix(C, dtype=float)
        self.lo = np.array(lo, dtype=float)     # a copy: it follows moving bounds
        self.hi = np.array(hi, dtype=float)
        self.D = np.ascontiguousarray(D, dtype=float)
        self.s = bound_scale(self.lo, self.hi)
        abar = float(A.diagonal().mean())
        self.qmat = (A / (-self.s * abar)).tocsr()    # q̂ = −A x_free /(s ā)
        self.state = np.zeros(self.lo.size, dtype=np.int8)
        self.zeros = np.zeros(self.lo.size)
        self.repairs = 0
        import osqp   # here, not at import: a run that does not use it does not load it
        self._solved = osqp.SolverStatus.OSQP_SOLVED
        self.prob = osqp.OSQP()
        self.prob.setup(sp.triu(A / abar, format="csc"), np.zeros(A.shape[0]), C,
                        self.lo / self.s, self.hi / self.s, verbose=False,
                        eps_abs=EPS, eps_rel=EPS, polishing=True, warm_starting=True,
                        max_iter=100000)

    def solve(self, x_free, y_free, lo=None, hi=None):
        if lo is not None and not (np.array_equal(lo, self.lo) and np.array_equal(hi, self.hi)):
            self.lo[:], self.hi[:] = lo, hi
            self.prob.update(l=self.lo / self.s, u=self.hi / self.s)
        self.prob.update(q=self.qmat @ x_free)
        out = sys.stdout
        sys.stdout = _NULL
        try:
            r = self.prob.solve(raise_error=False)
        finally:
            sys.stdout = out
        info = r.info
        if info.status_val != self._solved:
            raise SolverError(f"OSQP returned status '{info.status}' after {info.iter} "
                              f"iterations")
        if info.status_polish not in _POLISH_OK:
            raise SolverError(f"OSQP's polishing failed (status_polish={info.status_polish})")
        # OSQP's dual y: Px̂ + q̂ + Cᵀy = 0, y > 0 at the upper, < 0 at the lower bound, so
        # μ = −s·ā·y; only its sign pattern is used (μ is recomputed exactly).  Polished
        # duals are exactly 0 off the active set; without polishing (no active set)
        # the ADMM duals are only small, so they are not used.
        duals = self.zeros if info.status_polish == 2 else r.y
        mu = np.empty(self.lo.size)
        self.repairs += exact_finish(self.D, y_free, self.lo, self.hi, duals, self.state, mu,
                                     self.s, "OSQP")
        return mu, int(info.iter)

    def checkpoint(self) -> dict:
        return {"active": self.state.copy()}

    def restore(self, saved: dict) -> None:
        if "active" in saved:
            self.state[:] = saved["active"]


class OSQP(ContactLaw):
    """The general QP engine, called from Python each step (set up once per run)."""
    name = "osqp"

    def solver(self, step):
        return OSQPSolver(step.A, step.C, step.lo, step.hi, step.D)
