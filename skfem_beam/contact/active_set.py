"""Exact active-set solver for the box-constrained step problem in y (compiled).

Placeholder: primal–dual active set (semi-smooth Newton) with warm start; replaced by
a safeguarded exact method in the longitudinal-obstacles work.
"""
import numpy as np
from numba import njit


@njit(cache=True)
def box_qp(D, yf, lo, hi, state, mu):
    """Solve y = yf + Dμ, lo ≤ y ≤ hi with complementarity; ``state`` (int8: −1 at lo,
    +1 at hi, 0 free) is the warm start and is updated.  Returns iterations (< 0: failed)."""
    m = yf.size
    for it in range(1, 50 + 2 * m):
        idx = np.flatnonzero(state != 0)
        mu[:] = 0.0
        if idx.size:
            rhs = np.empty(idx.size)
            for a in range(idx.size):
                i = idx[a]
                rhs[a] = (lo[i] if state[i] < 0 else hi[i]) - yf[i]
            sol = np.linalg.solve(D[idx][:, idx], rhs)
            for a in range(idx.size):
                mu[idx[a]] = sol[a]
        y = yf + D @ mu
        changed = False
        for i in range(m):
            if state[i] == 0:
                if y[i] < lo[i]:
                    state[i] = -1
                    changed = True
                elif y[i] > hi[i]:
                    state[i] = 1
                    changed = True
            elif state[i] * mu[i] > 0:   # wrong-signed multiplier: release
                state[i] = 0
                changed = True
        if not changed:
            return it
    return -1
