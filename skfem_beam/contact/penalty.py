"""Normal compliance (penalty): the obstacles are one-sided springs of stiffness κ = 1/ε.

Inside the β-scheme the spring force r(y) = −κ[(y − hi)⁺ − (lo − y)⁺] is weighted like
the elastic force: β r(y^{n+1}) + (1−2β) r(yⁿ) + β r(y^{n−1}).  The explicit part
(1−2β) r(yⁿ) + β r(y^{n−1}) is the law's ``explicit``: it enters the step's load; the
implicit part makes the step a piecewise-linear monotone equation in y:
y = y_free + D μ,  μ = Δt² β r(y),  solved exactly by a semi-smooth Newton iteration
(finite for piecewise-linear monotone maps; one step when m = 1).  The contact force
recorded is the whole β-weighted spring force.

A support's damping c (``damping``, Kelvin–Voigt: a dashpot beside the spring) adds
−c ẏ on the values whose spring is compressed at tₙ, with ẏ = (y^{n+1} − y^{n−1})/(2Δt)
as the scheme takes B's (so μ gains −(cΔt/2)(y^{n+1} − y^{n−1}) there).  Its activity
is that of tₙ, known before the step: the equation stays piecewise linear, continuous
and monotone (with the activity of t_{n+1} the dashpot would switch on with a jump
c·ẏ and Newton could cycle).  Like every linear Kelvin–Voigt contact, it also pulls
while the support unloads.

The start step weights the spring at u⁰ by ½(1−2β) instead (see scheme.run).
"""
import numpy as np
from numba import njit

from ..checks import check_nonnegative, check_positive
from .base import ContactLaw, compiled_explicit, compiled_law


@njit(cache=True)
def spring(y, lo, hi, stiffness):
    """The one-sided springs' force r(y) = −κ[(y − hi)⁺ − (lo − y)⁺] on one value."""
    return -stiffness * (max(y - hi, 0.0) - max(lo - y, 0.0))


@njit(cache=True)
def damped(y, lo, hi):
    """The dashpot acts: the spring is compressed (y beyond its bound) at tₙ."""
    return y > hi or y < lo


@njit(cache=True)
def compliance_solve(D, yf, lo, hi, c, state, mu, d, y_cur, y_prev):
    """Solve y = yf − c·D·[(y − hi)⁺ − (lo − y)⁺] − d·D·δ(y − y_prev) (c = Δt²βκ ≥ 0; the
    dashpot d = cΔt/2 on the values compressed at tₙ, δ their indicator: `damped`) for
    μ = (y − yf) in D-scaled form; ``state`` (−1/0/+1) is the warm start.  Returns
    iterations (< 0: failed)."""
    m = yf.size
    if c == 0.0:
        mu[:] = 0.0
        return 0
    y = yf.copy()
    for it in range(1, 60 + 4 * m):
        # Newton system on the current pattern: y + c D P (y − b) + d D δ (y − y_prev) = yf
        Amat = np.eye(m)
        rhs = yf.copy()
        for j in range(m):
            if state[j] != 0:
                b = hi[j] if state[j] > 0 else lo[j]
                for i in range(m):
                    Amat[i, j] += c * D[i, j]
                    rhs[i] += c * D[i, j] * b
            if d != 0.0 and damped(y_cur[j], lo[j], hi[j]):
                for i in range(m):
                    Amat[i, j] += d * D[i, j]
                    rhs[i] += d * D[i, j] * y_prev[j]
        y = np.linalg.solve(Amat, rhs)
        changed = False
        for j in range(m):
            s = 1 if y[j] > hi[j] else (-1 if y[j] < lo[j] else 0)
            if s != state[j]:
                state[j] = s
                changed = True
        if not changed:
            break
    else:
        return -1
    # μ with y = yf + D μ: μ = −c·[(y − hi)⁺ − (lo − y)⁺] − d·δ(y − y_prev)
    for j in range(m):
        mu[j] = -c * (max(y[j] - hi[j], 0.0) - max(lo[j] - y[j], 0.0))
        if d != 0.0 and damped(y_cur[j], lo[j], hi[j]):
            mu[j] -= d * (y[j] - y_prev[j])
    return it


@compiled_explicit
def penalty_explicit(y_cur, y_prev, lo, hi, params, r):
    """r = w_cur r(yⁿ) + w_prev r(yⁿ⁻¹): (1−2β) and β in a step, ½(1−2β) and 0 at the start."""
    stiffness, w_cur, w_prev = params[0], params[2], params[3]
    for j in range(r.size):
        r[j] = w_cur * spring(y_cur[j], lo[j], hi[j], stiffness) \
            + w_prev * spring(y_prev[j], lo[j], hi[j], stiffness)
    return 0


@compiled_law
def penalty_kernel(D, yf, y_cur, y_prev, lo, hi, params, state, mu, active):
    """The implicit springs (params[1] = Δt²βκ) and dashpots (params[4] = cΔt/2, on the
    values compressed at tₙ): y = yf + Dμ."""
    its = compliance_solve(D, yf, lo, hi, params[1], state, mu, params[4], y_cur, y_prev)
    m = yf.size
    for i in range(m):   # in contact: the spring is compressed at y^{n+1}
        y = yf[i]
        for j in range(m):
            y += D[i, j] * mu[j]
        active[i] = y < lo[i] or y > hi[i]
    return its


class Penalty(ContactLaw):
    """Normal compliance: the obstacles are one-sided springs of stiffness ``stiffness``
    (in the units of the semi-discrete equation: per unit mass for the beam)."""
    name = "penalty"
    kernel = penalty_kernel
    explicit = penalty_explicit

    def __init__(self, stiffness: float, damping: float = 0.0):
        self.stiffness = check_positive("stiffness", stiffness)
        self.damping = check_nonnegative("damping", damping)

    def setup(self, step, first=False):
        beta, k = step.beta, self.stiffness
        w_cur, w_prev = (0.5 * (1 - 2 * beta), 0.0) if first else (1 - 2 * beta, beta)
        return np.array([k, step.dt ** 2 * beta * k, w_cur, w_prev,
                         0.5 * step.dt * self.damping])

    def __repr__(self) -> str:
        return f"Penalty(stiffness={self.stiffness:g}, damping={self.damping:g})"
