"""Lemma 4.1 of Dumont & Paoli (2006): with decoupled constraints the step's solution
projects the free value onto [lo, hi] and corrects x along W = A⁻¹Cᵀ."""
from numba import njit

from ..errors import InputError
from .base import ContactLaw, compiled_law


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


@compiled_law
def projection_kernel(D, yf, y_cur, y_prev, lo, hi, params, state, mu, active):
    for i in range(yf.size):
        y = min(max(yf[i], lo[i]), hi[i])
        mu[i] = (y - yf[i]) / D[i, i]
        active[i] = mu[i] != 0.0
    return 0    # closed form: no iterations


class Projection(ContactLaw):
    name = "projection"
    kernel = projection_kernel

    def setup(self, step, first=False):
        if not step.decoupled:
            raise InputError(f"solver='projection' needs decoupled constraints; this scene has "
                             f"{step.D.shape[0]} coupled constrained values: use active-set, "
                             f"osqp or daqp")
        return super().setup(step, first)
