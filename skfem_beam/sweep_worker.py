"""Preloaded in each local Dask worker of a sweep (:func:`skfem_beam.sweep_cluster.dask_client`).

Ctrl-C in a terminal sends SIGINT to the whole process group, the workers included: each
printed a KeyboardInterrupt traceback (30–80 lines) around the sweep's own one-line
message.  The sweep process handles Ctrl-C and closes its cluster, so a worker ignores it.
A worker compiles as its command does, without two of numba's idle costs (numba_speed).
"""
import signal


def dask_setup(worker) -> None:
    # called in the worker process's main thread, where its event loop runs
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    from skfem_beam import numba_speed
    numba_speed.apply()
