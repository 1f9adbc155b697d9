"""The one entry point: ``solve(system, dt, T, method=...)`` → :class:`Result` (and
``moreau_jean(system, dt, T, theta, restitution)``, the same with Moreau–Jean)."""
from __future__ import annotations

import math
import sys

from ..checks import check_beta
from ..errors import InputError, SolverError
from ..system import SemiDiscrete
from .methods import MoreauJean, Penalty, PositionLevel, with_beta
from .run import Run
from .stepping import Result, Stepping

MAX_VALUES = 2 * 10**8    # saved values a Result may hold (1.6 GB)


RECORDING = ("save_every", "frames", "load_window", "growth_limit")   # solve's **recording


def solve(system, dt: float, T: float, beta: float | None = None, method=None, *,
          progress: bool | None = None, **recording) -> Result:
    """Integrate ``system`` over [0, T] with step ``dt``, in the style of ``solve_ivp``.

    ``method``: a :mod:`skfem_beam.methods` object, the one way a run names its method
    (``PositionLevel(solver, restitution, massless, beta=...)``: the solver a name of
    ``contact.STEP_SOLVERS`` or a law object; ``Penalty(stiffness, beta=...)`` in N/m, or
    in the units of the semi-discrete equation with ``equation_units=True``; ``MoreauJean(theta,
    restitution)``); None: ``PositionLevel()``, exact contact by the cheapest exact law.
    β is the β-scheme method's (default: the method's own, 1/2 for exact contact, 1/4 for
    springs); ``beta``: a shorthand that sets it (``replace(method, beta=beta)``); None:
    the method's as it is.  A ``beta`` beside a method that sets another than its
    default, or beside Moreau–Jean (no β), is refused in one line (it was overridden or
    ignored silently).
    ``recording``: any of ``save_every`` (1), ``frames`` (200),
    ``load_window`` ("forward"), ``growth_limit`` (10): see :class:`Stepping`.

    The run stops with status "unstable" when the discrete energy exceeds
    ``growth_limit`` × the a-priori bound (√E¹ + Σ‖Gⁿ‖_{N⁻¹}Δt)² (operators.load_norms),
    turns negative, or a state is non-finite or runs away (scheme.watch); what was
    computed up to the last state that passed is returned (up to the start of the
    20,000-step chunk where that was found, when the energy is no norm: Watch.norm).
    """
    if not isinstance(system, SemiDiscrete):
        raise InputError(f"solve needs a semi-discrete system (beam_system(problem), "
                         f"bar_system(bar), plate_system(space, ...)), not "
                         f"{type(system).__name__}")
    method = PositionLevel() if method is None else method
    if not isinstance(method, (PositionLevel, Penalty, MoreauJean)):
        raise InputError(f"method={method!r}: a method object is needed "
                         f"(skfem_beam.methods.PositionLevel(solver=...), Penalty(stiffness), "
                         f"MoreauJean(theta))")
    unknown = sorted(set(recording) - set(RECORDING))
    if unknown:
        raise TypeError(f"solve() got an unexpected keyword argument {unknown[0]!r} "
                        f"(it takes {', '.join(RECORDING)} and progress)")
    _check_beta_beside(method, beta)
    method = with_beta(method, beta)
    stepping = Stepping(dt, T, **recording, massless=method.massless)
    rows = stepping.steps // stepping.save_every + 1
    values = rows * (2 * len(system.observe) + system.C.shape[0] + 4)
    if values > MAX_VALUES:   # a Result holds every saved row; the commands stream them
        raise InputError(f"keeping every {stepping.save_every}-th of {stepping.steps:.3g} "
                         f"steps would hold {rows:.3g} rows in memory: raise save_every to at "
                         f"least {math.ceil(stepping.save_every * values / MAX_VALUES)}, or "
                         f"run it from the command line, which streams them to disk")
    run = method.build(system, stepping)
    drive(run, progress=progress)
    return run.result()


def _check_beta_beside(method, beta) -> None:
    """``beta`` given with ``method``: refused where one of them would be dropped."""
    if beta is None:
        return
    if isinstance(method, MoreauJean):
        raise InputError(f"beta={beta!r}: Moreau–Jean has no β (its parameter is "
                         f"theta={method.theta:g}); leave beta out")
    # a method's β is its default unless set (the two are one value once it is built)
    if method.beta != method.default_beta and check_beta(beta) != method.beta:
        raise InputError(f"beta={beta:g} beside the method's beta={method.beta:g}: give one")


def moreau_jean(system, dt: float, T: float, theta: float = 0.5, restitution: float = 0.0,
                save_every: int = 1, frames: int = 200, progress: bool | None = None) -> Result:
    """Integrate ``system`` over [0, T] with Moreau–Jean (θ-scheme, Newton impact law
    with coefficient ``restitution``): ``solve(..., method=methods.MoreauJean(theta,
    restitution))``, whose :class:`Result` has ``theta`` and ``beta`` None."""
    return solve(system, dt, T, method=MoreauJean(theta, restitution), save_every=save_every,
                 frames=frames, progress=progress)


def drive(run: Run, chunk: int = 20000, progress: bool | None = None, on_chunk=None) -> None:
    """Advance ``run`` to its end in chunks, with a progress bar on a terminal and an
    optional ``on_chunk(run)`` after each chunk (streaming output, checkpoints)."""
    show = sys.stderr.isatty() if progress is None else progress
    bar = None
    if show and run.n_steps - run.n > 10 * chunk:
        from tqdm import tqdm
        bar = tqdm(total=run.n_steps, initial=run.n, unit="step", unit_scale=True, leave=False)
    try:
        while not run.done:
            n0 = run.n
            run.advance(n0 + chunk)
            if run.n == n0 and not run.done:     # never loop without progress
                raise SolverError(f"the run made no progress at step {n0} of "
                                  f"{run.n_steps}; stopped")
            if bar is not None:
                bar.update(run.n - n0)
            if on_chunk is not None:
                on_chunk(run)
    finally:
        if bar is not None:
            bar.close()
