"""An output folder and its summary: checked before anything is written, one status.

Every command writes through :class:`Folder`.  The folder is made only after every
input has been checked (:func:`check_output_dir` is the last check), so bad input leaves
nothing behind.  Its ``summary.json`` says ``"running"`` from the start, and at the end
``"success"`` or ``"unstable"`` (the run's own status), or ``"failed"`` with the error's
message when a solver fails or the disk is full.  A killed command leaves ``"running"``.
"""
from __future__ import annotations

import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from .. import __version__
from ..errors import InputError, SolverError

EXIT_INPUT, EXIT_SOLVER, EXIT_UNSTABLE = 2, 3, 4
SUMMARY = "summary.json"


def check_output_dir(out: str | os.PathLike, overwrite: bool = False) -> Path:
    """Refuse an ``--out`` that cannot be written, or holds another run (unless overwrite)."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out} exists and is not a folder")
    if out.is_dir() and any(out.iterdir()) and not overwrite:
        raise InputError(f"--out {out} already holds files; pass --overwrite to replace them")
    # missing parents are made when the run starts (after every check); probe the
    # nearest folder that exists: permission bits say little (root, read-only mounts, /proc)
    parent = out.resolve().parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(f"--out {out}: {parent} is not a folder")
    try:
        os.rmdir(tempfile.mkdtemp(prefix=f".{out.name}.", dir=parent))
    except OSError as e:
        raise InputError(f"--out {out}: folder {parent} is not writable ({e.strerror})") from None
    return out


def stamp() -> dict:
    """The package version and the time of writing, for every summary."""
    return {"package_version": __version__, "written": time.strftime("%Y-%m-%dT%H:%M:%S%z")}


def _plain(value):
    """JSON-friendly: numpy scalars to Python, non-finite floats to strings."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return str(value)
    return value


def atomic_write(path: Path, write) -> None:
    """``write(fh)`` into a hidden sibling of ``path``, then rename it into place."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "w", newline="") as fh:
            write(fh)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_json(path: Path, data: dict) -> None:
    """``data`` as indented JSON (numpy scalars and non-finite floats made plain)."""
    def write(fh):
        json.dump(_plain(data), fh, indent=2, ensure_ascii=False)
        fh.write("\n")
    atomic_write(Path(path), write)


def write_summary(folder: Path, summary: dict) -> None:
    write_json(Path(folder) / SUMMARY, summary)


def csv_rows(columns: dict, names: list[str]) -> str:
    """Rows of equal-length columns as CSV text, every value to 17 digits (exact round trip)."""
    data = np.column_stack([np.asarray(columns[k], dtype=float) for k in names])
    return "".join(",".join(f"{v:.17g}" for v in row) + "\n" for row in data)


def write_timeseries(folder: Path, columns: dict[str, np.ndarray],
                     name: str = "timeseries.csv") -> None:
    """One CSV with a header row; columns of equal length."""
    with open(Path(folder) / name, "w") as fh:
        fh.write(",".join(columns) + "\n" + csv_rows(columns, list(columns)))


class Folder:
    """The output folder of one command and the status in its ``summary.json``.

    ``Folder.open(out, summary, overwrite)`` after every check: makes the folder (replacing
    it with ``overwrite``) and writes the summary with status "running"; ``resume=True``
    reopens a folder a killed command left.  Used as a context manager, a solver error or
    an OSError inside marks it "failed" (and propagates); :meth:`close` writes the final
    summary.
    """

    def __init__(self, path: Path, summary: dict):
        self.path, self.summary = Path(path), dict(summary)

    @classmethod
    def open(cls, out, summary: dict, overwrite: bool = False, resume: bool = False) -> "Folder":
        out = Path(out)
        if not resume:
            if out.exists() and overwrite:
                shutil.rmtree(out)
            out.mkdir(parents=True, exist_ok=True)
        folder = cls(out, summary)
        folder.write(status="running", **stamp())
        return folder

    def __truediv__(self, name: str) -> Path:
        return self.path / name

    def write(self, **entries) -> None:
        self.summary.update(entries)
        write_summary(self.path, self.summary)

    def fail(self, error: BaseException, **entries) -> None:
        """Mark the folder "failed" (quietly, if even that cannot be written: a full disk)."""
        try:
            self.write(status="failed", message=str(error), **entries)
        except OSError:
            pass

    def close(self, status: str = "success", **entries) -> dict:
        """The final summary: ``entries`` and the status, with the version stamp."""
        self.write(**{"status": status, **entries, **stamp()})
        return self.summary

    def __enter__(self):
        return self

    def __exit__(self, kind, error, tb):
        if isinstance(error, (SolverError, OSError)):
            self.fail(error)
        return False


def report(summary: dict, out) -> int:
    """One line for a finished run (stdout, or stderr when it went unstable); the exit code."""
    steps, wall = summary["steps"], summary["wall_time_s"]
    if summary["status"] != "success":
        print(f"error: {summary['message']}; results up to t={steps * summary['dt']:.6g} s "
              f"written to {out}", file=sys.stderr)
        return EXIT_UNSTABLE
    print(f"{steps} steps in {wall:.3g} s ({1e6 * wall / max(1, steps):.3g} µs/step), "
          f"{summary['impacts']} impacts, max nodal violation "
          f"{summary['max_nodal_violation']:.2e} m -> {out}")
    return 0
