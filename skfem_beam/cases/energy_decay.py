"""Energy of the discrete scheme with f = 0: constant between impacts, dropping at impacts.

    python -m skfem_beam.cases.energy_decay [--beta 0.5] [--compare-beta 0.25] ...

The second paper's Figs 4–7: u0 = 0.005 x², v0 = −x, g = ±(0.2 + 0.3 (x − L/2)²).
Writes the usual folder for --beta, plus energy.csv / energy_decay.png with the
energy history ½E_β^n of --beta and of --compare-beta side by side.
"""
from __future__ import annotations


from .. import cli, scenes
from ..scheme import solve
from ..scheme.methods import PositionLevel
from ..output.folder import write_timeseries
from ..chart_process import draw
from ..output.charts import trajectory_chart
from ..checks import check_beta
from ..semidiscrete import beam_system
from . import pipe_parser
from ._beam import run_beam_case


def main(argv=None) -> int:
    p = pipe_parser("skfem_beam.cases.energy_decay", __doc__, J=40, dt=1e-3, T=1.0,
                    L=scenes.PIPE10_L)
    p.add_argument("--compare-beta", type=float, default=0.25,
                   help="a second β whose energy is charted beside --beta (negative: none)")
    args = cli.parse(p, argv)
    pb = scenes.energy_decay(J=args.J, element=args.element, L=args.L, k2=args.k2,
                             nodes=cli.mesh_nodes(args))
    other = None if args.compare_beta < 0 else check_beta(args.compare_beta)

    def energy_files(folder, data, run):
        columns = {"t": data["t"], f"energy_{run.label.replace('=', '_')}": data["energy"]}
        if other is not None:
            r2 = solve(beam_system(pb), args.dt, args.T, method=PositionLevel(args.solver,
                       beta=other), save_every=args.save_every, frames=2)
            columns[f"energy_beta_{other:g}"] = r2.energy[:data["t"].size]
        write_timeseries(folder, columns, "energy.csv")
        draw(trajectory_chart, folder / "energy_decay.png", data["t"],
             {k: v for k, v in columns.items() if k != "t"},
             title=f"discrete energy ½E_β, f = 0 (J={pb.J}, {pb.element}, Δt={args.dt:g} s)",
             ylabel="energy (m³/s²)")

    config = {"f": "0", "u0": "0.005 x²", "v0": "-x", "g": "±(0.2 + 0.3 (x − L/2)²)"}
    return run_beam_case("energy_decay", pb, cli.spec(args, config), extra=energy_files)


if __name__ == "__main__":
    cli.main_guard(main)
