"""The ``run`` and ``modes`` subcommands of ``python -m skfem_beam`` on a scene file."""
from __future__ import annotations

import argparse
import csv
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from .. import methods
from ..errors import InputError
from ..output.options import OutputOptions
from ..problem import BeamProblem
from ..spec import RunSpec
from .build import Scene, load, wear
from .parts import named_section
from .read import scene_path


def _run_parser() -> argparse.ArgumentParser:
    from ..parser import Parser
    p = Parser(prog="python -m skfem_beam run",
               description="Run the scene a TOML file describes (docs/scene_files.md).")
    p.add_argument("scene", nargs="?", default=None, help="the scene file (TOML)")
    p.add_argument("--set", action="append", default=None, metavar="KEY=VALUE",
                   help="override a key of the file, e.g. time.dt=1e-5 (repeatable)")
    p.add_argument("--T", type=float, default=None, help="final time (s): [time] T")
    p.add_argument("--out", default=None, help="output folder (default out/<scene name>)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace the --out folder of an earlier run (never other files)")
    for flag in ("format", "frames", "save-every", "flush-every", "checkpoint-every"):
        p.add_argument(f"--{flag}", default=None,
                       type=str if flag == "format" else float if flag == "checkpoint-every"
                       else int, help=f"[output] {flag.replace('-', '_')}")
    p.add_argument("--probe", action="append", type=float, default=None, metavar="X",
                   help="also record u, velocity, moment and shear at x = X (m), with "
                        "[output] probes (repeatable)")
    p.add_argument("--resume", metavar="DIR", default=None,
                   help="continue the stopped run in DIR from its last checkpoint (with "
                        "none: run it again from step 0)")
    return p


def run_main(argv) -> int:
    """``python -m skfem_beam run``: the scene through the scenes' own pipeline."""
    from ..cli import stored_args
    p = _run_parser()
    args = stored_args(p.parse_args(argv), p, argv)
    scene = _scene_of(args.scene, args.set, args.resume, args.T)
    try:
        return _run_scene(scene, args)
    except InputError as e:     # found once the scene is built: say which file it is about
        raise about_file(e, args.scene) from None


def about_file(e: InputError, scene) -> InputError:
    """``e``'s line naming the scene file, unless it names it or a flag already."""
    file = f"{Path(scene or 'scene.toml').name}: "
    return e if str(e).startswith((file, "--")) else InputError(file + str(named_section(e)))


def _run_scene(scene: Scene, args) -> int:
    name = f"scene {Path(args.scene).stem}" if args.scene else "scene"
    if scene.kind == "plate":
        from ..cases._plate import run_plate_case
        flags = {k: v for k, v in vars(args).items() if k != "resume"}
        return run_plate_case(name, scene.problem, _plate_spec(scene, flags, args.resume))
    spec = _spec(scene, {k: v for k, v in vars(args).items() if k != "resume"}, args.resume)
    if scene.kind == "bar":
        from ..cases.impacting_bar import run_bar_case
        return run_bar_case(scene.problem, spec)
    from ..cases._beam import run_beam_case
    return run_beam_case(name, scene.problem, spec, stops=_chart_stops(scene.problem))


