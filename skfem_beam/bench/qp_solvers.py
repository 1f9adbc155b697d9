"""Per-step cost of each contact solver on the convex-obstacle scene, beside the floor.

    python -m skfem_beam.bench.qp_solvers [--J 40,80,160] [--T 1] [--dt 1e-3]
        [--element hermite] [--repeat 3]

For each J and solver: µs per step of the whole time loop (``r.wall_time_s`` / steps,
best of ``--repeat`` runs), beside the same beam without obstacles (the floor: the
scheme alone).  active-set runs in the compiled loop; daqp and osqp are called from
the integrator's Python-level step, whose own cost is in their rows.  So the column
"solver µs" also times the solver alone: the run's steps are replayed (y_free and
x_free rebuilt from the saved states and forces) through the solver only.  Also: QP
iterations per step, impacts, the largest nodal violation and the largest
difference of any step's coefficients from the active-set run (relative).
"""
from __future__ import annotations

import time

import numpy as np
from numba import njit

from ..contact.active_set import box_qp
from ..parser import Parser, count, counts

SOLVERS = ("active-set", "daqp", "osqp")


def scene(J: int, element: str, obstacles: bool = True):
    """The convex-obstacle scene (``obstacles=False``: the same beam without them)."""
    from dataclasses import replace

    from .. import scenes
    from ..problem import Obstacles
    from ..semidiscrete import beam_system
    pb = scenes.convex_obstacles(J=J, element=element)
    return beam_system(pb if obstacles else replace(pb, obstacles=Obstacles()))


def best_run(system, solver: str, dt: float, T: float, repeat: int):
    from ..scheme import solve
    from ..scheme.methods import PositionLevel
    frames = int(round(T / dt))              # every step: for the comparison and replay
    runs = [solve(system, dt=dt, T=T, method=PositionLevel(solver, beta=0.5), frames=frames,
                  progress=False) for _ in range(repeat)]
    return min(runs, key=lambda r: r.wall_time_s)


@njit(cache=True)
def _replay_box_qp(D, YF, lo, hi):
    state = np.zeros(lo.size, np.int8)
    mu = np.zeros(lo.size)
    for n in range(YF.shape[0]):
        box_qp(D, YF[n], lo, hi, state, mu)


def replay(system, r, solver: str, dt: float, repeat: int) -> float:
    """µs per call of the solver alone over the run's steps (states n = 2..N)."""
    from ..contact import StepData, resolve
    A = (system.M + dt**2 * 0.5 * system.K).tocsr()
    C = system.C.tocsr()
    W = np.linalg.solve(A.toarray(), C.T.toarray())
    D = np.ascontiguousarray(C @ W)
    MU = r.contact_force[2:] * dt**2           # μ of state n, as the integrator saved it
    X = r.frames_u[2:] - MU @ W.T              # x_free = u − Wμ
    YF = np.ascontiguousarray(X @ C.T.toarray())
    lo, hi = np.ascontiguousarray(system.lo), np.ascontiguousarray(system.hi)
    best = np.inf
    for _ in range(repeat):
        if solver == "active-set":
            _replay_box_qp(D, YF[:1], lo, hi)  # compiled before the clock starts
            t0 = time.perf_counter()
            _replay_box_qp(D, YF, lo, hi)
        else:
            s = resolve(solver).solver(StepData(A, C, D, lo, hi, dt, 0.5))
            t0 = time.perf_counter()
            for n in range(YF.shape[0]):
                s.solve(X[n], YF[n])
        best = min(best, time.perf_counter() - t0)
    return 1e6 * best / YF.shape[0]


def main(argv=None) -> int:
    ap = Parser(prog="skfem_beam.bench.qp_solvers",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--J", type=counts, default="40,80,160")
    ap.add_argument("--T", type=float, default=1.0)
    ap.add_argument("--dt", type=float, default=1e-3)
    ap.add_argument("--element", default="hermite", choices=("hermite", "bspline"))
    ap.add_argument("--repeat", type=count, default=3)
    args = ap.parse_args(argv)
    print(f"convex obstacles, {args.element}, dt={args.dt:g}, T={args.T:g}, beta=1/2; "
          f"best of {args.repeat}")
    print(f"{'J':>4s} {'solver':11s} {'µs/step':>9s} {'solver µs':>10s} {'its/step':>9s} "
          f"{'impacts':>8s} {'max viol m':>11s} {'max Δu rel':>11s}")
    for J in args.J:
        floor = best_run(scene(J, args.element, obstacles=False), "auto", args.dt, args.T,
                         args.repeat)
        print(f"{J:4d} {'(no obst.)':11s} {1e6 * floor.wall_time_s / floor.steps:9.1f}")
        system = scene(J, args.element)
        ref = None
        for solver in SOLVERS:
            r = best_run(system, solver, args.dt, args.T, args.repeat)
            ref = r if ref is None else ref
            alone = replay(system, ref, solver, args.dt, args.repeat)
            du = np.abs(r.frames_u - ref.frames_u).max() / np.abs(ref.frames_u).max()
            print(f"{J:4d} {solver:11s} {1e6 * r.wall_time_s / r.steps:9.1f} {alone:10.2f} "
                  f"{r.qp_iterations / r.steps:9.2f} {r.impacts:8d} "
                  f"{r.max_nodal_violation:11.1e} {du:11.1e}", flush=True)
    return 0


if __name__ == "__main__":
    from ..cli import main_guard
    main_guard(main)
