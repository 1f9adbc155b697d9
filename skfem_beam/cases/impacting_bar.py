"""The third paper's scene: a (visco)elastic bar hitting an obstacle at one end.

    python -m skfem_beam.cases.impacting_bar [--obstacle rigid|elastic] [--k 100]
        [--a|--E 1] [--b 0] [--rho 1] [--A m²] [--L 1] [--f 0] [--v0 -1] [--u0 0]
        [--u0-csv FILE] [--v0-csv FILE] [--far-end free|clamped]
        [--obstacle-at left|right] [--N 100]
        [--dt 1e-3] [--T 3] [--beta 0.25] [--method contact|penalty]
        [--mass average|consistent|lumped|redistributed] [--massless beta|quasi-static]
        [--law LAW] [--restitution E] [--save-every 1] [--frames 200] [--out DIR]
        [--checkpoint-every S] [--resume DIR]

Example 1 of Do, Raupp & Feijoo is the default (add ``--obstacle elastic`` for the
spring k = 100); Example 2 is ``--f -1 --T 6``.  The periodic rod (exact solution
known, docs/design.md §1) is ``--far-end clamped --v0 0 --u0-csv rod.csv`` with the two
rows ``0,0.5`` and ``1,0``.  ``--u0-csv``/``--v0-csv`` read x,value rows (linear in
between; they replace --u0/--v0).  With ``--A`` forces are in N, energies in J and
``--k`` is in N/m; without it everything is per unit cross-section (Pa, J/m², Pa/m).
Writes into DIR: summary.json, timeseries.csv (u(0,t), u(L,t), reaction, energies, and
the exact solution beside them when it is known: b = 0 and uniform data with a free far
end, or the periodic rod), the field series (XDMF and/or VTU, --format), and charts,
through the same streaming pipeline as the beam scenes (checkpoints, --resume).

Defaults and why: ``--mass average`` (the mean of consistent and lumped mass cancels
the leading dispersion error of P1 waves; it is the only one of the three that meets
the accuracy targets at N = 100, Δt = 1e-3); ``--beta 0.25`` (unconditionally stable,
the paper's α = 1/4; β = 0 is a little more accurate here but only conditionally
stable).  ``--method penalty`` replaces the rigid obstacle by a one-sided spring of
stiffness ``--stiffness``; the elastic obstacle is a spring either way.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .. import cli
from ..bar import (Bar, BarSeries, bar_run, contact_periods, describe, energy_report, errors,
                   profile_values, read_profile, spring_step_ratio)
from ..bar.run import ALL_STATES_LIMIT
from ..chart_process import draw
from ..output.charts import compare_chart
from ..output.events import bar_impacts
from ..output.stream import Series, execute, note_last_row, prepare
from ..methods import Penalty, PositionLevel
from ..spec import RunSpec
from ..reference import BarExact
from ..checks import check_choice
from ..errors import InputError
from ..spaces.lagrange import ELEMENTS, MASSES

CASE = "impacting_bar"


def main(argv=None) -> int:
    p = cli.parser(f"skfem_beam.cases.{CASE}", __doc__.splitlines()[0], dt=1e-3, T=3.0,
                   beta=0.25, element=False, mass=MASSES[2:3] + MASSES[:2] + MASSES[3:])
    p.add_argument("--obstacle", default="rigid", help="rigid | elastic")
    p.add_argument("--k", type=float, default=100.0, help="elastic obstacle: R = k·U⁻ (Pa/m)")
    p.add_argument("--a", "--E", dest="a", type=float, default=1.0, metavar="E",
                   help="Young's modulus E (Pa)")
    p.add_argument("--b", type=float, default=0.0, help="Kelvin–Voigt viscosity (Pa·s)")
    p.add_argument("--rho", type=float, default=1.0, help="density (kg/m³)")
    p.add_argument("--A", type=float, default=None, metavar="AREA",
                   help="cross-section (m²): forces in N, energies in J, --k in N/m "
                        "(default: per unit cross-section)")
    p.add_argument("--L", type=float, default=1.0, help="length (m)")
    p.add_argument("--f", type=float, default=0.0, help="uniform body force (N/m³)")
    p.add_argument("--v0", type=float, default=-1.0, help="uniform initial velocity (m/s)")
    p.add_argument("--u0", type=float, default=0.0,
                   help="uniform initial displacement, the gap to the obstacle (m)")
    p.add_argument("--u0-csv", default=None, metavar="FILE",
                   help="initial displacement as x,u rows (replaces --u0)")
    p.add_argument("--v0-csv", default=None, metavar="FILE",
                   help="initial velocity as x,v rows (replaces --v0)")
    p.add_argument("--far-end", default="free", help="free | clamped: the end without obstacle")
    p.add_argument("--obstacle-at", default="left", help="left (x = 0) | right (x = L)")
    p.add_argument("--N", type=int, default=100, help="number of elements")
    p.add_argument("--element", default="p1",
                   help="p1 | p2: Lagrange elements of degree 1 or 2 (p2: twice the unknowns, "
                        "half the wave error at Δt/h = 0.4 with --beta 0.09)")
    args = cli.parse(p, argv)
    check_choice("--element", args.element, tuple(ELEMENTS))
    _check_springs(args, {} if args.resume else cli.given_flags(p, argv))

    u0 = read_profile(args.u0_csv, "--u0-csv") if args.u0_csv else args.u0
    v0 = read_profile(args.v0_csv, "--v0-csv") if args.v0_csv else args.v0
    try:
        bar = Bar(a=args.a, b=args.b, rho=args.rho, L=args.L, f=args.f, v0=v0, u0=u0,
                  obstacle=args.obstacle, k=args.k, N=args.N, mass=args.mass,
                  element=args.element, far_end=args.far_end, obstacle_at=args.obstacle_at,
                  A=args.A)
    except InputError as e:     # Bar's field names as the flags ("a=-1": --E -1)
        name, eq, rest = str(e).partition("=")
        if eq and name in FLAGS:
            raise InputError(f"{FLAGS[name]}={rest}") from None
        raise
    return run_bar_case(bar, cli.spec(args))


# Bar's fields whose refusals name them (``a=-1 must be > 0``), as the command's flags
FLAGS = {"a": "--E", "b": "--b", "rho": "--rho", "L": "--L", "f": "--f", "k": "--k",
         "N": "--N", "A": "--A", "obstacle": "--obstacle", "mass": "--mass",
         "far_end": "--far-end", "obstacle_at": "--obstacle-at"}


def _check_springs(args, given: dict) -> None:
    """--k is the elastic obstacle's spring, --stiffness the rigid one's penalty springs:
    each given where the other obstacle runs was read and not used."""
    if "k" in given and args.obstacle != "elastic":
        raise InputError(f"--k {args.k:g} is the elastic obstacle's stiffness: with "
                         f"--obstacle {args.obstacle} it is not used (--obstacle elastic, or "
                         "--law penalty --stiffness for springs at a rigid one)")
    if "stiffness" in given and args.obstacle == "elastic":
        raise InputError(f"--stiffness {args.stiffness:g} is the penalty springs' at a rigid "
                         "obstacle: the elastic obstacle's spring is --k")


def run_bar_case(bar: Bar, spec: RunSpec) -> int:
    """Run ``bar`` as ``spec`` says (its Stepping's Δt, T; its method, with β; its output
    options), write the folder through the streaming pipeline, return the exit code."""
    s = spec.stepping
    if isinstance(spec.method, Penalty) and bar.obstacle == "rigid":
        bar = replace(bar, k=spec.method.stiffness)   # the rigid obstacle as springs 1/ε
    prepare(spec.options)                                # fail before the run, not after
    warn_first_step_restitution(bar, spec.method, s.dt)
    run = bar_run(bar, s.dt, s.T, beta=None, method=spec.method, frames=s.frames)
    if run.frame_every != 1 and run.beta is not None:
        cli.warn(f"energy_kinetic and energy_strain are NaN in this run: the β split needs "
                 f"every state, and {run.n_steps + 1} states of {run.system.n} unknowns pass "
                 f"the {ALL_STATES_LIMIT:,} values kept (energy, the total, is written)")
    exact = bar_exact(bar, s.T)
    method = "penalty" if isinstance(spec.method, Penalty) else "contact"
    series = BarSeries(bar, run, s.T, method, every=s.save_every, exact=exact)
    spring = series.spring
    if spring:
        warn_spring_rings(bar)
    if spring and spring_step_ratio(bar, s.dt) > 1:
        cli.warn(f"stiff spring: √(k/m₀)·Δt = {spring_step_ratio(bar, s.dt):.3g} > 1 (m₀ the "
                 f"contact node's mass); impacts on it are under-resolved and may gain "
                 f"energy: lower --dt or use --method contact")
    # field frames: about --frames of the states up to T (every state is kept for the
    # energy split when it fits; else the run keeps --frames frames itself)
    field_every = max(1, series.n_steps // s.frames) if run.frame_every == 1 \
        else run.frame_every
    stream = Series(series.columns, ready=series.ready, field_every=field_every,
                    field_until=series.n_steps, keep_all=True,   # errors need every row
                    events=lambda folder, run, last: bar_impacts(folder, run, bar, last))
    summary = bar_summary(bar, run, series, method, spec.config)
    code = execute(run, spec.options, summary, stream, bar_charts(bar, series, exact, s.T))
    if code == 0:      # the bar's run saves every state: its rows are the series' own
        note_last_row(series.every, series.n_steps, run.dt)
    return code


def warn_spring_rings(bar: Bar) -> None:
    """One warning line when the contact node alone on the spring would ring above the
    mesh's highest frequency 2c/h (P1): it cannot radiate that into the bar, so the force
    oscillates about the exact one however small Δt (k = 1e4, E = ρ = 1: ±32 % at N = 5000,
    ratio 1.1, ±13 % at N = 8000, 0.87; the node lifting off the spring 37–82 % of the
    contact from ratio 2.4)."""
    if bar.element != "p1":
        return
    c = math.sqrt(bar.a / bar.rho)
    ratio = spring_step_ratio(bar, bar.h / (2 * c))       # √(k/m₀) · h/(2c)
    if ratio > 1:
        need = math.ceil(bar.N * ratio * ratio)           # the ratio goes as √h
        cli.warn(f"stiff spring for the mesh: the contact node alone on it rings at "
                 f"√(k/m₀) = {ratio:.3g} × the mesh's highest frequency 2c/h, which the bar "
                 f"cannot carry away: its contact force oscillates about the exact one "
                 f"(±32 % at 1.1 ×, ±13 % at 0.87 ×) and from about 2 × the node lifts off "
                 f"the spring; a finer mesh (the ratio goes as 1/√N: N = {need} for 1 ×) or "
                 f"a softer --k")


def warn_first_step_restitution(bar: Bar, method, dt: float) -> None:
    """One warning line when a position-level restitution cannot act on the first impact:
    the bar reaches the rigid obstacle within the first step (Example 1 touches it at
    t = 0), and the Paoli–Schatzman rule restitutes from the state before, which the
    first step does not have; e = 0 and e = 1 then gave the same run, silently."""
    e = getattr(method, "restitution", 0.0)
    if not isinstance(method, PositionLevel) or not e or bar.obstacle != "rigid":
        return
    end = 0.0 if bar.obstacle_at == "left" else bar.L
    gap = bar.gap_sign * float(profile_values(bar.u0, np.array([end]))[0])
    speed = -bar.gap_sign * float(profile_values(bar.v0, np.array([end]))[0])
    if speed > 0 and gap <= speed * dt:
        cli.warn(f"restitution {e:g} does not act on the first impact: the bar reaches the "
                 f"obstacle within the first step (gap {gap:g} m at {speed:g} m/s), and the "
                 "position-level rule needs the state before; it acts from the next impact "
                 "on (--law moreau-jean restitutes this one)")


def bar_exact(bar: Bar, T: float):
    """The exact solution where it is known, else None (a warning when it could not be
    computed)."""
    try:
        return BarExact.of(bar, T)
    except RuntimeError as e:      # very long runs with many switches
        cli.warn(f"no exact solution written: {e}")
        return None


def bar_summary(bar: Bar, run, series, method: str, config: dict) -> dict:
    """summary.json's entries of a bar run (before the run's own)."""
    spring = series.spring
    return {
        "case": CASE, "J": bar.N, "N": bar.N, "dt": run.dt, "T": series.n_steps * run.dt,
        "beta": run.beta, "theta": run.theta, "element": bar.element, "mass": bar.mass,
        "method": method, "obstacle": bar.obstacle,
        "spring_stiffness": bar.k if spring else None,
        "bar": {"a": bar.a, "b": bar.b, "rho": bar.rho, "L": bar.L, "f": bar.f,
                "v0": describe(bar.v0), "u0": describe(bar.u0), "k": bar.k, "c": bar.c,
                "far_end": bar.far_end, "obstacle_at": bar.obstacle_at, "A": bar.A},
        "units": {"displacement": "m",
                  "contact_force": "Pa (force per unit cross-section)" if bar.A is None
                  else "N",
                  "energy": "J/m² (per unit cross-section)" if bar.A is None else "J",
                  "spring_stiffness": "Pa/m" if bar.A is None else "N/m",
                  "errors": "L² in time over the saved rows: √(Δt Σ eₙ²) (Δt the row "
                            "spacing); contact force from t₁ on",
                  "max_penetration": "m: max(−U(tₙ)) over the saved rows, U = u(0) or "
                                     "−u(L) at the obstacle (a spring's compression)",
                  "wall_time_s": "the time loop alone (one step past T, for R at T)"},
        "notes": ("energy = kinetic + strain + obstacle, the scheme's E_β/2 split; "
                  "energy_final and the energy report add the load potential −fL·ū"),
        "config": config,
    }


def bar_charts(bar: Bar, series, exact, T: float):
    """The charts and the summary entries of a bar run, from its rows in memory."""
    spring = series.spring

    def finish(folder, data, run):
        b = series.bar_run(data, run.result())
        periods = contact_periods(b.t, b.force, 0.1 * bar.L / bar.c)
        side = "" if (bar.obstacle_at, bar.far_end) == ("left", "free") else \
            f" at x={'0' if bar.obstacle_at == 'left' else 'L'}, {bar.far_end} far end"
        title = (f"{bar.obstacle} obstacle{f' k={bar.k:g}' if spring else ''}{side}, f={bar.f:g}, "
                 f"N={bar.N}, Δt={run.dt:g}, {run.label}, {bar.mass} mass")
        draw(compare_chart, folder / "displacement.png", b.t, {"u(0, t)": b.u0, "u(L, t)": b.uL},
             {"u(0, t) exact": data.get("u_0_exact"),
              "u(L, t) exact": data.get("u_L_exact")}, title, "displacement (m)")
        draw(compare_chart, folder / "contact_force.png", b.t, {"reaction R": b.force},
             {"R exact": data.get("contact_force_exact")}, title,
             "R (Pa)" if bar.A is None else "R (N)")
        draw(compare_chart, folder / "energy.png", b.t,
             {"kinetic": b.kinetic, "strain": b.strain, "obstacle": b.obstacle,
              "total": b.energy + b.load_potential},
             {"exact total": data.get("energy_exact")}, title,
             "energy (J/m²)" if bar.A is None else "energy (J)")
        return {
            "T": min(run.n, series.n_steps) * run.dt, "steps": min(run.n, series.n_steps),
            "max_penetration": b.penetration, "max_nodal_violation": b.penetration,
            "energy_final": float(b.energy[-1] + b.load_potential[-1]),
            # in J where the cross-section is given (--A), else per unit cross-section
            "energy_final_J": float(b.energy[-1] + b.load_potential[-1])
            if bar.A is not None else None,
            "impacts": len(periods), "contact_periods": periods,
            "exact_contact_periods": [(a, min(e, T)) for a, e in exact.contact_intervals()
                                      if a <= T] if exact is not None else None,
            "exact_solution": exact is not None,
            "errors": errors(b, exact) if exact is not None else None,
            "energy": energy_report(b)}

    return finish


if __name__ == "__main__":
    cli.main_guard(main)
