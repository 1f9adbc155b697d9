"""Cold start of the README's main job: the first run of a fresh install against a warm one.

    python -m skfem_beam.bench.cold_compile [--repeat 3] [--job skfem_beam.cases.flat_obstacles]
                                            [--against OTHER_CHECKOUT/skfem_beam]
    python -m skfem_beam.bench.cold_compile --scene NAME.toml [--scene ...] | --scenes

``--scene`` measures ``python -m skfem_beam run NAME.toml`` instead of a job (a shipped
scene by file name, or a path); ``--scenes`` every shipped scene file in turn, then a table
(with ``--against``, a row per scene and checkout).

Each repeat copies the package's sources to a fresh temporary folder and byte-compiles them,
as ``pip install`` does, so that no numba cache exists, and runs ``python -m JOB`` there
twice in child processes, exactly as a user types it (cold, then warm): their wall times
against the target (cold ≤ 6 s), their difference (the compile a first run pays) and the
time loop beside them.  Then, unless ``--no-attribute``, a second fresh copy runs the job
cold once more in a child that registers a ``numba:compile`` listener and times the law's C
callbacks (``CFunc.compile``), so the compile time is attributed per function: ``self``
excludes the functions compiled inside it (callees that are not inlined), ``total``
includes them; what is compiled aside in a child process (a fresh install on two cores or
more, see skfem_beam.aside) is not listed: ``--one-core`` lists it.  That child calls the job's
``main`` (not ``python -m``), so it draws its charts itself: its times are not the
command's.  The per-function times are CPU seconds, which a busy shared machine disturbs
less than wall time.  ``--against`` another checkout's ``skfem_beam`` folder: each repeat
runs both, in alternating order (this VM's speed drifts by ±30 % within minutes), and the
medians of both are printed.
"""
from __future__ import annotations

import argparse
import compileall
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1]
COLD_TARGET = 6.0   # seconds: the main job's first run after an install, on 2 cores
WARM_TARGET = 1.5   # seconds: its later runs


def _listen() -> list:
    """Records (name, start, end, depth) of every compile in this process."""
    from numba.core import ccallback, event

    records, stack = [], []

    class Timer(event.Listener):
        def on_start(self, ev):
            stack.append(time.process_time())

        def on_end(self, ev):
            t0 = stack.pop()
            d = ev.data or {}
            disp = d.get("dispatcher")
            name = getattr(getattr(disp, "py_func", None), "__qualname__", str(disp))
            records.append((name, t0, time.process_time(), len(stack),
                            str(d.get("args", ""))))

    event.register("numba:compile", Timer())
    original = ccallback.CFunc.compile

    def timed(self):      # C callbacks (the laws) do not send a numba:compile event
        stack.append(time.process_time())
        try:
            original(self)
        finally:
            t0 = stack.pop()
            records.append((f"cfunc {self.__name__}", t0, time.process_time(), len(stack), ""))

    ccallback.CFunc.compile = timed
    return records


def _argv(job: str) -> list:
    """The command's arguments after ``python``: ``-m job``, or ``-m skfem_beam run FILE``
    for a scene file (a job ending in .toml)."""
    return ["-m", "skfem_beam", "run", job] if job.endswith(".toml") else ["-m", job]


def _main_of(job: str):
    """The function ``python -m job`` (or ``skfem_beam run`` for a scene file) calls."""
    import importlib
    if job.endswith(".toml"):
        from skfem_beam.__main__ import COMMANDS
        module, name = COMMANDS["run"].target.split(":")
        return lambda argv: getattr(importlib.import_module(module), name)([job, *argv])
    return importlib.import_module(job).main


def _child(job: str, out: str, threshold: str) -> None:
    """Runs the job (_argv) with ``--out out`` in this process with the compile listener,
    its garbage collected at ``threshold`` (a command's: "n0,n1,n2")."""
    import gc
    gc.set_threshold(*map(int, threshold.split(",")))
    records = _listen()
    t0 = time.process_time()
    code = _main_of(job)(["--out", out, "--overwrite"])
    cpu = time.process_time() - t0
    rows = []
    for i, (name, a, b, depth, args) in enumerate(records):
        inner = sum(b2 - a2 for (_, a2, b2, d2, _) in records
                    if d2 == depth + 1 and a <= a2 and b2 <= b)
        rows.append({"name": name, "total_s": b - a, "self_s": b - a - inner, "depth": depth,
                     "args": args})
    print(json.dumps({"code": code, "cpu_s": cpu, "compiles": rows}))


