"""Exact solutions the numerical results are tested against."""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

# roots of 1 + cos(βL) cosh(βL) = 0: the clamped–free Euler–Bernoulli beam
CANTILEVER_BETA_L = (1.87510407, 4.69409113, 7.85475744, 10.99554073)


def cantilever_beta_l(count: int) -> np.ndarray:
    """The first ``count`` roots βₙL of 1 + cos x cosh x = 0, to machine precision."""
    f = lambda x: np.cos(x) + 1.0 / np.cosh(x)  # noqa: E731  (same roots, no overflow)
    return np.array([brentq(f, (n + 0.5) * np.pi - 1.0, (n + 0.5) * np.pi + 0.5, xtol=1e-15)
                     for n in range(count)])


def cantilever_omegas(L: float, k2: float, count: int = 4) -> np.ndarray:
    """Angular eigenfrequencies ωₙ = (βₙL)² √k² / L² of u_tt + k² u_xxxx = 0, clamped–free."""
    return cantilever_beta_l(count) ** 2 * np.sqrt(k2) / L**2


def cantilever_mode(x, L: float, n: int) -> np.ndarray:
    """Mode shape n (0-based), normalised to 1 at the free end x = L."""
    bl = cantilever_beta_l(n + 1)[n]
    s = bl * np.asarray(x, dtype=float) / L
    sigma = (np.cosh(bl) + np.cos(bl)) / (np.sinh(bl) + np.sin(bl))
    phi = lambda z: np.cosh(z) - np.cos(z) - sigma * (np.sinh(z) - np.sin(z))  # noqa: E731
    return phi(s) / phi(bl)
