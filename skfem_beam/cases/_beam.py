"""The part every beam scene shares: checks, stability warning, run, output contract."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import cli
from ..output.charts import energy_chart, shape_chart, trajectory_chart
from ..output.events import beam_impacts
from ..output.fields import physical_tip
from ..output.probes import probe_columns, probe_units
from ..output.series import Series, execute, prepare
from ..scheme import Stepping
from ..scheme.kernels import WORK_TERMS
from ..checks import check_positive
from ..semidiscrete import add_probes, beam_system
from ..spaces.redistribution import redistributed
from ..stability import kappa_h, linear_limit



def run_beam_case(case: str, problem, args, config: dict, stops=(), extra=None) -> int:
    """Discretise ``problem``, run it with the flags in ``args``, write DIR, return exit code.

    ``extra(folder, data, run)`` may write more files into the output folder (``data``:
    the timeseries columns, from memory).
    """
    cli.check_method(args)
    stepping = Stepping(args.dt, args.T, args.beta, args.save_every, args.frames,
                        massless=cli.massless(args))
    options = cli.output_options(args)
    prepare(options)  # fail before the run, not after it
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
    if args.mass == "redistributed":
        system = redistributed(system)
    run = cli.make_run(system, stepping, args, stiffness)

    view = system.view

    def columns(run, k0, k1):
        force = run.lam[k0:k1].sum(axis=1)   # net force on the beam, m²/s² = N/(kg/m)
        t = np.arange(k0, k1) * run.save_every * run.dt
        # the physical ũ(L) = u(L) + h(L)φ(t), whatever the lifting (u(L) when h(L) = 0)
        tip, tip_v = physical_tip(view, t, run.obs[k0:k1, 0], run.obsv[k0:k1, 0])
        cols = {"t": t, "tip_displacement": tip, "tip_velocity": tip_v,
                "energy": run.energy[k0:k1], "contact_force": force}
        if rho_S:                            # physical units: N and J
            cols["contact_force_N"] = force * rho_S
            cols["energy_J"] = run.energy[k0:k1] * rho_S
        # work since state 1, in the units of energy: energy − energy[0] + damping
        # = input + contact (the scheme's identity, docs/design.md §3)
        work = run.work[k0:k1]
        terms = {f"work_{name}": work[:, i] for i, name in enumerate(WORK_TERMS)}
        cols.update(terms)
        if rho_S:
            cols.update({f"{k}_J": v * rho_S for k, v in terms.items()})
        return {**cols, **probe_columns(run, k0, k1)}

    def finish(folder: Path, data: dict, run):
        t, beta, dt = data["t"], run.beta, run.dt
        about = f"β={beta:g}, Δt={dt:g} s, J={problem.J}, {problem.element}"
        trajectory_chart(folder / "tip_displacement.png", t, {"ũ(L, t)": data["tip_displacement"]},
                         stops=stops, title=f"{case}: tip displacement ({about})")
        joules = "energy_J" in data         # in J when the mass per length ρS is known
        energy_chart(folder / "energy.png", t, data["energy_J" if joules else "energy"],
                     title=f"{case}: discrete energy ½E_β ({about})",
                     work={k: data[f"work_{k}" + ("_J" if joules else "")] for k in WORK_TERMS},
                     joules=joules)
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

    summary = {
        "case": case, "J": problem.J, "dt": run.dt, "T": run.n_steps * run.dt, "beta": run.beta,
        "element": problem.element, "method": args.method,
        "kappa_h": kh, "linear_stability_limit_dt": limit,
        "units": {**units(rho_S, system), "probes": probe_units(system)},
        "penalty_stiffness_N_per_m": args.stiffness if args.method == "penalty" else None,
        "config": {**config, **{k: v for k, v in vars(args).items() if k != "resume"}},
    }
    def events(folder: Path, run, last: int) -> dict:
        return beam_impacts(folder, run, problem, last)

    return execute(run, options, summary, Series(columns, events=events), finish)


def units(rho_S, system) -> dict:
    """summary.json's ``units``: what every timeseries column is, in which unit and frame."""
    lift = system.view.lift if system.view is not None else None
    frame = ("ũ(L) = u(L) + h(L)φ(t): the physical displacement in the fixed frame, "
             "support motion included" if lift is not None else "u(L): the support is at rest")
    per_mass = "per unit mass per length (the equation is divided by ρS)"
    out = {"t": "s", "displacement": "m",
           "tip_displacement": f"m, {frame}",
           "tip_velocity": "m/s, backward difference of u(L)"
                           + (" plus h(L)φ'(t)" if lift is not None else ""),
           "energy": f"½E_β, m³/s² {per_mass}; of u, relative to the lifted support motion",
           "contact_force": f"net nodal λ, m²/s² (N per kg/m), {per_mass}; positive upwards",
           **{f"work_{k}": f"m³/s² (as energy), {what}, cumulative since t = 0"
              for k, what in zip(WORK_TERMS, ("work lost in damping (≥ 0)",
                                        "work of the loads (the support's motion included)",
                                        "work of the contact forces (≤ 0 for exact contact)"))},
           "energy_balance": "energy − energy[0] + work_damping = work_input + work_contact "
                             "(to round-off)"}
    if rho_S:
        out.update({"contact_force_N": "N (contact_force × rho_S)",
                    "energy_J": "J (energy × rho_S)",
                    **{f"work_{k}_J": f"J (work_{k} × rho_S)" for k in WORK_TERMS},
                    "rho_S": f"{rho_S:g} kg/m"})
    return out
