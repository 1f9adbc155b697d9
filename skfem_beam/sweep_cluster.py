"""The Dask cluster of a sweep (:mod:`skfem_beam.sweep`): a client to a new local cluster
or to an existing scheduler, and the tasks run on it with a dead worker's values retried.

Dask is an extra (``skfem_beam[cluster]``): it is imported when a client is made, never by a
run; a sweep without it runs its values in its own process (``--workers 0``).
"""
from __future__ import annotations

import contextlib

from .errors import InputError


@contextlib.contextmanager
def dask_client(workers: int | None = None, scheduler: str | None = None):
    """A Dask client: to ``scheduler`` if given, else to a new local cluster of processes.

    The local workers are spawned processes: a script that calls this must keep its
    top-level code under ``if __name__ == "__main__":``.
    """
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise InputError("a sweep on workers or a --scheduler needs Dask, which a run does "
                         "not: pip install \"skfem_beam[cluster]\", or run without it with "
                         "--workers 0") from None
    import logging
    if scheduler:
        try:
            client = Client(scheduler, timeout="15s")
        except (OSError, TimeoutError, ValueError) as e:
            raise InputError(f"--scheduler {scheduler}: cannot connect ({e})") from None
        with client:
            yield client
        return
    # Dask sets MALLOC_TRIM_THRESHOLD_ in its workers, which makes every chunk's load array
    # a fresh mmap: 3× the page faults and ~15 % more CPU per run, measured here.  Unset it.
    import dask
    no_trim = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}
    with dask.config.set(no_trim), \
            LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                         host="127.0.0.1", dashboard_address="127.0.0.1:0", scheduler_port=0,
                         silence_logs=logging.CRITICAL) as cluster, \
            Client(cluster) as client:
        yield client


RETRIES = 2     # a value whose worker dies is tried again this many times


def on_cluster(client, task, settings: dict, todo: list[float], give_up):
    """Results as they finish; a task that raises (a killed worker: KilledWorker) is tried
    again, alone, up to RETRIES times after the others, then given up: its result is
    ``give_up(settings, value, error, attempts)`` (the sweep's :func:`~skfem_beam.sweep.lost`).
    Alone: a worker that dies takes the tasks queued on it along, so a value retried
    beside the one that kills it could be lost with it (seen once in CI)."""
    from distributed import as_completed
    attempts = {v: 1 for v in todo}
    key = {}

    def submit(v):
        f = client.submit(task, settings, v, key=f"sweep-{v!r}-{attempts[v]}", pure=False)
        key[f.key] = v
        return f

    failed = {}
    for f in as_completed([submit(v) for v in todo]):
        v = key[f.key]
        try:
            yield f.result()
        except Exception as e:     # the worker died (KilledWorker) or the task broke
            failed[v] = e
    for v, e in failed.items():
        while attempts[v] <= RETRIES:
            attempts[v] += 1
            try:
                yield submit(v).result()
                break
            except Exception as err:
                e = err
        else:
            yield give_up(settings, v, e, attempts[v])
