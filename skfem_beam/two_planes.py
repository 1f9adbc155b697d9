"""A beam bending in two planes: v(x, t) and w(x, t), each in the one-plane space.

The planes share the space, the ends, the supports and the mass; each has its own
bending stiffness (k2 = EI/ρA and k2_w = EI_w/ρA), its own loads, and the support moves along a
direction d = (dy, dz).  The coefficients are [v; w], so the matrices are block-diagonal,

    M = diag(M₁, M₁),  K = diag(k2·S, k2_w·S),  B = diag(B_v, B_w),

and a banded solve keeps the one-plane band (twice the unknowns, the same bandwidth).
The constraints couple the planes only at the nodes: a row is lo ≤ n·(v, w)(x_i) ≤ hi
(the first plane's flat obstacles: n = (1, 0); a hole's faces, antiparallel ones in one
row: holes.Hole.rows), and a round hole adds the pair of rows v(x_i), w(x_i) whose box
[c − r, c + r] carries the disk (``disks``; contact.round_hole); a broached hole is such
a pair too, with its lands (``lands``; contact.lands).  A face of a hole with Coulomb
friction adds its tangent row t·(v, w) right after its own (t = (−n_z, n_y), bounds ±∞;
``tangents``: the pairs; contact.round_hole_friction).  Obstacles that move with
the support move along d: a row's bound moves by (carried − h(x_i))·(n·d)·φ(t).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from .errors import InputError
from .holes import land_excess
from .problem import InitialState, Load, Obstacles, Support
from .system import SemiDiscrete, snap
from .timefunctions import Scaled


def along(support: Support, share: float) -> Support:
    """The support's motion times ``share`` (one plane's part of its direction)."""
    if not support.moves or share == 0.0:
        return Support(at=support.at, lifting=support.lifting)
    if share == 1.0:
        return replace(support, direction=(1.0, 0.0))
    if support.motion is None:
        return Support(support.amplitude * share, support.omega, at=support.at,
                       lifting=support.lifting)
    return Support(motion=Scaled(support.motion, share), at=support.at,
                   lifting=support.lifting)


def _blocks(a, b):
    return None if a is None and b is None else sp.block_diag([a, b], format="csr")


def _pad(rows, n: int, second: bool):
    """Rows of one plane as rows of [v; w] (in the first or the second block)."""
    rows = sp.csr_matrix(rows)
    zero = sp.csr_matrix((rows.shape[0], n))
    return sp.hstack([zero, rows] if second else [rows, zero], format="csr")


def plane_problems(problem):
    """(pv, pw): the one-plane problems of a ``planes = 2`` BeamProblem's planes, each with
    its own bending stiffness, loads and share of the support's motion (the flat
    obstacles act in the first; the holes are the caller's)."""
    dy, dz = problem.support.direction
    one = dict(planes=1, holes=(), load_w=Load())
    pv = replace(problem, **one, support=along(problem.support, dy))
    pw = replace(problem, **one, load=problem.load_w, obstacles=Obstacles(),
                 beam=problem.beam.plane_w(), support=along(problem.support, dz),
                 initial=InitialState(fixed_frame=problem.initial.fixed_frame))
    return pv, pw


