"""Natural frequencies and mode shapes of a beam with its end conditions and supports.

The free vibrations u(x, t) = φ(x) cos(ωt) of ρA u_tt + (EI u'')'' = 0 solve the discrete
generalised eigenproblem  K φ = ω² M φ  (K = k² S, both weighted per element for a
stepped beam, mass-normalised by ρA_ref) on the space of the problem
(Hermite or B-spline, with ``ends`` and ``supports``).  Obstacles, loads, the support
motion and the initial state are ignored.

Why not ``scipy.linalg.eigh(K, M)``: dense LAPACK computes every eigenvalue with an
error of about eps·‖M⁻¹K‖ = eps·ω²_max, and ω²_max/ω²_1 grows like J⁴ (≈1e9 at J = 40
for a cantilever), so the lowest modes — the ones wanted — lose most of their digits
on fine meshes.  We solve the inverted pencil instead: ``eigh(M, K + sM)`` gives
μ = 1/(ω² + s) with errors of about eps·μ_max, i.e. relative accuracy ~eps for the
lowest modes (the largest μ); for large spaces ARPACK in shift-invert mode on the
factored banded K + sM does the same.  The shift s > 0 is only used when the ends and
supports leave rigid motions (K singular: free–free, pinned–free, sliding–free, ...).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla
from skfem.quadrature import get_quadrature
from skfem.refdom import RefLine

from .errors import InputError
from .problem import BeamProblem
from .spaces import has_rigid_motion, make_space

DENSE_MAX = 400   # up to this many dofs a dense solve is fast and needs no iteration


def beam_space(problem: BeamProblem):
    """The space of ``problem`` (weighted per element when the beam is stepped)."""
    weights = None
    if problem.beam.segments:
        x = problem.nodes
        weights = problem.beam.factors(0.5 * (x[:-1] + x[1:]))
    return make_space(problem.element, problem.nodes, problem.ends, problem.supports, weights)


@dataclass(frozen=True)
class Modes:
    """The lowest natural modes, ascending.

    ``omega`` (rad/s) and ``f`` (Hz) of shape (m,); ``vectors`` (n, m): the coefficient
    vectors in the space, M-orthonormal (vᵀMv = 1); ``x`` (s,) and ``shapes`` (s, m):
    the mode shapes sampled at x (sign: the first sizeable value is positive).
    """
    omega: np.ndarray
    f: np.ndarray
    vectors: np.ndarray
    x: np.ndarray
    shapes: np.ndarray
    space: Any


def modes(problem: BeamProblem, n: int = 6, samples_per_element: int = 10) -> Modes:
    """The ``n`` lowest natural frequencies and mode shapes of ``problem``'s beam."""
    if not isinstance(problem, BeamProblem):
        raise InputError(f"modes needs the BeamProblem (not {type(problem).__name__}; a "
                         "plate's: skfem_beam.plate.natural_frequencies)")
    space = beam_space(problem)
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= space.n:
        raise InputError(f"n={n!r} modes: must be a whole number in [1, {space.n}] (the "
                         f"number of degrees of freedom of this mesh)")
    if isinstance(samples_per_element, bool) or not isinstance(
            samples_per_element, (int, np.integer)) or samples_per_element < 1:
        raise InputError(f"samples_per_element={samples_per_element!r} must be a whole "
                         "number ≥ 1")
    k2, L = problem.beam.k2, problem.beam.L
    M, K = space.M, (k2 * space.S).tocsr()
    s = k2 / L**4 if has_rigid_motion(space) else 0.0   # of the order of the lowest flexible ω²
    A = (K + s * M).tocsc()
    if space.n <= DENSE_MAX:
        mu, V = sla.eigh(M.toarray(), A.toarray(), subset_by_index=[space.n - n, space.n - 1])
        mu, V = mu[::-1], V[:, ::-1]
        w2 = 1.0 / mu - s
    else:
        # shift-invert about −s: the eigenvalues of K nearest −s are the lowest ones
        w2, V = spla.eigsh(K.tocsc(), k=n, M=M.tocsc(), sigma=-s, which="LM")
        order = np.argsort(w2)
        w2, V = w2[order], V[:, order]
    V = V / np.sqrt(np.einsum("im,im->m", V, M @ V))          # M-orthonormal
    # polish: ω² = k²∫(v'')² / vᵀMv with ∫(v'')² summed as squares at Gauss points.  The
    # assembled S·v is a fourth difference of smooth data (round-off ~eps·J⁴, 1e-9 in ω
    # at J = 80); the Rayleigh quotient is second order in the eigenvector's error.
    X, W = get_quadrature(RefLine, 4)                          # exact: (v'')² is quadratic
    E2 = space.sampler(X[0]).E2
    # EI(x)/ρA_ref per element for a stepped beam (k2 · the bending factor)
    bend = np.ones(space.J) if space.weights is None else np.asarray(space.weights[1])
    wq = ((bend * np.asarray(space.h))[:, None] * W[None, :]).ravel()
    polished = k2 * np.einsum("q,qm->m", wq, (E2 @ V) ** 2)
    w2 = np.where(w2 > 1e-6 * k2 / L**4, polished, w2)        # rigid modes: keep ~0
    omega = np.sqrt(np.clip(w2, 0.0, None))

    xi = np.linspace(0.0, 1.0, samples_per_element + 1)
    smp = space.sampler(xi)
    keep = np.ones(smp.x.size, dtype=bool)
    keep[samples_per_element:-1:samples_per_element + 1] = False   # element ends, but x_J
    x, shapes = smp.x[keep], smp.E0[np.flatnonzero(keep)] @ V
    big = np.abs(shapes) > 1e-3 * np.abs(shapes).max(axis=0)
    sign = np.sign(shapes[big.argmax(axis=0), np.arange(n)])
    return Modes(omega=omega, f=omega / (2 * np.pi), vectors=V * sign, x=x,
                 shapes=shapes * sign, space=space)
