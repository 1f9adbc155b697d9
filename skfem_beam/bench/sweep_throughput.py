"""Sweep throughput (runs per second) serially and on local Dask clusters; overhead per task.

    python -m skfem_beam.bench.sweep_throughput [--values "linspace(8, 30, 16)"] [--periods 10]
        [--transient 0.5] [--workers 1,2] [--out sweep_throughput.json]

Every configuration runs the same sweep (``skfem_beam.sweep.sweep``, per-value files
included) ``--repeat`` times, each into a fresh temporary folder, and keeps the fastest;
its processes load the compiled kernels first (the warm-up and the cluster start are
reported apart: they are paid once per sweep, not per value).  Overhead per task is measured two ways:

* ``vs serial``: (wall with 1 Dask worker − wall of the serial loop) / values;
* ``idle``: (wall × workers − Σ task time measured inside the tasks) / values, i.e. the
  time per value a worker was not computing (scheduling, transfer, the client writing
  files, and waiting at the end for the last value);

plus the round trip of an empty task (``client.map`` of 200 no-ops) on the same cluster.
The machine may be shared: ``os.getloadavg()`` before and after each configuration is
reported, and timings on a busy machine are noisy.  Σcpu (CPU time of the tasks' own
processes) beside Σtask (their wall time) shows it: when they differ, the workers were
waiting for a core.
"""
from __future__ import annotations

import argparse
import contextlib
import json
import os
import tempfile
import time


def _noop(i):
    return i


def _load():
    return [round(x, 2) for x in os.getloadavg()]


def measure(settings, values, workers: int, repeat: int) -> dict:
    """One configuration, best of ``repeat`` sweeps: 0 = serial loop in this process,
    N = a local cluster of N workers (started once, warmed up by the first sweep)."""
    from ..sweep import sweep
    from ..sweep_cluster import dask_client
    row = {"workers": workers, "load_before": _load()}
    with contextlib.ExitStack() as stack:
        client = None
        if workers:
            t0 = time.perf_counter()
            client = stack.enter_context(dask_client(workers))
            row["cluster_start_s"] = time.perf_counter() - t0
        best = None
        for i in range(repeat):
            with tempfile.TemporaryDirectory() as tmp:
                tm = sweep(settings, values, tmp, client, progress=False)["timing"]
            if i == 0:
                row["warm_up_s"] = tm["warm_up_s"]
            if best is None or tm["runs_wall_s"] < best["runs_wall_s"]:
                best = tm
        if client is not None:
            t0 = time.perf_counter()
            for f in client.map(_noop, range(200), pure=False):
                f.result()
            row["empty_task_round_trip_ms"] = 1e3 * (time.perf_counter() - t0) / 200
    row.update(wall_s=best["runs_wall_s"], runs_per_s=best["runs_per_s"],
               task_s_sum=best["task_s_sum"], task_cpu_s_sum=best["task_cpu_s_sum"],
               idle_per_task_ms=1e3 * (best["runs_wall_s"] * max(1, workers)
                                       - best["task_s_sum"]) / len(values),
               load_after=_load())
    return row


def main(argv=None) -> int:
    from ..sweep import make_settings, parse_values
    ap = argparse.ArgumentParser(prog="skfem_beam.bench.sweep_throughput",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--values", default="linspace(8, 30, 16)", help="ω values, linspace(a, b, n)")
    ap.add_argument("--transient", type=float, default=0.5)
    ap.add_argument("--periods", type=int, default=10)
    ap.add_argument("--workers", default="1,2", help="Dask worker counts to measure")
    ap.add_argument("--repeat", type=int, default=3, help="best of this many sweeps")
    ap.add_argument("--out", default="sweep_throughput.json")
    args = ap.parse_args(argv)
    settings = make_settings("point_stops", "omega", transient=args.transient,
                             periods=args.periods)
    values = parse_values(args.values)
    rows = [measure(settings, values, 0, args.repeat)]
    for n in (int(w) for w in args.workers.split(",")):
        rows.append(measure(settings, values, n, args.repeat))
    serial = rows[0]["wall_s"]
    for r in rows[1:]:
        r["speedup_vs_serial"] = serial / r["wall_s"]
        if r["workers"] == 1:
            r["overhead_vs_serial_per_task_ms"] = 1e3 * (r["wall_s"] - serial) / len(values)
    print(f"{len(values)} values of ω in [{values[0]:g}, {values[-1]:g}], {args.periods} periods "
          f"after {args.transient:g} s, J=19, dt≈5e-5 s; best of {args.repeat}; "
          f"{os.cpu_count()} cores")
    print(f"{'config':>10} {'runs/s':>8} {'wall s':>8} {'Σtask s':>8} {'Σcpu s':>7} "
          f"{'idle ms/task':>13} "
          f"{'vs serial':>10} {'empty task':>11} {'warm-up s':>10} {'start s':>8}  load")
    for r in rows:
        name = "serial" if r["workers"] == 0 else f"dask×{r['workers']}"
        vs = r.get("overhead_vs_serial_per_task_ms")
        vs = "" if vs is None else f"{vs:+.3g} ms"
        empty = f"{r['empty_task_round_trip_ms']:.3g} ms" if r["workers"] else ""
        print(f"{name:>10} {r['runs_per_s']:8.3g} {r['wall_s']:8.3g} {r['task_s_sum']:8.3g} "
              f"{r['task_cpu_s_sum']:7.3g} "
              f"{r['idle_per_task_ms']:13.3g} {vs:>10} {empty:>11} "
              f"{r['warm_up_s']:10.3g} {r.get('cluster_start_s', 0):8.3g}  "
              f"{r['load_before'][0]}→{r['load_after'][0]}")
    with open(args.out, "w") as fh:
        json.dump({"values": values, "settings": settings, "cores": os.cpu_count(),
                   "repeat": args.repeat,
                   "rows": rows}, fh, indent=2)
        fh.write("\n")
    print(f"-> {args.out}")
    return 0


if __name__ == "__main__":
    from ..cli import main_guard
    main_guard(main)