def two_plane_system(problem, sv: SemiDiscrete, sw: SemiDiscrete) -> SemiDiscrete:
    """The semi-discrete system of a ``planes = 2`` BeamProblem (module docstring) from the
    systems ``sv``, ``sw`` of its two planes (:func:`plane_problems`, each discretised by
    :func:`skfem_beam.semidiscrete.beam_system`, which calls this)."""
    sup = problem.support
    dy, dz = sup.direction
    space, n = sv.space, sv.n
    lift = sv.view.lift or sw.view.lift
    phi = sup.phi if lift is not None else None
    nodes = problem.nodes

    def node_of(x):
        return int(np.abs(nodes - x).argmin())

    def shift_at(x, carried):
        return 0.0 if lift is None else float(snap(np.array([float(carried)
                                                              - lift.h(np.array([x]))[0]]))[0])

    # the first plane's flat obstacles: rows [C, 0]; their shifts were per dy·φ
    rows = [_pad(sv.C, n, False)]
    lo, hi, xs = [sv.lo], [sv.hi], [sv.x_contact]
    carried_v = problem.obstacles.carried_at(sv.x_contact) if sv.x_contact.size else []
    shift = [np.array([shift_at(x, c) * dy for x, c in zip(sv.x_contact, carried_v)])]
    centre = [np.column_stack([np.zeros((sv.lo.size, 2)),
                               np.array([[shift_at(x, c) * dy, shift_at(x, c) * dz]
                                         for x, c in zip(sv.x_contact, carried_v)])
                               .reshape(-1, 2)])]
    disks, mu, lands, m = [], [], [], sv.C.shape[0]
    faces = []      # (face row, its tangent row, μ): faces with Coulomb friction
    free = set(space.value_nodes.tolist())
    for k, h in enumerate(problem.holes):
        at = np.flatnonzero(h.acts_at(nodes, problem.beam.L))
        if not at.size:
            raise InputError(f"hole {k} at x={h.x:g} has no mesh node in its span")
        for i in at:
            if i not in free:
                raise InputError(f"hole {k} at x={nodes[i]:g}: the beam is held there (an "
                                 "end or a support); a hole needs a free node")
            x = float(nodes[i])
            ev = space.nodal[i]
            s = shift_at(x, h.carried)
            c = np.array([[h.hole.centre[0], h.hole.centre[1], s * dy, s * dz]])
            if h.hole.is_disk_pair:
                if any(d[2] == i for d in disks):
                    raise InputError(f"two round or broached holes at x={x:g}: give the "
                                     "smaller one")
                r, (cy, cz) = h.hole.radius, h.hole.centre
                rows += [_pad(ev, n, False), _pad(ev, n, True)]
                lo.append(np.array([cy - r, cz - r]))
                hi.append(np.array([cy + r, cz + r]))
                shift.append(np.array([s * dy, s * dz]))
                disks.append((m, m + 1, i))
                lands.append(h.hole.land_row() if h.hole.is_broached else (0.0, 0.0, 0.0))
                mu.append(h.friction)
                m += 2
                xs.append(np.array([x, x]))
                centre.append(np.repeat(c, 2, axis=0))
                continue
            for ny, nz, a, b in h.hole.rows():
                rows.append(sp.hstack([ny * ev, nz * ev], format="csr"))
                lo.append(np.array([a]))
                hi.append(np.array([b]))
                shift.append(np.array([s * (ny * dy + nz * dz)]))
                xs.append(np.array([x]))
                centre.append(c)
                m += 1
                if h.friction > 0:       # the face's tangent row t·(v, w), t = (−nz, ny)
                    rows.append(sp.hstack([-nz * ev, ny * ev], format="csr"))
                    lo.append(np.array([-np.inf]))
                    hi.append(np.array([np.inf]))
                    shift.append(np.zeros(1))
                    xs.append(np.array([x]))
                    centre.append(c)
                    faces.append((m - 1, m, h.friction))
                    m += 1
    C = sp.vstack(rows, format="csr") if m else sp.csr_matrix((0, 2 * n))
    lo, hi, x_c = (np.concatenate(a) for a in (lo, hi, xs))
    shift, centre = np.concatenate(shift), np.concatenate(centre).reshape(-1, 4)
    motion = phi if lift is not None and np.any(shift != 0) else None
    u0, v0 = np.concatenate([sv.u0, sw.u0]), np.concatenate([sv.v0, sw.v0])
    _check_start(C @ u0, lo, hi, disks, x_c, motion, shift, lands)

    # penetration samples: the first plane's flat obstacles (a hole acts at its nodes)
    sample_E = _pad(sv.sample_E, n, False)
    s_shift = None
    if motion is not None and sv.sample_x.size:
        carried = problem.obstacles.carried_at(sv.sample_x)
        s_shift = np.array([shift_at(x, c) * dy for x, c in zip(sv.sample_x, carried)])
    observe = {}
    for name, plane, second in (("v", sv, False), ("w", sw, True)):
        for key, row in plane.observe.items():
            observe[f"{key}_{name}"] = np.concatenate([np.zeros(n), row] if second
                                                      else [row, np.zeros(n)])
    for x in sorted({float(nodes[i]) for h in problem.holes
                     for i in np.flatnonzero(h.acts_at(nodes, problem.beam.L))}):
        ev = space.nodal[node_of(x)].toarray().ravel()     # the orbit at every hole node
        observe[f"hole_{x:g}_displacement_v"] = np.concatenate([ev, np.zeros(n)])
        observe[f"hole_{x:g}_displacement_w"] = np.concatenate([np.zeros(n), ev])
    node_rows = sp.vstack([sp.vstack([_pad(space.nodal[node_of(x)], n, False),
                                      _pad(space.nodal[node_of(x)], n, True)])
                           for x in x_c], format="csr") if m else sp.csr_matrix((0, 2 * n))
    view = replace(sv.view, lift=None if lift is None else replace(lift, motion=sup),
                   support=None, planes=2, direction=(dy, dz), k2_w=sw.view.k2,
                   holes=problem.holes)
    return SemiDiscrete(
        M=_blocks(sv.M, sw.M), K=_blocks(sv.K, sw.K), C=C, lo=lo, hi=hi, x_contact=x_c,
        loads=np.hstack([np.vstack([sv.loads, np.zeros_like(sv.loads)]),
                         np.vstack([np.zeros_like(sw.loads), sw.loads])]),
        load_time=list(sv.load_time) + list(sw.load_time), u0=u0, v0=v0, observe=observe,
        B=_blocks(sv.B, sw.B), space=space, sample_x=sv.sample_x, sample_E=sample_E,
        sample_lo=sv.sample_lo, sample_hi=sv.sample_hi,
        meta={**sv.meta, "planes": 2, "k2_w": sw.meta["k2"], "problem": problem,
              "n_plane": n},
        view=view, bound_motion=motion, bound_shift=shift if motion is not None else None,
        sample_shift=s_shift if motion is not None else None,
        planes=2, disks=np.array([d[:2] for d in disks], dtype=np.int64).reshape(-1, 2),
        lands=np.array(lands, dtype=float).reshape(-1, 3)
        if any(row[0] > 0 for row in lands) else None,
        friction=_friction(m, disks, mu, faces),
        tangents=np.array([f[:2] for f in faces], dtype=np.int64).reshape(-1, 2),
        row_nodes=node_rows, row_centres=centre)


