"""What a plate step costs: ``python -m skfem_beam.plate.bench [--meshes 20 40 80]
[--steps 100 100 40]``.

A simply supported 1 × 1 m steel plate (h = 1 cm, BFS on n × n), a flat obstacle under
the whole plate at w ≥ −0.2 w_s (w_s: the static centre deflection under the load), the
plate starting flat at rest under a uniform −10 kPa: it falls onto the obstacle within a
quarter period and stays pressed on it.  Printed per mesh: the half bandwidth, the setup
(the banded Cholesky of A = M + βΔt²K alone, and the whole of scheme.operators:
step_operators, with W = A⁻¹Cᵀ and D = C W where "auto" builds them, W within
contact.registry.W_BUDGET bytes) and the bytes of W and D; per step, one banded solve
with A's factor (the scheme's, linalg.band_solve, LAPACK's dpbtrf and dpbtrs on one
thread, and CHOLMOD's numeric factorisation and solve: the x-space laws' two Cholesky
factors, contact.sparse_qp), the scheme's step without obstacles, and the step pressed on
the obstacle with each exact law (its mean over the run, with the fraction of steps in
contact, and its ratio to the scheme's banded solve and to dpbtrs); the process's peak
memory after each mesh.  The laws that need W and D (active-set, daqp, osqp) run only
where W is built; the x-space laws (contact.sparse_qp) build neither.  Only measured,
nothing tuned (docs/plate.md, "Which engine at which size").
"""
from __future__ import annotations

import resource
import time

import numpy as np
import scipy.linalg

from ..contact.registry import Auto
from ..contact.sparse_qp import COUNTS, SparseCholesky, _one_thread, cholesky_kind
from ..linalg import Banded, band_solve
from ..methods import PositionLevel
from ..parser import Parser, about
from ..scheme import solve
from ..scheme.operators import step_operators
from .model import Plate
from .space import plate_space
from .system import PlateInitial, PlateObstacle, Pressure, half_bandwidth, plate_system

LOAD = -1e4                  # Pa
DT = 2e-4                    # s (the first period is 20 ms)
STEPS = 100                  # steps of each law's run (--steps: one number per mesh)
DELASSUS_LAWS = ("active-set", "daqp", "osqp")               # need W and D
X_SPACE_LAWS = ("pdas-sparse", "osqp-sparse", "clarabel-sparse")   # neither


def timed(f, repeat: int = 1) -> float:
    """The best of ``repeat`` wall times of f() (s)."""
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t0)
    return best


def systems(n: int):
    """(the plate without obstacles, the plate over the flat obstacle) on n × n."""
    space = plate_space(Plate(nx=n, ny=n))
    load = [Pressure(LOAD)]
    free = plate_system(space, loads=load)
    w_s = float(free.observe["w(0.5,0.5)"]
                @ plate_system(space, initial=PlateInitial(static=load[0])).u0)
    return free, plate_system(space, obstacles=[PlateObstacle(g1=0.2 * w_s)], loads=load)


def setup_row(system) -> dict:
    """The band, the factor's and step_operators' times (with W and D where "auto" builds
    them: W within contact.registry.W_BUDGET, else without), and W's and D's bytes."""
    A = system.M + 0.5 * DT**2 * system.K
    factor = timed(lambda: Banded(A, factor=True), 3)
    delassus = Auto.before_operators(system.n, system.C) is None     # where auto builds W
    t0 = time.perf_counter()
    ops = step_operators(system, DT, 0.5, delassus=delassus)
    total = time.perf_counter() - t0
    b = np.ones(system.n)
    solve_s = timed(lambda: band_solve(ops.Ab.chol, b), 50)
    with _one_thread():
        lapack_f = timed(lambda: scipy.linalg.lapack.dpbtrf(ops.Ab.lapack_band(), lower=0), 3)
        lap, _ = scipy.linalg.lapack.dpbtrf(ops.Ab.lapack_band(), lower=0)
        lapack_s = timed(lambda: scipy.linalg.lapack.dpbtrs(lap, b, lower=0), 50)
    return {**cholmod_row(A, b), "lapack_factor_ms": 1e3 * lapack_f,
            "n": system.n, "m": system.C.shape[0], "kd": half_bandwidth(A),
            "factor_s": factor, "operators_s": total, "W_MB": ops.W.nbytes / 1e6,
            "D_MB": ops.D.nbytes / 1e6, "band_solve_ms": 1e3 * solve_s,
            "lapack_solve_ms": 1e3 * lapack_s, "delassus": delassus}


def cholmod_row(A, b) -> dict:
    """CHOLMOD's times on A (cvxopt.cholmod, as SelectorQP uses it): the symbolic
    factorisation (once a run), a numeric one (once a set), a solve (ms)."""
    import cvxopt.cholmod  # noqa: F401  (its first import is not the symbolic step's time)
    t0 = time.perf_counter()
    G = SparseCholesky(A)
    symbolic = time.perf_counter() - t0
    none = np.zeros(0, dtype=np.int64)
    numeric = timed(lambda: G.factor(none), 3)
    return {"cholmod_symbolic_ms": 1e3 * symbolic, "cholmod_numeric_ms": 1e3 * numeric,
            "cholmod_solve_ms": 1e3 * timed(lambda: G.solve(b), 50)}


