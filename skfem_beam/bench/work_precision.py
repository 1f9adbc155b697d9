"""Every class of contact time-stepping on one chart: error against the wall time of the
time loop, on the two benchmarks with exact solutions, at two Courant numbers.

    python -m skfem_beam.bench.work_precision
        [--scene all|rod|bar|beams|point_stops|flat_obstacles] [--out docs] [--quick]

Classes (Doyen, Ern & Piperno's four): position-level exact enforcement (our scheme,
restitution e = 0, two settings of mass and β), penalty (one-sided springs of two
stiffnesses, β = 1/4, average mass), velocity level (Moreau–Jean, θ = 1/2, e = 0, average
mass) and modified mass (mass redistributed away from the contact node: β = 1/2, and
β = 1/4 and 1/100 with the massless row in equilibrium at t_{n+1},
``massless="quasi-static"``; β = 1/100 is the central-difference limit, conditionally
stable).

Benchmarks: the periodic rod (``scenes.periodic_rod``, T = 12 = four periods) and the
impacting bar (``scenes.impacting_bar``, rigid obstacle, T = 3), each at Δt/h = 0.04 and
0.4 on a ladder of N (h and Δt refined together).  Errors against the exact solution:
L²(0, T) of u(0, ·) (the chart's error), of the contact stress, L∞(L²) and L²(L²) of u,
L²(H¹) of u and L²(L²) of u_t (Gauss points in every element, on about 1500 frames; u_t is
each scheme's own velocity: backward differences for the position and penalty schemes,
v for Moreau–Jean), the largest penetration, and the energy drift (E(T) − E)/E against
the exact energy E (1/8 and 1/2): ½E_β for the β-schemes, ½vᵀMv + ½uᵀKu for
Moreau–Jean.  The wall time is the time loop alone (Result.wall_time_s).  Writes
work_precision.csv and work_precision.png into --out (about 1 min once the kernels are
compiled).

The beams (``--scene beams``, or one of them; ``all`` runs them too: about 15 s) have no
exact solution: ``scenes.point_stops`` (the first paper's pipe, J = 19, stops ±0.1 m at
the tip; the tip's u(L, ·)) and ``scenes.flat_obstacles`` (the 10 m pipe, J = 40, flat
obstacles ±0.01 m on [L/2, L]; a probe's u(7.5, ·)), on a ladder of Δt at the fixed mesh
(point stops 2e-4 to 1.25e-5 s, flat obstacles 1e-3 to 6.25e-5 s, halving; ``--quick``
the four coarsest).  Each setting's error is the relative L²(0, t₂) distance to a
reference run by the papers' scheme (position level, consistent mass, β = 1/2) on the
same mesh at Δt_ref = (the ladder's smallest Δt)/16, compared at the coarse run's steps,
t₂ the reference's second impact (its first rise of contact after a flight of 1 ms or
more: the rises after shorter flights are the first impact's chatter).  Vibro-impact is
chaotic: nothing after t₂ is compared.  The reference's own error (the same run at
2Δt_ref against it) is the ``ref_error`` column.  Beside the error, the largest
penetration at the nodes (``penetration``; between them: ``penetration_between``) and
the wall time of the time loop up to t₂.  Settings: the beam-applicable ones of METHODS
(a beam's mass is consistent or redistributed; penalty stiffness in N/m, per scene; the
modified mass only on point stops: flat obstacles along a span leave no neighbour to
carry the mass, ``redistributed`` refuses them).  Writes work_precision_beam.csv and
work_precision_beam.png (rod and bar keep their own files).
"""
from __future__ import annotations

import csv
from dataclasses import replace
from pathlib import Path

import numpy as np

from .. import scenes
from ..bar import bar_system, l2_time
from ..reference import exact_of
from .. import methods
from ..methods import MOREAU_JEAN
from ..parser import Parser, about
from ..errors import InputError
from ..scheme import solve
from ..semidiscrete import add_probes, beam_system

COURANTS = (0.04, 0.4)
BENCHMARKS = {"rod": (scenes.periodic_rod, 12.0, 0.125),
              "bar": (lambda N, mass: scenes.impacting_bar(N=N, mass=mass), 3.0, 0.5)}
