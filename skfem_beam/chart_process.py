"""A command's charts, drawn in a process of their own beside the run.

Charts cost a short run most of its time: 0.3 s to import matplotlib and ~0.1 s a chart,
against a time loop of milliseconds.  A command therefore starts a chart process as it
starts (:func:`start`, from ``skfem_beam._startup``): it imports matplotlib while the
command imports its own modules and runs.  :func:`draw` sends it one chart (a module-level
chart function and its arguments, plain arrays, pickled) and returns at once (a thread
writes it into the pipe: a chart's data larger than the pipe waits there for the process
to read it, not the command, which goes on writing its fields); :func:`wait` returns
once every chart sent is drawn, raising the first chart's error as drawing it in the
command would have.  Without a chart process (the Python API, notebooks, tests calling a
command's ``main``), or should it fail to start or die, :func:`draw` draws here: the same
functions, the same files.

The process cannot outlive its command: it reads its work from a pipe, whose end ends it,
and on Linux the kernel kills it when the command's process dies (PR_SET_PDEATHSIG), so no
chart is written into a folder after its command was killed.  It runs in a session of its
own, so a Ctrl-C at the terminal goes to the command alone, which stops it.  Its
standard output is the command's standard error (its pipe to the command is a file of its
own), so a library's warning is seen as it would be in the command.

The process draws each chart in a child of its own, forked once matplotlib is loaded (Linux):
a run's charts then take the machine's cores together instead of one after the other
(four charts: 0.28 s instead of 0.47 s on two cores, docs/design.md), while the command
writes its fields at a higher priority.  Its reports still reach the command in the order
the charts were sent.

Only the standard library is imported here: the command imports this module first.
"""
from __future__ import annotations

import atexit
import collections
import importlib
import os
import pickle
import queue
import select
import signal
import struct
import subprocess
import sys
import threading

# The chart process loads matplotlib and the modules its caller names (a command's chart
# functions, _startup.CHART_MODULES: numpy and matplotlib) and nothing else of the package:
# the packages' __init__ would import numba, scipy and scikit-fem (~100 MB and 0.5 s it has
# no use for).  They are entered in sys.modules as bare modules with their folder, so that
# importing a submodule does not run them.  Its arguments: the command's pid, the modules
# to load (comma-separated), then name=folder per package.
_SERVE = """
import sys, types
for entry in sys.argv[3:]:
    name, _, path = entry.partition("=")
    package = types.ModuleType(name)
    package.__path__ = [path]
    sys.modules[name] = package
from skfem_beam.chart_process import serve
serve(int(sys.argv[1]), [m for m in sys.argv[2].split(",") if m])
"""
_HERE = os.path.dirname(os.path.abspath(__file__))
_process: subprocess.Popen | None = None
_outbox: queue.SimpleQueue | None = None   # pickled jobs for the process's sender thread
_pending: list = []        # the jobs sent and not yet reported drawn, in order
PIPE_BYTES = 1 << 20       # Linux's default limit for an unprivileged process
NICE = 10                  # the chart process's priority below its command's
JOB_LENGTH = "<Q"          # each job on the pipe: its length in bytes, then the pickled job
# BLAS without its worker threads in the chart process: it forks (serve), and a fork
# copies only the thread that calls it
ONE_THREAD = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def _packages(modules) -> list[str]:
    """name=folder of this package and of every package above ``modules``, outermost
    first."""
    top = __name__.rpartition(".")[0]
    names = {top} | {".".join(m.split(".")[:i]) for m in modules
                     for i in range(2, len(m.split(".")))}
    return [f"{name}={os.path.join(_HERE, *name.split('.')[1:])}" for name in sorted(names)]


def start(preload=()) -> None:
    """Start the chart process (once; nothing when it cannot be started).  ``preload``:
    the modules of this package it imports while it waits for its first chart (the chart
    functions its caller will send, ``_startup.CHART_MODULES``)."""
    global _process, _outbox
    if _process is not None:
        return
    try:
        _process = subprocess.Popen(
            [sys.executable, "-c", _SERVE, str(os.getpid()), ",".join(preload),
             *_packages(preload)],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, start_new_session=True,
            env={**os.environ, **ONE_THREAD})
    except OSError:
        return
    try:    # room for a short run's charts while the process is still importing (Linux)
        import fcntl
        fcntl.fcntl(_process.stdin.fileno(), fcntl.F_SETPIPE_SZ, PIPE_BYTES)
    except (ImportError, AttributeError, OSError):
        pass
    _outbox = queue.SimpleQueue()
    threading.Thread(target=_send, args=(_process.stdin, _outbox), daemon=True,
                     name="chart-sender").start()
    atexit.register(stop)


def _send(pipe, outbox) -> None:
    """The sender thread: write each job into the chart process's pipe, until
    :func:`stop` sends None.  A failed write means the process died: :func:`wait` then
    reads the end of its reports and draws what it did not."""
    while True:
        data = outbox.get()
        if data is None:
            return
        try:
            pipe.write(data)
            pipe.flush()
        except (OSError, ValueError):     # a broken pipe, or closed by stop()
            return


def running() -> bool:
    return _process is not None and _process.poll() is None


def draw(chart, *args, **kwargs) -> None:
    """``chart(*args, **kwargs)`` in the chart process when one runs, else here."""
    if running():
        job = (chart, args, kwargs)
        try:
            data = pickle.dumps(job, protocol=pickle.HIGHEST_PROTOCOL)
        except (pickle.PicklingError, TypeError, AttributeError):
            data = None                 # not a module-level function: drawn here
        if data is not None:
            _pending.append(job)
            _outbox.put(struct.pack(JOB_LENGTH, len(data)) + data)
            return
    chart(*args, **kwargs)


