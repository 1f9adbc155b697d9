"""What every case's command line shares: flags, one-line errors, exit codes.

Exit codes: 0 success, 2 bad input, 3 a solver failed, 4 the run went unstable
(its files up to the last good step are written, with status "unstable").
"""
from __future__ import annotations

import argparse
import importlib.util
import os
import shlex
import signal
import sys
import threading
from pathlib import Path

from . import _startup
from ._version import __version__
from . import methods
from .contact import SOLVERS
from .checks import check_choice, check_positive
from .errors import Deferred, InputError, SolverError
from .output.folder import (EXIT_INPUT, EXIT_SOLVER, EXIT_UNSTABLE, NO_MEMORY,  # noqa: F401
                            OPENED, Interrupted, release, report, stamp)
from .output.options import OutputOptions
from .output.folder import lock_folder
from .output.checkpoint import (_resume_folder, check_resumable, has_checkpoint,
                                read_checkpoint, read_summary)
from .parser import Defaults, Parser, same_sets
from .scheme.stepping import MASSLESS, Stepping
from .spec import RunSpec


# the defaults of the flags every scene shares, as parser() takes them: J (None: no --J,
# --mesh, --probe), dt, T, beta, element and solver (False: no such flag), mass (the mass
# options the scene's space allows, the first the default)
SHARED = {"J": None, "dt": None, "T": None, "beta": None, "element": True, "solver": True,
          "mass": ("consistent", "redistributed")}


def parser(prog: str, description: str, **defaults) -> Parser:
    """The flags every scene takes; a scene adds its own.  ``defaults``: any of
    :data:`SHARED`, which gives the others."""
    unknown = sorted(set(defaults) - set(SHARED))
    if unknown:
        raise TypeError(f"parser() got an unexpected default {unknown[0]!r} "
                        f"(one of {', '.join(SHARED)})")
    d = {**SHARED, **defaults}
    J, dt, T, beta, mass = d["J"], d["dt"], d["T"], d["beta"], d["mass"]
    p = Parser(prog=prog, description=description,
               formatter_class=Defaults)
    if J is not None:
        p.add_argument("--J", type=int, default=J, help="number of elements")
        p.add_argument("--mesh", default=None, metavar="FILE",
                       help="a 1-D line mesh meshio reads (non-uniform allowed; replaces --J); "
                            "the papers' meshes are in meshes/")
        p.add_argument("--probe", type=float, action="append", default=None, metavar="X",
                       help="repeatable: write displacement, velocity, bending moment and "
                            "shear force at x=X (m) into timeseries.csv "
                            "(probe_<X>_displacement, ...)")
    p.add_argument("--dt", type=float, default=dt, help="time step (s)")
    p.add_argument("--T", type=float, default=T, help="final time (s)")
    p.add_argument("--beta", type=float, default=beta,
                   help="Newmark β in [0, 1/2]" if beta is not None else
                   "Newmark β in [0, 1/2] (default 1/2; 1/4 with --method penalty, the papers' choice)")
    if d["element"]:
        p.add_argument("--element", default="hermite", help="hermite | bspline")
    if d["solver"]:
        p.add_argument("--solver", default="auto", help=" | ".join(SOLVERS))
        p.add_argument("--param", action="append", default=None, metavar="NAME=VALUE",
                       help="repeatable: a parameter of the --solver's law (its table: "
                            "docs/design.md, 'Adding a contact law')")
    p.add_argument("--law", default=None, help=" | ".join(methods.LAWS) + ": exact contact at "
                   "position level (the papers' scheme), at velocity level (Moreau–Jean, "
                   "θ = 1/2), or one-sided springs (default: from --method)")
    p.add_argument("--method", default="contact",
                   help="contact (= --law position) | penalty (= --law penalty)")
    p.add_argument("--theta", type=float, default=None,
                   help=f"θ in [1/2, 1] of --law {methods.MoreauJean.name} (default 1/2)")
    p.add_argument("--restitution", type=float, default=0.0, metavar="E",
                   help="Newton coefficient of restitution e in [0, 1] (position, "
                        f"{methods.MoreauJean.name})")
    p.add_argument("--mass", default=mass[0], help=" | ".join(mass))
    if "redistributed" in mass:
        p.add_argument("--massless", default=None, help=" | ".join(MASSLESS) + ": how the "
                       "massless rows of --mass redistributed step: β-weighted (default) or "
                       "in equilibrium at the new time (use it at β = 1/4)")
    p.add_argument("--stiffness", type=float, default=1e8,
                   help="penalty stiffness 1/ε (N/m) for --method penalty")
    return output_flags(p, prog)