# (label, class, mass, how to run): every class of the chart
METHODS = [
    ("position, average, β=1/4", "position", "average", dict(beta=0.25)),
    ("position, consistent, β=1/2", "position", "consistent", dict(beta=0.5)),
    ("penalty k=1e3, average, β=1/4", "penalty", "average", dict(beta=0.25, stiffness=1e3)),
    ("penalty k=1e5, average, β=1/4", "penalty", "average", dict(beta=0.25, stiffness=1e5)),
    ("Moreau–Jean θ=1/2 e=0, average", MOREAU_JEAN, "average", dict(theta=0.5)),
    ("modified mass (redistributed), β=1/2", "modified mass", "redistributed", dict(beta=0.5)),
    ("modified mass (redistributed), β=1/4, quasi-static", "modified mass", "redistributed",
     dict(beta=0.25, massless="quasi-static")),
    ("modified mass (redistributed), β=1/100, quasi-static", "modified mass", "redistributed",
     dict(beta=0.01, massless="quasi-static")),
]
STYLE = {"position": "-", "penalty": "--", MOREAU_JEAN: "-.", "modified mass": ":"}


def run_method(system, dt, T, kw, frames):
    """One run of a setting: ``kw`` holds beta, or theta (Moreau–Jean), and optionally
    stiffness (penalty), restitution e (e = 0: the papers' scheme, bit for bit) and
    massless ("beta" or "quasi-static": how a redistributed mass's massless rows step,
    see Stepping)."""
    e, beta = kw.get("restitution", 0.0), kw.get("beta", 0.5)
    if "theta" in kw:
        method = methods.MoreauJean(kw["theta"], e)
    elif "stiffness" in kw:     # per unit of the equation, as the studies give it
        method = methods.Penalty(kw["stiffness"], equation_units=True, beta=beta)
    else:
        method = methods.PositionLevel("auto", e, kw.get("massless", "beta"), beta=beta)
    return solve(system, dt, T, frames=frames, progress=False, method=method)


def field_errors(result, exact, points: int = 4) -> dict:
    """L∞(L²) and L²(L²) of u, L²(H¹) of u and L²(L²) of u_t on the result's frames."""
    space = result.system.space
    xi, w = np.polynomial.legendre.leggauss(points)
    smp = space.sampler(0.5 * (xi + 1.0))
    weights = np.tile(0.5 * w, space.J) * np.repeat(space.h, points)
    t = result.frames_t
    dtf = t[1] - t[0]
    U, V = result.frames_u, result.frames_v
    X = smp.x[None, :]
    eu = (smp.E0 @ U.T).T - exact.u(X, t[:, None])
    ev = (smp.E0 @ V.T).T - exact.velocity(X, t[:, None])
    # P1 slopes per element at its Gauss points (the nodal values of every node)
    nodal = (space.C @ U.T).T
    slope = np.repeat(np.diff(nodal, axis=1) / space.h, points, axis=1)
    ex_strain = exact.strain(X, t[:, None] + 1e-12)
    l2 = lambda e: np.sqrt((e * e) @ weights)                       # noqa: E731
    return {"linf_l2_u": float(l2(eu).max()), "l2_l2_u": l2_time(l2(eu), dtf),
            "l2_h1_u": l2_time(np.sqrt(l2(eu) ** 2 + l2(slope - ex_strain) ** 2), dtf),
            "l2_l2_ut": l2_time(l2(ev), dtf)}


def rung(scene: str, method: tuple, N: int, courant: float) -> dict:
    label, klass, mass, kw = method
    make, T, E = BENCHMARKS[scene]
    bar = make(N, mass=mass)
    system = bar_system(bar)
    dt = courant * bar.h / bar.c
    steps = int(np.ceil(T / dt - 1e-9))
    r = run_method(system, dt, T, kw, frames=min(steps, 1500))
    row = {"scene": scene, "class": klass, "method": label, "courant": courant, "N": N,
           "dt": dt, "wall_time_s": r.wall_time_s, "status": r.status}
    if r.status != "success":   # kept only to the chunk before it went unstable: no error
        return {**row, **dict.fromkeys(("error", "l2_stress", "linf_l2_u", "l2_l2_u",
                                        "l2_h1_u", "l2_l2_ut", "penetration", "max_d2_u0",
                                        "energy_drift"), np.nan)}
    exact = exact_of(replace(bar, mass="average"), T)
    t = r.t
    force = r.contact_force[1:, 0]            # the force of the step tₙ → tₙ₊₁, at tₙ
    return {**row, "error": l2_time(r.observed["u0"] - exact.u(0.0, t), dt),
            "l2_stress": l2_time(force - exact.contact_force(t[:-1]), dt),
            **field_errors(r, exact), "penetration": r.max_penetration,
            # the contact node's step-to-step oscillation (a massless node at β = 1/4)
            "max_d2_u0": float(np.abs(np.diff(r.observed["u0"], 2)).max(initial=0.0)),
            "energy_drift": float((r.energy[-1] - E) / E)}


