"""Compiling aside: a child process that compiles kernels into numba's on-disk cache while
this process compiles others (the first run of a fresh install, on two cores or more).

The child is a new interpreter.  The packages above the kernels' modules are entered in
its ``sys.modules`` bare (their folder, not their ``__init__``), so that it imports what
those modules need (numpy, scipy.sparse, numba), not the package's whole API (0.5 → 0.25 s,
on a core that this process's compile shares).  It ends without the interpreter's teardown
(0.3 s with numba loaded), which a run waiting for it would wait for too, it collects
garbage as seldom as the process that started it (a command's ``_startup.GC_THRESHOLD``),
and its numba compiles without two idle costs, as a command's does (``numba_speed``).
A kernel it has compiled is loaded from the cache by this process when its own compile
reaches it; one it has not compiled yet is compiled here, as without the child (the same
code either way).
"""
from __future__ import annotations

import atexit
import gc
import os
import pickle
import subprocess
import sys

_CHILD = """
import gc, importlib, os, pickle, sys, types
packages, jobs, threshold, speed = pickle.load(sys.stdin.buffer)
gc.set_threshold(*threshold)
for package, folder in packages.items():
    sys.modules[package] = types.ModuleType(package)
    sys.modules[package].__path__ = [folder]
importlib.import_module(speed).apply()
for module, name, sig in jobs:
    kernel = getattr(importlib.import_module(module), name)
    kernel.cfunc if sig is None else kernel.compile(sig)
os._exit(0)
"""
_CHILDREN = []
SPEED = __name__.rpartition(".")[0] + ".numba_speed"    # applied in the child (numba_speed)


def cores() -> int:
    affinity = getattr(os, "sched_getaffinity", None)
    return len(affinity(0)) if affinity else (os.cpu_count() or 1)


def start(kernels) -> subprocess.Popen | None:
    """A child compiling ``kernels``, in order: (numba dispatcher, argument types), or
    (``contact.base.Compiled`` kernel, None); each must be a module-level name of its
    module.  None with one core, or when it cannot start."""
    if cores() < 2:
        return None
    jobs = []
    for kernel, sig in kernels:
        func = kernel.py_func if sig is not None else kernel.func
        jobs.append((func.__module__, func.__name__, sig))
    packages = {}
    for module, _, _ in jobs:
        parts = module.split(".")
        for i in range(1, len(parts)):
            package = ".".join(parts[:i])
            packages[package] = list(sys.modules[package].__path__)[0]
    # the child imports the same package: this process's sys.path, '' as the cwd
    path = os.pathsep.join(os.path.abspath(p or os.curdir) for p in sys.path)
    try:
        child = subprocess.Popen([sys.executable, "-c", _CHILD],
                                 env={**os.environ, "PYTHONPATH": path}, stdin=subprocess.PIPE,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    except OSError:
        return None
    _CHILDREN.append(child)
    try:
        child.stdin.write(pickle.dumps((packages, jobs, gc.get_threshold(), SPEED)))
        child.stdin.close()
    except OSError:         # it died: what it was to compile is compiled here
        pass
    return child


@atexit.register
def _stop_children() -> None:
    """A process that ends before it needed a kernel leaves no compiler running."""
    for child in _CHILDREN:
        if child.poll() is None:
            child.kill()
            child.wait()
