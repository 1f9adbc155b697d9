"""Output folders that are never half written, and the files of the output contract.

A run writes into a hidden sibling folder and renames it into place at the end, so a
failed or interrupted run leaves no partial ``--out`` folder behind.
"""
from __future__ import annotations

import json
import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from .errors import InputError


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


@contextmanager
def output_dir(out: str | os.PathLike, overwrite: bool = False):
    """Yield a temporary folder; on success it replaces ``out`` in one rename."""
    out = check_output_dir(out, overwrite)
    out.resolve().parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.resolve().parent))
    try:
        yield tmp
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    if out.exists():
        shutil.rmtree(out)
    os.replace(tmp, out)


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


def write_summary(folder: Path, summary: dict) -> None:
    with open(folder / "summary.json", "w") as fh:
        json.dump(_plain(summary), fh, indent=2, ensure_ascii=False)
        fh.write("\n")


def csv_rows(columns: dict, names: list[str]) -> str:
    """Rows of equal-length columns as CSV text, every value to 17 digits (exact round trip)."""
    data = np.column_stack([np.asarray(columns[k], dtype=float) for k in names])
    return "".join(",".join(f"{v:.17g}" for v in row) + "\n" for row in data)


def write_timeseries(folder: Path, columns: dict[str, np.ndarray],
                     name: str = "timeseries.csv") -> None:
    """One CSV with a header row; columns of equal length."""
    with open(folder / name, "w") as fh:
        fh.write(",".join(columns) + "\n" + csv_rows(columns, list(columns)))
