"""Running a case so that a long run loses nothing.

The output folder is created only after every input has been checked (bad input leaves
nothing behind).  Then ``summary.json`` says "running", ``timeseries.csv`` grows by
whole rows after every chunk (flushed and fsynced: a run killed at any moment leaves a
readable file up to its last flush), and, with ``--checkpoint-every S``, the integrator's
full state is written atomically (write, then rename) to ``checkpoint.npz``.
``--resume DIR`` rebuilds the same run from ``summary.json``, restores the checkpoint,
cuts the series back to it and continues: the result is identical, bit for bit, to an
uninterrupted run (values are written with 17 significant digits).
"""
from __future__ import annotations

import json
import os
import shutil
import time
from pathlib import Path

import numpy as np

from . import cli
from .errors import InputError, SolverError
from .fields import FieldWriter, check_format
from .integrators import Run, drive
from .io import check_output_dir, csv_rows, write_summary

CHECKPOINT = "checkpoint.npz"


class SeriesFile:
    """timeseries.csv written as the run goes: whole rows only, flushed per chunk."""

    def __init__(self, path: Path, names: list[str], keep_rows: int | None = None):
        self.path, self.names = path, names
        if keep_rows is None:
            self.fh = open(path, "w")
            self.fh.write(",".join(names) + "\n")
            self.rows = 0
        else:   # resume: keep the header and the first keep_rows rows, drop the rest
            with open(path, "rb") as fh:
                lines = fh.read().split(b"\n")
            if len(lines) < keep_rows + 1:
                raise InputError(f"{path} has fewer rows than its checkpoint: cannot resume")
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

    def sync(self) -> None:
        self.fh.flush()
        os.fsync(self.fh.fileno())

    def close(self) -> None:
        self.sync()
        self.fh.close()


def _atomic_savez(path: Path, **arrays) -> None:
    tmp = path.with_name(path.name + ".tmp.npz")
    np.savez(tmp, **arrays)
    with open(tmp, "rb") as fh:
        os.fsync(fh.fileno())
    os.replace(tmp, path)


def prepare(args) -> Path:
    """Check ``--out`` (or the ``--resume`` folder) before anything is computed."""
    if getattr(args, "resume", None):
        out = Path(args.resume)
        if not (out / CHECKPOINT).is_file() or not (out / "summary.json").is_file():
            raise InputError(f"--resume {out}: no {CHECKPOINT} and summary.json there to resume from")
        return out
    if getattr(args, "checkpoint_every", None) is not None and args.checkpoint_every < 0:
        raise InputError(f"--checkpoint-every={args.checkpoint_every:g} must be ≥ 0 seconds")
    check_format(getattr(args, "format", "none"))
    if getattr(args, "flush_every", 1) < 1:
        raise InputError(f"--flush-every={args.flush_every} must be a whole number ≥ 1")
    return check_output_dir(args.out, args.overwrite)


def execute(run: Run, out: Path, args, summary: dict, columns, finish, resume: bool = False) -> int:
    """Drive ``run`` with streaming output into ``out``; return the exit code.

    ``columns(run, k0, k1)``: the series rows for saved states k0..k1−1 (a dict).
    ``finish(folder, data, run)``: charts and extra files, from the series read back.
    """
    names = list(columns(run, 0, 0))
    series_path = out / "timeseries.csv"
    if resume:
        ck = dict(np.load(out / CHECKPOINT))
        run.restore(ck)
        series = SeriesFile(series_path, names, keep_rows=int(ck["rows"]))
    else:
        if out.exists():
            shutil.rmtree(out)          # --overwrite was given (prepare checked)
        out.mkdir(parents=True)
        write_summary(out, {**summary, "status": "running"})
        series = SeriesFile(series_path, names)
    every = getattr(args, "checkpoint_every", None)
    last_ck = time.monotonic()
    fmt = getattr(args, "format", "none")
    # fields: on resume the frames come back with the checkpoint and are written anew
    fields = FieldWriter(out, run.system, fmt) if fmt != "none" else None
    frames_written = 0

    def on_chunk(run):
        nonlocal last_ck, frames_written
        k1 = run.n // run.save_every + 1
        series.append(columns(run, series.rows, k1))
        series.sync()
        if fields is not None:
            for k in range(frames_written, run.n // run.frame_every + 1):
                fields.write(k * run.frame_every * run.dt, run.fr[k], run.frv[k], run.frf[k])
            frames_written = run.n // run.frame_every + 1
            fields.flush()
        if every is not None and time.monotonic() - last_ck >= every and not run.done:
            _atomic_savez(out / CHECKPOINT, rows=series.rows, **run.checkpoint())
            last_ck = time.monotonic()

    try:
        on_chunk(run)                      # state 1 (and, on resume, the frames so far)
        drive(run, chunk=getattr(args, "flush_every", 20000), on_chunk=on_chunk)
    except (SolverError, OSError) as e:
        series.close()
        if fields is not None:
            fields.close()
        write_summary(out, {**summary, "status": "failed", "message": str(e), "steps": run.n})
        raise
    series.close()
    if fields is not None:
        fields.close()
    result = run.result()
    data = np.genfromtxt(series_path, delimiter=",", names=True)
    data = {k: np.atleast_1d(data[k]) for k in data.dtype.names}
    write_summary(out, {**summary, **outcome(result, data), **cli.stamp()})
    finish(out, data, run)
    return cli.report(result, out)


def outcome(result, data) -> dict:
    """The summary entries that come from the run itself."""
    return {
        "solver": result.solver, "steps": result.steps, "wall_time_s": result.wall_time_s,
        "us_per_step": 1e6 * result.wall_time_s / max(1, result.steps),
        "max_penetration": result.max_penetration,
        "max_penetration_below_g1": result.max_penetration_below,
        "max_penetration_above_g2": result.max_penetration_above,
        "max_nodal_violation": result.max_nodal_violation,
        "energy_final": float(data["energy"][-1]) if "energy" in data else None,
        "impacts": result.impacts, "contact_fraction": result.contact_fraction,
        "qp_iterations": result.qp_iterations, "status": result.status,
        "message": result.message,
    }


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