def _friction(m: int, disks, mu, faces=()) -> np.ndarray | None:
    """μ per row: a round hole's at its first row, a face's at its row (its tangent row:
    0); None: no friction anywhere."""
    if not any(mu) and not faces:
        return None
    out = np.zeros(m)
    for (a, _, _), value in zip(disks, mu):
        out[a] = value
    for j, _, value in faces:
        out[j] = value
    return out


def _check_start(y0, lo, hi, disks, x_c, motion, shift, lands) -> None:
    """u0 must lie in every hole (and between the flat obstacles) at t = 0."""
    if motion is not None:
        p0 = float(motion(0.0))
        lo, hi = lo + shift * p0, hi + shift * p0
    tol = 1e-12 * max(1.0, np.abs(y0).max(initial=0.0))
    in_disk = np.zeros(y0.size, bool)
    for (a, b, _), land in zip(disks, lands):
        in_disk[[a, b]] = True
        c = 0.5 * (lo[[a, b]] + hi[[a, b]])
        r, p = 0.5 * (hi[a] - lo[a]), y0[[a, b]] - c
        out = land_excess(p[0], p[1], r, *land) if land[0] > 0 else np.hypot(*p) - r
        if out > tol:
            raise InputError(f"u0 leaves the {'broached' if land[0] > 0 else 'round'} "
                             f"hole at x={x_c[a]:g}")
    bad = ~in_disk & ((y0 < lo - tol) | (y0 > hi + tol))
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(f"u0 violates the obstacles at x={x_c[i]:g}: "
                         f"{y0[i]:g} not in [{lo[i]:g}, {hi[i]:g}]")
