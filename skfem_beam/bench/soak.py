"""Soak: runs killed at random instants, resumed until done, checked against an
uninterrupted run.

    python -m skfem_beam.bench.soak --cycles 1000 [--out DIR] [--seed 0]

Each cycle starts `point_stops` (Δt = 2e-6, T = 0.4, saved every 10th step, XDMF
fields, a checkpoint every 0.2 s) and stops it one way: SIGKILL, SIGINT or SIGTERM at a
random instant, or SIGKILL at a named boundary of the run's end (the test hook
``SKFEM_BEAM_KILL_AT``, output.series.PHASES).  Then `--resume` until the folder says
"success"; each resume runs under a timeout (a hang is counted, never waited for) and is
itself killed at a random instant with probability 1/3.  The finished folder's
timeseries.csv and impacts.csv must equal the uninterrupted run's byte for byte, and its
fields.h5 datasets value for value.  A folder a resume refuses (exit 2) is "stuck".
Prints one table row per kind of stop and the totals; exits 1 on any hang, stuck folder
or difference.
"""
from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

RUN = ["-m", "skfem_beam.cases.point_stops", "--dt", "2e-6", "--T", "0.4", "--save-every",
       "10", "--format", "xdmf", "--frames", "20", "--flush-every", "20000",
       "--checkpoint-every", "0.2"]
PHASES = ("last-chunk", "final-checkpoint", "charts", "impacts", "summary")
KINDS = ("SIGKILL", "SIGINT", "SIGTERM", "phase")
TIMEOUT = 120.0          # s: a resume longer than this is a hang


def start(args: list, env: dict | None = None) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, *args], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, env=env)


def killed_at_random(p: subprocess.Popen, rng: random.Random, sig, within: float) -> None:
    """Send ``sig`` after a random delay (unless the process ended first); wait for it."""
    deadline = time.monotonic() + rng.uniform(0.0, within)
    while time.monotonic() < deadline and p.poll() is None:
        time.sleep(0.005)
    if p.poll() is None:
        p.send_signal(sig)
    p.wait(timeout=TIMEOUT)


def status(folder: Path) -> str | None:
    try:
        return json.loads((folder / "summary.json").read_text())["status"]
    except (OSError, ValueError, KeyError):
        return None


def datasets(path: Path) -> dict:
    import h5py
    found = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: found.update({name: obj[()].tobytes()})
                     if isinstance(obj, h5py.Dataset) else None)
    return found


def same_files(a: Path, b: Path) -> bool:
    return all((a / n).read_bytes() == (b / n).read_bytes()
               for n in ("timeseries.csv", "impacts.csv")) \
        and datasets(a / "fields.h5") == datasets(b / "fields.h5")


def resume_until_done(folder: Path, rng: random.Random, tally: Counter) -> str:
    """Resume (sometimes killing the resume too) until success: "done", "hang", "stuck"."""
    for _ in range(20):
        if status(folder) == "success":
            return "done"
        p = start(RUN[:2] + ["--resume", str(folder)])
        try:
            if rng.random() < 1 / 3:
                tally["resume killed"] += 1
                killed_at_random(p, rng, rng.choice((signal.SIGKILL, signal.SIGTERM)), 3.0)
            else:
                p.wait(timeout=TIMEOUT)
        except subprocess.TimeoutExpired:
            p.kill()
            return "hang"
        if p.returncode == 2:
            return "stuck"
        tally["resumes"] += 1
    return "hang"


def cycle(ref: Path, work: Path, rng: random.Random, tally: Counter) -> tuple[str, str]:
    """One run stopped one way and resumed to the end: (kind, outcome)."""
    folder = work / "run"
    shutil.rmtree(folder, ignore_errors=True)
    kind = rng.choice(KINDS)
    args = RUN + ["--out", str(folder)]
    if kind == "phase":
        env = {**os.environ, "SKFEM_BEAM_KILL_AT": rng.choice(PHASES)}
        start(args, env).wait(timeout=TIMEOUT)
    else:
        killed_at_random(start(args), rng, getattr(signal, kind), 6.0)
    if not (folder / "checkpoint.npz").exists():   # stopped before its first checkpoint
        return kind, "no checkpoint"
    outcome = resume_until_done(folder, rng, tally)
    if outcome == "done" and not same_files(folder, ref):
        outcome = "different"
    return kind, outcome


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="skfem_beam.bench.soak", description=__doc__)
    ap.add_argument("--cycles", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=None, help="write the table as DIR/soak.json too")
    args = ap.parse_args(argv)
    rng, tally, rows = random.Random(args.seed), Counter(), Counter()
    t0 = time.monotonic()
    with tempfile.TemporaryDirectory() as tmp:
        ref = Path(tmp) / "ref"
        subprocess.run([sys.executable, *RUN, "--out", str(ref)], check=True,
                       capture_output=True)
        for i in range(args.cycles):
            rows[cycle(ref, Path(tmp), rng, tally)] += 1
            if (i + 1) % 50 == 0:      # a long soak shows where it is
                print(f"{i + 1} cycles: {dict(rows)}", file=sys.stderr, flush=True)
    bad = sum(n for (kind, outcome), n in rows.items()
              if outcome in ("hang", "stuck", "different"))
    print(f"{'stop':8s} {'outcome':14s} {'cycles':>7s}")
    for (kind, outcome), n in sorted(rows.items()):
        print(f"{kind:8s} {outcome:14s} {n:7d}")
    print(f"{args.cycles} cycles in {time.monotonic() - t0:.0f} s, {tally['resumes']} resumes "
          f"({tally['resume killed']} of them killed); hangs, stuck folders, differences: "
          f"{bad}")
    if args.out:
        Path(args.out).mkdir(parents=True, exist_ok=True)
        (Path(args.out) / "soak.json").write_text(json.dumps(
            {"cycles": args.cycles, "seed": args.seed, "rows": [[k, o, n] for (k, o), n
                                                                 in sorted(rows.items())],
             **tally, "bad": bad}, indent=1))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