def rows_of(scene: str, quick: bool):
    Ns = (10, 20, 40, 80) if quick else (20, 40, 80, 160, 320)
    for method in METHODS:
        for courant in COURANTS:
            for N in Ns:
                yield rung(scene, method, N, courant)


# --------------------------------------------------------------------------- the beams
# No exact solution: each setting is measured against the papers' scheme (position level,
# consistent mass, β = 1/2) on the same mesh at Δt_ref = (the ladder's smallest Δt)/16,
# on the window [0, t₂], t₂ the reference's second impact (the second rising edge of its
# contact force after a flight of MIN_FLIGHT or more: shorter flights are chatter of the
# first): vibro-impact is chaotic, nothing is compared after it.
REF_DIVISOR = 16
MIN_FLIGHT = 1e-3
PAPERS = "position, consistent, β=1/2 (the papers')"
# scene: (problem, observed row, ladder of Δt, quick ladder, soft and stiff springs in N/m)
BEAM_SCENES = {
    "point_stops": (lambda: scenes.point_stops(), "tip_displacement",
                    (2e-4, 1e-4, 5e-5, 2.5e-5, 1.25e-5), (2e-4, 1e-4, 5e-5, 2.5e-5),
                    (1e6, 1e8)),
    "flat_obstacles": (lambda: scenes.flat_obstacles(), "probe_7.5_displacement",
                       (1e-3, 5e-4, 2.5e-4, 1.25e-4, 6.25e-5), (1e-3, 5e-4, 2.5e-4, 1.25e-4),
                       (1e4, 1e6)),
}
GAPS = {"point_stops": 0.1, "flat_obstacles": 0.01}    # the scenes' default gaps (m)
BEAM_PROBE = 7.5       # flat obstacles: u(3L/4), the middle of the obstacles' span [L/2, L]


def beam_methods(stiffnesses):
    """The beam-applicable settings of METHODS (a beam's mass is consistent or
    redistributed: no average mass; the stiffnesses in N/m)."""
    soft, stiff = stiffnesses
    return [
        (PAPERS, "position", "consistent", dict(beta=0.5)),
        (f"penalty k={soft:g} N/m, consistent, β=1/4", "penalty", "consistent",
         dict(beta=0.25, stiffness=soft)),
        (f"penalty k={stiff:g} N/m, consistent, β=1/4", "penalty", "consistent",
         dict(beta=0.25, stiffness=stiff)),
        ("Moreau–Jean θ=1/2 e=0, consistent", MOREAU_JEAN, "consistent", dict(theta=0.5)),
        ("modified mass (redistributed), β=1/2", "modified mass", "redistributed",
         dict(beta=0.5)),
        ("modified mass (redistributed), β=1/4, quasi-static", "modified mass",
         "redistributed", dict(beta=0.25, massless="quasi-static")),
        ("modified mass (redistributed), β=1/100, quasi-static", "modified mass",
         "redistributed", dict(beta=0.01, massless="quasi-static")),
    ]


def beam_system_of(scene: str, mass: str = "consistent"):
    """The scene's system (with the flat obstacles' probe), its mass redistributed if
    asked; None when the scene refuses a redistributed mass (contact along a span)."""
    make = BEAM_SCENES[scene][0]
    try:
        system = beam_system(make(), mass=mass)
    except InputError:
        if mass == "redistributed":
            return None
        raise
    if scene == "flat_obstacles":
        add_probes(system, [BEAM_PROBE])
    return system


def run_beam(system, dt, T, kw):
    """run_method with the penalty's stiffness in N/m (converted by ρA)."""
    if "stiffness" in kw:
        return solve(system, dt, T, frames=2, progress=False,
                     method=methods.Penalty(kw["stiffness"], beta=kw["beta"]))
    return run_method(system, dt, T, kw, frames=2)


def second_impact(t, force, flight: float = MIN_FLIGHT) -> float:
    """The start of the second impact: the first rising edge of contact (any row) after a
    flight of at least ``flight`` s (rises after shorter flights are the first impact's
    chatter, whose pattern changes with Δt)."""
    on = np.any(np.asarray(force) != 0, axis=1)
    rises = np.flatnonzero(on[1:] & ~on[:-1]) + 1
    falls = np.flatnonzero(~on[1:] & on[:-1]) + 1
    for k in range(1, rises.size):
        if t[rises[k]] - t[falls[k - 1]] >= flight:
            return float(t[rises[k]])
    raise RuntimeError("the reference has fewer than two impacts: lengthen its run")