def output_flags(p: Parser, prog: str) -> Parser:
    """The flags of what a run writes and where (parser()'s tail)."""
    p.add_argument("--save-every", type=int, default=1,
                   help="keep every n-th step in timeseries.csv")
    p.add_argument("--frames", type=int, default=200,
                   help="field snapshots kept, about: every ⌊steps/frames⌋-th state from t = 0 "
                        "(up to twice as many; the last state only when that divides the steps)")
    p.add_argument("--format", default="both",
                   help="field time series for ParaView: xdmf | vtu | both | none")
    p.add_argument("--out", default=f"out/{prog.rsplit('.', 1)[-1]}", help="output folder")
    p.add_argument("--overwrite", action="store_true",
                   help="replace the --out folder of an earlier run (never other files)")
    p.add_argument("--flush-every", type=int, default=20000,
                   help="steps between writes of the series to disk")
    p.add_argument("--checkpoint-every", type=float, default=None, metavar="SECONDS",
                   help="write the full integrator state this often (atomically; default: "
                        "none while running, one at the end)")
    p.add_argument("--resume", metavar="DIR", default=None,
                   help="continue the killed run in DIR from its last checkpoint (with none: "
                        "run it again from step 0)")
    p.add_argument("--version", action="version", version=f"skfem_beam {__version__}")
    return p


def parse(p: Parser, argv=None):
    """Parse the flags; with --resume, the flags stored by the run being resumed.  The
    method's words are checked once here, and β takes the method's default."""
    args = stored_args(p.parse_args(argv), p, argv)
    given = {} if args.resume else given_flags(p, argv)
    if getattr(args, "mesh", None) is not None and "J" in given:   # J was recorded, not run
        raise InputError(f"--J {args.J} with --mesh {args.mesh}: the mesh file's nodes are "
                         "the elements; give one of them")
    if hasattr(args, "law"):
        check_law(args, p)
        if not args.resume:
            not_its_law(args, given)
        if args.beta is None:
            args.beta = methods.default_beta(method(args))
    return args


def not_its_law(args, given: dict) -> None:
    """Flags of another law than the one named are refused: they were checked and not used
    (--beta 0 with Moreau–Jean ran as stable; --stiffness nan ran exact contact)."""
    if args.law == methods.MOREAU_JEAN and "beta" in given:
        raise InputError(f"--beta {args.beta:g} is the β-scheme's β; --law "
                         f"{methods.MOREAU_JEAN} has none (its θ: --theta)")
    if args.law != "penalty" and "stiffness" in given:
        raise InputError(f"--stiffness {args.stiffness:g} is the penalty law's spring (N/m); "
                         f"--law {args.law} has none (give --law penalty)")
    if "method" in given and "law" in given \
            and methods.summary_word(args.law) != given["method"]:
        raise InputError(f"--method {given['method']} and --law {given['law']} name two "
                         "laws: give one of them")


def check_law(args, p: Parser) -> None:
    """--law (or its alias --method), --mass and --massless, and the method they name;
    sets args.method to "penalty" for the penalty law and "contact" otherwise."""
    check_choice("--method", args.method, ("contact", "penalty"))
    if args.law is None:
        args.law = methods.law_of(args.method, "--method")
    check_choice("--law", args.law, methods.LAWS)
    args.method = methods.summary_word(args.law)
    allowed = next(a.help.split(" | ") for a in p._actions if a.dest == "mass")
    check_choice("--mass", args.mass, allowed)
    methods.check_massless(getattr(args, "massless", None), args.mass)
    method(args)


def method(args) -> methods.Method:
    """The method the flags name (--law, --solver, --restitution, --stiffness N/m,
    --massless, --theta, --beta: the β-scheme's β, None its default)."""
    return methods.make(args.law, getattr(args, "solver", "auto"), args.restitution,
                        args.stiffness if args.law == "penalty" else None,
                        getattr(args, "massless", None), words=methods.FLAGS,
                        params=law_params(getattr(args, "param", None),
                                          theta=getattr(args, "theta", None),
                                          beta=getattr(args, "beta", None)))