def _run(folder: Path, job: str, listen: bool, one_core: bool) -> tuple[float, float, dict]:
    out = folder / "out"
    from skfem_beam._startup import GC_THRESHOLD, NUMBA_OPT
    # the listener runs from this file, so that an older checkout can be measured too; it
    # calls main(), so it compiles at the level and collects garbage as a command does
    argv = ([sys.executable, str(Path(__file__).resolve()), "--child", job, str(out),
             ",".join(map(str, GC_THRESHOLD))]
            if listen else [sys.executable, *_argv(job), "--out", str(out), "--overwrite"])
    before, t0 = resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
    # one core: the run compiles its law itself (not aside), so every compile is listed
    pin = (lambda: os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})) if one_core else None
    env = {**_env(), "PYTHONPATH": str(folder)}
    if listen:
        env.setdefault("NUMBA_OPT", NUMBA_OPT)
    p = subprocess.run(argv, cwd=folder, env=env,
                       capture_output=True, text=True, check=True, preexec_fn=pin)
    wall, after = time.perf_counter() - t0, resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    info = json.loads(p.stdout.strip().splitlines()[-1]) if listen else {}
    info["stderr"] = p.stderr
    info["loop_s"] = json.loads((out / "summary.json").read_text())["wall_time_s"]
    return cpu, wall, info


def _fresh(tmp: str, package: str) -> Path:
    """A copy of the package's sources in ``tmp`` as ``pip install`` leaves it: byte-compiled
    (pip's default), no numba cache."""
    shutil.copytree(package, Path(tmp) / "skfem_beam",
                    ignore=shutil.ignore_patterns("__pycache__"))
    compileall.compile_dir(Path(tmp) / "skfem_beam", quiet=1)
    return Path(tmp)


def _listened(package: str, job: str, one_core: bool) -> None:
    """The job cold in a listener run (_child), and its compile times per function."""
    with tempfile.TemporaryDirectory() as tmp:
        _, listened, info = _run(_fresh(tmp, package), job, True, one_core)
    print(f"  listener run (it draws its charts itself): wall {listened:.2f} s")
    _attribution(info)


def _attribution(info: dict) -> None:
    by = {}
    for c in info["compiles"]:
        by.setdefault(c["name"], [0.0, 0.0, 0])
        by[c["name"]][0] += c["self_s"]
        by[c["name"]][1] += c["total_s"] if c["depth"] == 0 else 0.0
        by[c["name"]][2] += 1
    top = sum(c["total_s"] for c in info["compiles"] if c["depth"] == 0)
    print(f"  {'function (listener run)':40s} {'self s':>7s} {'top-level s':>11s} "
          f"{'compiles':>8s}   (top-level total {top:.2f} s)")
    for name, (s, t, k) in sorted(by.items(), key=lambda kv: -kv[1][0]):
        if s >= 0.05:
            print(f"  {name:40s} {s:7.2f} {t:11.2f} {k:8d}")


