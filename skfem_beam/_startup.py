"""A command's first second: the imports (numpy, scipy, matplotlib, ...) run before its
own signal handlers exist, and a Ctrl-C there would end in an ImportError traceback."""
import os
import signal
import threading


def _leave(signum, frame):
    name = signal.Signals(signum).name
    os.write(2, f"interrupted by {name} while starting: no output written\n".encode())
    os._exit(128 + signum)


def exit_on_signals() -> None:
    """SIGINT and SIGTERM end the process with one line and 128 + the signal, until
    ``cli.main_guard`` installs the command's handlers."""
    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, _leave)
