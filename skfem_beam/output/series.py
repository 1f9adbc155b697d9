"""Running a command's :class:`~skfem_beam.scheme.Run` so that a long run loses nothing.

One pipeline for the beam scenes and the bar.  After every input has been checked the
output :class:`~.folder.Folder` is made (summary "running"); ``timeseries.csv`` grows by
whole rows after every chunk (flushed and fsynced: a run killed at any moment leaves a
readable file up to its last flush) and the rows are also kept in memory for the charts
and the summary; the field frames are written as they come.  With ``--checkpoint-every
S`` the run's full state is written atomically (write, then rename) to
``checkpoint.npz``.  ``--resume DIR`` rebuilds the same run from ``summary.json``,
restores the checkpoint, cuts the series back to it and continues: the result is
identical, bit for bit, to an uninterrupted run (values are written with 17 significant
digits).

What a command streams is a :class:`Series`: its columns, computed from the run's saved
buffers, and which field frames to write.
"""
from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ..errors import InputError, SolverError
from ..scheme import Run, drive
from .fields import FieldWriter, check_format
from .folder import Folder, check_output_dir, csv_rows, report

CHECKPOINT = "checkpoint.npz"
BUFFERS = ("obs", "obsv", "energy", "lam")   # the run's saved series (not in its checkpoint)


class SeriesFile:
    """timeseries.csv written as the run goes (whole rows only, flushed per chunk), and the
    same rows kept in memory (:meth:`data`), so nothing is read back from the file."""

    def __init__(self, path: Path, names: list[str], keep_rows: int | None = None):
        self.path, self.names = path, names
        self._chunks: list[dict] = []
        if keep_rows is None:
            self.fh = open(path, "w")
            self.fh.write(",".join(names) + "\n")
            self.rows = 0
        else:   # resume: keep the header and the first keep_rows rows, drop the rest
            with open(path, "rb") as fh:
                lines = fh.read().split(b"\n")
            if len(lines) < keep_rows + 1:
                raise InputError(f"{path} has fewer rows than its checkpoint: cannot resume")
            kept = lines[1:keep_rows + 1]
            # the rows a killed process wrote come back exactly (17 digits round-trip)
            values = np.array([[float(v) for v in row.split(b",")] for row in kept]) \
                .reshape(len(kept), len(names))
            self._chunks.append({k: values[:, i] for i, k in enumerate(names)})
            self.fh = open(path, "wb")
            self.fh.write(b"\n".join(lines[:keep_rows + 1]) + b"\n")
            self.fh.close()
            self.fh = open(path, "a")
            self.rows = keep_rows
        self.sync()

    def append(self, columns: dict) -> None:
        text = csv_rows(columns, self.names)
        self.fh.write(text)
        self.rows += text.count("\n")
        self._chunks.append({k: np.asarray(columns[k], dtype=float) for k in self.names})

    def data(self) -> dict[str, np.ndarray]:
        """Every row written so far, as columns."""
        return {k: np.concatenate([c[k] for c in self._chunks] or [np.zeros(0)])
                for k in self.names}

    def sync(self) -> None:
        self.fh.flush()
        os.fsync(self.fh.fileno())

    def close(self) -> None:
        if not self.fh.closed:
            self.sync()
            self.fh.close()


@dataclass
class Series:
    """What a command streams from its run.

    ``columns(run, k0, k1)``: the timeseries rows (a dict of columns; it may keep only some
    of them) for the run's saved rows k0..k1−1; ``ready(run)``: how many saved rows are final
    (default: all computed so far); ``field_every``: steps between field frames, a multiple
    of ``run.frame_every`` (0: every frame the run keeps); ``field_until``: the last step
    with a frame (None: the run's end).
    """
    columns: Callable
    ready: Callable | None = None
    field_every: int = 0
    field_until: int | None = None

    def rows_ready(self, run: Run) -> int:
        return self.ready(run) if self.ready is not None else run.n // run.save_every + 1


