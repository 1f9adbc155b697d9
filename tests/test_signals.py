"""Signals honoured at every phase of a command: while it imports, while its kernels
load (a signal raised inside numba's ctypes callback would be lost), while it runs, and
after its last step."""
import json
import random
import signal
import subprocess
import sys
import time

CASE = [sys.executable, "-m", "skfem_beam.cases.point_stops", "--T", "1", "--dt", "1e-5",
        "--format", "none"]


def signalled(out, sig, delay):
    p = subprocess.Popen(CASE + ["--out", str(out)], stdout=subprocess.DEVNULL,
                         stderr=subprocess.PIPE, text=True)
    time.sleep(delay)
    p.send_signal(sig)
    err = p.communicate(timeout=120)[1].strip().splitlines()
    summary = out / "summary.json"
    status = json.loads(summary.read_text())["status"] if summary.exists() else None
    return p.returncode, [e for e in err if not e.startswith("compiling")], status


def test_sigterm_at_random_instants_of_start_up_ends_the_run(tmp_path):
    """30 of 30: exit 143, one line, and the folder (if any) says "interrupted", or
    "success" when the signal came after the last step."""
    rng = random.Random(2026)
    for i in range(30):
        code, err, status = signalled(tmp_path / f"r{i}", signal.SIGTERM, rng.uniform(0, 1.6))
        assert code == 143 and len(err) == 1 and "SIGTERM" in err[0], (i, code, err)
        assert status in (None, "interrupted", "success"), (i, status)


def test_sigint_while_importing_is_one_line_and_130(tmp_path):
    for i, delay in enumerate((0.05, 0.15, 0.3)):
        code, err, status = signalled(tmp_path / f"i{i}", signal.SIGINT, delay)
        assert code == 130 and len(err) == 1 and "SIGINT" in err[0], (delay, code, err)
        assert status is None
