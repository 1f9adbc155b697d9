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

One builder makes the system for one plane or two
(:func:`skfem_beam.semidiscrete.beam_system`, from the planes of :func:`plane_problems`);
the rows of every obstacle are :mod:`skfem_beam.constraints`'.
"""
from __future__ import annotations

from dataclasses import replace

from .problem import Obstacles, Plane, Support
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


def plane_problems(problem) -> tuple:
    """The one-plane problems of a BeamProblem's planes: (problem,) for one plane; two
    planes (pv, pw), each with its own bending stiffness, load, initial state
    (``problem.plane(k)``) and share of the support's motion (the flat obstacles act in
    the first; the holes are the caller's)."""
    if problem.planes == 1:
        return (problem,)
    dy, dz = problem.support.direction
    one = dict(planes=1, holes=(), second=Plane())
    (load_v, initial_v), (load_w, initial_w) = problem.plane(0), problem.plane(1)
    pv = replace(problem, **one, load=load_v, initial=initial_v,
                 support=along(problem.support, dy))
    pw = replace(problem, **one, load=load_w, initial=initial_w, obstacles=Obstacles(),
                 beam=problem.beam.plane_w(), support=along(problem.support, dz))
    return pv, pw
