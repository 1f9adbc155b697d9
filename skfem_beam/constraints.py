"""Every obstacle of a beam as constraint rows at nodes, lo ≤ C u ≤ hi, in one plane or two.

The coefficients are the planes' stacked: u (one plane) or [v; w] (two, skfem_beam.two_planes).
Each row acts at a node x_i:

    the first plane's flat obstacles     g1 ≤ v(x_i) ≤ g2            (n = (1, 0))
    a hole's faces                       lo ≤ n·(v, w)(x_i) ≤ hi     (antiparallel faces:
                                                                      one row, Hole.rows)
    a face with Coulomb friction         its tangent row t·(v, w)(x_i), t = (−n_z, n_y),
                                         bounds ±∞, right after the face's own row
    a round or broached hole             the pair v(x_i), w(x_i) with the box [c − r, c + r]
                                         carrying the disk (contact.round_hole, lands)

Moving bounds, one rule for every row: the support moves by φ(t) along d = (dy, dz) (one
plane: d = (1, 0)); in the lifted variable u = ũ − hφ an obstacle fixed to the ground is
at g − hφ and a carried one at g + (1 − h)φ, so a row's bounds move by
(carried − h(x_i))·(n·d)·φ(t).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from .errors import InputError
from .holes import land_excess
from .system import snap


@dataclass
class ConstraintRows:
    """The rows gathered obstacle by obstacle.  Per row: its node's x, whether its obstacle
    is carried by the support, n·d (the share of the support's motion that moves its
    bounds) and its hole's centre (cy, cz) at rest (flat obstacles: (0, 0)).  ``carried``
    is kept per block: True/False, or the flat obstacles' Obstacles.carried_at, asked
    only when the support moves (it refuses a carried and a fixed obstacle at one x)."""
    n: int                  # unknowns per plane
    planes: int
    direction: tuple        # d, the support's direction
    blocks: list = field(default_factory=list)     # sparse rows of C
    lo: list = field(default_factory=list)
    hi: list = field(default_factory=list)
    x: list = field(default_factory=list)
    carried: list = field(default_factory=list)
    share: list = field(default_factory=list)
    centre: list = field(default_factory=list)
    disks: list = field(default_factory=list)      # (first row, second row, node) per disk
    lands: list = field(default_factory=list)      # per disk: Hole.land_row, or (0, 0, 0)
    mu: list = field(default_factory=list)         # per disk: Coulomb's μ
    faces: list = field(default_factory=list)      # (face row, tangent row, μ)
    m: int = 0

    def add(self, block, lo, hi, x, carried, share, centre=(0.0, 0.0)) -> None:
        k = block.shape[0]
        self.blocks.append(block)
        self.lo.append(np.asarray(lo, dtype=float))
        self.hi.append(np.asarray(hi, dtype=float))
        self.x.append(np.asarray(x, dtype=float))
        self.carried.append(carried)
        self.share.append(np.broadcast_to(np.asarray(share, dtype=float), (k,)))
        self.centre.append(np.broadcast_to(np.asarray(centre, dtype=float), (k, 2)))
        self.m += k

    def in_plane(self, block, plane: int):
        """Rows of one plane's unknowns as rows of all the unknowns (one plane: as given)."""
        block = sp.csr_matrix(block)
        if self.planes == 1:
            return block
        zero = sp.csr_matrix((block.shape[0], self.n))
        return sp.hstack([zero, block] if plane else [block, zero], format="csr")

    def arrays(self):
        """(C, lo, hi, x): the gathered rows as one matrix and three vectors."""
        C = self.blocks[0] if len(self.blocks) == 1 else sp.vstack(self.blocks, format="csr")
        return (C, *(np.concatenate(a) for a in (self.lo, self.hi, self.x)))


def constraint_rows(problem, space) -> ConstraintRows:
    """The rows of every obstacle of ``problem`` (module docstring); ``space`` is the
    (first) plane's."""
    direction = problem.support.direction if problem.planes == 2 else (1.0, 0.0)
    rows = ConstraintRows(space.n, problem.planes, direction)
    _flat_rows(problem, space, rows)
    for k, hole_at in enumerate(problem.holes):
        for i in _hole_nodes(problem, space, k, hole_at):
            if hole_at.hole.is_disk_pair:
                _disk_rows(rows, hole_at, space.nodal[i], float(problem.nodes[i]), i)
            else:
                _face_rows(rows, hole_at, space.nodal[i], float(problem.nodes[i]))
    return rows


def _flat_rows(problem, space, rows: ConstraintRows) -> None:
    """The flat obstacles, in the first plane: a row v(x_i) at each node where u is free
    (x_1..x_J when clamped) and a bound is finite."""
    x_nodes = problem.nodes[space.value_nodes]
    lo, hi = problem.obstacles.bounds(x_nodes)
    finite = np.isfinite(lo) | np.isfinite(hi)
    x = x_nodes[finite]
    rows.add(rows.in_plane(space.nodal[space.value_nodes[finite]], 0), lo[finite],
             hi[finite], x, problem.obstacles.carried_at, rows.direction[0])