def law_params(given, theta: float | None = None, beta: float | None = None) -> dict:
    """--param NAME=VALUE flags as {NAME: number} (the law checks names and ranges), and
    --theta (Moreau–Jean's) and --beta (the β-scheme's) when given."""
    out = {k: v for k, v in (("theta", theta), ("beta", beta)) if v is not None}
    for text in given or ():
        name, eq, value = text.partition("=")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            eq = None
        if not eq or not name.strip():
            raise InputError(f"--param {text!r}: give NAME=VALUE with a number, e.g. "
                             "--param gain=0.5")
    return out


def spec(args, config: dict | None = None) -> RunSpec:
    """The flags as one :class:`~skfem_beam.spec.RunSpec`: Stepping, method (with its β),
    output options, and summary.json's config (``config`` and every flag but --resume)."""
    m = method(args)
    stepping = Stepping(args.dt, args.T, args.save_every, args.frames, massless=m.massless)
    flags = {k: v for k, v in vars(args).items() if k != "resume"}
    return RunSpec(stepping, m, output_options(args), {**(config or {}), **flags},
                   mass=args.mass, probes=tuple(getattr(args, "probe", None) or ()))


def output_options(args) -> OutputOptions:
    """The output flags as one checked :class:`OutputOptions` (the only place they are
    read from the command line)."""
    return OutputOptions(out=args.out, overwrite=args.overwrite, resume=args.resume,
                         format=args.format, frames=args.frames, save_every=args.save_every,
                         flush_every=args.flush_every, checkpoint_every=args.checkpoint_every)


def mesh_nodes(args):
    """The nodes of ``--mesh FILE`` (checked, from 0 to L), or None for a uniform --J mesh."""
    if getattr(args, "mesh", None) is None:
        return None
    from .meshes import load_mesh
    return load_mesh(args.mesh, args.L)


def _terminate(signum, frame):
    if Deferred.holding:        # the kernels are loading: raised after (errors.Deferred)
        Deferred.pending.append(signum)
        return
    raise Interrupted(signum)


def main_guard(main) -> None:
    """Run ``main()``; turn the project's errors into one stderr line and an exit code.

    SIGTERM is turned into :class:`~skfem_beam.output.folder.Interrupted` like SIGINT
    (a run in progress handles both itself: it stops at a chunk and keeps its files);
    the exit code is 128 + the signal.  Folder locks are released on any exit."""
    opened = len(OPENED)
    old = {sig: signal.signal(sig, _terminate) for sig in (signal.SIGINT, signal.SIGTERM)} \
        if threading.current_thread() is threading.main_thread() else {}
    try:
        code = main() or 0
    except SystemExit as e:     # argparse's own exits (--help, a bad flag)
        code = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
        if isinstance(e.code, str):
            print(e.code, file=sys.stderr)
    except (InputError, SolverError) as e:
        print(f"error: {e}", file=sys.stderr)
        code = EXIT_INPUT if isinstance(e, InputError) else EXIT_SOLVER
    except MemoryError:         # numpy's own (an array too large): its traceback
        print(f"error: {NO_MEMORY}: a coarser mesh, fewer frames (--frames) or a machine "
              "with more memory", file=sys.stderr)
        code = EXIT_SOLVER
    except BrokenPipeError:     # stdout's reader went away (| head): nothing to say there,
        _quiet_stdout()         # and the folder's summary.json says how the run ended
        code = EXIT_PIPE
    except OSError as e:   # disk full, folder removed under us, ...
        print(f"error: could not write the results: {e}", file=sys.stderr)
        code = EXIT_SOLVER
    except KeyboardInterrupt as e:
        name = signal.Signals(getattr(e, "signum", signal.SIGINT)).name
        where = f"see {OPENED[-1] / 'summary.json'}" if len(OPENED) > opened \
            else "no output written"
        print(f"interrupted by {name}: {where}", file=sys.stderr)
        code = getattr(e, "code", 130)
    finally:
        release()
        Deferred.pending.clear()
        for sig, handler in old.items():
            signal.signal(sig, handler)
    _startup.end(code)