def beam_reference(scene: str, dt_ref: float, T: float):
    """The papers' scheme at Δt_ref: (t, observed, t₂, its own error), the last the
    relative L²(0, t₂) distance of the same run at 2Δt_ref (how far the reference is
    from converged on the window)."""
    row = BEAM_SCENES[scene][1]
    r = solve(beam_system_of(scene), dt_ref, T, 0.5, frames=2, progress=False)
    t2 = second_impact(r.t, r.contact_force)
    y = r.observed[row]
    y2 = solve(beam_system_of(scene), 2 * dt_ref, T, 0.5, frames=2,
               progress=False).observed[row]
    n = int(np.floor(t2 / (2 * dt_ref) + 1e-9)) + 1
    own = l2_time(y2[:n] - y[::2][:n], 2 * dt_ref) / l2_time(y[::2][:n], 2 * dt_ref)
    return r.t, y, t2, own


def beam_rows(scene: str, quick: bool):
    _, row, ladder, quick_ladder, springs = BEAM_SCENES[scene]
    dts = quick_ladder if quick else ladder
    dt_ref = min(dts) / REF_DIVISOR
    T_probe = {"point_stops": 0.15, "flat_obstacles": 0.3}[scene]    # past t₂
    t_ref, y_ref, t2, own = beam_reference(scene, dt_ref, T_probe)
    for label, klass, mass, kw in beam_methods(springs):
        system = beam_system_of(scene, mass)
        if system is None:          # a redistributed mass needs contact at isolated points
            continue
        for dt in dts:
            T = np.ceil(t2 / dt - 1e-9) * dt        # whole steps past t₂
            r = run_beam(system, dt, T, kw)
            stride = int(round(dt / dt_ref))
            n = int(np.floor(t2 / dt + 1e-9)) + 1   # the steps in [0, t₂]
            y = r.observed[row][:n]
            ref = y_ref[::stride][:n]
            ok = r.status == "success"    # an unstable run (above its linear limit) has no error
            yield {"scene": scene, "class": klass, "method": label, "mass": mass,
                   "beta": kw.get("beta", ""), "dt": dt, "dt_ref": dt_ref, "t2": t2,
                   "error": l2_time(y - ref, dt) / l2_time(ref, dt) if ok else np.nan,
                   "penetration": r.max_nodal_violation if ok else np.nan,
                   "penetration_between": r.max_penetration if ok else np.nan,
                   "gap": GAPS[scene],
                   "wall_time_s": r.wall_time_s, "steps": r.steps, "status": r.status,
                   "ref_error": own}


