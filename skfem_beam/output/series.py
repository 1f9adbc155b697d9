"""Running a command's :class:`~skfem_beam.scheme.Run` so that a long run loses nothing.

One pipeline for the beam scenes and the bar.  After every input has been checked the
output :class:`~.folder.Folder` is made (summary "running"); ``timeseries.csv`` grows by
whole rows after every chunk (flushed and fsynced: a run killed at any moment leaves a
readable file up to its last flush) and the rows are also kept in memory for the charts
and the summary; the field frames are written as they come.  With ``--checkpoint-every
S`` the run's full state is written atomically (write, then rename) to
``checkpoint.npz``.  ``--resume DIR`` rebuilds the same run from ``summary.json``,
restores the checkpoint, cuts the series back to it and continues: the result is
identical, bit for bit, to an uninterrupted run (values are written with the exact shortest
digits).  A folder with no checkpoint (the run stopped before its first) is emptied but
for its summary and run again from step 0: nothing computed was kept, the configuration was.

What a command streams is a :class:`Series`: its columns, computed from the run's saved
buffers, and which field frames to write.
"""
from __future__ import annotations

import errno
import hashlib
import io
import json
import os
import resource
import signal
import sys
import threading
import time
import zlib
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from .. import chart_process
from ..errors import InputError, SolverError
from ..scheme import Run, drive
from .fields import FieldWriter
from .options import OutputOptions
from .folder import (EXIT_SOLVER, SUMMARY, Folder, Interrupted, _plain, check_output_dir,
                     csv_rows, report)

CHECKPOINT = "checkpoint.npz"
CHECKPOINT_FORMAT = 3       # 3: impact events hold their first step off (State.impact)
BUFFERS = ("obs", "obsv", "energy", "work", "lam")   # saved series (not in the Run's checkpoint)


PAGE = 4096              # bytes: the largest write (see SeriesFile._write)
BLOCK = 1 << 23          # bytes read at a time on resume (CRC, rows): flat memory
KEEP_ROWS = 1 << 16       # rows kept whole in memory for the charts; beyond, an envelope
BINS = 1000               # time bins of that envelope (a chart is about 1000 pixels wide)
FRAMES_AFTER = 1.0        # s: a run's frames stream with its rows from then on (_Stream)


class Columns(dict):
    """The series a command's ``finish`` gets, name → array.  ``complete``: every row
    written; False for a long run, whose rows are then each column's extremes per time
    bin (see SeriesFile._reduce: what a chart shows), so that memory stays flat however
    long the run."""
    complete = True


def read_blocks(path: Path, nbytes: int, start: int = 0):
    """The bytes start..nbytes of ``path`` in blocks of at most BLOCK bytes."""
    with open(path, "rb") as fh:
        fh.seek(start)
        left = nbytes - start
        while left > 0:
            block = fh.read(min(BLOCK, left))
            if not block:
                return
            left -= len(block)
            yield block


def file_crc(path: Path, nbytes: int) -> int:
    """zlib.crc32 of the first ``nbytes`` of ``path``, read block by block."""
    crc = 0
    for block in read_blocks(path, nbytes):
        crc = zlib.crc32(block, crc)
    return crc


def read_rows(path: Path, nbytes: int, width: int):
    """The CSV rows in the first ``nbytes`` of ``path`` after its header, as arrays of
    ``width`` columns, block by block (np.loadtxt rounds correctly: the 17 written digits
    come back bit for bit)."""
    with open(path, "rb") as fh:
        start = len(fh.readline())
    rest = b""
    for block in read_blocks(path, nbytes, start):
        block = rest + block
        cut = block.rfind(b"\n") + 1
        rest = block[cut:]
        if cut:
            yield np.loadtxt(io.BytesIO(block[:cut]), delimiter=",", ndmin=2).reshape(-1, width)


