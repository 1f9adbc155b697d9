"""Where the β-family really fails: a map of stable and unstable runs over (β, Δt).

    python -m skfem_beam.cases.stability_map [--betas 0,0.1,0.2,0.25,0.5]
        [--ratios 0.5,0.9,1.2,2,10,100] [--T 0.5] [--methods contact,penalty]
        [--max-seconds 900] [--out DIR]

On the first paper's pipe.  For β < 1/4 a run's step is ratio × the linear limit
2/√(κ_h(1−4β)); for β ≥ 1/4 (no linear limit) ratio × the first paper's sufficient
bound of Prop. 3.1 at β = 1/4 with its κ̄ of (5.2) (3.35e-6 s for J = 19).  Each run
is marked stable or unstable by the energy detector of `solve`; the chart draws the
runs over the linear limit and the papers' bounds.  Writes stability_map.csv/.png.
"""
from __future__ import annotations

import math
import time
from functools import partial

import numpy as np

from .. import cli, scenes
from ..errors import InputError
from ..scheme import solve
from ..methods import FLAGS, Penalty, law_of, make
from ..chart_process import wanted
from ..output.charts import figure
from ..output.folder import Folder, check_output_dir
from ..parser import Defaults, about
from ..checks import check_beta, check_positive
from ..semidiscrete import beam_system
from ..stability import PAPER_KAPPA_BOUNDS, kappa_h, linear_limit, prop31_limit, stability_table

PAPER_KAPPA = "first paper (5.2), 24·420·19²/37"