EXIT_PIPE = 128 + signal.SIGPIPE      # a closed pipe's code (a shell's, for `yes | head`)


def _quiet_stdout() -> None:
    """stdout onto /dev/null: the exit flushes it, and would raise again."""
    try:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    except (OSError, ValueError):
        pass


def warn(message: str) -> None:
    print(f"warning: {message}", file=sys.stderr)


# ------------------------------------------------------------ --resume: the stored flags

def given_flags(parser, argv) -> dict:
    """The flags written on the command line (not the defaults)."""
    actions = [a for a in parser._actions if a.default is not argparse.SUPPRESS]
    saved = [a.default for a in actions]
    try:
        for a in actions:
            a.default = argparse.SUPPRESS
        return vars(parser.parse_args(argv))
    finally:
        for a, d in zip(actions, saved):
            a.default = d


def _as_given(k: str, v) -> str:
    """A flag's value as a user writes it: ``--set time.dt=5e-5 --set ...``, the scene file
    (positional), ``--dt 1e-06``; "no --set" when not given."""
    if v is None or v == []:
        return "no scene file" if k == "scene" else f"no --{k.replace('_', '-')}"
    if k == "scene":
        return f"scene file {v}"
    values = v if isinstance(v, list) else [v]
    return " ".join(f"--{k.replace('_', '-')} {x}" for x in values)


def _same_command(out: Path, summary: dict, prog: str) -> None:
    """Refuse a folder another command wrote (its flags are not this command's): a scene
    file's run (its config holds the scene) is `python -m skfem_beam run`'s, a case's is
    its own module's (``prog`` skfem_beam.cases.<case>)."""
    case, theirs = prog.rsplit(".", 1)[-1], summary.get("case")
    scene = "scene_text" in summary.get("config", {})
    if (prog.endswith(" run") if scene else theirs == case):
        return
    if scene:
        how = f"python -m skfem_beam run --resume {shlex.quote(str(out))}"
    elif theirs == "sweep":
        how = f"python -m skfem_beam.sweep, the same values and --out {out}"
    elif isinstance(theirs, str) and theirs.isidentifier() \
            and importlib.util.find_spec(f"skfem_beam.cases.{theirs}") is not None:
        how = f"python -m skfem_beam.cases.{theirs} --resume {shlex.quote(str(out))}"
    else:
        how = "the command that wrote it"
    raise InputError(f"--resume {out}: a run of {theirs!r}, not of {prog}: resume it with "
                     f"{how}")


def stored_args(args, parser, argv=None):
    """For ``--resume DIR``: the flags of the run stored in DIR/summary.json, once DIR is
    locked and its summary, checkpoint and rows agree.  ``--T`` may grow (extending the
    run); any other flag that differs from the stored one is refused by name.  A run
    stopped before its first checkpoint has only its summary to agree with: it is run
    again from step 0 with these flags (output.stream.execute)."""
    if not getattr(args, "resume", None):
        return args
    out = _resume_folder(args.resume)
    lock_folder(out)
    summary = read_summary(out)
    _same_command(out, summary, parser.prog)
    ck = read_checkpoint(out) if has_checkpoint(out) else None
    config = summary["config"]
    given = given_flags(parser, argv)
    T = config.get("T")
    for k, v in given.items():
        if k == "resume" or k == "out" and Path(v).resolve() == out.resolve():
            continue
        if k == "T" and T is not None and check_positive("T", v) >= T:
            T = v
            continue
        if k == "T":
            raise InputError(f"--resume {out}: --T {v:g} is shorter than the run's T={T:g} "
                             "(a run can only be extended)")
        if k == "set" and same_sets(v, config.get("set")):
            continue        # the same settings, written another way
        if k not in config or config[k] != v:
            raise InputError(f"--resume {out}: {_as_given(k, v)}, where the run had "
                             f"{_as_given(k, config.get(k))}; a resumed run keeps its scene "
                             "and flags (only --T may grow: extend it with --T)")
    check_resumable(out, summary, ck, extend=T is not None and T > config.get("T", T))
    stored = vars(parser.parse_args([]))
    for k in stored:
        if k in config:
            stored[k] = config[k]
    stored.update(resume=args.resume, out=args.resume, overwrite=False, T=T)
    return type(args)(**stored)
