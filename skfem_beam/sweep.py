"""Parameter sweeps and bifurcation diagrams, on one core or a Dask cluster.

    python -m skfem_beam.sweep --scene point_stops --param omega --values 'linspace(5, 40, 200)' \\
        [--transient 2 --periods 50] [--zeta 0.02] [--workers N | --scheduler tcp://HOST:PORT] --out DIR

Each parameter value is one independent, deterministic run (one Dask task).  The run
keeps a Poincaré section: the tip displacement and velocity sampled exactly at
t = k·2π/ω, once per forcing period, after the transient.  The time step is
dt = P / round(P / dt_target) (P = 2π/ω) and the integrator saves every P/dt steps, so
the saved states *are* the section (no interpolation).  The velocity is the
integrator's backward difference (uⁿ − uⁿ⁻¹)/Δt.

``--zeta Z`` adds Rayleigh damping B = αM + α_K K with the damping ratio Z at the beam's
first two natural frequencies f1, f2 (:func:`skfem_beam.modes`, obstacles and support
motion ignored; recomputed per value when L or k2 is swept); Z = 0 (the default) is the
papers' undamped pipe, run exactly as before.  Every run records ζ, f1, f2, α, α_K.

DIR receives, as runs finish, ``runs/<param>=<value>.json`` (written atomically); a
sweep started again with the same settings skips the values whose file exists.  At
the end the files are assembled into ``poincare.csv`` (one row per section point),
``runs.csv`` (one row per value: impacts, contact-time fraction, detected period),
``bifurcation.png`` and ``sweep.json``; the command's ``summary.json`` carries its status
("running" until the end).  On a cluster a value whose worker dies is tried again
(``RETRIES`` times), then recorded "failed" in ``runs.csv`` (not in ``runs/``: the same
command run again retries it) while the others finish.  The CSV files hold only deterministic data
(floats written exactly, as Python's repr): they are identical for any number of
workers.

By default the runs go to a local Dask cluster started inside this process
(``LocalCluster``, one thread per worker process; scheduler, workers and dashboard
listen on 127.0.0.1 only, on free ports); ``--scheduler ADDRESS`` sends them to an
existing Dask cluster instead (its workers must have skfem_beam installed; this process
writes the files); ``--workers 0`` runs them one after another in this process, no Dask.
"""
from __future__ import annotations

import argparse
import contextlib
import csv
import importlib.util
import inspect
import json
import math
import os
import re
import sys
import time
from pathlib import Path

import numpy as np

from . import cli, scenes
from .errors import InputError, SolverError
from .output.folder import (EXIT_SOLVER, EXIT_UNSTABLE, Folder, atomic_write,
                             check_output_dir, stamp)
from .output.stream import Signals
from .chart_process import draw, wanted as charts_wanted
from .checks import check_beta, check_nonnegative, check_positive
from .sweep_cluster import dask_client, on_cluster

# scene name -> (problem factory, parameters that may be swept or set)
SCENES = {
    "point_stops": (scenes.point_stops, ("omega", "amplitude", "gap", "k2", "L")),
}
SECTION = "tip_displacement"   # the observed value whose section is kept
CHUNK = 20000                  # steps per call into the compiled loop
WORKERS_PER_CORE = 4           # --workers at most this many a core: each is a process


# ---------------------------------------------------------------- inputs

def scene_defaults(scene: str) -> dict:
    """The scene's parameters and their default values (from its factory's signature)."""
    if scene not in SCENES:
        raise InputError(f"--scene {scene!r} is not one of: {', '.join(SCENES)}")
    factory, names = SCENES[scene]
    sig = inspect.signature(factory)
    return {n: sig.parameters[n].default for n in names}


_LINSPACE = re.compile(r"^linspace\(([^,()]+),([^,()]+),([^,()]+)\)$")
_PLAIN_NUMBER = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^[-+]?(inf|nan)$",
                           re.IGNORECASE)
_WHOLE = re.compile(r"^[-+]?\d+$")


