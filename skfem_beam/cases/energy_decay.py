"""Energy of the discrete scheme with f = 0: constant between impacts, dropping at impacts.

    python -m skfem_beam.cases.energy_decay [--beta 0.5] [--compare-beta 0.25] ...

The second paper's Figs 4–7: u0 = 0.005 x², v0 = −x, g = ±(0.2 + 0.3 (x − L/2)²).
Writes the usual folder for --beta, plus energy.csv / energy_decay.png with the
energy history ½E_β^n of --beta and of --compare-beta side by side.
"""
from __future__ import annotations


import numpy as np

from .. import cli, scenes
from ..errors import InputError
from ..scheme import solve
from ..scheme.methods import MoreauJean, with_beta
from ..output.folder import write_timeseries
from ..chart_process import draw
from ..output.charts import trajectory_chart
from ..semidiscrete import beam_system
from . import pipe_parser
from ._beam import run_beam_case


def main(argv=None) -> int:
    p = pipe_parser("skfem_beam.cases.energy_decay", __doc__, J=40, dt=1e-3, T=1.0,
                    L=scenes.PIPE10_L)
    p.add_argument("--compare-beta", type=float, default=None,
                   help="a second β whose energy (the same law) is charted beside --beta "
                        "(default 0.25; negative: none; Moreau–Jean: none)")
    args = cli.parse(p, argv)
    pb = scenes.energy_decay(J=args.J, element=args.element, L=args.L, k2=args.k2,
                             nodes=cli.mesh_nodes(args))
    spec = cli.spec(args, {"f": "0", "u0": "0.005 x²", "v0": "-x",
                           "g": "±(0.2 + 0.3 (x − L/2)²)"})
    other = args.compare_beta
    if isinstance(spec.method, MoreauJean) and other is not None and other >= 0:
        raise InputError(f"--compare-beta {other:g}: Moreau–Jean has no β to compare (give "
                         "no --compare-beta with --law moreau-jean)")
    if other is None:
        other = -1.0 if isinstance(spec.method, MoreauJean) else 0.25
    if not np.isfinite(other) or 0.5 < other:
        raise InputError(f"--compare-beta {other:g}: must lie in [0, 1/2] (negative: none)")
    other = None if other < 0 else other

    def energy_files(folder, data, run):
        own = f"energy_{run.label.replace('=', '_')}"
        columns = {"t": data["t"], own: data["energy"]}
        if other is not None and other != run.beta:      # the same β: the same run
            name = f"energy_beta_{other:g}"
            name = f"energy_beta_{other!r}" if name == own else name   # 0.3000001 vs 0.3
            columns[name] = compared(pb, args, spec, other, data["t"].size)
        write_timeseries(folder, columns, "energy.csv")
        draw(trajectory_chart, folder / "energy_decay.png", data["t"],
             {k: v for k, v in columns.items() if k != "t"},
             title=f"discrete energy ½E_β, f = 0 (J={pb.J}, {pb.element}, Δt={args.dt:g} s)",
             ylabel="energy (m³/s²)")

    return run_beam_case("energy_decay", pb, spec, extra=energy_files)


def compared(pb, args, spec, beta: float, rows: int) -> np.ndarray:
    """½E_β of the run's own method at ``beta``, on the run's saved steps; where that run
    goes unstable (β < 1/4 above its step limit), NaN from there on, and a line says so."""
    r = solve(beam_system(pb), args.dt, args.T, method=with_beta(spec.method, beta),
              save_every=args.save_every, frames=2)
    energy = np.full(rows, np.nan)
    kept = min(rows, r.energy.size)
    energy[:kept] = r.energy[:kept]
    if r.status != "success":
        cli.warn(f"--compare-beta {beta:g}: that run is {r.status} ({r.message}); "
                 f"energy.csv has its energy up to t={r.t[kept - 1]:g} s, NaN after")
    return energy


if __name__ == "__main__":
    cli.main_guard(main)