class _Fields:
    """The field frames of a run, written as they are computed."""

    def __init__(self, folder: Path, run: Run, fmt: str, series: Series):
        self.run, self.writer = run, FieldWriter(folder, run.system, fmt)
        every = series.field_every or run.frame_every
        if every % run.frame_every:
            raise InputError(f"field frames every {every} steps are not kept by the run "
                             f"(it keeps every {run.frame_every}-th)")
        self.every, self.until, self.written = every, series.field_until, 0

    def update(self) -> None:
        run, stride = self.run, self.every // self.run.frame_every
        last = run.n if self.until is None else min(run.n, self.until)
        for k in range(self.written, last // self.every + 1):
            i = k * stride
            self.writer.write(k * self.every * run.dt, run.fr[i], run.frv[i], run.frf[i])
        self.written = max(self.written, last // self.every + 1)
        self.writer.flush()

    def close(self) -> None:
        self.writer.close()


def _atomic_savez(path: Path, **arrays) -> None:
    tmp = path.with_name(path.name + ".tmp.npz")
    np.savez(tmp, **arrays)
    with open(tmp, "rb") as fh:
        os.fsync(fh.fileno())
    os.replace(tmp, path)


def _checkpoint(run: Run, rows: int, used: int) -> dict:
    """The run's state, the rows written, and the saved rows the series has not used yet
    (and one before them): a resumed run computes only what comes after the checkpoint."""
    first = max(0, used - 1)
    keep = run.n // run.save_every + 1
    pending = {f"pending_{k}": getattr(run, k)[first:keep] for k in BUFFERS}
    return {**run.checkpoint(), "rows": rows, "used": used, "pending_from": first, **pending}


def _restore(run: Run, ck: dict) -> int:
    """Restore ``run`` from a checkpoint; return the saved rows the series has used."""
    run.restore(ck)
    first = int(ck.get("pending_from", 0))
    for k in BUFFERS:
        if f"pending_{k}" in ck:
            part = ck[f"pending_{k}"]
            getattr(run, k)[first:first + len(part)] = part
    return int(ck.get("used", ck["rows"]))


def prepare(args) -> Path:
    """Check ``--out`` (or the ``--resume`` folder) and the output flags before anything is
    computed; return the folder."""
    if getattr(args, "resume", None):
        out = Path(args.resume)
        if not (out / CHECKPOINT).is_file() or not (out / "summary.json").is_file():
            raise InputError(f"--resume {out}: no {CHECKPOINT} and summary.json there to resume from")
        return out
    if getattr(args, "checkpoint_every", None) is not None and not args.checkpoint_every >= 0:
        raise InputError(f"--checkpoint-every={args.checkpoint_every:g} must be ≥ 0 seconds")
    check_format(getattr(args, "format", "none"))
    for flag in ("flush_every", "frames"):
        value = getattr(args, flag, 1)
        if isinstance(value, bool) or int(value) != value or value < 1:
            raise InputError(f"--{flag.replace('_', '-')}={value} must be a whole number ≥ 1")
    return check_output_dir(args.out, args.overwrite)


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
        "impacts": result.impacts, "contact_fraction": result.contact_fraction,
        "qp_iterations": result.qp_iterations, "status": result.status,
        "message": result.message,
    }


def execute(run: Run, out: Path, args, summary: dict, series, finish) -> int:
    """Drive ``run`` with streaming output into ``out``; return the exit code.

    ``series``: a :class:`Series` (or just its ``columns`` function).  ``finish(folder,
    data, run)``: charts and extra files from the rows in memory (``data``: name →
    column); it may return summary entries, which override the run's own.
    """
    if not isinstance(series, Series):
        series = Series(series)
    resume = bool(getattr(args, "resume", None))
    every = getattr(args, "checkpoint_every", None)
    if every is not None:
        run.checkpoint()            # refuses a solver that cannot checkpoint: before any file
    names = list(series.columns(run, 0, 0))
    used = 0
    if resume:
        ck = dict(np.load(Path(out) / CHECKPOINT))
        used = _restore(run, ck)
        folder = Folder.open(out, summary, resume=True)
        rows = SeriesFile(folder / "timeseries.csv", names, keep_rows=int(ck["rows"]))
    else:
        folder = Folder.open(out, summary, overwrite=getattr(args, "overwrite", False))
        rows = SeriesFile(folder / "timeseries.csv", names)
    fmt = getattr(args, "format", "none")
    last_ck = time.monotonic()
    fields = None

    def on_chunk(run):
        nonlocal last_ck, used
        k1 = series.rows_ready(run)
        if k1 > used:
            rows.append(series.columns(run, used, k1))
            used = k1
        rows.sync()
        if fields is not None:
            fields.update()
        if every is not None and time.monotonic() - last_ck >= every and not run.done:
            _atomic_savez(folder / CHECKPOINT, **_checkpoint(run, rows.rows, used))
            last_ck = time.monotonic()

    try:
        try:
            fields = _Fields(folder.path, run, fmt, series) if fmt != "none" else None
            on_chunk(run)                      # state 1 (and, on resume, the frames so far)
            drive(run, chunk=getattr(args, "flush_every", 20000), on_chunk=on_chunk)
        finally:
            rows.close()
            if fields is not None:
                fields.close()
        data = rows.data()
        entries = outcome(run.result(), data)
        entries.update(finish(folder.path, data, run) or {})
    except (SolverError, OSError) as e:
        folder.fail(e, steps=run.n)
        raise
    final = folder.close(**entries)
    return report(final, out)


def stored_args(args, parser):
    """For ``--resume DIR``: the flags of the run stored in DIR/summary.json."""
    if not getattr(args, "resume", None):
        return args
    prepare(args)
    config = json.loads((Path(args.resume) / "summary.json").read_text()).get("config", {})
    stored = vars(parser.parse_args([]))
    for k in stored:
        if k in config:
            stored[k] = config[k]
    stored.update(resume=args.resume, out=args.resume, overwrite=False)
    return type(args)(**stored)