def parse_values(spec: str) -> list[float]:
    """``linspace(a, b, n)`` (n values from a to b, both included, as numpy.linspace) or
    an explicit comma list ``v1,v2,...``.  ``a:b:c`` is refused: MATLAB reads it as
    start:step:stop, an older version of this command read it as start:stop:count."""
    spec = str(spec).strip()
    if re.search(r"[\d.]\s+[\d.]", spec):     # "5 10" had run one value, 510
        raise InputError(f"--values {spec!r}: numbers separated by spaces; a list is comma "
                         "separated (5,10,20), or linspace(5, 40, 200)")
    text = spec.replace(" ", "")
    if ":" in text:
        raise InputError(f"--values {spec!r}: a:b:c is ambiguous (start:step:stop in MATLAB); "
                         "write linspace(5, 40, 200) for 200 values from 5 to 40, or a "
                         "comma list 5,10,20")
    m = _LINSPACE.match(text)
    words = [m[1], m[2]] if m else text.split(",")
    # plain numbers only: Python's float() also reads "1_0" and full-width digits
    if not all(_PLAIN_NUMBER.match(w) for w in words) or m and not _WHOLE.match(m[3]):
        raise InputError(f"--values {spec!r} is not linspace(a, b, n) (n values from a to "
                         "b) or a comma list of numbers")
    if m:
        a, b, n = float(m[1]), float(m[2]), int(m[3])
        if n < 1:
            raise InputError(f"--values {spec!r}: n={n} must be at least 1")
        if not (math.isfinite(a) and math.isfinite(b)):   # numpy warned, then "nan"
            raise InputError(f"--values {spec!r}: {a if not math.isfinite(a) else b} is not "
                             "a finite number")
        values = [a] if n == 1 else np.linspace(a, b, n).tolist()
    else:
        values = [float(v) for v in words]
    bad = [v for v in values if not math.isfinite(v)]
    if bad:
        raise InputError(f"--values {spec!r}: {bad[0]} is not a finite number")
    if len(set(values)) != len(values):
        raise InputError(f"--values {spec!r}: values repeat")
    return values


# the sweep's settings other than the scene, the swept parameter and the scene's fixed
# parameters: one JSON key (and one command-line flag) each, with its default
SETTINGS = {"transient": 2.0, "periods": 50, "dt": 5e-5, "J": 19, "beta": 0.5,
            "element": "hermite", "solver": "auto", "zeta": 0.0}


def make_settings(scene="point_stops", param="omega", **given) -> dict:
    """Everything a run depends on except the swept value (checked; JSON-able).
    ``given``: any of :data:`SETTINGS` and fixed values of the scene's parameters."""
    defaults = scene_defaults(scene)
    if param not in defaults:
        raise InputError(f"--param {param!r} is not one of: {', '.join(defaults)}")
    unknown = sorted(set(given) - set(SETTINGS) - set(defaults))
    if unknown:
        raise InputError(f"{unknown[0]!r} is not a setting or a parameter of scene "
                         f"{scene!r}: one of {', '.join([*SETTINGS, *defaults])}")
    s = {k: given.get(k, v) for k, v in SETTINGS.items()}
    fixed = {k: float(v if given.get(k) is None else given[k])
             for k, v in defaults.items() if k != param}
    transient = float(s["transient"])
    if not (math.isfinite(transient) and transient >= 0):
        raise InputError(f"transient={transient:g} must be a finite number ≥ 0")
    periods, J = s["periods"], s["J"]
    if isinstance(periods, bool) or int(periods) != periods or periods < 1:
        raise InputError(f"periods={periods!r} must be a whole number ≥ 1")
    if isinstance(J, bool) or int(J) != J or J < 1:
        raise InputError(f"J={J!r} must be a whole number ≥ 1")
    return {"scene": scene, "param": param, "fixed": fixed, "transient": transient,
            "periods": int(periods), "dt_target": check_positive("dt", s["dt"]),
            "J": int(J), "beta": check_beta(s["beta"]), "element": str(s["element"]),
            "solver": str(s["solver"]), "zeta": check_nonnegative("zeta", s["zeta"])}


def damping_of(settings: dict, value: float) -> dict:
    """ζ, the first two natural frequencies f1, f2 (Hz) of the undamped scene's beam and
    the Rayleigh pair (α, α_K) that gives ζ at both (zero when ζ = 0)."""
    from .modes import modes
    from .problem import Damping
    f1, f2 = (float(f) for f in modes(build_problem(settings, value, None), 2).f)
    zeta = settings["zeta"]
    d = Damping.ratio(zeta, f1, f2) if zeta > 0 else Damping()
    return {"zeta": zeta, "f1": f1, "f2": f2, "alpha": d.alpha, "alpha_K": d.alpha_K}


