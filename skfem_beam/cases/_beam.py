"""The part every beam scene shares: checks, stability warning, run, output contract."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import cli
from ..contact import resolve
from ..output.charts import energy_chart, shape_chart, trajectory_chart
from ..output.events import beam_impacts
from ..output.probes import probe_columns, probe_units
from ..output.series import execute, prepare
from ..scheme import Run, Stepping
from ..checks import check_positive
from ..semidiscrete import add_probes, beam_system
from ..stability import kappa_h, linear_limit


def run_beam_case(case: str, problem, args, config: dict, stops=(), extra=None) -> int:
    """Discretise ``problem``, run it with the flags in ``args``, write DIR, return exit code.

    ``extra(folder, data, run)`` may write more files into the output folder (``data``:
    the timeseries columns, from memory).
    """
    cli.check_method(args)
    stepping = Stepping(args.dt, args.T, args.beta, args.save_every, args.frames)
    out = prepare(args)                            # fail before the run, not after it
    system = beam_system(problem)
    add_probes(system, getattr(args, "probe", None) or [])
    kh = kappa_h(system)
    limit = linear_limit(kh, args.beta)
    if args.dt > limit:
        cli.warn(f"dt={args.dt:g} s is above the linear stability limit "
                 f"2/√(κ_h(1−4β)) = {limit:.4g} s for beta={args.beta:g} (κ_h={kh:.4g} s⁻²); "
                 "the run will likely go unstable")
    stiffness = None
    rho_S = problem.beam.rho_S
    if args.method == "penalty":
        # physical N/m → the mass-normalised equation u_tt + k²u'''' = f needs N/m per kg/m
        stiffness = check_positive("stiffness", args.stiffness) / (rho_S or 1.0)
    run = Run(system, stepping, resolve(args.solver, stiffness))

    def columns(run, k0, k1):
        force = run.lam[k0:k1].sum(axis=1)   # net force on the beam, m²/s² = N/(kg/m)
        cols = {"t": np.arange(k0, k1) * run.save_every * run.dt,
                "tip_displacement": run.obs[k0:k1, 0], "tip_velocity": run.obsv[k0:k1, 0],
                "energy": run.energy[k0:k1], "contact_force": force}
        if rho_S:
            cols["contact_force_N"] = force * rho_S
        return {**cols, **probe_columns(run, k0, k1)}

    def finish(folder: Path, data: dict, run):
        t, beta, dt = data["t"], run.beta, run.dt
        about = f"β={beta:g}, Δt={dt:g} s, J={problem.J}, {problem.element}"
        trajectory_chart(folder / "tip_displacement.png", t, {"ũ(L, t)": data["tip_displacement"]},
                         stops=stops, title=f"{case}: tip displacement ({about})")
        energy_chart(folder / "energy.png", t, data["energy"],
                     title=f"{case}: discrete energy ½E_β ({about})")
        if np.any(data["contact_force"]):
            # in newtons when the mass per length ρS is known (the column is λ·ρS)
            newtons = "contact_force_N" in data
            force = data["contact_force_N" if newtons else "contact_force"]
            trajectory_chart(folder / "contact_force.png", t, {"net contact force λ": force},
                             title=f"{case}: net contact force on the beam ({about})"
                                   + (f", ρS={rho_S:g} kg/m" if newtons else ""),
                             ylabel="force (N)" if newtons else "force per mass (m²/s² = N per kg/m)")
        shape_chart(folder / "beam_shapes.png", run.result(),
                    title=f"{case}: displacement ũ(x, t) at saved times ({about})")
        if extra is not None:
            extra(folder, data, run)
        return beam_impacts(folder, run, problem, data)

    summary = {
        "case": case, "J": problem.J, "dt": run.dt, "T": run.n_steps * run.dt, "beta": run.beta,
        "element": problem.element, "method": args.method,
        "kappa_h": kh, "linear_stability_limit_dt": limit,
        "units": {"displacement": "m", "energy": "½E_β, m³/s² (per unit mass per length)",
                  "contact_force": "m²/s² (N per kg/m)",
                  "contact_force_N": "N (contact_force × rho_S)", "probes": probe_units(system)},
        "penalty_stiffness_N_per_m": args.stiffness if args.method == "penalty" else None,
        "config": {**config, **{k: v for k, v in vars(args).items() if k != "resume"}},
    }
    return execute(run, out, args, summary, columns, finish)