def step_ms(system, solver: str, steps: int) -> tuple[float, float]:
    """(the scheme's mean wall time per step in ms, the fraction of steps in contact),
    from a first short run (compiles, builds the operators) and the timed run's own
    loop time."""
    solve(system, DT, 2 * DT, method=PositionLevel(solver), progress=False)
    COUNTS.update(dict.fromkeys(COUNTS, 0))
    r = solve(system, DT, steps * DT, method=PositionLevel(solver), progress=False)
    return 1e3 * r.wall_time_s / r.steps, r.contact_fraction


def peak_mb() -> float:
    """The process's peak resident memory so far (MB; Linux reports kB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3


def law_rows(pressed, laws, solve_ms: float, lapack_ms: float, steps: int = STEPS,
             free_ms: float | None = None) -> None:
    """One line per law: its mean step, the fraction in contact, the ratio to a solve
    (the scheme's banded solve; LAPACK's dpbtrs); with ``free_ms`` (the step without
    obstacles), the contact's own share of a step, what the law adds, in dpbtrs."""
    for law in laws:
        try:
            ms, fraction = step_ms(pressed, law, steps)   # (COUNTS: the timed run's)
        except Exception as e:          # a law that does not run here says why
            print(f"  step with {law}: not run ({type(e).__name__}: {e})", flush=True)
            continue
        print(f"  step with {law}: {ms:.2f} ms = {ms / solve_ms:.1f} solves "
              f"({ms / lapack_ms:.0f} dpbtrs; {steps} steps, {100 * fraction:.0f} % in "
              f"contact)", flush=True)
        if free_ms is not None:
            print(f"    the contact's share: {ms - free_ms:.2f} ms = "
                  f"{(ms - free_ms) / lapack_ms:.1f} dpbtrs", flush=True)
        if law in X_SPACE_LAWS and COUNTS["steps"]:
            c = {k: v / COUNTS["steps"] for k, v in COUNTS.items()}
            kind = cholesky_kind(pressed.n)
            print(f"    per contact step: {c['factors']:.2f} factorisations ({kind}), "
                  f"{c['solves']:.1f} solves, {c['guesses']:.1f} inexact and "
                  f"{c['sweeps']:.1f} exact sweeps", flush=True)


def main(argv=None) -> None:
    parser = Parser(prog="python -m skfem_beam.plate.bench", description=about(__doc__))
    parser.add_argument("--meshes", type=int, nargs="+", default=[20, 40, 80])
    parser.add_argument("--steps", type=int, nargs="+", default=[STEPS],
                        help="steps of each run, one number per mesh (the last repeats)")
    parser.add_argument("--laws", nargs="+", default=DELASSUS_LAWS + X_SPACE_LAWS)
    args = parser.parse_args(argv)
    for i, n in enumerate(args.meshes):
        steps = args.steps[min(i, len(args.steps) - 1)]
        free, pressed = systems(n)
        row = setup_row(pressed)
        print(f"BFS {n} x {n}: {row['n']} unknowns, {row['m']} constrained vertices, half "
              f"bandwidth {row['kd']}")
        what = "(A, W, D)" if row["delassus"] else "(A; W would be " \
            f"{8e-6 * row['n'] * row['m']:.0f} MB: not built)"
        print(f"  setup: Cholesky of A {row['factor_s']:.3f} s, step_operators {what} "
              f"{row['operators_s']:.2f} s; W {row['W_MB']:.1f} MB, D {row['D_MB']:.1f} MB")
        print(f"  one banded solve: {row['band_solve_ms']:.3f} ms (LAPACK dpbtrs: "
              f"{row['lapack_solve_ms']:.3f} ms, dpbtrf {row['lapack_factor_ms']:.1f} ms)")
        print(f"  CHOLMOD (cvxopt): symbolic {row['cholmod_symbolic_ms']:.1f} ms, numeric "
              f"{row['cholmod_numeric_ms']:.1f} ms, solve {row['cholmod_solve_ms']:.3f} ms",
              flush=True)
        ms, _ = step_ms(free, "auto", steps)
        print(f"  step without obstacles: {ms:.2f} ms = {ms / row['band_solve_ms']:.1f} "
              f"solves", flush=True)
        laws = [law for law in args.laws if row["delassus"] or law not in DELASSUS_LAWS]
        law_rows(pressed, laws, row["band_solve_ms"], row["lapack_solve_ms"], steps, ms)
        print(f"  peak memory of the process so far: {peak_mb():.0f} MB", flush=True)


if __name__ == "__main__":
    from ..cli import main_guard
    main_guard(main)
