"""Normal compliance (penalty): the obstacles are one-sided springs of stiffness κ = 1/ε.

Inside the β-scheme the spring force r(y) = −κ[(y − hi)⁺ − (lo − y)⁺] is weighted like
the elastic force: β r(y^{n+1}) + (1−2β) r(yⁿ) + β r(y^{n−1}).  The explicit part is
added to the load; the implicit part makes the step a piecewise-linear monotone
equation in y:  y = y_free + D μ,  μ = Δt² β r(y),  solved exactly by a semi-smooth
Newton iteration (finite for piecewise-linear monotone maps; one step when m = 1).
"""
import numpy as np
from numba import njit


@njit(cache=True)
def spring_force(y, lo, hi, kappa, r):
    for i in range(y.size):
        r[i] = -kappa * (max(y[i] - hi[i], 0.0) - max(lo[i] - y[i], 0.0))


@njit(cache=True)
def compliance_solve(D, yf, lo, hi, c, state, mu):
    """Solve y = yf − c·D·[(y − hi)⁺ − (lo − y)⁺] (c = Δt²βκ ≥ 0) for μ = (y − yf) in
    D-scaled form; ``state`` (−1/0/+1) is the warm start.  Returns iterations (< 0: failed)."""
    m = yf.size
    if c == 0.0:
        mu[:] = 0.0
        return 0
    y = yf.copy()
    for it in range(1, 60 + 4 * m):
        # Newton system on the current pattern: y + c D P (y − b) = yf
        Amat = np.eye(m)
        rhs = yf.copy()
        for j in range(m):
            if state[j] != 0:
                b = hi[j] if state[j] > 0 else lo[j]
                for i in range(m):
                    Amat[i, j] += c * D[i, j]
                    rhs[i] += c * D[i, j] * b
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
    # μ with y = yf + D μ: μ = −c·[(y − hi)⁺ − (lo − y)⁺]
    for j in range(m):
        mu[j] = -c * (max(y[j] - hi[j], 0.0) - max(lo[j] - y[j], 0.0))
    return it
