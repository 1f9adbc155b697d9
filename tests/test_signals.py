"""Signals honoured at every phase of a command: while it imports, while its kernels
load (a signal raised inside numba's ctypes callback would be lost), while it runs, and
after its last step."""
import json
import random
import signal
import subprocess
import sys
import time

import numpy as np

# `python -m skfem_beam.cases.point_stops` as Python runs it (runpy, argv[0] "-m" while
# the package imports), once the interpreter has said it is up: the instants count from
# there, not from a process start whose length depends on the machine and its load (a
# signal inside Python's own start-up is Python's, not ours)
MODULE = ("import runpy, sys; print('up', flush=True); sys.argv[0] = '-m'; "
          "runpy._run_module_as_main('skfem_beam.cases.point_stops')")
# 10 million steps (a minute or more on any machine): the signals' random instants
# (≤ 1.6 s) land before its end however fast the machine is
CASE = [sys.executable, "-c", MODULE, "--T", "100", "--dt", "1e-5", "--format", "none"]


def signalled(out, sig, delay):
    p = subprocess.Popen(CASE + ["--out", str(out)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    assert p.stdout.readline() == "up\n"
    time.sleep(delay)
    assert p.poll() is None, f"the command ended before its signal at {delay:.3f} s"
    p.send_signal(sig)
    err = p.communicate(timeout=120)[1].strip().splitlines()
    summary = out / "summary.json"
    status = json.loads(summary.read_text())["status"] if summary.exists() else None
    return p.returncode, [e for e in err if not e.startswith("compiling")], status


def test_sigterm_at_random_instants_of_start_up_ends_the_run(tmp_path):
    """30 of 30: exit 143, one line, and the folder (if any) says "interrupted"."""
    rng = random.Random(2026)
    for i in range(30):
        code, err, status = signalled(tmp_path / f"r{i}", signal.SIGTERM, rng.uniform(0, 1.6))
        assert code == 143 and len(err) == 1 and "SIGTERM" in err[0], (i, code, err)
        assert status in (None, "interrupted"), (i, status)


def test_sigint_while_importing_is_one_line_and_130(tmp_path):
    """While importing on any machine we know of; on a faster one the last instants may
    fall in the run, which must then end the same way, its folder saying so."""
    for i, delay in enumerate((0.05, 0.15, 0.3)):
        code, err, status = signalled(tmp_path / f"i{i}", signal.SIGINT, delay)
        assert code == 130 and len(err) == 1 and "SIGINT" in err[0], (delay, code, err)
        assert status in (None, "interrupted"), (delay, status)


END = """
import atexit, os, signal, sys
from skfem_beam import _startup
_startup.COMMAND = True
print("printed, not yet flushed", end="")
how = sys.argv[1]
if how == "during":      # a SIGTERM while the exit handlers run
    atexit.register(lambda: os.kill(os.getpid(), signal.SIGTERM))
elif how == "pending":   # one that arrives blocked, just before the end (sent to this
    import threading     # thread: os.kill may hand it to another thread, e.g. BLAS's)
    atexit.register(lambda: (signal.pthread_sigmask(signal.SIG_BLOCK, [signal.SIGINT]),
                             signal.pthread_kill(threading.main_thread().ident,
                                                 signal.SIGINT)))
atexit.register(lambda: open(sys.argv[2], "w").close())
_startup.end(3)
"""


def test_a_signal_while_the_command_exits_is_one_line_and_its_code(tmp_path):
    """Python's finalisation resets the handlers before its ~0.2 s of module teardown, where
    a SIGTERM killed a finished command silently; `_startup.end` runs the exit handlers
    with its own handler, flushes, and honours a signal left pending."""
    for how, code, line in (("none", 3, None), ("during", 143, "SIGTERM"),
                            ("pending", 130, "SIGINT")):
        mark = tmp_path / how
        p = subprocess.run([sys.executable, "-c", END, how, str(mark)], capture_output=True,
                           text=True, timeout=60)
        assert p.returncode == code and p.stdout == "printed, not yet flushed", (how, p)
        err = p.stderr.strip().splitlines()
        assert err == ([] if line is None else
                       [f"interrupted by {line} while exiting: the command had finished"])
        assert mark.exists() or how == "during"


def test_the_resume_line_quotes_its_folder(tmp_path):
    """Pasted back, `--resume sp ace/r ü` was two arguments: the folder is quoted."""
    import shlex
    from types import SimpleNamespace
    from skfem_beam.output.stream import _resume_command
    folder = SimpleNamespace(path=tmp_path / "sp ace" / "r ü",
                             summary={"config": {"command": "python -m skfem_beam run"}})
    line = _resume_command(folder)
    assert shlex.split(line)[-2:] == ["--resume", str(tmp_path / "sp ace" / "r ü")], line


def test_the_kept_rows_line_reads_the_last_rows_time(tmp_path):
    """A bar run's rows are decimated by its writer, not by its run (save_every 1): the
    interrupt line said 'to t=0.84 s' for rows that reached 8.4 s."""
    from types import SimpleNamespace
    from skfem_beam.output.series import SeriesFile
    from skfem_beam.output.stream import _Stream
    rows = SeriesFile(tmp_path / "ts.csv", ["t", "u"])
    rows.append({"t": np.arange(0, 42001) * 2e-4, "u": np.zeros(42001)})
    rows.sync()
    s = SimpleNamespace(run=SimpleNamespace(save_every=1, dt=2e-5), rows=rows, kept=None,
                        fields=None, folder=SimpleNamespace(path=tmp_path))
    assert "kept 42001 whole rows of timeseries.csv (to t=8.4 s)" in _Stream.what_is_kept(s)
    rows.close()


def test_a_closed_stdout_ends_a_finished_run_silently_with_the_pipes_code(tmp_path):
    """`| true`: the run's end line met a closed pipe, and the command said "could not write
    the results" with code 3 over a folder whose summary.json said success."""
    out = tmp_path / "run"
    p = subprocess.Popen([sys.executable, "-m", "skfem_beam.cases.point_stops", "--T", "0.05",
                          "--format", "none", "--out", str(out)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    p.stdout.close()                # the reader has gone before the first line
    err = p.stderr.read()
    assert p.wait(timeout=120) == 128 + signal.SIGPIPE and err == "", err
    assert json.loads((out / "summary.json").read_text())["status"] == "success"