def floats(name: str, text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise InputError(f"--{name} {text!r} must be a comma-separated list of numbers") from None
    if not values or not all(math.isfinite(v) for v in values):
        raise InputError(f"--{name} {text!r} must list finite numbers")
    return values


def reference_step(kappa: float, kappa_paper: float, beta: float) -> float:
    """The step a ratio multiplies: the linear limit, or the papers' bound where there is none."""
    return linear_limit(kappa, beta) if beta < 0.25 else prop31_limit(kappa_paper, 0.25)


def check_budget(system, grid, T, step_of, max_seconds) -> None:
    """Refuse up front a grid of (β, ratio, method) runs that would not fit the budget;
    ``step_of(β)``: the step a ratio multiplies (:func:`reference_step`)."""
    steps = sum(math.ceil(T / (r * step_of(b))) for b, r, _ in grid)
    probe = solve(system, 1e-5, 0.02, 0.5, frames=1)            # cost per step, measured here
    per_step = 2.0 * probe.wall_time_s / probe.steps + 1e-6      # margin: penalty, contact
    estimate = steps * per_step + 0.05 * len(grid)
    if estimate > max_seconds:
        raise InputError(f"the grid needs about {estimate:.0f} s ({len(grid)} runs, {steps} steps) "
                         f"> --max-seconds={max_seconds:g}: use fewer or larger ratios, or a shorter --T")


def run_map(system, grid, T, stiffness, step_of) -> list[dict]:
    """Every (β, ratio, method) run of ``grid``, with Δt = ratio·``step_of(β)``."""
    rows = []
    for beta, ratio, method in grid:
        dt = ratio * step_of(beta)
        law = Penalty(stiffness, equation_units=True, beta=beta) \
            if law_of(method) == "penalty" else make(law_of(method), params={"beta": beta}, words=FLAGS)
        r = solve(system, dt, T, method=law, save_every=max(1, int(1e-4 / dt)), frames=2,
                  progress=False)
        tip = r.observed["tip_displacement"]
        rows.append({"beta": beta, "ratio": ratio, "dt": dt, "method": method,
                     "status": r.status, "steps": r.steps, "t_end": float(r.t[-1]),
                     "max_tip": float(np.abs(tip).max()), "energy_final": float(r.energy[-1]),
                     "wall_time_s": r.wall_time_s})
    return rows


def chart(path, rows, kappa, kappa_paper, title):
    with figure(path, figsize=(8, 5)) as (fig, ax):
        b = np.linspace(0, 0.5, 400)
        lin = [linear_limit(kappa, x) for x in b]
        ax.plot(b, lin, "k-", lw=1.5, label="linear limit 2/√(κ_h(1−4β))")
        ax.plot(b, [prop31_limit(kappa, x) for x in b], "b--", lw=1,
                label="Prop. 3.1 bound, exact κ_h")
        ax.plot(b, [prop31_limit(kappa_paper, x) for x in b], "b:", lw=1,
                label="Prop. 3.1 bound, the paper's κ̄ (5.2)")
        marker = {"contact": "o", "penalty": "s"}
        shift = {"contact": -0.006, "penalty": 0.006}
        for method in sorted({r["method"] for r in rows}):
            for ok in (True, False):
                sel = [r for r in rows if r["method"] == method and (r["status"] == "success") == ok]
                if sel:
                    ax.scatter([r["beta"] + shift[method] for r in sel], [r["dt"] for r in sel],
                               marker=marker[method], facecolors="none" if not ok else None,
                               color="tab:green" if ok else "tab:red", s=40,
                               label=f"{method}: {'stable' if ok else 'unstable'}")
        ax.set_yscale("log")
        ax.set_xlabel("β")
        ax.set_ylabel("Δt (s)")
        ax.set_title(title)
        ax.axvline(0.25, color="gray", lw=0.5)
        ax.legend(fontsize=7, loc="upper left")
        ax.grid(alpha=0.3, which="both")


def main(argv=None) -> int:
    p = cli.Parser(prog="skfem_beam.cases.stability_map", description=about(__doc__),
                   formatter_class=Defaults)
    p.add_argument("--betas", default="0,0.1,0.2,0.25,0.35,0.5",
                   help="comma-separated Newmark β in [0, 1/2]")
    p.add_argument("--ratios", default="0.5,0.9,1.2,2,10,100",
                   help="comma-separated Δt as multiples of the linear limit (β < 1/4) or of "
                        "the paper's Prop. 3.1 step (β ≥ 1/4)")
    p.add_argument("--methods", default="contact,penalty",
                   help="comma-separated: contact (= position), penalty, moreau-jean")
    p.add_argument("--T", type=float, default=0.5, help="final time of each run (s)")
    p.add_argument("--J", type=int, default=19, help="elements of the pipe")
    p.add_argument("--stiffness", type=float, default=1e8,
                   help="penalty stiffness (N/m), with penalty among --methods")
    p.add_argument("--max-seconds", type=float, default=900.0,
                   help="refuse a grid whose estimated run time exceeds this (s)")
    p.add_argument("--out", default="out/stability_map", help="output folder")
    p.add_argument("--overwrite", action="store_true",
                   help="replace the --out folder of an earlier map")
    args = p.parse_args(argv)
    betas = [check_beta(b) for b in floats("betas", args.betas)]
    ratios = [check_positive("ratio", r) for r in floats("ratios", args.ratios)]
    words = [m.strip() for m in args.methods.split(",") if m.strip()]
    for m in words:
        law_of(m, "--methods")
    T = check_positive("T", args.T)
    max_seconds = check_positive("max-seconds", args.max_seconds)
    stiffness = check_positive("stiffness", args.stiffness) / scenes.PIPE_RHO_S
    out = check_output_dir(args.out, args.overwrite)
    pb = scenes.point_stops(J=args.J)
    system = beam_system(pb)
    kappa = kappa_h(system)
    dx = pb.beam.L / pb.J
    kappa_paper = PAPER_KAPPA_BOUNDS["hermite"][PAPER_KAPPA] * pb.beam.k2 / dx**4
    t0 = time.perf_counter()
    grid = [(b, r, m) for b in betas for r in ratios for m in words]
    step_of = partial(reference_step, kappa, kappa_paper)
    check_budget(system, grid, T, step_of, max_seconds)
    rows = run_map(system, grid, T, stiffness, step_of)
    summary = {"case": "stability_map", "J": pb.J, "T": T, "kappa_h": kappa,
               "kappa_paper_5_2": kappa_paper, "config": vars(args)}
    with Folder.open(out, summary, args.overwrite) as folder:
        import csv
        with open(folder / "stability_map.csv", "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
        if wanted():        # SKFEM_BEAM_CHARTS=0: no picture, as every command
            chart(folder / "stability_map.png", rows, kappa, kappa_paper,
                  f"pipe scene J={pb.J}, T={T:g} s: κ_h={kappa:.4g}, paper's "
                  f"κ̄={kappa_paper:.4g} s⁻²")
        folder.close(runs=len(rows),
                     bounds={f"beta={b:g}": stability_table(kappa, "hermite", pb.beam.k2, dx, b)
                             for b in betas},
                     unstable=sum(r["status"] != "success" for r in rows),
                     wall_time_s=time.perf_counter() - t0)
    print(f"{len(rows)} runs, {sum(r['status'] != 'success' for r in rows)} unstable -> {args.out}")
    return 0


if __name__ == "__main__":
    cli.main_guard(main)