def _scene_of(path, sets, resume, T=None) -> Scene:
    """The scene file (or, resuming, the text the run stored) with the --set overrides
    and (a new run) --T as its [time] T, so that Δt is checked against the T that runs."""
    from ..output.checkpoint import read_summary
    stored, summary = {}, {}
    if resume:
        summary = read_summary(Path(resume))
        config = summary["config"]
        if "scene_text" not in config:
            raise InputError(f"--resume {resume}: not a run of python -m skfem_beam run")
        stored = {"text": config["scene_text"], "files": config.get("scene_files", {}),
                  "meshes": config.get("scene_meshes", {})}
    elif path is None:
        raise InputError("run needs a scene file: python -m skfem_beam run SCENE.toml")
    given = T is not None and not resume
    if given and not (math.isfinite(T) and T > 0):
        raise InputError(f"--T {T:g}: T must be a positive number of seconds")
    overrides = list(sets or ()) + ([f"time.T={T!r}"] if given else [])
    try:
        scene = load(path or "scene.toml", overrides, **stored)
    except InputError as e:     # Δt against the flag's T (its steps): named as the flag
        rule = str(e).partition("[time] ")[2] or str(e).partition(": ")[2]
        if not given or not ("must be less than T" in rule or rule.startswith("T/dt")):
            raise
        raise InputError(f"--T {T:g}: {rule}") from None
    if resume and scene.kind == "plate":
        _same_mesh(scene, summary, resume)
        for name in scene.meshes:       # read from the scene's folder: no stored copy
            if "base64" not in stored["meshes"].get(name, {}):
                where = scene_path(path or "scene.toml").parent / name
                print(f"notice: --resume {resume}: the run stored no copy of the mesh file "
                      f"{name}; read {where} (its sha256 is stored from now on)",
                      file=sys.stderr)
    return scene


def _same_mesh(scene, summary: dict, resume) -> None:
    """A resumed plate's mesh is the run's: its vertices, triangles and box as its
    summary.json records them (a folder written before the mesh file's bytes were stored
    has no sha256: this is what it can be checked against)."""
    from ..cases._plate import geometry
    built = geometry(scene.problem.space.plate)
    if "mesh" not in built or "vertices" not in summary:
        return
    differ = [k for k in ("vertices", "triangles", "box") if summary.get(k) != built[k]]
    if differ:
        k = differ[0]
        raise InputError(f"--resume {resume}: the mesh file {built['mesh']} has {k}="
                         f"{built[k]}, the run's had {summary.get(k)}: not the mesh the run "
                         "used; cannot resume, nothing was changed")


def _grid(scene, flags: dict, resume) -> tuple[OutputOptions, object]:
    """The output options and the time grid: the flags (completed in place from the
    scene's [output] and [time] T where not given) over the scene's."""
    from_file = set()
    for key, value in scene.output.items():
        if key != "probes" and flags[key] is None:
            flags[key] = value
            from_file.add(key)
    flags["T"] = scene.stepping.T if flags["T"] is None else flags["T"]
    if flags["out"] is None:
        flags["out"] = f"out/{Path(flags['scene']).stem}"
    try:
        options = OutputOptions(flags["out"], flags["overwrite"], resume, flags["format"],
                                flags["frames"], flags["save_every"], flags["flush_every"],
                                flags["checkpoint_every"])
    except InputError as e:       # the file's [output] value, named as the file has it
        flag = next((k for k in from_file if str(e).startswith(f"--{k.replace('_', '-')}")),
                    None)
        if flag is None:
            raise
        raise InputError(f"{Path(flags['scene']).name}: [output] {flag}"
                         f"{str(e)[len(flag) + 2:]}") from None
    try:
        return options, replace(scene.stepping, T=flags["T"], save_every=options.save_every,
                                frames=options.frames)
    except InputError as e:       # a flag's value (the file's own were checked at load)
        key = str(e).split("=")[0].strip()
        flag = "T" if key in ("T", "dt", "T/dt") else key    # dt: "must be less than T"
        if not isinstance(flags.get(flag), (int, float)):
            raise
        raise InputError(f"--{flag.replace('_', '-')} {flags[flag]:g}: {e}") from None