def build_problem(settings: dict, value: float, damping: dict | None = None):
    """The scene at ``value``; ``damping`` as :func:`damping_of` gives it (None: undamped)."""
    from .problem import Damping
    kw = {**settings["fixed"], settings["param"]: float(value)}
    if damping is not None and (damping["alpha"] or damping["alpha_K"]):
        kw["damping"] = Damping(damping["alpha"], damping["alpha_K"])
    return SCENES[settings["scene"]][0](J=settings["J"], element=settings["element"], **kw)


def section_plan(settings: dict, value: float) -> tuple[float, int, int, float]:
    """(dt, steps per forcing period, transient periods, ω) for one value."""
    omega = float(value) if settings["param"] == "omega" else settings["fixed"]["omega"]
    omega = check_positive("omega", omega)
    period = 2 * math.pi / omega
    spp = max(1, round(period / settings["dt_target"]))
    transient_periods = math.ceil(settings["transient"] / period - 1e-9)
    return period / spp, spp, transient_periods, omega


def check_values(settings: dict, values: list[float]) -> None:
    """Fail before any run: the solver must exist, and every value must give a valid
    scene, forcing period and time grid."""
    from .contact import resolve
    try:
        resolve(settings["solver"])
    except InputError as e:
        raise InputError(f"--solver: {e}") from None
    for v in values:
        try:
            stepping_of(settings, v)
            build_problem(settings, v, damping_of(settings, v))
        except InputError as e:
            raise InputError(f"--values {v:g}: {e}") from None


def stepping_of(settings: dict, value: float):
    """The time grid of ``value``'s run: the transient's periods and the sampled ones,
    a save at each period's end; T half a step short of n·dt, so that the run takes
    ceil(T/dt) = n steps whatever the round-off."""
    from .scheme import Stepping
    dt, spp, ntr, _ = section_plan(settings, value)
    n_total = (ntr + settings["periods"]) * spp
    return Stepping(dt, (n_total - 0.5) * dt, save_every=spp, frames=1)


# ---------------------------------------------------------------- one task

def blank_result(settings: dict, value: float, omega: float) -> dict:
    """A value's result before its run: every key run_value and a failure write, in their
    order (a saved file without one of them is run again: load_run)."""
    return {"param": settings["param"], "value": float(value), "settings": settings,
            "omega": omega, "dt": None, "steps_per_period": None, "transient_periods": None,
            "k": [], "t": [], "tip_displacement": [], "tip_velocity": [], "impacts": None,
            "impacts_per_period": None, "contact_fraction": None, "impacts_total": None,
            "damping": None, "status": "success", "message": ""}


def run_value(settings: dict, value: float) -> dict:
    """One parameter value → its Poincaré section and impact statistics (a plain dict).

    Deterministic: the same settings and value give the same numbers on any process.
    The statistics cover the sampled window (after the transient) only: the counters
    are read when the run reaches the end of the transient, and subtracted.
    """
    from .methods import PositionLevel
    from .scheme import drive
    from .semidiscrete import beam_system
    t_start, cpu_start = time.perf_counter(), time.process_time()
    dt, spp, ntr, omega = section_plan(settings, value)
    periods = settings["periods"]
    n_total, n_trans = (ntr + periods) * spp, ntr * spp
    out = {**blank_result(settings, value, omega), "dt": dt, "steps_per_period": spp,
           "transient_periods": ntr}
    run = None
    try:
        out["damping"] = damping_of(settings, value)
        system = beam_system(build_problem(settings, value, out["damping"]))
        run = PositionLevel(settings["solver"], beta=settings["beta"]).build(
            system, stepping_of(settings, value))
        pre = {"impacts": 0, "contacts": 0}
        while not run.done and run.n < n_trans:
            run.advance(min(run.n + CHUNK, n_trans))
        if run.n == n_trans >= 2:
            r = run.result()
            pre.update(impacts=r.impacts, contacts=round(r.contact_fraction * (n_trans - 1)))
        drive(run, CHUNK, progress=False)
        full = run.result()
        if full.status != "success":
            out.update(status=full.status, message=full.message)
        else:
            con = round(full.contact_fraction * (n_total - 1))
            keep = slice(ntr + 1, ntr + periods + 1)
            k = np.arange(ntr + 1, ntr + periods + 1)
            out.update(k=k.tolist(), t=(k * (spp * dt)).tolist(),
                       tip_displacement=full.observed[SECTION][keep].tolist(),
                       tip_velocity=full.velocity[SECTION][keep].tolist(),
                       impacts=full.impacts - pre["impacts"],
                       impacts_per_period=(full.impacts - pre["impacts"]) / periods,
                       contact_fraction=(con - pre["contacts"]) / (n_total - n_trans),
                       impacts_total=full.impacts)
    except (InputError, SolverError) as e:
        out.update(status="failed", message=str(e))
    out["timing"] = {"task_s": time.perf_counter() - t_start,
                     "task_cpu_s": time.process_time() - cpu_start,
                     "time_loop_s": 0.0 if run is None else run.wall, "steps": n_total,
                     "pid": os.getpid()}
    return out


