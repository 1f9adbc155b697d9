"""Mass redistribution (the modified-mass class of contact time-stepping): no inertia at
the degrees of freedom a contact constraint acts on, their mass moved to their
neighbours so that the total mass and the centre of mass are kept.

Which dofs lose mass: those the constraint rows C touch, and only those.

- P1 (bar): the contact node's value (its mass row of the average mass, the bar's
  default, is emptied);
- Hermite: the contact node's *displacement* dof.  Its rotation dof keeps its inertia:
  the constraint does not act on it, and a massless rotation would make the beam's
  rotation at the stop quasi-static for no reason;
- cubic B-splines: the coefficients whose B-splines are nonzero at the contact point
  (three at an interior node; at an end they are the end's coefficients).  A value
  u(x) = Σ c_j B_j(x) has no inertia only if every c_j it reads has none.

The neighbours are the other dofs coupled to those in M.  The redistributed matrix is
M₀ + Δ, M₀ = M with the massless rows and columns zeroed, Δ symmetric on the
neighbours, the least-squares-smallest one with r_aᵀ(M₀ + Δ)r_b = r_aᵀ M r_b for
(a, b) = (1, 1) (total mass) and (1, x) (first moment: the centre of mass), r_1 and r_x
the space's interpolants of 1 and x.  It is refused when the constraints touch more
than a quarter of the dofs (obstacles along the span: nothing would be left to carry
the mass) or when M₀ + Δ is not positive definite on the dofs that keep mass.

The step of a massless dof is quasi-static.  By default (``Stepping(massless="beta")``)
its row of the scheme is the β-weighted K row, β u^{n+1} + (1−2β) uⁿ + β u^{n−1}.  At
β = 1/4 that recursion has the double root −1 and the discrete energy does not control
it (its M/Δt² + (β−1/4)K part is zero there): the massless node oscillates step to
step.  At β = 1/2 the energy holds it (roots ±i, E_β ⊇ ¼δᵀKδ), and β < 1/4 is refused
(β = 0 makes the step matrix A = M singular).  ``massless="quasi-static"`` writes the row
as equilibrium at the new time, K u^{n+1} = f^{n+1} + Cᵀλ^{n+1} (scheme.operators): no
recursion, so any β > 0, down to the central-difference limit (β = 0.01).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from ..errors import InputError

MOMENTS = ((0, 0), (0, 1))      # total mass, first moment (centre of mass)


def massless_rows(M) -> np.ndarray:
    """The dofs without inertia (their rows of M are zero: a redistributed mass)."""
    return np.flatnonzero(np.asarray(abs(sp.csr_matrix(M)).sum(axis=1)).ravel() == 0)


def massless_dofs(C) -> np.ndarray:
    """The dofs the constraint rows act on."""
    C = sp.csr_matrix(C)
    C.eliminate_zeros()
    return np.unique(C.indices)


def neighbours(G, massless) -> np.ndarray:
    """The dofs coupled to ``massless`` in the pattern G (two layers when one holds fewer
    than two dofs, e.g. a lumped mass: one dof cannot keep both moments)."""
    near = np.setdiff1d(np.unique(G[massless].indices), massless)
    if near.size < 2:
        near = np.setdiff1d(np.unique(G[np.r_[massless, near]].indices), massless)
    return near


def redistribute(M, K, massless, modes) -> sp.csr_matrix:
    """M with no inertia at ``massless``, the mass moved to their neighbours (coupled in
    M or K) so that rᵀMr' is kept for the moment pairs of ``modes`` (n × 2: interpolants
    of 1 and x)."""
    M = sp.csr_matrix(M)
    n = M.shape[0]
    massless = np.asarray(massless, dtype=int)
    if massless.size == 0:
        return M
    if 4 * massless.size > n:
        raise InputError(f"mass='redistributed' needs contact at isolated points: the "
                         f"constraints act on {massless.size} of the {n} dofs (obstacles "
                         f"along the span leave nothing to carry the mass)")
    keep = np.ones(n)
    keep[massless] = 0.0
    P = sp.diags(keep)
    M0 = (P @ M @ P).tocsr()
    G = abs(M) + abs(sp.csr_matrix(K))
    live = np.flatnonzero(keep)
    near = neighbours(G, massless)
    for _ in range(4):        # widen the neighbourhood until M₀ + Δ is positive definite
        Mr = _moved(M, M0, near, modes)
        try:
            np.linalg.cholesky(Mr[live][:, live].toarray())
            return Mr
        except np.linalg.LinAlgError:
            near = np.setdiff1d(np.unique(G[np.r_[massless, near]].indices), massless)
    raise InputError("mass='redistributed': moving the contact dofs' mass to their "
                     "neighbours left a mass matrix that is not positive definite "
                     "(refine the mesh near the contact)")


def _moved(M, M0, near, modes) -> sp.csr_matrix:
    """M0 + Δ, Δ the smallest symmetric matrix on ``near`` that restores the moments."""
    n = M.shape[0]
    pairs = [(a, b) for i, a in enumerate(near) for b in near[i:]]
    R = np.asarray(modes, dtype=float)
    rows, rhs = [], []
    for r, s in MOMENTS:
        rows.append([R[a, r] * R[b, s] + (R[b, r] * R[a, s] if a != b else 0.0)
                     for a, b in pairs])
        rhs.append(R[:, r] @ (M @ R[:, s]) - R[:, r] @ (M0 @ R[:, s]))
    # least Frobenius norm of Δ relative to M's diagonal (Hermite rotation dofs have other
    # units than values); an off-diagonal unknown stands for two entries of Δ
    d = M.diagonal()
    w = np.array([(1.0 if a == b else np.sqrt(2.0)) / np.sqrt(d[a] * d[b]) for a, b in pairs])
    z = np.linalg.lstsq(np.array(rows) / w, np.array(rhs), rcond=None)[0] / w
    if np.abs(np.array(rows) @ z - rhs).max() > 1e-10 * max(np.abs(rhs).max(),
                                                            M.diagonal().max()):
        raise InputError("mass='redistributed': the neighbours of the contact dofs cannot "
                         "take their mass with the centre of mass kept")
    i, j = np.array(pairs).T
    D = sp.coo_matrix((np.r_[z, z[i != j]], (np.r_[i, j[i != j]], np.r_[j, i[i != j]])),
                      shape=(n, n))
    Mr = (M0 + D).tocsr()
    Mr.eliminate_zeros()
    return Mr


def rigid_modes(space) -> np.ndarray:
    """The space's interpolants of 1 and x (n × 2)."""
    return np.column_stack([space.interpolate(np.ones_like, np.zeros_like),
                            space.interpolate(lambda x: np.asarray(x, dtype=float),
                                              np.ones_like)])


def redistributed(system):
    """``system`` (a SemiDiscrete) with its mass redistributed away from the dofs its
    constraints act on.  Loads and moving supports are kept as they are (the run bounds
    their work in the norm of (M + βΔt²K)⁻¹, see scheme.operators.load_norms), and so is
    its damping B: a bar's (Kelvin–Voigt, bA S) holds no mass; a beam's Rayleigh or modal
    damping does, so a beam is built with ``beam_system(problem, mass="redistributed")``,
    which makes B from the redistributed mass."""
    M = redistribute(system.M, system.K, massless_dofs(system.C), rigid_modes(system.space))
    return replace(system, M=M)
