"""The part every beam scene shares: checks, stability warning, run, output contract."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .. import cli
from ..chart_process import draw
from ..errors import EXIT_UNSTABLE
from ..output.charts import (energy_chart, orbit_chart, shape_chart, shapes,
                             trajectory_chart, wear_chart)
from ..output.events import beam_impacts
from ..output.fields import physical_at, physical_tip
from ..output.probes import probe_columns, probe_units
from ..output.checkpoint import read_summary
from ..output.stream import Series, execute, prepare
from ..output.supports import support_table, support_wear, worn_through
from ..methods import MoreauJean, Penalty, summary_word
from ..scheme.kernels import WORK_TERMS
from ..spec import RunSpec
from ..semidiscrete import PLANE_SUFFIXES, add_probes, beam_system
from ..stability import kappa_h, linear_limit



def run_beam_case(case: str, problem, spec: RunSpec, stops=(), extra=None) -> int:
    """Discretise ``problem``, run it as ``spec`` says, write its folder, return the exit
    code.  ``extra(folder, data, run)`` may write more files into the output folder
    (``data``: the timeseries columns, from memory)."""
    prepare(spec.options)                         # fail before the run, not after it
    system = beam_system(problem, mass=spec.mass)
    add_probes(system, list(spec.probes))
    run = spec.method.build(system, spec.stepping)      # its refusals before any warning
    # Moreau–Jean (θ ≥ ½) has no β and no limit: a scene file's [time] beta is not its
    kh, limit = stability_warning(system, spec.stepping.dt,
                                  0.5 if isinstance(spec.method, MoreauJean) else spec.beta)
    rho_S = problem.beam.rho_S
    penalty = isinstance(spec.method, Penalty)
    summary = {
        "case": case, "J": problem.J, "dt": run.dt, "T": run.n_steps * run.dt, "beta": run.beta,
        "theta": run.theta,
        "element": problem.element, "method": summary_word(spec.method.name),
        "kappa_h": kh,
        "linear_stability_limit_dt": limit if math.isfinite(limit) else None,
        "observed_x": system.view.observed_x or problem.beam.L,
        "units": units(rho_S, system, "friction" in run.work_terms),
        "penalty_stiffness_N_per_m": spec.method.stiffness if penalty else None,
        "penalty_damping_N_s_per_m": spec.method.damping if penalty else None,
        "config": spec.config,
    }

    springs = (spec.method.stiffness, spec.method.damping) if penalty else None

    def events(folder: Path, run, last: int) -> dict:
        return beam_impacts(folder, run, problem, last, spec.wear, springs)

    series = Series(beam_columns(system.view, rho_S), events=events)
    code = execute(run, spec.options, summary, series,
                   beam_charts(case, problem, rho_S, stops, extra, system.view.observed_x,
                               spec.wear))
    if code == 0:
        print_supports(Path(spec.options.out), spec.wear)
        print_springs(Path(spec.options.out))
        warn_no_contact(run, system)
        warn_rough_start(run)
    if code in (0, EXIT_UNSTABLE):   # unstable: often why
        warn_contact_gain(run)
    return code


def print_supports(folder: Path, wear) -> None:
    """Under the run's end line, the supports' table (output.supports.support_table) read
    back from summary.json, so that the screen says what the file says; nothing when
    the run has no supports (one plane, or no hole and no flat obstacle at a node)."""
    stats = read_summary(folder).get("impact_statistics") or {}
    newtons = stats.get("units", {}).get("impact_work_rate", "W").startswith("W")
    text = support_table(stats.get("supports") or [], newtons, wear)
    if text:
        print(text)
    for line in worn_through(stats.get("supports") or [], wear):
        cli.warn(line)


def print_springs(folder: Path) -> None:
    """Under the run's end line, the spring supports' table (summary.json's
    ``spring_supports``, output.events.spring_supports): per obstacle its stiffness,
    impacts, largest deflection and force; nothing for rigid supports."""
    table = spring_table(read_summary(folder).get("spring_supports") or [])
    if table:
        print(table)


def spring_table(springs: list[dict]) -> str:
    """``spring_supports`` as plain text, one row per obstacle ("" without)."""
    if not springs:
        return ""
    head = ["obstacle", "where", "k (N/m)", "c (N·s/m)", "impacts", "deflection mm",
            "force N"]
    rows = [[str(s["obstacle"]), s["where"], f"{s['stiffness']:.4g}", f"{s['damping']:.4g}",
             str(s["impacts"]), f"{1e3 * s['max_deflection']:.4g}", f"{s['max_force']:.4g}"]
            for s in springs]
    widths = [max(len(r[i]) for r in [head] + rows) for i in range(len(head))]
    lines = ["spring supports (largest deflection and force per obstacle):"]
    lines += ["  ".join(c.rjust(w) for c, w in zip(r, widths)) for r in [head] + rows]
    return "\n".join(lines)


def warn_no_contact(run, system) -> None:
    """One warning line when a scene with obstacles never touched them and its clearance
    is over 100 times the largest displacement there (in the saved frames): a clearance
    in millimetres written as metres looks exactly like this."""
    lo, hi = np.asarray(system.lo, dtype=float), np.asarray(system.hi, dtype=float)
    gaps = np.abs(np.concatenate([lo[np.isfinite(lo)], hi[np.isfinite(hi)]]))
    if not gaps.size or run.n < 2 or run.record.contact_steps > 0:
        return
    reach = float(np.abs(system.C @ run.result().frames_u.T).max())
    if gaps.min() > 100 * reach:
        cli.warn(f"no contact in {run.n} steps: the largest displacement at the obstacles "
                 f"was {reach:.3g} m, their smallest clearance {gaps.min():.4g} m; g1, g2 "
                 "and x are in metres")


def warn_rough_start(run) -> None:
    """One warning line when the start's energy ½E_β¹ passes the initial data's (½v⁰ᵀMv⁰ +
    ½u⁰ᵀKu⁰) by more than a quarter (the first paper's own start, point_stops, whose
    lifted v⁰ does not vanish at the clamp, holds 1.08 at its Δt: under the line): the
    start step gives a mode the displacement Δt·v⁰, not
    v⁰/ω, so an initial velocity with content in modes the step does not resolve (ωΔt ≫ 1:
    a uniform velocity on a supported plate, whose projection has them at the edges) puts
    (ωΔt)² times their energy in, and the run carries it (a 1 × 0.6 m plate at 8 × 8,
    Δt = 1e-4: 2.46 times, at 16 × 16 12.4).  Not under a moving support: its first step
    takes in the support's motion, which the data's energy (in the moving frame) does not
    hold (a beam at rest on a shaken mid support read 5.8e23 times its round-off)."""
    data = getattr(run.scheme, "data_energy", None)
    view = getattr(run.system, "view", None)
    if data is None or getattr(view, "lift", None) is not None:
        return
    given, start = data(), float(run.scheme.E1)
    if given > 0 and start > 1.25 * given:
        cli.warn(f"the start holds {start / given:.3g} times the initial data's energy "
                 "(½v0ᵀMv0 + ½u0ᵀKu0): the initial velocity has content in modes that dt "
                 "does not resolve, which the start step overfills; a smoother initial "
                 "velocity, or a smaller dt")


def warn_contact_gain(run, body: str = "beam") -> None:
    """One warning line when the contact at obstacles that do not move did positive work on
    the ``body`` of more than 1 % of the energy given to it (its start's and the loads'
    work).  Exact contact never does (its work is ≤ 0); penalty springs only store energy
    and give it back, so a net gain is stiff springs under-resolved by Δt gaining it at
    impacts (docs/design.md, "Penalty units": point stops, Δt = 5e-5 s, the springs' work
    +301.7 against 1.4 + 1.6 given, ½E_β 1.4 → 305, "success"); Newton restitution e > 0
    at position level has no energy bound for a continuum (docs/methods.md: a free plate
    falling flat on an obstacle with e = 1 left it with 86 % more energy).  Such runs'
    numbers look like any other's; so does a redistributed mass's quasi-static step, whose
    energy sees the contact force averaged over three steps (point stops, β = 1/4: ½E_β
    1.38 → 36.5, the contact's work +32.8, "success").  Obstacles that move (a support
    carries them) may do work: no line."""
    e = getattr(run.scheme.law, "e", 0.0)
    massless = not run.watch.definite
    if not (run.springs or e > 0 or massless):
        return
    work = run.record.work
    gain = float(work[WORK_TERMS.index("contact")])
    given = float(run.E1) + abs(float(work[WORK_TERMS.index("input")]))
    if run.system.bound_motion is not None or not (given > 0 and gain > 0.01 * given):
        return
    what, fix = ("the penalty springs", "stiff springs that Δt does not resolve gain energy "
                 "at impacts; lower --dt or --stiffness, or use exact contact "
                 "(--law position)") if run.springs else (
        f"the contact with restitution e = {e:g}", "Newton restitution at position level "
        "does not bound a continuum's energy (docs/methods.md); e = 0 does") if e > 0 else (
        "the contact at the redistributed mass's massless rows", "its energy sees the "
        "contact force averaged over three steps, which can gain energy (docs/methods.md); "
        "β = 1/2, or a smaller dt")
    joules = " J" if body == "plate" else ""       # a beam's: per unit mass per length
    cli.warn(f"{what} did {gain:.4g}{joules} of work, {100 * gain / given:.0f} % of the energy "
             f"given to the {body} ({given:.4g}{joules}: its start's and the loads' work), at "
             f"obstacles that do not move (work_contact in timeseries.csv): {fix}")


def stability_warning(system, dt: float, beta: float):
    """κ_h and the linear limit 2/√(κ_h(1−4β)); a warning line when Δt is above it."""
    kh = kappa_h(system)
    limit = linear_limit(kh, beta)
    if dt > limit:
        cli.warn(f"dt={dt:g} s is above the linear stability limit "
                 f"2/√(κ_h(1−4β)) = {limit:.4g} s for beta={beta:g} (κ_h={kh:.4g} "
                 "s⁻²); the run will likely go unstable")
    return kh, limit


def plane_suffixes(planes: int) -> tuple[str, ...]:
    """The column suffix of each plane: ("",) for one plane, ("_v", "_w") for two."""
    return ("",) if planes == 1 else PLANE_SUFFIXES


def beam_columns(view, rho_S):
    """timeseries.csv's columns of saved rows k0..k1 of a beam run, for either plane count:
    the tip's displacement and velocity and the net contact force once per plane (named
    with the plane's suffix, :func:`plane_suffixes`), the orbit of every hole's node
    (``hole_<x>_displacement_v``, ``_w``: two planes), the energy and the work."""
    suffixes = plane_suffixes(view.planes)

    def columns(run, k0, k1):
        names = list(run.system.observe)
        t = np.arange(k0, k1) * run.save_every * run.dt
        cols = {"t": t}
        for suffix, share in zip(suffixes, view.direction):
            # the physical ũ(L) = u(L) + h(L)φ(t), whatever the lifting (u(L) when h(L) = 0)
            i = names.index(f"tip_displacement{suffix}")
            tip, tip_v = physical_tip(view, t, run.obs[k0:k1, i], run.obsv[k0:k1, i], share)
            cols[f"tip_displacement{suffix}"], cols[f"tip_velocity{suffix}"] = tip, tip_v
        for name in names:
            if name.startswith("hole_"):
                x = float(name.split("_")[1])
                share = view.direction[name.endswith("_w")]
                cols[name] = physical_at(view, x, t, run.obs[k0:k1, names.index(name)],
                                         share=share)[0]
        cols["energy"] = run.energy[k0:k1]
        if "friction" in run.work_terms:     # the friction's Gauss–Seidel at each saved step
            cols["friction_residual"] = run.resid[k0:k1]
        for suffix, force in zip(suffixes, plane_forces(run, k0, k1)):
            cols[f"contact_force{suffix}"] = force     # m²/s² = N/(kg/m)
            if rho_S:                                  # physical units: N and J
                cols[f"contact_force{suffix}_N"] = force * rho_S
        if rho_S:
            cols["energy_J"] = run.energy[k0:k1] * rho_S
        return {**cols, **work_columns(run, k0, k1, rho_S), **probe_columns(run, k0, k1)}
    return columns


def plane_forces(run, k0, k1) -> list:
    """The net contact force on the beam in each plane, saved rows k0..k1: one plane the
    sum of λ, two planes λ @ row_planes (each row's share of v and w)."""
    lam = run.lam[k0:k1]
    if run.system.planes == 1:
        return [lam.sum(axis=1)]
    force = lam @ run.record.row_planes
    return [force[:, c] for c in range(force.shape[1])]


def work_columns(run, k0, k1, rho_S) -> dict:
    """The work since state 1, in the units of energy (and J): energy − energy[0] +
    damping = input + contact (+ friction) (the scheme's identity, docs/design.md §3)."""
    work = run.work[k0:k1]
    terms = {f"work_{name}": work[:, i] for i, name in enumerate(run.work_terms)}
    if rho_S:
        terms.update({f"{k}_J": v * rho_S for k, v in list(terms.items())})
    return terms


PLANE_LABELS = {"": "ũ", "_v": "v", "_w": "w"}   # a plane's displacement, in chart labels


def beam_charts(case, problem, rho_S, stops, extra, observed_x=None, wear=None):
    """The charts of a beam run (and the case's ``extra`` files), from the rows in memory:
    the observed point's displacement, the energy and the net contact force, each plane's
    line named by its suffix (:func:`plane_suffixes`); one plane the beam's shapes, two
    planes an orbit per hole node; ``observed_x``: where the default series observes a
    beam whose end at L is held; ``wear``: the [wear] of a two-plane run
    (output.supports.Wear), a wear chart per hole."""
    where = "L" if observed_x is None else f"{observed_x:g} m"
    what = "tip displacement" if observed_x is None else f"displacement at x = {where}"
    suffixes = plane_suffixes(problem.planes)
    one = len(suffixes) == 1

    def finish(folder: Path, data: dict, run):
        t = data["t"]
        about = f"{run.label}, Δt={run.dt:g} s, J={problem.J}, {problem.element}"
        draw(trajectory_chart, folder / "tip_displacement.png", t,
             {f"{PLANE_LABELS[s]}({where}, t)": data[f"tip_displacement{s}"] for s in suffixes},
             stops=stops if observed_x is None and one else (),
             title=f"{case}: {what}{'' if one else ', both planes'} ({about})")
        joules = "energy_J" in data         # in J when the mass per length ρS is known
        draw(energy_chart, folder / "energy.png", t, data["energy_J" if joules else "energy"],
             title=f"{case}: discrete energy ½E_β ({about})",
             work={k: data[f"work_{k}" + ("_J" if joules else "")] for k in run.work_terms},
             joules=joules)
        force_chart(folder, data, case, about, rho_S if one else None, suffixes)
        if one:
            draw(shape_chart, folder / "beam_shapes.png",
                 shapes(run.result(), elastic=run.springs),
                 title=f"{case}: displacement ũ(x, t) at saved times ({about})")
        else:
            if wear is None:
                orbit_charts(folder, data, case, problem, about)
            else:       # each wear chart draws the orbit beside the wear
                wear_charts(folder, data, run, case, problem, about, rho_S, wear)
        if extra is not None:
            extra(folder, data, run)
    return finish


def force_chart(folder, data, case, about, rho_S, suffixes) -> None:
    """contact_force.png: the net contact force on the beam in each plane, in newtons when
    the mass per length ρS is known (the columns ending ``_N``: λ·ρS), drawn when it is
    not all zero; ``rho_S``: named in the title (None: not named)."""
    newtons = f"contact_force{suffixes[0]}_N" in data
    label = {"": "net contact force " + ("λρS" if newtons else "λ"),
             "_v": "net contact force, v", "_w": "net contact force, w"}
    if not any(np.any(data[f"contact_force{s}"]) for s in suffixes):
        return
    draw(trajectory_chart, folder / "contact_force.png", data["t"],
         {label[s]: data[f"contact_force{s}" + ("_N" if newtons else "")] for s in suffixes},
         title=f"{case}: net contact force on the beam ({about})"
               + (f", ρS={rho_S:g} kg/m" if newtons and rho_S is not None else ""),
         ylabel="force (N)" if newtons else "force per mass (m²/s² = N per kg/m)")


def orbit_charts(folder, data, case, problem, about) -> None:
    """orbit_<x>.png per hole node: w against v there, the hole's wall drawn (a run with
    [wear] draws it in its wear_<x>.png instead: one picture per support)."""
    for h, x in hole_nodes(problem):
        key = f"hole_{x:g}_displacement"
        draw(orbit_chart, folder / f"orbit_{x:g}.png", data[f"{key}_v"],
             data[f"{key}_w"], h.hole.outline(),
             f"{case}: orbit at x = {x:g} m, {h.hole.shape} hole\n({about})",
             h.hole.centre)


def hole_nodes(problem):
    """(hole, x) of every node a hole acts at: where the orbits are observed."""
    return [(h, float(x)) for h in problem.holes
            for x in problem.nodes[h.acts_at(problem.nodes, problem.beam.L)]]


def wear_charts(folder, data, run, case, problem, about, rho_S, wear) -> None:
    """wear_<x>.png per hole: the wear per sector round the hole beside the orbit.  The
    wear is computed as summary.json's (output.supports.support_wear, over the same
    T = n·Δt and in the same units), since the charts are drawn before that file."""
    for h, x in hole_nodes(problem):
        key = f"hole_{x:g}_displacement"
        entry = support_wear(run, x, rho_S or 1.0, run.n * run.dt, wear)
        draw(wear_chart, folder / f"wear_{x:g}.png", entry, data[f"{key}_v"],
             data[f"{key}_w"], h.hole.outline(),
             f"{case}: wear at x = {x:g} m after {wear.service_years:g} years, "
             f"{h.hole.shape} hole\n({about})", h.hole.centre)


PLANES = {"_v": "the first plane's, along y", "_w": "the second plane's, along z"}
PER_PLANE = ("tip_displacement", "tip_velocity", "contact_force", "contact_force_N")


def units(rho_S, system, friction: bool = False) -> dict:
    """summary.json's ``units``: what every timeseries column is, in which unit and frame,
    under the column's own name (two planes: each plane's columns with its suffix, after
    the probes'); ``friction``: the run has Coulomb friction (its work and residual)."""
    lift = system.view.lift if system.view is not None else None
    frame = ("ũ(L) = u(L) + h(L)φ(t): the physical displacement in the fixed frame, "
             "support motion included" if lift is not None else "u(L): the support is at rest")
    per_mass = "per unit mass per length (the equation is divided by ρS)"
    x = system.view.observed_x if system.view is not None else None
    held = "" if x is None else (f"at x = {x:g} m, not at L: the end at L is held, so the "
                                 "default series observes the node of largest first-mode "
                                 "amplitude (add --probe X for others); ")
    terms = WORK_TERMS + (("friction",) if friction else ())
    works = ("work lost in damping (≥ 0; with Moreau–Jean θ > ½ it also holds the scheme's "
             "numerical dissipation at impacts, (θ − ½)pᵀCΔv, whose step may be < 0)",
             "work of the loads (the support's motion included)",
             "work of the contact forces (≤ 0 for exact contact at obstacles at rest in the "
             "lifted frame; a gain, with restitution e > 0, springs or a quasi-static "
             "massless row, is warned of)",
             "work of Coulomb friction (≤ 0; Moreau–Jean's, taken on each step's "
             "displacement while Coulomb's law holds for v^{n+1}, may rise on a step whose "
             "slip reverses, its total ≤ 0)")
    out = {"t": "s", "displacement": "m: the field series' displacement (fields.xdmf, "
                                      "fields.pvd), no column here",
           "tip_displacement": f"m, {held}{frame}",
           "tip_velocity": "m/s, backward difference of tip_displacement"
                           + (" plus h(L)φ'(t)" if lift is not None else ""),
           "energy": f"½E_β, m³/s² {per_mass}; of u, relative to the lifted support motion",
           "contact_force": f"net nodal λ, m²/s² (N per kg/m), {per_mass}; positive upwards",
           **{f"work_{k}": f"m³/s² (as energy), {what}, cumulative since t = 0"
              for k, what in zip(terms, works)},
           "energy_balance": "energy − energy[0] + work_damping = work_input + work_contact"
                             + (" + work_friction" if friction else "") + " (to round-off)",
           "linear_stability_limit_dt": "s, 2/√(κ_h(1−4β)); null: no limit (β ≥ 1/4)",
           "max_support_deflection": "m: the largest compression of the supports' springs "
                                     "(a stiffness: the penalty law), null for rigid ones"}
    if friction:
        out["friction_residual"] = ("the friction's Gauss–Seidel residual at the saved step "
                                    "(largest impulse change of its last sweep, relative; 0 "
                                    "with one contact: exact)")
    if rho_S:
        out.update({"contact_force_N": "N (contact_force × rho_S)",
                    "energy_J": "J (energy × rho_S)",
                    **{f"work_{k}_J": f"J (work_{k} × rho_S)" for k in terms},
                    "rho_S": f"{rho_S:g} kg/m"})
    own = plane_units(out, system.planes)      # pops the one plane's names it replaces
    return {**out, "probes": probe_units(system), **own}


def plane_units(out: dict, planes: int) -> dict:
    """Two planes: each plane's columns (PER_PLANE and a hole's orbit) under their
    suffixed names, taking the place of the one plane's (popped from ``out``)."""
    if planes == 1:
        return {}
    own = {}
    for name in PER_PLANE:
        text = out.pop(name, None)
        if text is None:
            continue
        for s in plane_suffixes(planes):
            column = f"contact_force{s}_N" if name == "contact_force_N" else f"{name}{s}"
            own[column] = f"{text}; {PLANES[s]}"
    for s in plane_suffixes(planes):
        own[f"hole_<x>_displacement{s}"] = f"m, the node of a hole at x, {PLANES[s]} (the orbit)"
    return own
