"""Lemma 4.1 of Dumont & Paoli (2006): with decoupled constraints the step's solution
projects the free value onto [lo, hi] and corrects x along W = A⁻¹Cᵀ."""
from numba import njit


@njit(cache=True)
def project(Ddiag, yf, lo, hi, mu):
    """μ_i = (P_[lo,hi](y_free,i) − y_free,i) / D_ii; returns the number of active values."""
    active = 0
    for i in range(yf.size):
        y = min(max(yf[i], lo[i]), hi[i])
        mu[i] = (y - yf[i]) / Ddiag[i]
        if y != yf[i]:
            active += 1
    return active