def _spec(scene: Scene, flags: dict, resume) -> RunSpec:
    """The scene and the command line's flags (which override its [output] and [time] T)
    as one RunSpec; summary.json's config records both, in the flags' names."""
    given = flags.pop("probe", None) or []
    if given and scene.kind == "bar":       # it was taken and ignored
        raise InputError("--probe X is a beam's: the bar writes u(0) and u(L) only")
    options, stepping = _grid(scene, flags, resume)
    (law, solver), restitution = methods.split_law(scene.law), scene.restitution
    mass = scene.data.get("mesh", {}).get("mass", "consistent") if scene.kind == "beam" \
        else scene.problem.mass
    probes = [float(x) for x in np.atleast_1d(scene.output.get("probes", []))] + \
        [x for x in given if x not in scene.output.get("probes", [])]
    _probes_on_beam(scene, flags, given)
    config = {"command": "python -m skfem_beam run", "scene_text": scene.text,
              "scene_files": scene.files, **flags, "dt": stepping.dt, "beta": scene.beta,
              "method": methods.summary_word(law),
              "law": law, "solver": "auto" if restitution else solver,
              "stiffness": scene.stiffness, "restitution": restitution, "mass": mass,
              "massless": stepping.massless, "probe": probes}
    try:        # [wear] is read here, after the file's own build: its lines name it too
        worn = wear(scene) if scene.kind == "beam" else None
    except InputError as e:
        raise InputError(f"{Path(flags['scene'] or 'scene.toml').name}: {e}") from None
    return RunSpec(stepping, scene.method, options, config, mass, tuple(probes), worn)


def _probes_on_beam(scene: Scene, flags: dict, given) -> None:
    """A probe off the beam, named as the user gave it: ``[output] probes[i]`` of the
    file or ``--probe X`` (the system's own check names neither)."""
    if scene.kind != "beam":
        return
    L = scene.problem.beam.L
    named = [(f"{Path(flags['scene'] or 'scene.toml').name}: [output] probes[{i}] = {x!r}", x)
             for i, x in enumerate(scene.output.get("probes", []))]
    for text, x in named + [(f"--probe {x:g}", x) for x in given]:
        if not 0.0 <= x <= L:
            raise InputError(f"{text}: outside the beam [0, L = {L:.10g}] m")


def _plate_spec(scene, flags: dict, resume) -> RunSpec:
    """A plate scene and the command line's flags as one RunSpec (as :func:`_spec`; the
    probes are the file's [output] probes, vertices (x, y): --probe X is a beam's)."""
    if flags.pop("probe", None):
        raise InputError("--probe X is a beam's abscissa; a plate's probes are [output] "
                         "probes = [[x, y], ...] in the scene file")
    options, stepping = _grid(scene, flags, resume)
    config = {"command": "python -m skfem_beam run", "scene_text": scene.text,
              "scene_files": scene.files, **flags, "probe": None, "dt": stepping.dt,
              "beta": scene.beta, "law": scene.method.name}
    if scene.meshes:    # a mesh file's bytes: --resume builds the plate from them
        config["scene_meshes"] = scene.meshes
    return RunSpec(stepping, scene.method, options, config)


def _chart_stops(problem: BeamProblem) -> tuple:
    """The obstacle at the tip, for the tip chart (none when it has none)."""
    lo, hi = problem.obstacles.bounds([problem.beam.L])
    return tuple(float(g) for g in (lo[0], hi[0]) if np.isfinite(g))


def _modes_parser() -> argparse.ArgumentParser:
    from ..parser import Parser
    p = Parser(prog="python -m skfem_beam modes",
               description="Natural frequencies and mode shapes of a scene file's beam, with "
                           "its ends and supports (obstacles ignored).")
    p.add_argument("scene", help="the scene file (TOML)")
    p.add_argument("--n", type=int, default=6, help="number of modes")
    p.add_argument("--set", action="append", default=None, metavar="KEY=VALUE",
                   help="override a key of the file (repeatable)")
    p.add_argument("--out", default=None, help="write DIR/modes.csv")
    p.add_argument("--overwrite", action="store_true",
                   help="replace the --out folder of an earlier run (never other files)")
    return p


