"""The runs whose outputs are pinned in ``reference.npz`` (made before the redesign of
issue 15 by ``python tests/reference/make.py``; asserted by ``tests/test_reference.py``).

Each entry builds a run through the public API and returns a dict of arrays.  The
tolerance is 1e-12 relative to the array's largest value (bit for bit where the order
of operations is kept); the point-stops scene is chaotic, so it is pinned to t = 0.1 s.
"""
import numpy as np

from skfem_beam import beam_system, solve
from skfem_beam.bar import Bar, run_bar
from skfem_beam.methods import Penalty, PositionLevel


def _beam(problem, dt, T, **kw):
    r = solve(beam_system(problem), dt, T, progress=False, **kw)
    return {"t": r.t, "tip": r.observed["tip_displacement"],
            "tip_velocity": r.velocity["tip_displacement"], "energy": r.energy,
            "contact_force": r.contact_force, "frames_u": r.frames_u, "frames_v": r.frames_v,
            "frames_force": r.frames_force,
            "stats": np.array([r.impacts, r.max_nodal_violation, r.max_penetration,
                               r.contact_fraction, r.steps])}


def spring(k):
    """The penalty springs of stiffness k in the equation's units (per unit mass)."""
    return Penalty(k, equation_units=True)


def _bar(bar, dt, T, **kw):
    b = run_bar(bar, dt, T, **kw)
    return {"t": b.t, "u0": b.u0, "uL": b.uL, "force": b.force, "energy": b.energy,
            "kinetic": b.kinetic, "strain": b.strain, "obstacle": b.obstacle,
            "load_potential": b.load_potential}


def runs(scenes):
    """name -> zero-argument function returning the pinned arrays.

    ``scenes`` provides point_stops, flat_obstacles, convex_obstacles, energy_decay
    (problem builders with the papers' defaults) and PIPE_RHO_S.
    """
    s = scenes
    return {
        "point_stops": lambda: _beam(s.point_stops(), 5e-5, 0.1, beta=0.5),
        "point_stops_bspline": lambda: _beam(s.point_stops(element="bspline"), 5e-5, 0.1),
        "point_stops_centered": lambda: _beam(s.point_stops(), 5e-5, 0.1,
                                              load_window="centered"),
        "point_stops_penalty": lambda: _beam(s.point_stops(), 5e-5, 0.1, beta=0.25,
                                             method=spring(1e8 / s.PIPE_RHO_S)),
        "flat_obstacles": lambda: _beam(s.flat_obstacles(), 1e-3, 1.0),
        "flat_obstacles_bspline": lambda: _beam(s.flat_obstacles(element="bspline"), 1e-3, 1.0),
        "flat_obstacles_penalty": lambda: _beam(s.flat_obstacles(), 1e-3, 1.0, beta=0.25,
                                                method=spring(1e8 / s.PIPE_RHO_S)),
        "convex_obstacles": lambda: _beam(s.convex_obstacles(), 1e-3, 1.0),
        "convex_obstacles_osqp": lambda: _beam(s.convex_obstacles(), 1e-3, 0.3,
                                               method=PositionLevel("osqp")),
        "convex_obstacles_daqp": lambda: _beam(s.convex_obstacles(), 1e-3, 0.3,
                                               method=PositionLevel("daqp")),
        "energy_decay_half": lambda: _beam(s.energy_decay(), 1e-3, 1.0, beta=0.5),
        "energy_decay_quarter": lambda: _beam(s.energy_decay(), 1e-3, 1.0, beta=0.25),
        "bar_rigid": lambda: _bar(Bar(), 1e-3, 3.0),
        "bar_elastic": lambda: _bar(Bar(obstacle="elastic"), 1e-3, 3.0),
        "bar_example2": lambda: _bar(Bar(f=-1.0), 1e-3, 6.0),
        "bar_viscous": lambda: _bar(Bar(b=0.01, mass="consistent"), 1e-3, 3.0, beta=0.5),
        "bar_penalty": lambda: _bar(Bar(k=1e4), 1e-3, 3.0, method="penalty"),
    }
