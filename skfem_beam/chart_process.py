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

The process hands the charts to its workers, one per core, forked once matplotlib is loaded
(Linux): a run's charts then take the machine's cores together instead of one after the
other, while the command writes its fields at a higher priority (docs/design.md).  Its
reports still reach the command in the order the charts were sent.

With ``SKFEM_BEAM_CHARTS=0`` in the environment nothing is drawn and no chart process
starts (:func:`wanted`): for runs whose pictures nobody looks at (the test suite, scripted
sweeps of commands), the charts are about half of a short command's CPU time.

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
STOP_WAIT = 1.0            # s for the chart process to end its workers, then it is killed
JOB_LENGTH = "<Q"          # each job on the pipe: its length in bytes, then the pickled job
# BLAS without its worker threads in the chart process: it forks (serve), and a fork
# copies only the thread that calls it
ONE_THREAD = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
CHARTS = "SKFEM_BEAM_CHARTS"     # "0": no charts (module docstring)


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
    if _process is not None or not wanted():
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


def wanted() -> bool:
    """True with SKFEM_BEAM_CHARTS unset or 1, False with 0; another value is refused
    (InputError naming it: a command says so in one line as it starts, _startup)."""
    value = os.environ.get(CHARTS, "1")
    if value not in ("0", "1"):
        from .errors import InputError     # standard library only, as this module
        raise InputError(f"{CHARTS}={value!r} in the environment: allowed 0 (no charts) "
                         f"or 1 (charts, the default)")
    return value == "1"


def draw(chart, path, *args, **kwargs) -> None:
    """``chart(path, *args, **kwargs)`` in the chart process when one runs, else here;
    with charts not :func:`wanted`, nothing but the removal of an earlier picture at
    ``path`` (a resumed or overwritten folder's: it would not show this run)."""
    if not wanted():
        try:
            os.remove(path)
        except FileNotFoundError:
            pass
        return
    args = (path, *args)
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
    """End the chart process: SIGTERM, on which it ends its workers, waits for them and
    exits without its interpreter's teardown (~0.1 s that would add to its command's), so
    that the command's CPU time counts theirs; killed if it has not ended within
    ``STOP_WAIT`` seconds (a stopped process)."""
    if _outbox is not None:
        _outbox.put(None)               # its sender thread ends
    if _process is not None and _process.poll() is None:
        _process.terminate()
        try:
            _process.wait(timeout=STOP_WAIT)
        except subprocess.TimeoutExpired:
            _process.kill()
            _process.wait()


