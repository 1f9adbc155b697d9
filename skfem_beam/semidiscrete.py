"""From a scene to the semi-discrete system the integrator steps:

    M ü + B u̇ + K u = Σ_k a_k(t) b_k + Cᵀλ,   lo ≤ C u ≤ hi   (λ: nodal contact forces)

The same object serves the beam (Hermite or B-spline, B = 0) and the bar (P1, with
Kelvin–Voigt damping), so there is one time scheme for all scenes.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import scipy.sparse as sp

from .errors import InputError
from .problem import BeamProblem, lifting
from .spaces import make_space


@dataclass(frozen=True)
class SceneView:
    """What the output (fields, renders, charts) needs from the scene beyond the matrices.

    ``kind``: "beam" or "bar"; ``L``: length; ``k2``: bending stiffness per unit mass
    (beams, for the bending moment; None otherwise); ``support``: the moving support
    (with ``phi(t)``, optionally ``phi_d(t)``), None when it does not move; ``obstacles``:
    an object with ``bounds(x) -> (g1, g2)``, None when the obstacles are the bounds of
    the constrained values alone.
    """
    kind: str = "beam"
    L: float | None = None
    k2: float | None = None
    support: Any = None
    obstacles: Any = None


@dataclass
class SemiDiscrete:
    M: sp.csr_matrix
    K: sp.csr_matrix
    C: sp.csr_matrix                 # constrained values y = C u (only finite bounds)
    lo: np.ndarray
    hi: np.ndarray
    x_contact: np.ndarray            # abscissae of the constrained values
    loads: np.ndarray                # (n, K): b_k as load vectors (b_k, φ_i)
    load_time: list[Callable]        # a_k(t), vectorised
    u0: np.ndarray
    v0: np.ndarray
    observe: dict[str, np.ndarray]   # name -> row vector (e.g. tip displacement)
    B: sp.csr_matrix | None = None   # damping
    space: Any = None
    sample_x: np.ndarray | None = None       # abscissae where penetration is measured
    sample_E: sp.csr_matrix | None = None    # values there = sample_E @ u
    sample_lo: np.ndarray | None = None
    sample_hi: np.ndarray | None = None
    meta: dict = field(default_factory=dict)
    view: SceneView | None = None            # what the output needs (see SceneView)
    # moving bounds (obstacles fixed to the ground or carried by a moving support, in the
    # lifted variable): at time t the bounds are lo + bound_shift·φ(t), hi + bound_shift·φ(t)
    # (and sample_lo/hi + sample_shift·φ(t)); φ = bound_motion, vectorised in t
    bound_motion: Callable | None = None
    bound_shift: np.ndarray | None = None    # (m,)
    sample_shift: np.ndarray | None = None   # (samples,)

    @property
    def n(self) -> int:
        return self.M.shape[0]


def beam_system(problem: BeamProblem, samples_per_element: int = 20) -> SemiDiscrete:
    """Discretise a beam scene (the papers' V_h, K_h of (8), loads with the lifting)."""
    beam, sup = problem.beam, problem.support
    space = make_space(problem.element, problem.nodes, problem.ends, problem.supports)
    x_nodes = problem.nodes[space.value_nodes]     # where u is free (x_1..x_J when clamped)
    lo_all, hi_all = problem.obstacles.bounds(x_nodes)
    finite = np.isfinite(lo_all) | np.isfinite(hi_all)
    C = space.nodal[space.value_nodes[finite]]

    # f = f̃ − h φ'' − k² h'''' φ, with h'''' = −8/L⁴
    L, k2 = beam.L, beam.k2
    profiles, times = [], []
    if sup.moves:
        profiles += [lambda x: -lifting(x, L), lambda x: np.full(np.shape(x), 8 * k2 / L**4)]
        times += [sup.phi_dd, sup.phi]
    for b, a in problem.load.terms:
        profiles.append(b)
        times.append(a)
    loads = np.column_stack([space.load_vector(b) for b in profiles]) if profiles \
        else np.zeros((space.n, 0))

    ini = problem.initial
    u0 = space.interpolate(ini.u0, ini.du0) if ini.u0 is not None else np.zeros(space.n)
    # initial velocity: L² projection (v0 need not be in V: the first paper's v0 = −2h has
    # v0(0) = −2 ≠ 0; (2.1) asks for convergence in H, which the L² projection gives best)
    v_phys = ini.v0
    v0 = space.project(v_phys) if v_phys is not None else np.zeros(space.n)
    if not (np.isfinite(u0).all() and np.isfinite(v0).all()):
        raise InputError("the initial state u0, v0 is not finite")

    y0 = C @ u0
    lo, hi = lo_all[finite], hi_all[finite]
    tol = 1e-12 * max(1.0, np.abs(y0).max(initial=0.0))
    bad = (y0 < lo - tol) | (y0 > hi + tol)
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(f"u0 violates the obstacles at x={x_nodes[finite][i]:g}: "
                         f"u0={y0[i]:g} not in [{lo[i]:g}, {hi[i]:g}]")

    with np.errstate(over="ignore", invalid="ignore"):
        K = (k2 * space.S).tocsr()
    if not np.isfinite(K.data).all():
        raise InputError(f"k2={k2:g} on this mesh gives a stiffness outside floating-point range")

    sampler = space.sampler(np.linspace(0.0, 1.0, samples_per_element + 1))
    s_lo, s_hi = problem.obstacles.bounds(sampler.x)
    keep = np.isfinite(s_lo) | np.isfinite(s_hi)
    observe = {"tip_displacement": np.asarray(space.C[-1].toarray()).ravel()}
    return SemiDiscrete(
        M=space.M, K=K, C=sp.csr_matrix(C), lo=lo, hi=hi,
        x_contact=x_nodes[finite], loads=loads, load_time=times, u0=u0, v0=v0,
        observe=observe, space=space,
        sample_x=sampler.x[keep], sample_E=sampler.E0[np.flatnonzero(keep)].tocsr(),
        sample_lo=s_lo[keep], sample_hi=s_hi[keep],
        meta={"kind": "beam", "L": L, "k2": k2, "rho_S": beam.rho_S,
              "element": problem.element, "J": problem.J, "problem": problem},
        view=SceneView("beam", L, k2, sup if sup.moves else None, problem.obstacles))
