"""Soak: runs killed at random instants, resumed until done, checked against an
uninterrupted run.

    python -m skfem_beam.bench.soak --cycles 1000 [--out DIR] [--seed 0] [--only KIND]

Each cycle starts `point_stops` (Δt = 2e-6, T = 0.4, saved every 10th step, XDMF
fields, a checkpoint every 0.2 s) and stops it one way: SIGKILL, SIGINT or SIGTERM at a
random instant, SIGKILL at a named boundary of the run's end (the test hook
``SKFEM_BEAM_KILL_AT``, output.stream.PHASES), or a nearly full filesystem (as root: a
tmpfs holding 55–100 % of what the run writes; the run must exit 3, then a resume with a
little more room, which may fill it again, then room enough).  Then `--resume` until
the folder says "success"; each resume runs under a timeout (a hang is counted, never waited for) and is
itself killed at a random instant with probability 1/3.  The finished folder's
timeseries.csv and impacts.csv must equal the uninterrupted run's byte for byte, and its
fields.h5 datasets value for value.  A folder a resume refuses (exit 2) is "stuck"; a
run or resume that ends any other way than ENDINGS or by SIGKILL has "crashed".
Prints one table row per kind of stop and the totals; exits 1 on any hang, stuck folder
or difference.
"""
from __future__ import annotations

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

from ..parser import Parser, count

RUN = ["-m", "skfem_beam.cases.point_stops", "--dt", "2e-6", "--T", "0.4", "--save-every",
       "10", "--format", "xdmf", "--frames", "20", "--flush-every", "20000",
       "--checkpoint-every", "0.2"]
# the full-disk cycles checkpoint every chunk (20,000 steps): the whole run takes less than
# the 0.2 s of wall time between checkpoints, and a full disk stops it before its end
FULL_DISK_RUN = RUN[:-1] + ["0"]
PHASES = ("last-chunk", "final-checkpoint", "charts", "impacts", "summary")
KINDS = ("SIGKILL", "SIGINT", "SIGTERM", "phase", "full disk")
BAD = ("hang", "stuck", "different", "crashed")
ENDINGS = (0, 3, 130, 143)  # success, a failed write, SIGINT, SIGTERM (README's exit codes)
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
        if p.returncode not in ENDINGS and p.returncode >= 0:
            return "crashed"
        tally["resumes"] += 1
    return "hang"


def mount(disk: Path, kb: int, remount: bool = False) -> bool:
    opts = (f"remount,size={kb}k" if remount else f"size={kb}k")
    args = ["mount", "-o", opts, str(disk)] if remount else \
        ["mount", "-t", "tmpfs", "-o", opts, "tmpfs", str(disk)]
    return subprocess.run(args, capture_output=True).returncode == 0


def can_mount(work: Path) -> bool:
    """Root with tmpfs: the full-disk cycles can run."""
    disk = work / "probe"
    disk.mkdir(exist_ok=True)
    ok = os.geteuid() == 0 and mount(disk, 64)
    if ok:
        subprocess.run(["umount", "-l", str(disk)], capture_output=True)
    return ok