class SeriesFile:
    """timeseries.csv written as the run goes, and the same rows kept in memory for the
    charts (:meth:`data`: whole up to KEEP_ROWS rows, then reduced), so nothing is read
    back from the file.

    Whole rows only: rows are written with ``os.write`` (no buffer to flush later), and a
    write that fails (a full disk) cuts the file back to its last whole row before the
    error goes on.  A chunk is formatted, written and fsynced by a writer thread while the
    run computes the next one (the compiled loop releases the GIL): formatting 17-digit
    rows costs more than computing them (measured: 4.4 s against 2.7 s for 2,000,000
    rows).  One chunk at most is in flight; :meth:`sync` waits for it and re-raises its
    error.  ``nbytes`` and ``crc`` (zlib.crc32 of the file so far) go into every
    checkpoint, so that a resume can check the rows on disk are the ones it continues.
    ``keep``: a checkpoint; the file is cut back to its rows (resume).  ``limit``: rows
    held whole before the envelope (None: every row, for a command whose analysis needs
    them all).
    """

    def __init__(self, path: Path, names: list[str], keep: dict | None = None,
                 limit: int | None = KEEP_ROWS):
        self.path, self.names, self.limit = path, names, limit
        self._chunks: list[dict] = []
        self._held, self.complete, self._width = 0, True, None
        self._writer, self._pending = ThreadPoolExecutor(max_workers=1), None
        if keep is None:
            self.fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
            self.rows, self.nbytes, self.crc = 0, 0, 0
            self._write((",".join(names) + "\n").encode())
        else:   # resume: keep the header and the checkpoint's rows (checked), drop the rest
            self.rows, self.nbytes = int(keep["rows"]), int(keep["nbytes"])
            self.crc = int(keep["crc"])
            if "envelope" in keep:   # a long run: its chart rows came with the checkpoint
                self._chunks = [dict(zip(names, np.asarray(keep["envelope"], dtype=float).T))]
                self._held, self.complete = len(keep["envelope"]), False
                self._width = float(keep["envelope_width"])
            else:                    # at most `limit` rows (or every row: limit None)
                for values in read_rows(path, self.nbytes, len(names)):
                    self._chunks.append({k: values[:, i] for i, k in enumerate(names)})
                    self._held += len(values)
                    if self.limit is not None and self._held > self.limit:
                        self._reduce()
            self.fd = os.open(path, os.O_WRONLY)
            os.ftruncate(self.fd, self.nbytes)
            os.lseek(self.fd, self.nbytes, os.SEEK_SET)
        self.sync()

    def _write(self, data: bytes) -> None:
        """Whole rows in writes of at most a page: a process killed (SIGKILL) in the middle
        of a large write() leaves a part of it, but not of a one-page write, so the file
        ends on a whole row whenever the process dies."""
        try:
            start = 0
            while start < len(data):
                end = data.rfind(b"\n", start, start + PAGE) + 1 or len(data)
                view = memoryview(data)[start:end]
                while view:
                    view = view[os.write(self.fd, view):]
                start = end
        except OSError:
            self.cut()
            raise
        self.nbytes += len(data)
        self.crc = zlib.crc32(data, self.crc)

    def cut(self) -> None:
        """Back to the last whole row (shrinking a file needs no disk space)."""
        os.ftruncate(self.fd, self.nbytes)
        os.lseek(self.fd, self.nbytes, os.SEEK_SET)

    def append(self, columns: dict) -> None:
        """Rows to write (copied: the run's buffers move on); written in the background."""
        cols = {k: np.array(columns[k], dtype=float) for k in self.names}
        self._chunks.append(cols)
        self._held += len(cols[self.names[0]])
        if self.limit is not None and self._held > self.limit:
            self._reduce()
        self._wait()
        self._pending = self._writer.submit(self._write_rows, cols)

    def _write_rows(self, cols: dict) -> None:
        text = csv_rows(cols, self.names)
        self._write(text.encode())
        self.rows += text.count("\n")
        os.fsync(self.fd)

    def _wait(self) -> None:
        pending, self._pending = self._pending, None
        if pending is not None:
            pending.result()          # its OSError (a full disk) goes on from here

    def _reduce(self) -> None:
        """The rows held, reduced to each column's minimum and maximum in every time bin
        (at most 2·BINS bins over the rows so far, the bin width doubling as the run
        grows): what a chart can show, with every extreme kept, in bounded memory."""
        data = self.data()
        t = data[self.names[0]]
        if self._width is None:
            self._width = max((t[-1] - t[0]) / BINS, np.finfo(float).tiny)
        while (t[-1] - t[0]) / self._width > 2 * BINS:
            self._width *= 2
        bins = np.floor((t - t[0]) / self._width).astype(np.int64)
        starts = np.concatenate([[0], np.flatnonzero(np.diff(bins)) + 1])
        counts = np.diff(np.concatenate([starts, [t.size]]))
        keep = np.zeros(t.size, dtype=bool)
        keep[starts] = keep[-1] = True
        for k in self.names[1:]:
            y = data[k]
            for extreme in (np.minimum, np.maximum):   # its first row in each bin (ties:
                hit = np.flatnonzero(y == np.repeat(extreme.reduceat(y, starts), counts))
                keep[hit[np.unique(bins[hit], return_index=True)[1]]] = True   # one only)
        self._chunks = [{k: v[keep] for k, v in data.items()}]
        self._held, self.complete = int(keep.sum()), False

    def envelope(self) -> dict:
        """What a checkpoint keeps of the rows in memory: nothing while they are complete
        (a resume reads them back from the file, at most ``limit`` rows), else the
        reduced rows and the bin width, so that a resume of a long run reads no row and
        goes on reducing exactly as the run it continues."""
        if self.complete:
            return {}
        data = self.data()
        return {"envelope": np.column_stack([data[k] for k in self.names]),
                "envelope_width": self._width}

    def data(self) -> Columns:
        """The rows written so far, as columns (all of them, or their envelope)."""
        out = Columns({k: np.concatenate([c[k] for c in self._chunks] or [np.zeros(0)])
                       for k in self.names})
        out.complete = self.complete
        return out

    def sync(self) -> None:
        """Every row appended is written and on disk (closed: it was at close)."""
        self._wait()
        if self.fd >= 0:
            os.fsync(self.fd)

    def close(self) -> None:
        if self.fd >= 0:
            try:
                self._wait()
            finally:
                self._writer.shutdown()
                fd, self.fd = self.fd, -1
                try:
                    os.fsync(fd)
                finally:
                    os.close(fd)


