"""Newton restitution for the position-level scheme (Paoli & Schatzman).

With a coefficient e ∈ [0, 1] the constraint acts on (u^{n+1} + e·u^{n−1})/(1 + e) instead
of u^{n+1}:  lo ≤ (y^{n+1} + e·y^{n−1})/(1 + e) ≤ hi, i.e. the bounds of the step are

    (1 + e)·lo − e·y^{n−1}  ≤  y^{n+1}  ≤  (1 + e)·hi − e·y^{n−1},

and the step is the same QP with shifted bounds (projection or the exact active set).
e = 0 is today's scheme, bit for bit.  For a rigid body the discrete rebound velocity is
e times the approach velocity; for a continuum the papers prove convergence for e = 0
only: e > 0 is a model of the energy lost at a contact that the continuum does not
resolve, and a node in contact may sit up to e·|y^{n−1} − bound| beyond the obstacle for
a step (the O(Δt) penetration of the Paoli–Schatzman scheme), reported as nodal violation.
"""
import numpy as np

from ..checks import check_restitution
from .active_set import box_qp
from .base import ContactLaw, compiled_law


@compiled_law
def restitution_projection(D, yf, y_cur, y_prev, lo, hi, params, state, mu, active):
    e = params[0]
    for i in range(yf.size):
        y = min(max(yf[i], (1.0 + e) * lo[i] - e * y_prev[i]), (1.0 + e) * hi[i] - e * y_prev[i])
        mu[i] = (y - yf[i]) / D[i, i]
        active[i] = mu[i] != 0.0
    return 0


@compiled_law
def restitution_active_set(D, yf, y_cur, y_prev, lo, hi, params, state, mu, active):
    e = params[0]
    lo_e = np.empty(lo.size)
    hi_e = np.empty(hi.size)
    for i in range(lo.size):
        lo_e[i] = (1.0 + e) * lo[i] - e * y_prev[i]
        hi_e[i] = (1.0 + e) * hi[i] - e * y_prev[i]
    its = box_qp(D, yf, lo_e, hi_e, state, mu)
    for i in range(mu.size):
        active[i] = mu[i] != 0.0
    return its


class Restitution(ContactLaw):
    """The position-level scheme with a Newton coefficient of restitution ``e``; the
    step's QP is solved by projection (decoupled constraints) or the exact active set."""
    name = "restitution"

    def __init__(self, e: float):
        self.e = check_restitution(e)

    def setup(self, step, first=False):
        self.kernel = restitution_projection if step.decoupled else restitution_active_set
        return np.array([self.e])

    def __repr__(self) -> str:
        return f"Restitution(e={self.e:g})"