def full_disk_cycle(ref: Path, work: Path, rng: random.Random, tally: Counter) -> str:
    """The run on a tmpfs too small for it (exit 3 expected), one resume with a little more
    room (it may fill it again), then room enough and `resume_until_done`."""
    need = sum(f.stat().st_size for f in ref.iterdir()) // 1024 \
        + 2 * (ref / "checkpoint.npz").stat().st_size // 1024 + 512
    disk = work / "disk"
    disk.mkdir(exist_ok=True)
    kb = int(need * rng.uniform(0.55, 1.0))
    if not mount(disk, kb):
        raise RuntimeError(f"cannot mount a tmpfs at {disk}")
    try:
        folder = disk / "run"
        p = start(FULL_DISK_RUN + ["--out", str(folder)])
        p.wait(timeout=TIMEOUT)
        if p.returncode not in (0, 3):
            return "crashed"
        tally["disk full" if p.returncode == 3 else "fitted"] += 1
        if p.returncode == 0:           # it fitted: finished, nothing to resume
            return "done" if same_files(folder, ref) else "different"
        if not (folder / "checkpoint.npz").exists():
            return "no checkpoint"
        mount(disk, kb + int((need - kb) * rng.uniform(0.0, 0.5)), remount=True)
        p = start(RUN[:2] + ["--resume", str(folder)])
        p.wait(timeout=TIMEOUT)
        if p.returncode == 2:
            return "stuck"
        if p.returncode not in (0, 3):
            return "crashed"
        mount(disk, 2 * need, remount=True)
        outcome = resume_until_done(folder, rng, tally)
        if outcome == "done" and not same_files(folder, ref):
            outcome = "different"
        return outcome
    except subprocess.TimeoutExpired:
        return "hang"
    finally:
        subprocess.run(["umount", "-l", str(disk)], capture_output=True)


def cycle(ref: Path, work: Path, rng: random.Random, tally: Counter,
          kinds=KINDS) -> tuple[str, str]:
    """One run stopped one way and resumed to the end: (kind, outcome)."""
    folder = work / "run"
    shutil.rmtree(folder, ignore_errors=True)
    kind = rng.choice(kinds)
    if kind == "full disk":
        return kind, full_disk_cycle(ref, work, rng, tally)
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
    ap = Parser(prog="skfem_beam.bench.soak", description=__doc__)
    ap.add_argument("--cycles", type=count, default=20)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=None, help="write the table as DIR/soak.json too")
    ap.add_argument("--only", choices=KINDS, default=None, help="one kind of stop only")
    args = ap.parse_args(argv)
    rng, tally, rows = random.Random(args.seed), Counter(), Counter()
    t0 = time.monotonic()
    with tempfile.TemporaryDirectory() as tmp:
        ref = Path(tmp) / "ref"
        subprocess.run([sys.executable, *RUN, "--out", str(ref)], check=True,
                       capture_output=True)
        kinds = KINDS if can_mount(Path(tmp)) else KINDS[:-1]
        if len(kinds) < len(KINDS):
            print("not root (or no tmpfs): no full-disk cycles", file=sys.stderr)
        if args.only is not None:
            if args.only not in kinds:
                print(f"--only {args.only!r}: not possible here", file=sys.stderr)
                return 2
            kinds = (args.only,)
        for i in range(args.cycles):
            rows[cycle(ref, Path(tmp), rng, tally, kinds)] += 1
            if (i + 1) % 50 == 0:      # a long soak shows where it is
                print(f"{i + 1} cycles: {dict(rows)}", file=sys.stderr, flush=True)
    bad = sum(n for (kind, outcome), n in rows.items() if outcome in BAD)
    print(f"{'stop':10s} {'outcome':14s} {'cycles':>7s}")
    for (kind, outcome), n in sorted(rows.items()):
        print(f"{kind:10s} {outcome:14s} {n:7d}")
    print(f"{args.cycles} cycles in {time.monotonic() - t0:.0f} s, {tally['resumes']} resumes "
          f"({tally['resume killed']} of them killed); full-disk runs: {tally['disk full']} "
          f"exited 3, {tally['fitted']} fitted; hangs, stuck folders, differences, crashes: "
          f"{bad}")
    if args.out:
        Path(args.out).mkdir(parents=True, exist_ok=True)
        (Path(args.out) / "soak.json").write_text(json.dumps(
            {"cycles": args.cycles, "seed": args.seed, "rows": [[k, o, n] for (k, o), n
                                                                 in sorted(rows.items())],
             **tally, "bad": bad}, indent=1))
    return 1 if bad else 0


if __name__ == "__main__":
    from ..cli import main_guard
    main_guard(main)
