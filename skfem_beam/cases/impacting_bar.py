"""The third paper's scene: a (visco)elastic bar hitting an obstacle at x = 0.

    python -m skfem_beam.cases.impacting_bar [--obstacle rigid|elastic] [--k 100]
        [--a 1] [--b 0] [--rho 1] [--L 1] [--f 0] [--v0 -1] [--u0 0] [--N 100]
        [--dt 1e-3] [--T 3] [--beta 0.25] [--method contact|penalty]
        [--mass average|consistent|lumped] [--out DIR]

Example 1 of Do, Raupp & Feijoo is the default (add ``--obstacle elastic`` for the
spring k = 100); Example 2 is ``--f -1 --T 6``.  Writes into DIR: summary.json,
timeseries.csv (u(0,t), u(L,t), reaction, energies, and the exact solution beside
them when it is known, i.e. b = 0), the field series (XDMF and/or VTU, --format), and charts.

Defaults and why: ``--mass average`` (the mean of consistent and lumped mass cancels
the leading dispersion error of P1 waves; it is the only one of the three that meets
the accuracy targets at N = 100, Δt = 1e-3); ``--beta 0.25`` (unconditionally stable,
the paper's α = 1/4; β = 0 is a little more accurate here but only conditionally
stable).  ``--method penalty`` replaces the rigid obstacle by a one-sided spring of
stiffness ``--stiffness``; the elastic obstacle is a spring either way.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .. import cli
from ..bar import (Bar, contact_periods, energy_report, errors, run_bar,
                   spring_step_ratio)
from ..errors import InputError
from ..fields import check_format, write_fields
from ..io import check_output_dir, output_dir, write_summary, write_timeseries
from ..plotting import plt
from ..problem import check_beta, check_positive
from ..reference import BarExact

CASE = "impacting_bar"


def main(argv=None) -> int:
    p = cli.parser(f"skfem_beam.cases.{CASE}", __doc__.splitlines()[0], dt=1e-3, T=3.0,
                   beta=0.25, element=False)
    p.add_argument("--obstacle", default="rigid", help="rigid | elastic")
    p.add_argument("--k", type=float, default=100.0, help="elastic obstacle: R = k·U⁻ (Pa/m)")
    p.add_argument("--a", type=float, default=1.0, help="modulus (Pa)")
    p.add_argument("--b", type=float, default=0.0, help="Kelvin–Voigt viscosity (Pa·s)")
    p.add_argument("--rho", type=float, default=1.0, help="density (kg/m³)")
    p.add_argument("--L", type=float, default=1.0, help="length (m)")
    p.add_argument("--f", type=float, default=0.0, help="uniform body force (N/m³)")
    p.add_argument("--v0", type=float, default=-1.0, help="uniform initial velocity (m/s)")
    p.add_argument("--u0", type=float, default=0.0,
                   help="uniform initial displacement, the gap to the obstacle (m)")
    p.add_argument("--N", type=int, default=100, help="number of P1 elements")
    p.add_argument("--mass", default="average", help="average | consistent | lumped")
    args = p.parse_args(argv)
    if args.resume or args.checkpoint_every is not None:
        raise InputError("--resume and --checkpoint-every are for the streamed beam cases; "
                         "a bar run keeps every state for the exact comparison")
    check_format(args.format)

    cli.check_method(args)
    check_beta(args.beta)
    dt, T = check_positive("dt", args.dt), check_positive("T", args.T)
    bar = Bar(a=args.a, b=args.b, rho=args.rho, L=args.L, f=args.f, v0=args.v0, u0=args.u0,
              obstacle=args.obstacle, k=args.k, N=args.N, mass=args.mass)
    penalty = args.method == "penalty" and bar.obstacle == "rigid"
    if penalty:   # the rigid obstacle approximated by a spring of stiffness 1/ε
        bar = replace(bar, k=check_positive("stiffness", args.stiffness))
    out = check_output_dir(args.out, args.overwrite)     # fail before the run, not after
    spring = bar.obstacle == "elastic" or penalty
    if spring and spring_step_ratio(bar, dt) > 1:
        cli.warn(f"stiff spring: √(k/m₀)·Δt = {spring_step_ratio(bar, dt):.3g} > 1 (m₀ the "
                 f"contact node's mass); impacts on it are under-resolved and may gain "
                 f"energy: lower --dt or use --method contact")

    run = run_bar(bar, dt, T, beta=args.beta, method=args.method, solver=args.solver)
    r = run.result
    try:
        exact = BarExact.of(bar, T)
    except RuntimeError as e:      # very long runs with many switches
        cli.warn(f"no exact solution written: {e}")
        exact = None
    energy = energy_report(run)
    merge = 0.1 * bar.L / bar.c
    periods = contact_periods(run.t, run.force, merge)

    columns = {"t": run.t, "u_0": run.u0, "u_L": run.uL, "contact_force": run.force,
               "energy": run.energy, "energy_kinetic": run.kinetic,
               "energy_strain": run.strain, "energy_obstacle": run.obstacle}
    if bar.f != 0:
        columns["load_potential"] = run.load_potential
    summary_errors = None
    if exact is not None:
        columns.update(u_0_exact=exact.u(0.0, run.t), u_L_exact=exact.u(bar.L, run.t),
                       contact_force_exact=exact.contact_force(run.t))
        if bar.f == 0:   # an elastic bar with f = 0 conserves its energy
            columns["energy_exact"] = np.full(run.t.size, energy["energy_initial"])
        summary_errors = errors(run, exact)

    steps = run.t.size - 1
    summary = {
        "case": CASE, "J": bar.N, "N": bar.N, "dt": r.dt, "T": float(run.t[-1]),
        "beta": r.beta, "element": "p1", "mass": bar.mass, "solver": r.solver,
        "method": args.method, "obstacle": bar.obstacle,
        "spring_stiffness": bar.k if spring else None,
        "steps": steps, "wall_time_s": r.wall_time_s,
        "us_per_step": 1e6 * r.wall_time_s / max(1, r.steps),
        "max_penetration": run.penetration, "max_nodal_violation": run.penetration,
        "energy_final": float(run.energy[-1] + run.load_potential[-1]),
        "impacts": len(periods), "contact_periods": periods,
        "exact_contact_periods": [(a, min(b, T)) for a, b in exact.contact_intervals()
                                  if a <= T] if exact is not None else None,
        "exact_solution": exact is not None, "errors": summary_errors,
        "energy": energy, "status": r.status, "message": r.message,
        "bar": {"a": bar.a, "b": bar.b, "rho": bar.rho, "L": bar.L, "f": bar.f,
                "v0": bar.v0, "u0": bar.u0, "k": bar.k, "c": bar.c},
        "units": {"displacement": "m", "contact_force": "Pa (force per unit cross-section)",
                  "energy": "J/m² (per unit cross-section)",
                  "errors": "L² in time: √(Δt Σ eₙ²); contact force from t₁ on",
                  "max_penetration": "m: max(−u(0,tₙ)) (a spring's compression)",
                  "wall_time_s": "the time loop alone (one step past T, for R at T)"},
        "notes": ("energy = kinetic + strain + obstacle, the scheme's E_β/2 split; "
                  "energy_final and the energy report add the load potential −fL·ū"),
        "config": vars(args), **cli.stamp(),
    }

    with output_dir(out, args.overwrite) as tmp:
        write_summary(tmp, summary)
        write_timeseries(tmp, columns)
        write_fields(tmp, r, fmt=args.format)
        title = (f"{bar.obstacle} obstacle{f' k={bar.k:g}' if spring else ''}, f={bar.f:g}, "
                 f"N={bar.N}, Δt={r.dt:g}, β={r.beta:g}, {bar.mass} mass")
        _compare_chart(tmp / "displacement.png", run.t,
                       {"u(0, t)": run.u0, "u(L, t)": run.uL},
                       {"u(0, t) exact": columns.get("u_0_exact"),
                        "u(L, t) exact": columns.get("u_L_exact")},
                       title, "displacement (m)")
        _compare_chart(tmp / "contact_force.png", run.t, {"reaction R": run.force},
                       {"R exact": columns.get("contact_force_exact")}, title, "R (Pa)")
        _compare_chart(tmp / "energy.png", run.t,
                       {"kinetic": run.kinetic, "strain": run.strain,
                        "obstacle": run.obstacle, "total": run.energy + run.load_potential},
                       {"exact total": columns.get("energy_exact")}, title, "energy (J/m²)")
    return cli.report(_Report(r, steps), out)


class _Report:
    """What cli.report reads, for the N steps to T (the run made one more)."""

    def __init__(self, r, steps):
        self.status, self.message, self.t = r.status, r.message, r.t[:steps + 1]
        self.steps, self.wall_time_s, self.impacts = steps, r.wall_time_s, r.impacts
        self.max_nodal_violation = r.max_nodal_violation


def _compare_chart(path, t, computed: dict, exact: dict, title: str, ylabel: str):
    """Computed lines solid, exact ones dashed and darker, drawn on top."""
    fig, ax = plt.subplots(figsize=(9, 4), dpi=110)
    for (label, y), (elabel, ye) in zip(computed.items(),
                                        list(exact.items()) + [(None, None)] * len(computed)):
        line, = ax.plot(t, y, lw=1.0, label=label)
        if ye is not None:
            ax.plot(t, ye, lw=1.1, ls=(0, (4, 3)), color="k", alpha=0.8, zorder=3,
                    label=elabel)
    ax.set_xlabel("t (s)")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.legend(loc="best", fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


if __name__ == "__main__":
    cli.main_guard(main)
