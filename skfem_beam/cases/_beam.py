"""The part every beam scene shares: stability check, run, output contract."""
from __future__ import annotations

import numpy as np

from .. import cli
from ..integrators import solve
from ..stability import kappa_h, linear_limit
from ..io import check_output_dir, output_dir, write_summary, write_timeseries
from ..plotting import energy_chart, shape_chart, trajectory_chart
from ..problem import check_beta, check_positive
from ..semidiscrete import beam_system


def run_beam_case(case: str, problem, args, config: dict, stops=(), extra=None) -> int:
    """Discretise ``problem``, run it with the flags in ``args``, write DIR, return exit code.

    ``extra(folder, result)`` may write more files into the output folder.
    """
    cli.check_method(args)
    check_beta(args.beta)
    check_positive("dt", args.dt)
    check_positive("T", args.T)
    out = args.out
    check_output_dir(out, args.overwrite)          # fail before the run, not after it
    system = beam_system(problem)
    kappa = kappa_h(system)
    limit = linear_limit(kappa, args.beta)
    if args.dt > limit:
        cli.warn(f"dt={args.dt:g} s is above the linear stability limit "
                 f"2/√(κ_h(1−4β)) = {limit:.4g} s for beta={args.beta:g} (κ_h={kappa:.4g} s⁻²); "
                 "the run will likely go unstable")
    stiffness = None
    rho_S = problem.beam.rho_S
    if args.method == "penalty":
        # physical N/m → the mass-normalised equation u_tt + k²u'''' = f needs N/m per kg/m
        stiffness = check_positive("stiffness", args.stiffness) / (rho_S or 1.0)
    result = solve(system, args.dt, args.T, args.beta, solver=args.solver, stiffness=stiffness,
                   save_every=args.save_every, frames=args.frames)

    force = result.contact_force.sum(axis=1)   # net force on the beam, m²/s² = N/(kg/m)
    columns = {"t": result.t,
               "tip_displacement": result.observed["tip_displacement"],
               "tip_velocity": result.velocity["tip_displacement"],
               "energy": result.energy,
               "contact_force": force}
    if rho_S:
        columns["contact_force_N"] = force * rho_S
    summary = {
        "case": case, "J": problem.J, "dt": result.dt, "T": result.T, "beta": result.beta,
        "element": problem.element, "solver": result.solver, "method": args.method,
        "steps": result.steps, "wall_time_s": result.wall_time_s,
        "us_per_step": 1e6 * result.wall_time_s / max(1, result.steps),
        "max_penetration": result.max_penetration,
        "max_penetration_below_g1": result.max_penetration_below,
        "max_penetration_above_g2": result.max_penetration_above,
        "max_nodal_violation": result.max_nodal_violation,
        "energy_final": float(result.energy[-1]), "impacts": result.impacts,
        "contact_fraction": result.contact_fraction, "qp_iterations": result.qp_iterations,
        "kappa_h": kappa, "linear_stability_limit_dt": limit,
        "status": result.status, "message": result.message,
        "units": {"displacement": "m", "energy": "½E_β, m³/s² (per unit mass per length)",
                  "contact_force": "m²/s² (N per kg/m)",
                  "contact_force_N": "N (contact_force × rho_S)"},
        "penalty_stiffness_N_per_m": args.stiffness if args.method == "penalty" else None,
        "config": {**config, **vars(args)}, **cli.stamp(),
    }
    with output_dir(out, args.overwrite) as tmp:
        write_summary(tmp, summary)
        write_timeseries(tmp, columns)
        trajectory_chart(tmp / "tip_displacement.png", result.t,
                         {"ũ(L, t)": columns["tip_displacement"]}, stops=stops,
                         title=f"{case}: tip displacement (β={result.beta:g}, Δt={result.dt:g} s, "
                               f"J={problem.J}, {problem.element})")
        energy_chart(tmp / "energy.png", result.t, result.energy)
        if np.any(force):
            trajectory_chart(tmp / "contact_force.png", result.t, {"contact force": force},
                             title=f"{case}: net contact force", ylabel="force (m²/s²)")
        shape_chart(tmp / "beam_shapes.png", result, title=f"{case}: u(x, t) at saved times")
        if extra is not None:
            extra(tmp, result)
    return cli.report(result, out)
