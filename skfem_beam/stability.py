"""Stability of the β-family: the exact κ_h, the papers' bounds, the step limits.

κ_h = sup a(u,u)/|u|² over V_h is the largest generalised eigenvalue of (K, M).  The
papers bound it from above by closed forms; the critical steps follow from

- Prop. 3.1 of the first paper:  Δt < 2 √((1−α)/(κ_h (1−2β)))   (α → 0 here),
- eq. (10) of the second paper:  Δt < √(2(1−α)/(κ_h (1−2β))),
- linear Newmark (γ = 1/2):      Δt < 2/√(κ_h (1−4β)) for β < 1/4, none for β ≥ 1/4.

The papers' conditions are sufficient only; the linear limit is where runs really fail.
"""
from __future__ import annotations

import math

import numpy as np
import scipy.linalg
import scipy.sparse.linalg

from .spaces.redistribution import massless_rows

# upper bounds κ_h ≤ c · k²/Δx⁴ printed in the papers
PAPER_KAPPA_BOUNDS = {
    "hermite": {
        "first paper (5.2), 24·420·19²/37": 24 * 420 * 19**2 / 37,
        "first paper (5.2) as printed, 2⁵·5·19²·21/37": 2**5 * 5 * 19**2 * 21 / 37,
        "second paper, 2729160/37": 2729160 / 37,
    },
    "bspline": {"second paper, 5040": 5040.0},
}


def kappa_h(system) -> float:
    """κ_h: the largest generalised eigenvalue of (K, M) of a SemiDiscrete system.

    Dense below 100 dofs, sparse Lanczos (eigsh) above: the largest eigenvalue is well
    separated and well conditioned (it is the smallest ones that dense eigh(K, M) loses).
    """
    M, K = system.M.tocsr(), system.K.tocsr()
    massless = massless_rows(M)
    if massless.size:
        # a redistributed mass: the massless dofs held (contact) leave K on the others, and
        # free (in equilibrium) a softer Schur complement, so (K, M) there bounds both
        mass = np.setdiff1d(np.arange(M.shape[0]), massless)
        M, K = M[mass][:, mass], K[mass][:, mass]
    n = M.shape[0]
    if n < 100:
        return float(scipy.linalg.eigh(K.toarray(), M.toarray(), eigvals_only=True,
                                       subset_by_index=[n - 1, n - 1])[0])
    # a fixed start vector: ARPACK's own random one made summary.json's kappa_h differ in
    # its last digits from run to run
    v0 = np.random.default_rng(0).standard_normal(n)
    return float(scipy.sparse.linalg.eigsh(K.tocsc(), k=1, M=M.tocsc(), v0=v0,
                                           which="LM", return_eigenvectors=False,
                                           tol=1e-10)[0])


def linear_limit(kappa: float, beta: float) -> float:
    """2/√(κ_h(1−4β)); ∞ for β ≥ 1/4."""
    return math.inf if beta >= 0.25 else 2.0 / math.sqrt(kappa * (1.0 - 4.0 * beta))


def prop31_limit(kappa: float, beta: float) -> float:
    """First paper, Prop. 3.1 with α → 0: 2/√(κ_h(1−2β)); ∞ for β = 1/2."""
    return math.inf if beta >= 0.5 else 2.0 / math.sqrt(kappa * (1.0 - 2.0 * beta))


def eq10_limit(kappa: float, beta: float) -> float:
    """Second paper, eq. (10) with α → 0: √(2/(κ_h(1−2β))); ∞ for β = 1/2."""
    return math.inf if beta >= 0.5 else math.sqrt(2.0 / (kappa * (1.0 - 2.0 * beta)))


def stability_table(kappa: float, element: str, k2: float, dx: float, beta: float) -> list[dict]:
    """κ (exact and the papers' bounds) with the step limits each gives, for one β."""
    rows = [{"kappa_from": "exact (largest eigenvalue of (K, M))", "kappa": kappa}]
    for name, c in PAPER_KAPPA_BOUNDS.get(element, {}).items():
        rows.append({"kappa_from": name, "kappa": c * k2 / dx**4})
    for r in rows:
        r.update(ratio_to_exact=r["kappa"] / kappa,
                 dt_linear=linear_limit(r["kappa"], beta),
                 dt_prop31=prop31_limit(r["kappa"], beta),
                 dt_eq10=eq10_limit(r["kappa"], beta))
    return rows