def _panels(scenes, rows: list[dict]):
    """(pyplot, figure, axes, the scenes among ``scenes`` that ``rows`` has): three panels
    a scene."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    benches = [s for s in scenes if any(r["scene"] == s for r in rows)]
    fig, axes = plt.subplots(len(benches), 3, figsize=(17, 4.6 * len(benches)), dpi=100,
                             squeeze=False)
    return plt, fig, axes, benches


def chart(path: Path, rows: list[dict]):
    plt, fig, axes, benches = _panels(BENCHMARKS, rows)
    for row_axes, scene in zip(axes, benches):
        sel = [r for r in rows if r["scene"] == scene]
        for ax, courant in zip(row_axes, COURANTS):
            for i, (label, klass, _, _) in enumerate(METHODS):
                pts = [r for r in sel if r["method"] == label and r["courant"] == courant]
                ax.loglog([max(r["wall_time_s"], 1e-5) for r in pts],
                          [r["error"] for r in pts], STYLE[klass], marker="o", ms=3.5,
                          lw=1.2, label=label, color=f"C{i}")
            ax.set_xlabel("wall time of the time loop (s)")
            ax.set_ylabel("L²(0,T) error of u(0,·)")
            ax.set_title(f"{scene}: Δt/h = {courant:g}", fontsize=10)
            ax.grid(alpha=0.3, which="both")
        row_axes[0].legend(fontsize=7, loc="best")
        ax = row_axes[2]
        for i, (label, klass, _, _) in enumerate(METHODS):   # one colour per setting
            for courant, marker in zip(COURANTS, "os"):
                pts = [r for r in sel if r["method"] == label and r["courant"] == courant]
                ax.semilogx([r["N"] for r in pts], [100 * r["energy_drift"] for r in pts],
                            STYLE[klass], marker=marker, ms=3.5, lw=1.0, color=f"C{i}",
                            label=f"{label}, Δt/h={courant:g}")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_yscale("symlog", linthresh=1.0)   # linear within ±1 %: the stiff penalty's
        ax.set_xlabel("N (elements)")             # +850 % would flatten the others'
        Ns = sorted({r["N"] for r in sel})
        ax.set_xticks(Ns, [str(n) for n in Ns], minor=False)
        ax.set_xticks([], minor=True)
        ax.set_ylabel("energy drift (E(T) − E)/E (%)")
        ax.set_title(f"{scene}: energy drift at T (○ Δt/h = 0.04, □ 0.4)", fontsize=10)
        ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def beam_chart(path: Path, rows: list[dict]):
    """Per beam scene: error against the time loop's wall time, error against Δt, and the
    largest penetration at the nodes against Δt (relative to the gap; 0 drawn at 1e-18)."""
    from matplotlib.ticker import NullFormatter
    plt, fig, axes, benches = _panels(BEAM_SCENES, rows)
    for row_axes, scene in zip(axes, benches):
        sel = [r for r in rows if r["scene"] == scene]
        first = sel[0]
        for i, label in enumerate(beam_methods(BEAM_SCENES[scene][4])):
            pts = [r for r in sel if r["method"] == label[0]]
            if not pts:
                continue
            style = dict(ls=STYLE[label[1]], marker="o", ms=3.5, lw=1.2, color=f"C{i}",
                         label=label[0])
            row_axes[0].loglog([max(r["wall_time_s"], 1e-5) for r in pts],
                               [r["error"] for r in pts], **style)
            row_axes[1].loglog([r["dt"] for r in pts], [r["error"] for r in pts], **style)
            row_axes[2].loglog([r["dt"] for r in pts],
                               [max(r["penetration"] / r["gap"], 1e-18) for r in pts], **style)
        what = "u(L,·) (tip)" if scene == "point_stops" else f"u({BEAM_PROBE:g},·) (probe)"
        window = f"[0, t₂ = {first['t2']:.4g} s]"
        row_axes[0].set_xlabel("wall time of the time loop (s)")
        row_axes[1].set_xlabel("Δt (s)")
        row_axes[2].set_xlabel("Δt (s)")
        for ax in row_axes[:2]:
            ax.set_ylabel(f"relative L² error of {what} on {window}")
        row_axes[2].set_ylabel("max penetration at the nodes / gap (0 at 1e-18)")
        row_axes[0].set_title(f"{scene}: error vs the papers' scheme at Δt_ref = "
                              f"{first['dt_ref']:.3g} s", fontsize=10)
        row_axes[1].set_title(f"{scene}: error against Δt (reference's own "
                              f"{first['ref_error']:.1e})", fontsize=10)
        row_axes[2].set_title(f"{scene}: penetration (gap {first['gap']:g} m)", fontsize=10)
        for ax in row_axes:
            ax.grid(alpha=0.3, which="both")
            ax.xaxis.set_minor_formatter(NullFormatter())   # the decades only
        row_axes[0].legend(fontsize=7, loc="best")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def write(out: Path, name: str, rows: list[dict], draw) -> None:
    with open(out / f"{name}.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    draw(out / f"{name}.png", rows)
    print(f"written {out}/{name}.csv and {name}.png")


def main(argv=None) -> int:
    ap = Parser(prog="skfem_beam.bench.work_precision", description=about(__doc__))
    ap.add_argument("--scene", default="all",
                    choices=["all", *BENCHMARKS, "beams", *BEAM_SCENES])
    ap.add_argument("--out", default="docs")
    ap.add_argument("--quick", action="store_true",
                    help="coarser ladders (rod, bar: N = 10 to 80; beams: four Δt)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    chosen = {"all": [*BENCHMARKS, *BEAM_SCENES], "beams": list(BEAM_SCENES)}.get(
        args.scene, [args.scene])
    rows = []
    for scene in (s for s in chosen if s in BENCHMARKS):
        for row in rows_of(scene, args.quick):
            rows.append(row)
            print(f"{scene:4s} {row['method']:51s} Δt/h={row['courant']:<5g} N={row['N']:4d} "
                  f"u(0) {row['error']:8.2e} stress {row['l2_stress']:8.2e} "
                  f"pen {row['penetration']:8.1e} drift {100 * row['energy_drift']:+7.3f} % "
                  f"loop {row['wall_time_s']:7.4f} s", flush=True)
    beam = []
    for scene in (s for s in chosen if s in BEAM_SCENES):
        for row in beam_rows(scene, args.quick):
            beam.append(row)
            print(f"{scene:14s} {row['method']:51s} Δt={row['dt']:<8.3g} error "
                  f"{row['error']:8.2e} pen/gap {row['penetration'] / row['gap']:8.1e} "
                  f"loop {row['wall_time_s']:7.4f} s", flush=True)
    if rows:
        write(out, "work_precision", rows, chart)
    if beam:
        write(out, "work_precision_beam", beam, beam_chart)
    return 0


if __name__ == "__main__":
    from ..cli import main_guard
    main_guard(main)
