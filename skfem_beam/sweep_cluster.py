"""The Dask cluster of a sweep (:mod:`skfem_beam.sweep`): a client to a new local cluster
or to an existing scheduler, and the tasks run on it with a dead worker's values retried.

Dask is an extra (``skfem_beam[cluster]``): it is imported when a client is made, never by a
run; a sweep without it runs its values in its own process (``--workers 0``).
"""
from __future__ import annotations

import contextlib
import time
import uuid

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
                         silence_logs=logging.CRITICAL,
                         # Ctrl-C reaches the workers too: they ignore it (sweep_worker)
                         preload=["skfem_beam.sweep_worker"]) as cluster, \
            Client(cluster) as client:
        yield client


RETRIES = 2     # a value whose worker dies is tried again this many times
# seconds a task may wait in a cluster that has no worker at all before its value is given
# up: a nanny that cannot restart its dead worker (its start timed out on a loaded machine)
# leaves the cluster empty, and the task would wait forever
NO_WORKERS_PATIENCE = 120.0
POLL = 2.0      # seconds between two looks at the cluster while waiting


class NoWorkers(RuntimeError):
    """The cluster has had no worker for NO_WORKERS_PATIENCE seconds."""


def _finished(client, futures):
    """``futures`` as they finish (a batch at a time); NoWorkers once the cluster has had no
    worker for NO_WORKERS_PATIENCE seconds while some are still pending."""
    from distributed import wait
    pending, empty_since = list(futures), None
    while pending:
        try:
            wait(pending, timeout=POLL, return_when="FIRST_COMPLETED")
        except TimeoutError:
            if client.scheduler_info()["workers"]:
                empty_since = None
            elif empty_since is None:
                empty_since = time.monotonic()
            elif time.monotonic() - empty_since >= NO_WORKERS_PATIENCE:
                raise NoWorkers(f"no Dask worker for {NO_WORKERS_PATIENCE:g} s: every worker "
                                "died and none came back") from None
            continue
        done = [f for f in pending if f.done()]
        pending = [f for f in pending if f not in done]
        yield from done


def on_cluster(client, task, settings: dict, todo: list[float], give_up):
    """Results as they finish; a task that raises (a killed worker: KilledWorker) is tried
    again, alone, up to RETRIES times after the others, then given up: its result is
    ``give_up(settings, value, error, attempts)`` (the sweep's :func:`~skfem_beam.sweep.lost`).
    Alone: a worker that dies takes the tasks queued on it along, so a value retried
    beside the one that kills it could be lost with it (seen once in CI).  A cluster left
    without any worker for NO_WORKERS_PATIENCE seconds gives up every value not yet
    finished, at once."""
    attempts = {v: 1 for v in todo}
    key, finished = {}, set()
    # this sweep's own keys: on a shared scheduler another sweep's task of the same value
    # had the same key, and Dask handed this one its results (other settings, silently)
    this = uuid.uuid4().hex[:12]

    def submit(v):
        f = client.submit(task, settings, v, key=f"sweep-{this}-{v!r}-{attempts[v]}",
                          pure=False)
        key[f.key] = v
        return f

    def result(f):
        r = f.result()
        finished.add(key[f.key])
        return r

    def lost(v, error):
        finished.add(v)
        return give_up(settings, v, error, attempts[v])

    failed = {}
    try:
        for f in _finished(client, [submit(v) for v in todo]):
            try:
                yield result(f)
            except Exception as e:     # the worker died (KilledWorker) or the task broke
                failed[key[f.key]] = e
        for v, e in failed.items():
            while attempts[v] <= RETRIES:
                attempts[v] += 1
                f = submit(v)
                next(_finished(client, [f]))
                try:
                    yield result(f)
                    break
                except Exception as err:
                    e = err
            else:
                yield lost(v, e)
    except NoWorkers as e:
        yield from (lost(v, e) for v in todo if v not in finished)
