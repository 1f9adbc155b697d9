"""A command's first and last moments, when its own signal handlers do not exist.

First: the imports (numpy, scipy, numba, ...) run before ``cli.main_guard`` installs its
handlers, and a Ctrl-C there would end in an ImportError traceback; a scene command also
starts its chart process then (``chart_process``), to load matplotlib beside them.
Last: Python's finalisation resets the signal handlers to the default before it tears
the modules down (~0.2 s with numba and matplotlib loaded), so a SIGTERM then killed
the finished command silently; a command process therefore runs its exit handlers
itself and ends with ``os._exit`` (`end`)."""
import atexit
import gc
import os
import signal
import sys
import tempfile
import threading

SIGNALS = (signal.SIGINT, signal.SIGTERM)
COMMAND = False     # this process is a ``python -m skfem_beam...`` command
NUMBA_OPT = "1"     # LLVM's optimisation level for a command's kernels (command_starting)
# A command's garbage collector runs a young collection every GC_THRESHOLD[0] allocations,
# not Python's 700: numba's compile of a first run makes millions of short-lived objects,
# and at 700 the main job's ~730 collections took 0.7–0.8 CPU s (docs/design.md)
GC_THRESHOLD = (50_000, 20, 100)


def _leave(signum, frame):
    name = signal.Signals(signum).name
    os.write(2, f"interrupted by {name} while starting: no output written\n".encode())
    os._exit(128 + signum)


def exit_on_signals() -> None:
    """SIGINT and SIGTERM end the process with one line and 128 + the signal, until
    ``cli.main_guard`` installs the command's handlers."""
    global COMMAND
    if threading.current_thread() is threading.main_thread():
        COMMAND = True
        for sig in SIGNALS:
            signal.signal(sig, _leave)


# the commands that draw charts: their chart process starts with them (chart_process) and
# loads the output's chart functions meanwhile
CHARTING = ("skfem_beam.cases.", "skfem_beam run")
CHART_MODULES = ("skfem_beam.output.charts",)


def command_starting() -> None:
    """A ``python -m skfem_beam...`` command is starting: signals end it in one line
    (`exit_on_signals`), its garbage is collected less often (GC_THRESHOLD), and one that
    draws charts starts its chart process now, to load matplotlib beside the command's own
    imports."""
    exit_on_signals()
    gc.set_threshold(*GC_THRESHOLD)
    # LLVM at -O1 for what a first run compiles: the loop and the laws step as fast as at
    # numba's default -O3 and compile in less time (docs/design.md, "The whole command");
    # numba reads it at import, which comes after this; a NUMBA_OPT of the user's is kept
    os.environ.setdefault("NUMBA_OPT", NUMBA_OPT)
    argv = getattr(sys, "orig_argv", [])
    i = argv.index("-m") if "-m" in argv else -1
    command = " ".join(argv[i + 1:i + 3]) if i >= 0 else ""
    helping = {"-h", "--help"} & set(argv[i + 1:]) if i >= 0 else set()
    if command.startswith(CHARTING) and not helping:     # --help draws nothing
        from . import chart_process
        try:
            chart_process.start(CHART_MODULES)
        except ValueError as e:     # a bad SKFEM_BEAM_CHARTS: one line, nothing written
            os.write(2, f"error: {e}\n".encode())
            os._exit(2)


def _ending(signum, frame):
    name = signal.Signals(signum).name
    os.write(2, f"interrupted by {name} while exiting: the command had finished\n".encode())
    os._exit(128 + signum)


def end(code: int) -> None:
    """The command's exit with ``code`` (sys.exit outside a command process, e.g. in
    tests).  What Python's finalisation does first runs here, with a handler (a signal
    meanwhile: one line, 128 + the signal): its threads are joined and its exit handlers
    run; the streams are flushed, then the signals are blocked and a pending one still
    honoured.  The module teardown, which would run with default handlers, is skipped.
    Left open: a signal the kernel hands to another thread (BLAS's) in the microseconds
    between the last check and ``os._exit`` trips Python's flag too late to be acted on;
    the command had finished and exits with ``code``."""
    if not COMMAND or threading.current_thread() is not threading.main_thread():
        sys.exit(code)
    for sig in SIGNALS:
        signal.signal(sig, _ending)
    threading._shutdown()       # what finalisation does first: threads' exit hooks, joins
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    signal.pthread_sigmask(signal.SIG_BLOCK, SIGNALS)
    pending = sorted(set(signal.sigpending()) & set(SIGNALS))
    if pending:
        _ending(pending[0], None)
    os._exit(code)


def numba_cache() -> None:
    """A folder for numba's cache: beside the sources (numba's first choice) or the user's
    cache folder; when neither can be written (a shared read-only install, no writable
    HOME) a folder of this user's in the temporary directory, since numba then raised at
    import ("no locator available") and every command, --help included, was a traceback.
    A NUMBA_CACHE_DIR of the user's is kept where it can be written; else one warning line
    and the temporary folder."""
    given = os.environ.get("NUMBA_CACHE_DIR")
    if given:
        if _writable(given):
            return
        os.write(2, f"warning: NUMBA_CACHE_DIR={given} cannot be written\n".encode())
    elif os.access(os.path.dirname(__file__), os.W_OK) or _writable(
            os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"),
                         "numba")):
        return
    path = os.path.join(tempfile.gettempdir(), f"skfem_beam-numba-{os.getuid()}")
    os.environ["NUMBA_CACHE_DIR"] = path
    if "numba" in sys.modules:      # imported before us: its config read the environment
        sys.modules["numba"].config.CACHE_DIR = path


def _writable(folder: str) -> bool:
    """Whether ``folder`` exists or can be made, and takes a file (as numba checks it)."""
    try:
        os.makedirs(folder, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
        return True
    except OSError:
        return False