def modes_main(argv) -> int:
    """``python -m skfem_beam modes``: natural frequencies of the scene's beam."""
    from ..modes import modes
    from ..two_planes import plane_problems
    args = _modes_parser().parse_args(argv)
    scene = load(args.scene, args.set or (), dynamic=False)
    if scene.kind == "plate":
        try:
            return _plate_modes(scene, args)
        except InputError as e:     # the plate's own check: say which file it is about
            raise about_file(e, args.scene) from None
    if scene.kind != "beam":
        raise InputError(f"modes: {args.scene} is a {scene.kind}; modes are computed for "
                         "beams")
    out = None
    if args.out is not None:
        from ..output.folder import check_output_dir
        out = check_output_dir(args.out, args.overwrite)
    problem = scene.problem
    # two planes: each plane's modes (its own EI), the lowest n of both, with their plane
    planes = [("", modes(problem, args.n))] if problem.planes == 1 else \
        [(p, modes(one, args.n)) for p, one in zip("vw", plane_problems(problem))]
    rows = sorted(((m.f[i], m.omega[i], p, m.shapes[:, i]) for p, m in planes
                   for i in range(m.f.size)), key=lambda r: r[0])[:args.n]
    two = problem.planes == 2
    print(f"{'mode':>4s}{' plane' if two else ''} {'f (Hz)':>14s} {'ω (rad/s)':>14s}")
    for i, (f, w, p, _) in enumerate(rows, 1):
        print(f"{i:4d}{p:>6s} {f:14.6g} {w:14.6g}" if two else f"{i:4d} {f:14.6g} {w:14.6g}")
    if out is not None:
        with _modes_folder(out, args.overwrite) as folder:
            _write_modes(folder.path, rows, planes[0][1].x, two)
            _modes_written(folder, len(rows))
    return 0


def _write_modes(out: Path, rows: list, x, two: bool) -> None:
    """DIR/modes.csv: each mode's number, plane (two planes), f, ω and shape at ``x``."""
    with open(out / "modes.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["mode"] + (["plane"] if two else []) + ["f_Hz", "omega_rad_s"]
                   + [f"u({float(xi):.12g})" for xi in x])
        for i, (f, om, p, shape) in enumerate(rows, 1):
            w.writerow([i] + ([p] if two else []) + [f"{f:.17g}", f"{om:.17g}"]
                       + [f"{u + 0.0:.17g}" for u in shape])     # −0 at a held node: 0


def _modes_folder(out: Path, overwrite: bool):
    """The folder of ``modes --out``, made, locked and (``overwrite``) emptied as a run's
    is: over a run's folder it left the run's files beside its own."""
    from ..output.folder import Folder
    return Folder.open(out, {"command": "python -m skfem_beam modes"}, overwrite=overwrite)


def _modes_written(folder, n: int) -> None:
    """The folder's summary.json (so that --overwrite knows a folder this command wrote)
    and the line naming modes.csv."""
    folder.close(modes=n)
    print(f"written: {folder / 'modes.csv'}", file=sys.stderr)


def _plate_modes(scene, args) -> int:
    """The plate's lowest natural frequencies (its edges' supports; obstacles ignored),
    printed, and with --out DIR/modes.csv: mode, f, ω and w at every vertex."""
    from ..plate.modes import natural_frequencies
    out = None
    if args.out is not None:
        from ..output.folder import check_output_dir
        out = check_output_dir(args.out, args.overwrite)
    space = scene.problem.space
    omega, shapes = natural_frequencies(space, args.n)
    print(f"{'mode':>4s} {'f (Hz)':>14s} {'ω (rad/s)':>14s}")
    for i, w in enumerate(omega, 1):
        print(f"{i:4d} {w / (2 * np.pi):14.6g} {w:14.6g}")
    if out is not None:
        x, y = space.vertices
        with _modes_folder(out, args.overwrite) as folder:
            with open(folder / "modes.csv", "w", newline="") as fh:
                w = csv.writer(fh)
                w.writerow(["mode", "f_Hz", "omega_rad_s"]
                           + [f"w({xi:.12g};{yi:.12g})" for xi, yi in zip(x, y)])
                for i, om in enumerate(omega):
                    w.writerow([i + 1, f"{om / (2 * np.pi):.17g}", f"{om:.17g}"]
                               + [f"{v:.17g}" for v in shapes[space.w_dofs, i]])
            _modes_written(folder, len(omega))
    return 0