def wait(quiet: bool = False) -> None:
    """Return once every chart sent is drawn; raise the first one's error (``quiet``:
    none, for a command already failing for its own reason)."""
    errors = []
    while _pending:
        try:
            result = pickle.load(_process.stdout)
        except (EOFError, OSError, pickle.UnpicklingError):
            _lost(quiet)
            break
        _pending.pop(0)
        if result is not None:
            errors.append(result)
    if errors and not quiet:
        raise errors[0]


def _lost(quiet: bool = False) -> None:
    """The chart process died: the charts it did not report are drawn here."""
    global _process
    jobs = list(_pending)
    _pending.clear()
    stop()
    _process = None
    for chart, args, kwargs in jobs:
        try:
            chart(*args, **kwargs)
        except Exception:
            if not quiet:
                raise


def stop() -> None:
    """End the chart process (killed: it holds nothing to save, and the ~0.1 s of its
    interpreter's teardown would add to its command's)."""
    if _outbox is not None:
        _outbox.put(None)               # its sender thread ends
    if _process is not None and _process.poll() is None:
        _process.kill()
        _process.wait()


def serve(parent: int, preload=()) -> None:
    """The chart process: import ``preload``, then draw the charts that arrive on stdin,
    each in a child of its own (at most one per core at a time), and send one report per
    chart, in the order they came, on the pipe that was stdout (None, or the chart's
    exception), until stdin ends."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _die_with(parent)
    # below the command: on a first run it compiles its kernels on every core it has
    os.nice(NICE)
    report = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)                       # print() and warnings go to the command's stderr
    import matplotlib.pyplot  # noqa: F401  (what every chart needs, loaded while waiting)
    for module in preload:              # the chart functions the command will send
        importlib.import_module(module)
    from .aside import cores            # the standard library only, as here
    most = cores()                      # charts drawn at once
    # a child per chart where forking is safe: Linux, and this process has one thread
    forks = sys.platform.startswith("linux") and len(os.listdir("/proc/self/task")) == 1
    drawing = collections.deque()       # (job, pid, read end) per chart, in the order sent
    while True:
        # the first chart's report as soon as it is ready; a new chart while a core is free
        head_done = bool(drawing) and drawing[0][1] is None     # drawn here
        if not head_done:
            wait_on = ([drawing[0][2]] if drawing else []) + ([0] if len(drawing) < most else [])
            head_done = bool(drawing) and drawing[0][2] in select.select(wait_on, [], [])[0]
        if head_done:
            pickle.dump(_result(*drawing.popleft()), report, protocol=pickle.HIGHEST_PROTOCOL)
            report.flush()
            continue
        header = _read(0, struct.calcsize(JOB_LENGTH))
        if header is None:
            os._exit(0)                 # nothing to tear down: the command has ended
        job = pickle.loads(_read(0, struct.unpack(JOB_LENGTH, header)[0]))
        drawing.append(_fork_draw(job) if forks else (_draw(job), None, None))


def _read(fd: int, n: int) -> bytes | None:
    """Exactly ``n`` bytes from ``fd``; None at its end."""
    data = b""
    while len(data) < n:
        block = os.read(fd, n - len(data))
        if not block:
            return None
        data += block
    return data


def _draw(job):
    """Draw one chart: None, or its exception (picklable)."""
    chart, args, kwargs = job
    try:
        chart(*args, **kwargs)
        return None
    except Exception as e:              # noqa: BLE001  (reported to the command, raised there)
        return _picklable(e)


def _fork_draw(job):
    """(job, pid, read end) of a child drawing ``job``; where no child can be forked,
    (report, None, None): the chart is drawn here, now."""
    server = os.getpid()
    try:
        r, w = os.pipe()
    except OSError:
        return _draw(job), None, None
    try:
        pid = os.fork()
    except OSError:
        os.close(r)
        os.close(w)
        return _draw(job), None, None
    if pid == 0:                        # the child: draw, write the report, end
        try:
            os.close(r)
            _die_with(server)
            data = pickle.dumps(_draw(job), protocol=pickle.HIGHEST_PROTOCOL)
            while data:
                data = data[os.write(w, data):]
        finally:
            sys.stdout.flush()          # what the chart printed (os._exit flushes nothing)
            sys.stderr.flush()
            os._exit(0)
    os.close(w)
    return job, pid, r


def _result(job, pid, fd):
    """The report of a chart from :func:`_fork_draw`; one whose child died without
    reporting is drawn here."""
    if pid is None:
        return job                      # drawn already: its report
    chunks = []
    while block := os.read(fd, 1 << 16):
        chunks.append(block)
    os.close(fd)
    os.waitpid(pid, 0)
    try:
        return pickle.loads(b"".join(chunks))
    except Exception:                   # noqa: BLE001  (no report: it died, drawn again)
        return _draw(job)


def _picklable(e: Exception) -> Exception:
    """``e`` if it can be sent back (an OSError keeps its errno: a full disk is reported as
    the command reports one), else a RuntimeError that says what it was."""
    import traceback
    text = "".join(traceback.format_exception(e))
    try:
        e.add_note(f"(in the chart process)\n{text}")
        pickle.loads(pickle.dumps(e))
        return e
    except Exception:                   # noqa: BLE001
        return RuntimeError(f"a chart failed in the chart process:\n{text}")


def _die_with(parent: int) -> None:
    """Be killed when ``parent`` dies (Linux); exit now if it already has."""
    if sys.platform.startswith("linux"):
        try:
            import ctypes
            ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)   # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent:
        os._exit(0)