def _cold_then_warm(package: str, job: str, one_core: bool) -> tuple:
    """A fresh copy of ``package`` runs the job cold, then warm: both wall times, both CPU
    times and a line."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = _fresh(tmp, package)
        cold, cold_wall, info = _run(folder, job, False, one_core)
        warm, warm_wall, again = _run(folder, job, False, one_core)
    met = "yes" if cold_wall <= COLD_TARGET else "NO"
    notice = "compiling numerical kernels"
    return cold_wall, warm_wall, cold, warm, (
        f"python {' '.join(_argv(job))}: wall cold {cold_wall:.2f} s (≤ {COLD_TARGET:g} s: {met}), warm "
        f"{warm_wall:.2f} s, compile {cold_wall - warm_wall:.2f} s; CPU cold {cold:.2f} s, warm "
        f"{warm:.2f} s; its loop {info['loop_s']:.4f} s (cold {cold_wall / info['loop_s']:.0f}×, "
        f"warm {warm_wall / again['loop_s']:.0f}× the loop); notice: cold "
        f"{info['stderr'].count(notice)}, warm {again['stderr'].count(notice)}")


def _scene_path(name: str) -> str:
    """A shipped scene by file name, or a path (absolute: the runs' folder is a temporary
    one)."""
    found = sorted((PACKAGE / "scene_files").glob(f"**/{name}"))   # plates/ too
    shipped = found[0] if found else PACKAGE / "scene_files" / name
    path = shipped if shipped.exists() and not Path(name).exists() else Path(name)
    if not path.exists():
        names = sorted(p.name for p in (PACKAGE / "scene_files").glob("**/*.toml"))
        raise SystemExit(f"--scene {name}: no such file (shipped: {', '.join(names)})")
    return str(path.resolve())


def _scenes(args, paths: list) -> int:
    """Each scene cold then warm, ``--repeat`` times (with ``--against``: both checkouts,
    in alternating order), then one row each (and checkout): the medians."""
    packages = [args.package] + ([args.against] if args.against else [])
    rows = []
    for path in paths:
        runs = {p: [] for p in packages}
        for r in range(args.repeat):
            for package in packages if r % 2 == 0 else packages[::-1]:   # alternated: drift
                runs[package].append(_cold_then_warm(package, path, args.one_core))
                label = f" ({package})" if args.against else ""
                print(f"run {r + 1}{label}: {runs[package][-1][-1]}", flush=True)
        if not args.no_attribute:
            _listened(args.package, path, args.one_core)
        for i, package in enumerate(packages):
            name = Path(path).name + (f" [{i + 1}]" if args.against else "")
            rows.append((name, *(statistics.median(r[k] for r in runs[package])
                                 for k in range(4))))
    if args.against:
        print("\n" + "\n".join(f"[{i + 1}] {p}" for i, p in enumerate(packages)))
    print(f"\n{'scene file':34s} {'cold s':>7s} {'warm s':>7s} {'CPU cold':>9s} {'CPU warm':>9s}"
          f"   (wall and CPU, medians of {args.repeat}; targets: cold ≤ {COLD_TARGET:g} s, warm "
          f"≤ {WARM_TARGET:g} s)")
    for name, cold, warm, cpu_cold, cpu_warm in rows:
        print(f"{name:34s} {cold:7.2f} {warm:7.2f} {cpu_cold:9.2f} {cpu_warm:9.2f}   "
              f"{'yes' if cold <= COLD_TARGET else 'NO':>3s} "
              f"{'yes' if warm <= WARM_TARGET else 'NO':>3s}")
    return 0


def _env() -> dict:
    return {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_CACHE_DIR")}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="skfem_beam.bench.cold_compile",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--job", default="skfem_beam.cases.flat_obstacles")
    ap.add_argument("--scene", action="append", default=[], metavar="FILE",
                    help="a scene file (a shipped one by name) run by `python -m skfem_beam "
                         "run`, instead of --job (repeatable)")
    ap.add_argument("--scenes", action="store_true", help="every shipped scene file")
    ap.add_argument("--package", default=str(PACKAGE),
                    help="the skfem_beam folder to copy (another checkout, to compare)")
    ap.add_argument("--against", metavar="FOLDER",
                    help="another skfem_beam folder (an older checkout's): each repeat runs "
                         "both, in alternating order, and the medians are printed")
    ap.add_argument("--one-core", action="store_true",
                    help="pin the runs to one core: the law compiles in the run itself, so the "
                         "table lists it (by default it compiles in a child process, unlisted)")
    ap.add_argument("--no-attribute", action="store_true",
                    help="no listener run: only the command's cold and warm wall times")
    ap.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        _child(*args.child)
        return 0
    scenes = sorted(str(p) for p in (PACKAGE / "scene_files").glob("**/*.toml")) \
        if args.scenes else args.scene
    if scenes:
        return _scenes(args, [_scene_path(s) for s in scenes])
    packages = [args.package] + ([args.against] if args.against else [])
    walls = {p: [] for p in packages}
    for r in range(args.repeat):
        for package in packages if r % 2 == 0 else packages[::-1]:   # alternated: drift
            walls[package].append(_cold_then_warm(package, args.job, args.one_core))
            label = f" ({package})" if args.against else ""
            print(f"run {r + 1}{label}: {walls[package][-1][-1]}", flush=True)
        if not args.no_attribute:
            _listened(args.package, args.job, args.one_core)
    if args.against:
        for package, runs in walls.items():
            print(f"{package}: median cold {statistics.median(r[0] for r in runs):.2f} s, warm "
                  f"{statistics.median(r[1] for r in runs):.2f} s over {len(runs)} runs")
    return 0


if __name__ == "__main__":
    # absolute: the listener child runs this file by its path, outside the package
    from skfem_beam.cli import main_guard
    main_guard(main)