def warm_up(settings: dict, value: float) -> float:
    """Load (or compile, ~15 s the first time) the compiled kernels in this process:
    one forcing period of 4 steps of the sweep's own scene."""
    t0 = time.perf_counter()
    dt, spp = section_plan(settings, value)[:2]
    dt = dt * spp / 4
    run_value({**settings, "periods": 1, "transient": 0.0, "dt_target": dt}, value)
    return time.perf_counter() - t0


def detect_period(u: np.ndarray, tol: float) -> int:
    """Smallest p with |u[k+p] − u[k]| ≤ tol over the section (0: none up to len/2)."""
    for p in range(1, len(u) // 2 + 1):
        if np.all(np.abs(u[p:] - u[:-p]) <= tol):
            return p
    return 0


# ---------------------------------------------------------------- files

def run_path(out: Path, param: str, value: float) -> Path:
    return Path(out) / "runs" / f"{param}={float(value)!r}.json"


def save_run(out: Path, result: dict) -> None:
    path = run_path(out, result["param"], result["value"])
    atomic_write(path, lambda fh: json.dump(result, fh))


def load_run(out: Path, settings: dict, value: float) -> dict | None:
    """The finished run of ``value`` in ``out``, or None; refuses runs of other settings."""
    path = run_path(out, settings["param"], value)
    if not path.exists():
        return None
    try:
        result = json.loads(path.read_text())
    except (OSError, ValueError):
        return None   # unreadable: run it again
    if not isinstance(result, dict) or not blank_result(settings, value, 0.0).keys() \
            <= result.keys():
        return None   # not a whole result (an edited or damaged file): run it again
    same_settings(out, result.get("settings"), settings)
    return result


def same_settings(out: Path, theirs, settings: dict) -> None:
    """Refuse a sweep folder ``out`` whose runs were made with other ``settings``."""
    if theirs != settings:
        theirs = theirs if isinstance(theirs, dict) else {}
        diff = [f"{k} {settings[k]!r} where it has {theirs.get(k)!r}" for k in settings
                if theirs.get(k) != settings[k]]
        raise InputError(f"--out {out} holds a sweep with other settings "
                         f"({'; '.join(diff) or 'its format differs'}); use another --out "
                         "or --overwrite")


def check_out(out, overwrite: bool) -> Path:
    """Refuse an ``--out`` that cannot be written or holds something other than a sweep
    (a folder with ``runs/`` is a sweep to resume, unless ``overwrite``)."""
    out = Path(out)
    if overwrite or not (out / "runs").is_dir():
        check_output_dir(out, overwrite)
    return out


def stored_settings(out: Path) -> dict | None:
    """The settings of the sweep in ``out``: its summary.json's, else a run's (None:
    neither is readable)."""
    for path in [out / "summary.json", *sorted((out / "runs").glob("*.json"))]:
        try:
            settings = json.loads(path.read_text()).get("settings")
        except (OSError, ValueError, AttributeError):
            continue
        if isinstance(settings, dict):
            return settings
    return None


def _csv(fh, header, rows):
    w = csv.writer(fh)
    w.writerow(header)
    for row in rows:
        w.writerow(["" if v is None else repr(v) if isinstance(v, float) else v for v in row])


PARAM_UNITS = {"omega": "rad/s", "amplitude": "m", "gap": "m", "k2": "m⁴/s²", "L": "m"}


def assemble(out: Path, settings: dict, results: list[dict], extra: dict | None = None) -> dict:
    """poincare.csv, runs.csv, bifurcation.png, sweep.json from the finished runs."""
    param = settings["param"]
    results = sorted(results, key=lambda r: r["value"])
    for r in results:
        gap = r["value"] if param == "gap" else settings["fixed"].get("gap", 0.1)
        r["period"] = detect_period(np.array(r["tip_displacement"]), 1e-6 * gap) \
            if r["status"] == "success" else None
    points = [(r["value"], k, t, u, v) for r in results
              for k, t, u, v in zip(r["k"], r["t"], r["tip_displacement"], r["tip_velocity"])]
    atomic_write(out / "poincare.csv", lambda fh: _csv(
        fh, [param, "k", "t", "tip_displacement", "tip_velocity"], points))
    cols = ["omega", "dt", "steps_per_period", "transient_periods", "impacts",
            "impacts_per_period", "contact_fraction", "impacts_total", "period"]
    damp = ["zeta", "f1", "f2", "alpha", "alpha_K"]
    atomic_write(out / "runs.csv", lambda fh: _csv(
        fh, [param] + [c for c in cols if c != param] + damp + ["status"],
        [[r["value"]] + [r[c] for c in cols if c != param]
         + [(r.get("damping") or {}).get(c) for c in damp] + [r["status"]] for r in results]))
    from .output.charts import bifurcation_chart   # charts where one is drawn, not in workers
    draw(bifurcation_chart, out / "bifurcation.png", settings, results)  # SKFEM_BEAM_CHARTS
    summary = {"settings": settings, "values": len(results),
               "failed": sum(r["status"] != "success" for r in results),
               "files": ["poincare.csv", "runs.csv"]
               + (["bifurcation.png"] if charts_wanted() else []) + ["runs/"],
               "units": {param: PARAM_UNITS.get(param, "the swept value"),
                         "omega": "rad/s, the support's circular frequency",
                         "dt": "s, the time step (a whole number of steps per period)",
                         "k": "the forcing period of the sample (t = k·2π/ω)",
                         "steps_per_period": "time steps in one forcing period",
                         "transient_periods": "forcing periods skipped before sampling",
                         "tip_displacement": "m", "tip_velocity": "m/s (backward difference)",
                         "t": "s", "contact_fraction": "fraction of time steps in contact",
                         "impacts": "contacts that start in the sampled window",
                         "impacts_per_period": "impacts / the sampled periods",
                         "impacts_total": "contacts that start in the whole run",
                         "status": "the run's: success, unstable or failed",
                         "period": "smallest p such that the section repeats every p forcing "
                                   "periods (to 1e-6·gap); 0: none up to periods/2",
                         "zeta": "Rayleigh damping ratio at f1 and f2",
                         "f1, f2": "the beam's first two natural frequencies (Hz), "
                                   "obstacles and support motion ignored",
                         "alpha, alpha_K": "B = alpha·M + alpha_K·K (1/s, s)"},
               **(extra or {}), **stamp()}
    atomic_write(out / "sweep.json", lambda fh: json.dump(summary, fh, indent=2,
                                                           ensure_ascii=False))
    return summary


# ---------------------------------------------------------------- the sweep

def lost(settings: dict, value: float, error: BaseException, attempts: int) -> dict:
    """The result of a value whose task never finished (its worker died every time):
    "failed", not saved in runs/, so that the same command run again retries it."""
    return {**blank_result(settings, value, section_plan(settings, value)[3]),
            "status": "failed",
            "message": f"{type(error).__name__} after {attempts} attempts: {error}",
            "timing": {"task_s": 0.0, "task_cpu_s": 0.0, "time_loop_s": 0.0, "steps": 0,
                       "pid": None}}


def sweep(settings: dict, values: list[float], out, client=None, progress: bool = True,
          warm: bool = True, task=None) -> dict:
    """Run every value not yet in ``out/runs`` (serially, or on ``client``), then assemble.

    Returns the summary (also written to ``out/sweep.json``); the per-value results are
    the files in ``out/runs``.  On a cluster a value whose worker dies is retried
    (RETRIES times), then marked failed in runs.csv while the others finish.
    ``task``: what runs one value (default :func:`run_value`).
    """
    out = Path(out)         # a str too (bench.sweep_throughput's temporary folder)
    results, timing = run_values(settings, values, out, client, progress, warm, task)
    return assemble(out, settings, results, {"timing": timing})


def run_values(settings: dict, values: list[float], out, client=None, progress: bool = True,
               warm: bool = True, task=None) -> tuple[list[dict], dict]:
    """:func:`sweep`'s runs: every value's result (those in ``out/runs`` read back) and
    the timing."""
    task = task or run_value
    from tqdm import tqdm
    out = Path(out)
    (out / "runs").mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    done = {v: r for v in values if (r := load_run(out, settings, v)) is not None}
    todo = [v for v in values if v not in done]
    bar = tqdm(total=len(values), initial=len(done), unit="run", disable=not progress,
               file=sys.stderr, mininterval=1.0, desc=f"{settings['param']} sweep")
    warm_s = 0.0
    try:
        if todo and warm:   # load the compiled kernels before the timed runs
            t = time.perf_counter()
            if client is None:
                warm_up(settings, todo[0])
            else:
                client.run(warm_up, settings, todo[0])
            warm_s = time.perf_counter() - t
        t_runs = time.perf_counter()
        finished = (task(settings, v) for v in todo) if client is None else \
            on_cluster(client, task, settings, todo, lost)
        for r in finished:
            if r["timing"]["pid"] is not None:    # a lost value is not saved: retried later
                save_run(out, r)
            done[r["value"]] = r
            bar.update(1)
        runs_s = time.perf_counter() - t_runs
    finally:
        bar.close()
    results = [done[v] for v in values]
    timing = {"values_run": len(todo), "values_lost": sum(
        done[v]["timing"]["pid"] is None for v in todo), "values_resumed": len(values) - len(todo),
              "warm_up_s": warm_s, "runs_wall_s": runs_s, "total_wall_s": time.perf_counter() - t0,
              "runs_per_s": len(todo) / runs_s if todo and runs_s > 0 else None,
              "workers": 0 if client is None else len(client.nthreads()),
              "task_s_sum": sum(done[v]["timing"]["task_s"] for v in todo),
              "task_cpu_s_sum": sum(done[v]["timing"]["task_cpu_s"] for v in todo)}
    return results, timing


# ---------------------------------------------------------------- command line

def parser():
    p = cli.Parser(prog="skfem_beam.sweep", description=__doc__.splitlines()[0],
                   formatter_class=cli.Defaults)
    p.add_argument("--scene", default="point_stops", help=" | ".join(SCENES))
    p.add_argument("--param", default="omega", help="the swept parameter: "
                   + " | ".join(SCENES["point_stops"][1]))
    p.add_argument("--values", required=True, default=argparse.SUPPRESS,
                   help="'linspace(a, b, n)' (n values from a to b inclusive) or v1,v2,...")
    p.add_argument("--transient", type=float, default=SETTINGS["transient"],
                   help="seconds skipped before sampling (rounded up to whole periods)")
    p.add_argument("--periods", type=int, default=SETTINGS["periods"],
                   help="forcing periods sampled")
    p.add_argument("--dt", type=float, default=SETTINGS["dt"],
                   help="target time step (s); the period is a whole number of steps")
    p.add_argument("--J", type=int, default=SETTINGS["J"], help="number of elements")
    p.add_argument("--beta", type=float, default=SETTINGS["beta"], help="Newmark β in [0, 1/2]")
    p.add_argument("--element", default=SETTINGS["element"], help="hermite | bspline")
    p.add_argument("--solver", default=SETTINGS["solver"], help="contact solver")
    p.add_argument("--zeta", type=float, default=SETTINGS["zeta"],
                   help="damping ratio (e.g. 0.02), Rayleigh, at the beam's first two natural "
                        "frequencies; 0: undamped, as the papers")
    for name, default in scene_defaults("point_stops").items():
        p.add_argument(f"--{name}", type=float, default=argparse.SUPPRESS,
                       help=f"fixed value of {name} when not swept (default {default:g})")
    p.add_argument("--workers", type=int, default=argparse.SUPPRESS,
                   help="local Dask worker processes (default: one per core; without "
                        "Dask installed, none; at most 4 a core, and no more than the "
                        "values); 0 = no Dask")
    p.add_argument("--scheduler", default=argparse.SUPPRESS,
                   help="address of an existing Dask scheduler, e.g. tcp://10.0.0.5:8786")
    p.add_argument("--out", default="out/sweep", help="output folder (resumed if it exists)")
    p.add_argument("--overwrite", action="store_true", help="start over in --out")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    return p


def _workers(workers: int | None, scheduler: str | None, values: int) -> int:
    """The local Dask workers: --workers (default one a core; none without Dask), at most
    WORKERS_PER_CORE a core and no more than the values."""
    if scheduler and workers is not None:
        raise InputError("give either --workers or --scheduler, not both")
    if workers is None and not scheduler and importlib.util.find_spec("distributed") is None:
        print("note: Dask is not installed (pip install \"skfem_beam[cluster]\" for one "
              "worker per core): the values run one after the other", file=sys.stderr)
        workers = 0
    cores = os.cpu_count() or 1
    workers = cores if workers is None else workers
    if workers < 0:
        raise InputError(f"--workers {workers} must be ≥ 0")
    if workers > WORKERS_PER_CORE * cores:      # each a process: 1000 exhausted the memory
        raise InputError(f"--workers {workers} on {cores} cores: at most "
                         f"{WORKERS_PER_CORE * cores} (the default is one a core)")
    return min(workers, values)                 # one value each at most: no idle process


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    fixed = {n: getattr(args, n) for n in SCENES["point_stops"][1] if hasattr(args, n)}
    if args.param in fixed:     # it was ignored (and recorded in the summary's config)
        raise InputError(f"--{args.param} {fixed[args.param]:g} is the swept parameter's "
                         f"value: --values gives them (--{args.param} fixes it when another "
                         "is swept)")
    settings = make_settings(args.scene, args.param,
                             **{k: getattr(args, k) for k in SETTINGS}, **fixed)
    values = parse_values(args.values)
    check_values(settings, values)
    charts_wanted()         # a bad SKFEM_BEAM_CHARTS: one line before any folder
    scheduler = getattr(args, "scheduler", None)
    workers = _workers(getattr(args, "workers", None), scheduler, len(values))
    out = check_out(args.out, args.overwrite)
    progress = not args.no_progress
    serial = (scheduler is None and workers == 0) or not args.overwrite and all(
        run_path(out, settings["param"], v).exists() for v in values)   # nothing left to run
    resume = not args.overwrite and (out / "runs").is_dir()
    stored = stored_settings(out) if resume else None
    if stored is not None:  # its runs are named by their parameter: others' would mix in
        same_settings(out, stored, settings)
    try:
        with contextlib.nullcontext() if serial else dask_client(workers, scheduler) as client:
            with Folder.open(out, {"case": "sweep", "settings": settings,
                                   "config": {k: v for k, v in vars(args).items()}},
                             args.overwrite, resume) as folder:
                (out / "runs").mkdir(exist_ok=True)
                results, timing = run_values(settings, values, out, client, progress)
                with Signals() as held:     # every value done: the files are completed
                    summary = folder.close(sweep_status(results), **assemble(
                        out, settings, results, {"timing": timing}))
    except KeyboardInterrupt as e:     # SIGINT, or SIGTERM (main_guard)
        n = sum(run_path(out, settings["param"], v).exists() for v in values)
        print(f"interrupted: {n} of {len(values)} values done in {out / 'runs'}; "
              "run the same command again to resume", file=sys.stderr)
        return getattr(e, "code", 130)
    if held.signum is not None:
        print(f"interrupted after its last value: every file of {out} is complete",
              file=sys.stderr)
        return 128 + held.signum
    tm = summary["timing"]
    failed, lost_ = summary["failed"], tm["values_lost"]
    rate = f", {tm['runs_per_s']:.3g} runs/s" if tm["runs_per_s"] else ""
    why = (f" ({lost_} lost with their workers: run the same command again to retry them)"
           if lost_ else " (failed or unstable: status column of runs.csv)" if failed else "")
    print(f"{len(values)} values: {len(values) - failed} done, {failed} failed{why}; "
          f"{tm['values_run']} run, {tm['values_resumed']} resumed in "
          f"{tm['total_wall_s']:.3g} s{rate} -> {out}", file=sys.stderr if failed else sys.stdout)
    if summary["status"] != "success":      # no value ran through: as a single run's
        return EXIT_UNSTABLE if summary["status"] == "unstable" else EXIT_SOLVER
    return EXIT_SOLVER if lost_ else 0


def sweep_status(results) -> str:
    """The sweep's status: "success" when some value ran through, else "unstable" (every
    one went unstable: it had said success, exit 0) or "failed"."""
    statuses = {r["status"] for r in results}
    return "success" if "success" in statuses or not statuses else \
        "unstable" if statuses == {"unstable"} else "failed"


if __name__ == "__main__":
    cli.main_guard(main)