def _hole_nodes(problem, space, k: int, hole_at) -> np.ndarray:
    """The nodes hole ``k`` acts at; InputError when there is none or one is held."""
    nodes = problem.nodes
    at = np.flatnonzero(hole_at.acts_at(nodes, problem.beam.L))
    if not at.size:
        raise InputError(f"hole {k} at x={hole_at.x:g} has no mesh node in its span")
    free = set(space.value_nodes.tolist())
    for i in at:
        if i not in free:
            raise InputError(f"hole {k} at x={nodes[i]:g}: the beam is held there (an "
                             "end or a support); a hole needs a free node")
    return at


def _disk_rows(rows: ConstraintRows, hole_at, ev, x: float, node: int) -> None:
    """A round or broached hole at a node: the rows v(x), w(x), box [c − r, c + r]."""
    if any(d[2] == node for d in rows.disks):
        raise InputError(f"two round or broached holes at x={x:g}: give the smaller one")
    hole = hole_at.hole
    r, (cy, cz) = hole.radius, hole.centre
    dy, dz = rows.direction
    rows.disks.append((rows.m, rows.m + 1, node))
    rows.lands.append(hole.land_row() if hole.is_broached else (0.0, 0.0, 0.0))
    rows.mu.append(hole_at.friction)
    rows.add(sp.vstack([rows.in_plane(ev, 0), rows.in_plane(ev, 1)]),
             [cy - r, cz - r], [cy + r, cz + r], [x, x], hole_at.carried, [dy, dz],
             hole.centre)


def _face_rows(rows: ConstraintRows, hole_at, ev, x: float) -> None:
    """A hole's faces at a node: a row n·(v, w)(x) per face (pair), and after it the
    tangent row t·(v, w)(x) of a face with friction."""
    dy, dz = rows.direction
    for ny, nz, a, b in hole_at.hole.rows():
        rows.add(sp.hstack([ny * ev, nz * ev], format="csr"), [a], [b], [x],
                 hole_at.carried, ny * dy + nz * dz, hole_at.hole.centre)
        if hole_at.friction > 0:
            rows.faces.append((rows.m - 1, rows.m, hole_at.friction))
            rows.add(sp.hstack([-nz * ev, ny * ev], format="csr"), [-np.inf], [np.inf],
                     [x], hole_at.carried, 0.0, hole_at.hole.centre)


def moving_bounds(problem, lift, rows: ConstraintRows, sample_x):
    """(motion, shift, sample_shift, centres): the rows' bounds move by shift·φ(t) and the
    samples' (the first plane's flat obstacles at ``sample_x``) by sample_shift·φ(t),
    φ = ``motion`` (module docstring; all three None when nothing moves); ``centres``:
    per row [cy, cz, sy, sz], its centre at rest and how it moves per unit φ."""
    x = np.concatenate(rows.x)
    dy, dz = rows.direction
    if lift is None:
        unit = np.zeros(x.size)
    else:
        carried = [c(xb) if callable(c) else np.full(xb.shape, float(c))
                   for c, xb in zip(rows.carried, rows.x)]
        unit = snap(np.concatenate(carried) - lift.h(x))
    centres = np.column_stack([np.concatenate(rows.centre), unit * dy, unit * dz])
    if lift is None:
        return None, None, None, centres
    shift = unit * np.concatenate(rows.share)
    shift[[t for _, t, _ in rows.faces]] = 0.0      # a tangent row's bounds are ±∞
    sample_shift = snap(problem.obstacles.carried_at(sample_x) - lift.h(sample_x)) * dy
    if np.any(shift != 0) or np.any(sample_shift != 0):
        return problem.support.phi, shift, sample_shift, centres
    return None, None, None, centres


def check_start(y0, rows: ConstraintRows, motion, shift) -> None:
    """InputError unless the constrained values y0 = C u0 lie in every hole and between
    the bounds of the other rows at t = 0 (bounds moved by shift·φ(0))."""
    _, lo, hi, x = rows.arrays()
    if motion is not None:
        p0 = float(motion(0.0))
        lo, hi = lo + shift * p0, hi + shift * p0
    tol = 1e-12 * max(1.0, np.abs(y0).max(initial=0.0))
    in_disk = np.zeros(y0.size, bool)
    for (a, b, _), land in zip(rows.disks, rows.lands):
        in_disk[[a, b]] = True
        c = 0.5 * (lo[[a, b]] + hi[[a, b]])
        r, p = 0.5 * (hi[a] - lo[a]), y0[[a, b]] - c
        out = land_excess(p[0], p[1], r, *land) if land[0] > 0 else np.hypot(*p) - r
        if out > tol:
            raise InputError(f"u0 leaves the {'broached' if land[0] > 0 else 'round'} "
                             f"hole at x={x[a]:g}")
    bad = ~in_disk & ((y0 < lo - tol) | (y0 > hi + tol))
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(f"u0 violates the obstacles at x={x[i]:g}: "
                         f"u0={y0[i]:.10g} not in [{lo[i]:.10g}, {hi[i]:.10g}]")


def friction(rows: ConstraintRows) -> np.ndarray | None:
    """μ per row: a round hole's at its first row, a face's at its row (its tangent row:
    0); None: no friction anywhere."""
    if not any(rows.mu) and not rows.faces:
        return None
    out = np.zeros(rows.m)
    for (a, _, _), value in zip(rows.disks, rows.mu):
        out[a] = value
    for j, _, value in rows.faces:
        out[j] = value
    return out