@dataclass
class Series:
    """What a command streams from its run.

    ``columns(run, k0, k1)``: the timeseries rows (a dict of columns; it may keep only some
    of them) for the run's saved rows k0..k1−1; ``ready(run)``: how many saved rows are final
    (default: all computed so far); ``field_every``: steps between field frames, a multiple
    of ``run.frame_every`` (0: every frame the run keeps); ``field_until``: the last step
    with a frame (None: the run's end); ``events(folder, run, last)``: writes impacts.csv
    and returns its summary entries (``last``: the last state the loop computed), on every
    way a run ends: finished, unstable, interrupted, failed.
    """
    columns: Callable
    ready: Callable | None = None
    field_every: int = 0
    field_until: int | None = None
    keep_all: bool = False      # finish needs every row (not only what a chart shows)
    events: Callable | None = None

    def rows_ready(self, run: Run) -> int:
        return self.ready(run) if self.ready is not None else run.n // run.save_every + 1


class _Fields:
    """The field frames of a run, written as they are computed.  Their files are made with
    the first frames (:class:`_Stream`: after the loop, in a short run), so that their
    writer's imports come then too (:mod:`.xdmf`)."""

    def __init__(self, folder: Path, run: Run, fmt: str, series: Series):
        self.run, self.folder, self.fmt, self._writer = run, folder, fmt, None
        every = series.field_every or run.frame_every
        if every % run.frame_every:
            raise InputError(f"field frames every {every} steps are not kept by the run "
                             f"(it keeps every {run.frame_every}-th)")
        self.every, self.until, self.written = every, series.field_until, 0

    @property
    def writer(self) -> FieldWriter:
        if self._writer is None:
            self._writer = FieldWriter(self.folder, self.run.system, self.fmt)
        return self._writer

    def update(self) -> None:
        run, stride = self.run, self.every // self.run.frame_every
        last = run.n if self.until is None else min(run.n, self.until)
        for k in range(self.written, last // self.every + 1):
            i = k * stride
            self.writer.write(k * self.every * run.dt, run.fr[i], run.frv[i], run.frf[i])
        self.written = max(self.written, last // self.every + 1)
        self.writer.flush()

    def close(self) -> None:
        if self._writer is not None:   # a run stopped before its first frame has no field
            self._writer.close()       # files (none made on a disk that may be full)


def _digest(arrays: dict) -> str:
    """sha256 of every array (name, dtype, shape, bytes), in name order."""
    h = hashlib.sha256()
    for k in sorted(arrays):
        a = np.ascontiguousarray(arrays[k])
        h.update(f"{k}:{a.dtype.str}:{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def write_checkpoint(path: Path, arrays: dict, config: dict) -> None:
    """The arrays, the run's configuration (JSON) and their sha256, atomically: written to
    a hidden sibling, fsynced, renamed into place (a stopped write leaves the old one)."""
    arrays = {k: np.asarray(v) for k, v in arrays.items()}
    arrays["config"] = np.array(json.dumps(_plain(config), sort_keys=True))
    arrays["format"] = np.array(CHECKPOINT_FORMAT)
    arrays["sha256"] = np.array(_digest(arrays))
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp.npz")
    try:
        np.savez(tmp, **arrays)
        with open(tmp, "rb") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def read_checkpoint(folder: Path) -> dict:
    """The checkpoint in ``folder``, read without pickle and checked against its sha256;
    anything else is one InputError naming the file and what is wrong."""
    path = Path(folder) / CHECKPOINT
    try:
        with np.load(path, allow_pickle=False) as z:
            ck = {k: z[k] for k in z.files}
    except Exception as e:     # zip, zlib, npy header, pickle refusal, I/O: all unreadable
        raise InputError(f"{path} is unreadable ({type(e).__name__}: {e}); "
                         "cannot resume, nothing was changed") from None
    missing = [k for k in ("sha256", "config", "format", "n", "rows", "nbytes", "crc")
               if k not in ck]
    if missing:
        raise InputError(f"{path} has no {missing[0]!r} (not a checkpoint of this version); "
                         "cannot resume, nothing was changed")
    if _digest({k: v for k, v in ck.items() if k != "sha256"}) != str(ck["sha256"]):
        raise InputError(f"{path} does not match its sha256 checksum (changed or cut); "
                         "cannot resume, nothing was changed")
    if int(ck["format"]) != CHECKPOINT_FORMAT:
        raise InputError(f"{path} is of checkpoint format {int(ck['format'])}, this version "
                         f"reads format {CHECKPOINT_FORMAT}; cannot resume, nothing was changed")
    ck["config"] = json.loads(str(ck["config"]))
    return ck


def read_summary(folder: Path) -> dict:
    path = Path(folder) / SUMMARY
    try:
        summary = json.loads(path.read_bytes().decode("utf-8"))
        if not isinstance(summary, dict) or not isinstance(summary.get("config"), dict):
            raise ValueError("no 'config' object")
    except (OSError, ValueError) as e:   # UnicodeDecodeError and JSONDecodeError included
        raise InputError(f"{path} is not a readable summary ({type(e).__name__}: {e}); "
                         "cannot resume, nothing was changed") from None
    return summary


NOT_IDENTITY = {"out", "overwrite"}   # a folder moved, copied or spelled another way resumes


def check_resumable(folder: Path, summary: dict, ck: dict | None, extend: bool) -> None:
    """Refuse a resume whose summary, checkpoint and rows on disk do not agree.  ``ck``
    None (no checkpoint: the run starts again from step 0): its status alone is checked,
    the rows on disk are not used."""
    if ck is not None:
        _check_config(folder, summary, ck)
    _check_status(folder, summary, extend)
    if ck is not None:
        _check_rows(folder, ck)


def _check_config(folder: Path, summary: dict, ck: dict) -> None:
    """The summary's configuration is the checkpoint's (but for the folder, and a T grown
    by an extension stopped before its first checkpoint)."""
    name = f"{Path(folder) / SUMMARY}"
    mine, theirs = _plain(summary["config"]), ck["config"]
    diff = sorted(k for k in (set(mine) | set(theirs)) - NOT_IDENTITY
                  if mine.get(k) != theirs.get(k)
                  # an extension (--T longer) stopped before its first checkpoint
                  and not (k == "T" and _longer(mine.get(k), theirs.get(k))))
    if diff:
        k = diff[0]
        raise InputError(f"{name}: {k}={mine.get(k)!r} differs from the checkpoint's "
                         f"{k}={theirs.get(k)!r}; cannot resume, nothing was changed")


def _check_status(folder: Path, summary: dict, extend: bool) -> None:
    """A run that went unstable, or finished (unless extended), has nothing to resume."""
    name = f"{Path(folder) / SUMMARY}"
    status = summary.get("status")
    if status == "unstable":
        raise InputError(f"{name}: the run went unstable; there is nothing to resume")
    # the summary's checkpoint_step is not checked against n: the checkpoint is the one
    # truth (a full disk can refuse the summary's write after the checkpoint's went in)
    if status == "success" and not extend:
        raise InputError(f"{folder} holds a finished run (status success): nothing to "
                         f"resume; give a longer --T to extend it")


def _check_rows(folder: Path, ck: dict) -> None:
    """timeseries.csv holds the rows the checkpoint was written with (size and CRC)."""
    csv = Path(folder) / "timeseries.csv"
    size = csv.stat().st_size if csv.is_file() else -1
    nbytes = int(ck["nbytes"])
    if size < nbytes:
        raise InputError(f"{csv} has {max(size, 0)} bytes, fewer than the {nbytes} of the "
                         f"checkpoint's {int(ck['rows'])} rows; cannot resume")
    if file_crc(csv, nbytes) != int(ck["crc"]):
        raise InputError(f"{csv}: its first {int(ck['rows'])} rows are not the ones the "
                         "checkpoint was written with; cannot resume, nothing was changed")


def _longer(a, b) -> bool:
    return isinstance(a, (int, float)) and isinstance(b, (int, float)) and a > b


def _checkpoint(run: Run, rows: SeriesFile, used: int) -> dict:
    """The run's state, the rows written, and the saved rows the series has not used yet
    (and one before them): a resumed run computes only what comes after the checkpoint."""
    first = max(0, used - 1)
    keep = run.n // run.save_every + 1
    pending = {f"pending_{k}": getattr(run, k)[first:keep] for k in BUFFERS}
    return {**run.checkpoint(), "rows": rows.rows, "nbytes": rows.nbytes, "crc": rows.crc,
            "used": used, "pending_from": first, **pending, **rows.envelope()}


def _restore(run: Run, ck: dict) -> int:
    """Restore ``run`` from a checkpoint; return the saved rows the series has used."""
    try:
        run.restore(ck)
        first = int(ck["pending_from"])
        for k in BUFFERS:
            part = ck[f"pending_{k}"]
            getattr(run, k)[first:first + len(part)] = part
    except (KeyError, ValueError, IndexError) as e:
        raise InputError(f"{CHECKPOINT} does not fit this run ({type(e).__name__}: {e}); "
                         "cannot resume") from None
    return int(ck["used"])


def prepare(options: OutputOptions) -> Path:
    """Check the output folder (or the resumed one) before anything is computed; return it."""
    if options.resume:
        return _resume_folder(options.resume)
    return check_output_dir(options.out, options.overwrite)


def _resume_folder(out) -> Path:
    """The folder of ``--resume``; refused when it is not a run's (no summary.json: a
    checkpoint alone cannot say how to rebuild the run)."""
    out = Path(out)
    if not (out / SUMMARY).is_file():
        raise InputError(f"--resume {out}: no {SUMMARY} (nor {CHECKPOINT}) there: not the "
                         "folder of a run, nothing to resume from")
    return out


def has_checkpoint(folder) -> bool:
    """False for a run stopped before its first checkpoint: its resume runs it again from
    step 0 with the configuration its summary.json stores."""
    return (Path(folder) / CHECKPOINT).is_file()


def outcome(result, data: dict) -> dict:
    """The summary entries that come from the run itself."""
    return {
        "solver": result.solver, "steps": result.steps, "wall_time_s": result.wall_time_s,
        "us_per_step": 1e6 * result.wall_time_s / max(1, result.steps),
        "max_penetration": result.max_penetration,
        "max_penetration_below_g1": result.max_penetration_below,
        "max_penetration_above_g2": result.max_penetration_above,
        "max_nodal_violation": result.max_nodal_violation,
        "energy_final": float(data["energy"][-1]) if "energy" in data and data["energy"].size
        else None,
        # springs (the penalty law): their compression is the supports' deflection, the
        # physics of an elastic support, not a numerical error
        "max_support_deflection": result.max_penetration if result.springs else None,
        "impacts": result.impacts, "contact_fraction": result.contact_fraction,
        "qp_iterations": result.qp_iterations, "status": result.status,
        "message": result.message,
        # the process's peak resident memory so far (Linux: kB): flat in T, see KEEP_ROWS
        "peak_rss_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }


class _Signals:
    """SIGINT and SIGTERM set a flag, read between chunks: the run stops at a whole chunk,
    not in the middle of a write (a compiled chunk cannot be stopped anyway)."""

    def __init__(self):
        self.signum, self._old = None, {}

    def _catch(self, signum, frame):
        self.signum = signum

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                self._old[sig] = signal.signal(sig, self._catch)
        return self

    def __exit__(self, *exc):
        for sig, old in self._old.items():
            signal.signal(sig, old)
        return False


def _command(summary: dict) -> str:
    """The command that made the folder (a scene file's run stores its own)."""
    return summary.get("config", {}).get("command") \
        or f"python -m skfem_beam.cases.{summary.get('case', '<case>')}"


def execute(run: Run, options: OutputOptions, summary: dict, series, finish) -> int:
    """Drive ``run`` with streaming output into the folder of ``options`` (checked by
    :func:`prepare`); return the exit code.

    ``series``: a :class:`Series` (or just its ``columns`` function).  ``finish(folder,
    data, run)``: charts and extra files from the rows in memory (``data``: name →
    column); it may return summary entries, which override the run's own.

    SIGINT/SIGTERM stop the run at the next chunk: the rows and frames so far are kept,
    a checkpoint is written, summary.json says "interrupted", one line says how to resume,
    and the exit code is 130/143.  A failed write (full disk) cuts the series back to its
    last whole row, marks the folder "failed" and says what is kept (exit 3).
    """
    if not isinstance(series, Series):
        series = Series(series)
    out = Path(options.out)
    resume = bool(options.resume)
    every = options.checkpoint_every
    try:
        run.checkpoint()            # refuses a solver that cannot checkpoint: before any file
        can_checkpoint = True
    except InputError:
        if every is not None:
            raise
        can_checkpoint = False
    used, ck = 0, None
    restart = resume and not has_checkpoint(out)
    if resume and not restart:
        ck = read_checkpoint(out)       # checked again: the lock is held since the parse
        used = _restore(run, ck)
        # the checkpoint is the one truth: a resume that stops before its first new
        # checkpoint leaves a summary that still names it
        summary = {**summary, "checkpoint_step": int(ck["n"])}
    with _Signals() as stop:
        folder = Folder.open(out, summary, overwrite=options.overwrite, resume=resume)
        try:
            if restart:
                # nothing computed is kept without a checkpoint, and the configuration
                # is in hand (rebuilt from summary.json): the run starts again from step 0
                folder.clear()
                print(f"{out} had no checkpoint: running it again from step 0",
                      file=sys.stderr)
            return _stream(run, folder, options, series, finish, stop, used, ck,
                           can_checkpoint)
        finally:
            folder.release()


PHASES = ("last-chunk", "final-checkpoint", "charts", "impacts", "summary")
FIRST_CHUNK = "first-chunk"     # not one of PHASES (the end's, which the soak draws from)


def phase(name: str, before: Callable | None = None) -> None:
    """A test hook: the environment variable SKFEM_BEAM_KILL_AT=<name> (one of PHASES, the
    boundaries of a run's end, or FIRST_CHUNK: the loop's first chunk, before any
    checkpoint of a run without --checkpoint-every) makes the process SIGKILL itself
    there, as a scheduler or a power cut would (tests/test_resume.py resumes each to the
    uninterrupted files).  ``before``: called first, when the process is killed there."""
    if os.environ.get("SKFEM_BEAM_KILL_AT") == name:
        if before is not None:
            before()
        os.kill(os.getpid(), signal.SIGKILL)


def _stream(run, folder, options, series, finish, stop, used, ck, can_checkpoint) -> int:
    """The body of :func:`execute`, in the open ``folder``: the run to its end, or what a
    stop (signal, failed solver, failed write) leaves and says."""
    s = _Stream(run, folder, options, series, stop, used, ck, can_checkpoint)
    try:
        entries = s.to_the_end(finish)
    except Interrupted as e:
        return s.interrupted(e)
    except SolverError as e:
        # the loop stopped inside a chunk: its events reach the state before the failed step
        folder.fail(e, steps=run.n, **s.write_events(run.stopped_at - 1))
        raise
    except OSError as e:
        return s.failed_write(e)
    phase("summary")
    final = folder.close(**entries)
    code = report(final, folder.path)
    if stop.signum is not None:     # during the charts or the summary: nothing is missing
        name = signal.Signals(stop.signum).name
        print(f"interrupted by {name} after the run's last step: its results are complete "
              f"(status {final['status']})", file=sys.stderr)
        return 128 + stop.signum
    return code


def _once_fixed(e: OSError) -> str:
    """When a failed write can be retried, by its cause."""
    if e.errno in (errno.ENOSPC, errno.EDQUOT):
        return "once there is room"
    if e.errno in (errno.EPERM, errno.EACCES):
        return ("once its files can be written again (permissions, or an immutable file: "
                "lsattr, chattr -i)")
    if e.errno == errno.EROFS:
        return "once its filesystem is writable again"
    return "once that is fixed"


class _Stream:
    """A run streaming into its folder: rows and frames written after every chunk, the
    checkpoints, and the words of what is kept when it stops.

    The field frames of a run's first FRAMES_AFTER seconds wait in memory (the run holds
    them all anyway): a short run writes them after sending its charts, so that the chart
    process draws while this one writes (0.2 s of the 1.4 s of point stops at Δt = 5e-5,
    whose two chunks wrote their first frames before the charts could go); a stop writes
    them before it says what is kept."""

    def __init__(self, run, folder, options, series, stop, used, ck, can_checkpoint):
        self.run, self.folder, self.options, self.series = run, folder, options, series
        self.stop, self.used, self.ck, self.can_checkpoint = stop, used, ck, can_checkpoint
        self.started = self.last_ck = time.monotonic()
        self.rows = self.fields = None
        self.kept = int(ck["n"]) if ck is not None else None   # the last checkpoint's step

    def save_checkpoint(self) -> None:
        run, folder = self.run, self.folder
        self.rows.sync()
        write_checkpoint(folder / CHECKPOINT, _checkpoint(run, self.rows, self.used),
                         folder.summary["config"])
        self.kept = run.n
        folder.write(checkpoint_step=run.n)

    def on_chunk(self, run) -> None:
        k1 = self.series.rows_ready(run)
        if k1 > self.used:
            self.rows.append(self.series.columns(run, self.used, k1))
            self.used = k1
            run.release(self.used - 1)   # written: memory stays flat (one row kept before)
        stopping = self.stop.signum is not None and not run.done
        # the last frames, and a short run's: after the charts (class docstring)
        if not run.done and (stopping or time.monotonic() - self.started >= FRAMES_AFTER):
            self.write_frames(quiet=False)
        if stopping:
            raise Interrupted(self.stop.signum)
        if run.n and not run.done:      # in the loop, with more to compute: killed with
            phase(FIRST_CHUNK, before=self.rows.sync)   # its rows on disk (known state)
        every = self.options.checkpoint_every
        if every is not None and time.monotonic() - self.last_ck >= every and not run.done:
            self.save_checkpoint()
            self.last_ck = time.monotonic()

    def to_the_end(self, finish) -> dict:
        """Stream the run to its end, then the charts and impacts.csv: the summary's
        entries.  The charts are sent to the chart process (:mod:`..chart_process`) before
        the last chunk's field frames are written, so that both are made at once."""
        run, series, fmt = self.run, self.series, self.options.format
        try:
            self.rows = SeriesFile(self.folder / "timeseries.csv",
                                   list(series.columns(run, 0, 0)), keep=self.ck,
                                   limit=None if series.keep_all else KEEP_ROWS)
            self.fields = _Fields(self.folder.path, run, fmt, series) if fmt != "none" else None
            self.on_chunk(run)              # state 1's row (on resume: the rows so far)
            try:
                drive(run, chunk=self.options.flush_every, on_chunk=self.on_chunk)
            except (SolverError, InputError):   # a failed step (not a write refused: no
                self.write_frames()             # more writes) keeps the whole chunks' frames
                raise
            data = self.rows.data()
            entries = outcome(run.result(), data)
            try:
                entries.update(finish(self.folder.path, data, run) or {})
                if self.fields is not None:
                    self.fields.update()
                phase("last-chunk")
                if self.can_checkpoint and run.status == "success":
                    self.save_checkpoint()  # so that --resume DIR --T longer extends it
                    phase("final-checkpoint")
            except BaseException:
                chart_process.wait(quiet=True)   # no chart is drawn after the folder's end
                raise
        finally:
            if self.rows is not None:
                self.rows.close()
            if self.fields is not None:
                self.fields.close()
        chart_process.wait()
        phase("charts")
        entries.update(self.write_events(run.n, quiet=False))
        phase("impacts")
        return entries

    def write_frames(self, quiet: bool = True) -> None:
        """The frames up to the last whole chunk (``quiet``: none when the disk refuses
        them, in a run already stopping on an error)."""
        if self.fields is None:
            return
        try:
            self.fields.update()
        except OSError:
            if not quiet:
                raise

    def write_events(self, last: int, quiet: bool = True) -> dict:
        """impacts.csv of the events up to state ``last`` (its summary entries); nothing
        when the command has none, or (``quiet``, a run already stopping on an error) when
        the disk refuses it: that run's own error is the one to report."""
        if self.series.events is None:
            return {}
        try:
            return self.series.events(self.folder.path, self.run, last)
        except OSError:
            if not quiet:
                raise
            return {}

    def what_is_kept(self) -> str:
        run, rows, kept = self.run, self.rows, self.kept
        t = (rows.rows - 1) * run.save_every * run.dt if rows is not None and rows.rows else 0.0
        ck_line = (f"the checkpoint at step {kept} (t={kept * run.dt:.6g} s)"
                   if kept is not None else "no checkpoint")
        frames = f", {self.fields.written} field frames" if self.fields is not None else ""
        return (f"kept {rows.rows if rows is not None else 0} whole rows of timeseries.csv "
                f"(to t={t:.6g} s){frames} and {ck_line} in {self.folder.path}")

    def interrupted(self, e: Interrupted) -> int:
        """SIGINT/SIGTERM between chunks: a checkpoint, status "interrupted", one line."""
        run, folder = self.run, self.folder
        name, why = signal.Signals(e.signum).name, ""
        if self.can_checkpoint:
            try:
                self.save_checkpoint()
            except OSError as err:
                why = f" (no new checkpoint: {err.strerror})"
        entries = outcome(run.result(), self.rows.data())
        entries.update(self.write_events(run.n))
        folder.close(**{**entries, "status": "interrupted", "steps": run.n,
                        "message": f"interrupted by {name} at step {run.n} "
                                   f"(t={run.n * run.dt:.6g} s)"})
        resume = (f"continue with: {_command(folder.summary)} --resume {folder.path}"
                  if self.kept is not None else "no checkpoint: run it again from step 0 "
                  f"with: {_command(folder.summary)} --resume {folder.path}")
        print(f"interrupted by {name}: {self.what_is_kept()}{why}; {resume}", file=sys.stderr)
        return e.code

    def failed_write(self, e: OSError) -> int:
        """A write refused (full disk, ...): status "failed", what is kept, exit 3."""
        run, folder = self.run, self.folder
        folder.fail(e, steps=run.n, kept=self.what_is_kept(), **self.write_events(run.n))
        resume = (f"{_once_fixed(e)}, continue with: {_command(folder.summary)} --resume "
                  f"{folder.path}" if self.kept is not None else
                  f"{_once_fixed(e)}, with no checkpoint (--checkpoint-every) run it again "
                  f"from step 0 with: {_command(folder.summary)} --resume {folder.path}")
        print(f"error: could not write the results: {e}; {self.what_is_kept()}; {resume}",
              file=sys.stderr)
        return EXIT_SOLVER
