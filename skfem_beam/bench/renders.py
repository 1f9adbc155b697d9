"""The rendered images of ``docs/``: the beam as a tube between its obstacles.

    python -m skfem_beam.bench.renders [--out docs] [--gif]

- ``point_stops_render.png``: the first paper's pipe (J=19, Δt=5e-5 s, β=1/2) at four
  times of its first 0.6 s, unscaled: the tip meets the stops at ±0.1 m;
- ``flat_obstacles_render.png``: the second paper's 10 m pipe (J=40 Hermite, Δt=1e-3 s)
  forced by sin 10t, with the flat obstacles ±0.01 m on [L/2, L], displacement ×50.

``--gif`` also writes an animation of each run.  Rendering is off-screen (EGL, no
display needed; see :mod:`skfem_beam.output.render`).
"""
from __future__ import annotations

import argparse
from pathlib import Path

from .. import beam_system, scenes, solve
from ..output.render import animate, render_beam


def point_stops_run():
    return solve(beam_system(scenes.point_stops()), dt=5e-5, T=0.6, frames=120)   # β = 1/2


def flat_obstacles_run():
    return solve(beam_system(scenes.flat_obstacles()), dt=1e-3, T=1.0, frames=100)   # β = 1/2


SCENES = {
    "point_stops": (point_stops_run, [0.1, 0.3, 0.45, 0.6]),
    "flat_obstacles": (flat_obstacles_run, [0.2, 0.5, 0.8, 1.0]),
}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m skfem_beam.bench.renders",
                                description=__doc__.splitlines()[0])
    p.add_argument("--out", default="docs", help="folder for the images (default: docs)")
    p.add_argument("--gif", action="store_true", help="also write an animation of each run")
    args = p.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for name, (run, times) in SCENES.items():
        result = run()
        path = out / f"{name}_render.png"
        render_beam(path, result, times, case=name)
        print(path)
        if args.gif:
            print(animate(out / f"{name}.gif", result, case=name))
    return 0


if __name__ == "__main__":
    from ..cli import main_guard
    main_guard(main)
