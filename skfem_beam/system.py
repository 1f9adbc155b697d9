"""The semi-discrete system as data: what a scene is discretised into and the scheme steps,

    M ü + B u̇ + K u = Σ_k a_k(t) b_k + Cᵀλ,   lo ≤ C u ≤ hi   (λ: nodal contact forces)

:class:`SemiDiscrete` (the matrices, bounds, loads, initial state, observers), the
:class:`SceneView` the writers read and the :class:`Lifting` of a moving support.  One
plane (:mod:`skfem_beam.semidiscrete`), two planes (:mod:`skfem_beam.two_planes`) and the
bar (:mod:`skfem_beam.bar`) build it; nothing is discretised here.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import scipy.sparse as sp


@dataclass(frozen=True)
class Lifting:
    """The lifting of a moving support: ũ = u + h(x)φ(t) (docs/design.md §1).

    ``kind``: "paper" or "static"; ``h(x)``, ``h_d(x)``, ``h_dd(x)``: h, h', h'' at any
    abscissae; ``motion``: the support (``phi``, ``phi_d``, ``phi_dd`` of t).
    """
    kind: str
    h: Callable
    h_d: Callable
    h_dd: Callable
    motion: Any


@dataclass(frozen=True)
class SceneView:
    """What the output (fields, renders, charts) needs from the scene beyond the matrices.

    ``kind``: "beam" or "bar"; ``L``: length; ``k2``: bending stiffness per unit mass
    (beams, for the bending moment; None otherwise); ``support``: the moving support
    (with ``phi(t)``, optionally ``phi_d(t)``) when the lifting is the first paper's h,
    None otherwise; ``obstacles``: an object with ``bounds(x) -> (g1, g2)``, None when
    the obstacles are the bounds of the constrained values alone.

    Units (docs/design.md §1, Units): the beam's equation is divided by ``rho_S`` = ρA_ref
    (kg/m; None when unknown), so forces × rho_S are in N (per length: N/m) and energies
    × rho_S in J; ``EI`` = k2·rho_S (N·m², the first segment's for a stepped beam).
    ``lift``: the lifting (:class:`Lifting`) when the support moves, whatever its kind;
    the physical displacement is u + lift.h(x)·φ(t).  ``observed_x``: where the default
    series (``tip_displacement``) observes the beam when its end at L is held (None:
    x = L, the tip), see :func:`skfem_beam.semidiscrete.observed_node`.
    """
    kind: str = "beam"
    L: float | None = None
    k2: float | None = None
    support: Any = None
    obstacles: Any = None
    rho_S: float | None = None
    EI: float | None = None
    lift: Lifting | None = None
    observed_x: float | None = None     # the default observed point (None: the tip, x = L)
    planes: int = 1                     # 2: coefficients [v; w] (two_planes)
    direction: tuple = (1.0, 0.0)       # two planes: the support moves along it
    k2_w: float | None = None           # two planes: the second plane's k2
    holes: tuple = ()                   # two planes: the holes (holes.HoleAt)


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
    # two planes (two_planes): the round holes' row pairs (q, 2); per constrained row its
    # node's values v, w (rows 2j, 2j+1 of row_nodes) and [cy, cz, sy, sz]: the centre of
    # its hole at rest and how it moves per unit φ (None: one plane)
    planes: int = 1
    disks: np.ndarray | None = None
    lands: np.ndarray | None = None          # per disk (lands, half width, angle): a
    #                                          broached hole's; (0, 0, 0) round (None: all)
    friction: np.ndarray | None = None       # Coulomb's μ per row (a round hole's first,
    #                                          a face's own)
    tangents: np.ndarray | None = None       # (k, 2) a face with friction's row and its
    #                                          tangent row t·(v, w), t = R n (bounds ±∞)
    row_nodes: sp.csr_matrix | None = None
    row_centres: np.ndarray | None = None
    # per constrained row, the obstacle (Obstacles.parts index; one obstacle: 0) whose g1
    # and whose g2 is its lo and its hi (m, 2), −1 none (an infinite bound); None: unknown
    # (two planes, a bar): the penalty law then takes one stiffness for all
    row_obstacle: np.ndarray | None = None

    @property
    def n(self) -> int:
        return self.M.shape[0]


def snap(shift: np.ndarray) -> np.ndarray:
    """Shifts within 1e-9 of 0 are 0: h is 1 or 0 there up to round-off (the paper's h(L)
    is −5.6e-17 in floating point, the static h of a cantilever 1 ± 1e-11), and an exactly
    zero shift keeps bounds at rest (the papers' runs unchanged)."""
    return np.where(np.abs(shift) <= 1e-9, 0.0, shift)