def serve(parent: int, preload=()) -> None:
    """The chart process: import ``preload``, then have the charts that arrive on stdin
    drawn by its workers (one per core, forked once: :class:`_Worker`), and send one
    report per chart, in the order they came, on the pipe that was stdout (None, or the
    chart's exception), until stdin ends."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _die_with(parent)
    # below the command: on a first run it compiles its kernels on every core it has
    os.nice(NICE)
    report = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)                       # print() and warnings go to the command's stderr
    import matplotlib.pyplot  # noqa: F401  (what every chart needs, loaded while waiting)
    for module in preload:              # the chart functions the command will send
        importlib.import_module(module)
    workers = _start_workers()
    idle = collections.deque(workers)
    charts = collections.deque()        # [job, report, done] per chart, in the order sent
    waiting = collections.deque()       # the charts no worker has taken yet
    busy = {}                           # a worker's report pipe: (worker, its chart)
    while True:
        while charts and charts[0][2]:  # the reports, in order, as soon as they are ready
            pickle.dump(charts.popleft()[1], report, protocol=pickle.HIGHEST_PROTOCOL)
            report.flush()
        while waiting and idle:
            worker, chart = idle.popleft(), waiting.popleft()
            if worker.send(chart[0]):
                busy[worker.reports] = worker, chart
            else:                       # it died: drawn here, and it is no worker any more
                workers.remove(worker)  # (else charts would wait for it when none is left)
                worker.end()
                chart[1:] = _draw(pickle.loads(chart[0])), True
        if waiting and not workers:     # none left (or none could be forked): drawn here
            chart = waiting.popleft()
            chart[1:] = _draw(pickle.loads(chart[0])), True
            continue
        for fd in select.select([0, *busy], [], [])[0]:
            if fd == 0:
                header = _read(0, struct.calcsize(JOB_LENGTH))
                if header is None:
                    _end(workers)       # nothing to tear down: the command has ended
                job = _read(0, struct.unpack(JOB_LENGTH, header)[0])
                charts.append([job, None, False])
                waiting.append(charts[-1])
                continue
            worker, chart = busy.pop(fd)
            result = worker.result()
            if result is _DIED:         # it died without a report: drawn here
                workers.remove(worker)
                result = _draw(pickle.loads(chart[0]))
            else:
                idle.append(worker)
            chart[1:] = result, True


def _start_workers() -> list:
    """One :class:`_Worker` per core where forking is safe (Linux, and this process has one
    thread); a SIGTERM (:func:`stop`) then ends them and this process (:func:`_end`)."""
    from .aside import cores            # the standard library only, as here
    forks = sys.platform.startswith("linux") and len(os.listdir("/proc/self/task")) == 1
    workers = []
    for _ in range(cores() if forks else 0):
        if worker := _Worker.fork(workers):
            workers.append(worker)
    signal.signal(signal.SIGTERM, lambda *_: _end(workers))
    return workers


def _end(workers) -> None:
    """The workers killed and waited for (so that the command's CPU time counts theirs),
    then this process, without its interpreter's teardown."""
    for worker in workers:
        worker.end()
    os._exit(0)


_DIED = object()


class _Worker:
    """A child of the chart process that draws the charts it is sent, one at a time, and
    reports each (the pickled report's length, then the report).  Forked once, before the
    first chart: a child forked per chart paid, on each chart, the copies of the pages it
    touched (0.25–0.3 CPU s a chart against 0.18 drawn in a warm process); a worker pays
    them once, drawing a small figure while the command still imports and runs."""

    def __init__(self, pid: int, jobs: int, reports: int):
        self.pid, self.jobs, self.reports = pid, jobs, reports

    @classmethod
    def fork(cls, others=()) -> _Worker | None:
        """A new worker (``others``: the workers forked before it, whose pipes it closes),
        or None where it cannot be forked."""
        server = os.getpid()
        try:
            jobs_r, jobs_w = os.pipe()
            reports_r, reports_w = os.pipe()
            pid = os.fork()
        except OSError:
            return None
        if pid == 0:                    # the worker
            try:
                os.close(jobs_w)
                os.close(reports_r)
                for fd in [0] + [f for w in others for f in (w.jobs, w.reports)]:
                    os.close(fd)        # the command's pipe is the chart process's alone
                _die_with(server)
                _warm_up()
                while (header := _read(jobs_r, struct.calcsize(JOB_LENGTH))) is not None:
                    job = pickle.loads(_read(jobs_r, struct.unpack(JOB_LENGTH, header)[0]))
                    data = pickle.dumps(_draw(job), protocol=pickle.HIGHEST_PROTOCOL)
                    sys.stdout.flush()  # what the chart printed: a worker is killed, not ended
                    sys.stderr.flush()
                    data = struct.pack(JOB_LENGTH, len(data)) + data
                    while data:
                        data = data[os.write(reports_w, data):]
            finally:
                os._exit(0)
        os.close(jobs_r)
        os.close(reports_w)
        return cls(pid, jobs_w, reports_r)

    def send(self, job: bytes) -> bool:
        """Give it a chart (its pickled job); False if it has died."""
        data = struct.pack(JOB_LENGTH, len(job)) + job
        try:
            while data:
                data = data[os.write(self.jobs, data):]
            return True
        except OSError:
            return False

    def end(self) -> None:
        """Kill it and wait for it."""
        try:
            os.kill(self.pid, signal.SIGKILL)
            os.waitpid(self.pid, 0)
        except OSError:                 # gone already (its chart's report said so)
            pass

    def result(self):
        """Its report of the chart it was sent, or _DIED."""
        header = _read(self.reports, struct.calcsize(JOB_LENGTH))
        data = header and _read(self.reports, struct.unpack(JOB_LENGTH, header)[0])
        if data is None:
            os.waitpid(self.pid, 0)
            return _DIED
        return pickle.loads(data)


def _warm_up() -> None:
    """A small chart drawn and thrown away: the pages and caches a first chart touches."""
    import io
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(3, 2))
    ax.plot([0.0, 1.0], [0.0, 1.0], label="½E_β")
    ax.set_title("t (s)", fontsize=9)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(io.BytesIO(), format="png")
    plt.close(fig)


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
