"""daqp (a dual active-set QP solver) as a per-step contact solver.

It solves the reduced problem in the contact values,

    min ½(ŷ − ŷ_f)ᵀ Ĥ (ŷ − ŷ_f)   s.t.  lo/s ≤ ŷ ≤ hi/s,   ŷ = y/s,  Ĥ = d̄·D⁻¹,

as a problem with simple bounds only (no general constraint rows).  s (the largest
finite |bound|) and d̄ (mean of diag D) make ŷ and Ĥ O(1) so daqp's absolute
tolerances are relative ones.  One ``daqp.Model`` lives for the whole run: each step
only updates f = −Ĥŷ_f, and Model.solve starts from the previous step's active set
(daqp keeps its working set in the workspace between solves).

daqp's multipliers: Ĥ(ŷ − ŷ_f) + λ = 0 with λ < 0 at a lower and λ > 0 at an upper
bound, so μ = −(s/d̄)λ; only the sign pattern is used, and μ is recomputed exactly on
that active set (see ``osqp_solver.exact_finish``), so y = y_f + Dμ is on its bounds
to round-off (`active_set.exact_finish`).
"""
from __future__ import annotations

import numpy as np
import scipy.linalg

from ..errors import InputError, SolverError
from .active_set import bound_scale, exact_finish
from .base import ContactLaw

DAQP_INF = 1e30      # daqp's "no bound"


class DAQPSolver:
    """Per-run daqp workspace; ``solve(x_free, y_free, lo, hi) -> (μ, iterations)`` with
    the step's bounds (updated in daqp's model when they move); ``checkpoint()`` /
    ``restore()``: the exact finish's warm start (daqp's own working set only changes how
    fast the unique active set is found)."""

    def __init__(self, lo, hi, D):
        self.lo = np.array(lo, dtype=float)     # a copy: it follows moving bounds
        self.hi = np.array(hi, dtype=float)
        self.D = np.ascontiguousarray(D, dtype=float)
        m = self.lo.size
        self.s = bound_scale(self.lo, self.hi)
        dbar = float(np.diag(self.D).mean())
        H = dbar * scipy.linalg.cho_solve(scipy.linalg.cho_factor(self.D), np.eye(m))
        self.H = np.ascontiguousarray(0.5 * (H + H.T))
        self.Hs = self.H / self.s                    # f = −Ĥ y_f / s
        self.state = np.zeros(m, dtype=np.int8)
        self.repairs = 0
        import daqp   # here, not at import: a run that does not use it does not load it
        self.model = daqp.Model()
        flag, _ = self.model.setup(self.H, np.zeros(m), np.zeros((0, m)),
                                   np.minimum(self.hi / self.s, DAQP_INF),
                                   np.maximum(self.lo / self.s, -DAQP_INF),
                                   np.zeros(m, dtype=np.intc))
        if flag < 0:
            raise SolverError(f"daqp setup failed (exitflag {flag})")
        # H is SPD: no proximal regularisation; feasibility to round-off, not 1e-6
        self.model.settings = {"eps_prox": 0.0, "primal_tol": 1e-12, "iter_limit": 100 * m + 100}

    def solve(self, x_free, y_free, lo=None, hi=None):
        if lo is not None and not (np.array_equal(lo, self.lo) and np.array_equal(hi, self.hi)):
            self.lo[:], self.hi[:] = lo, hi
            self.model.update(bupper=np.minimum(self.hi / self.s, DAQP_INF),
                              blower=np.maximum(self.lo / self.s, -DAQP_INF))
        self.model.update(f=-(self.Hs @ y_free))
        _, _, flag, info = self.model.solve()
        if flag != 1:
            raise SolverError(f"daqp returned exitflag {flag} after {info['iterations']} "
                              f"iterations")
        mu = np.empty(self.lo.size)
        self.repairs += exact_finish(self.D, y_free, self.lo, self.hi, info["lam"],
                                     self.state, mu, self.s, "daqp")
        return mu, int(info["iterations"])

    def checkpoint(self) -> dict:
        return {"active": self.state.copy()}

    def restore(self, saved: dict) -> None:
        if "active" in saved:
            self.state[:] = saved["active"]


class DAQP(ContactLaw):
    """daqp's exact dual active set, called from Python each step."""
    name = "daqp"

    def setup(self, step, first=False):
        # the reduced problem inverts D: rows that depend on one another (a polygon's
        # faces on a node's two values, two planes) leave it singular
        D = step.D
        if D.size and np.linalg.cond(D) > 1e12:
            raise InputError("solver='daqp' needs independent constraint rows; this scene "
                             "has more faces at a node than the node has values (a polygon "
                             "hole): use active-set or osqp")
        return super().setup(step, first)

    def solver(self, step):
        return DAQPSolver(step.lo, step.hi, step.D)
