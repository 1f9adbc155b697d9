"""Checkpoints and resume: a run's full state in ``checkpoint.npz``, and the checks that a
folder can be resumed.

With ``--checkpoint-every S`` the run's full state is written atomically (write, then
rename) to ``checkpoint.npz``, with the rows of ``timeseries.csv`` written so far (their
size and CRC) and the saved rows the series has not used yet.  ``--resume DIR`` rebuilds the
same run from ``summary.json``, restores the checkpoint, cuts the series back to it and
continues (:mod:`.stream`): the result is identical, bit for bit, to an uninterrupted run.
"""
from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..results import CHECKPOINT  # noqa: F401 (the name a folder's reader knows too)
from ..scheme import Run
from .folder import SUMMARY, _plain, check_writable
from .series import SeriesFile, file_crc

CHECKPOINT_FORMAT = 3       # 3: impact events hold their first step off (State.impact)
BUFFERS = ("obs", "obsv", "energy", "work", "lam")   # saved series (not in the Run's checkpoint)


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
    except (OSError, ValueError) as e:   # UnicodeDecodeError and JSONDecodeError included
        summary = e
    if isinstance(summary, dict) and "config" not in summary \
            and isinstance(summary.get("command"), str):     # `modes`' folder
        raise InputError(f"{folder} holds the results of `{summary['command']}`, not a run: "
                         "there is nothing to resume, nothing was changed")
    if not isinstance(summary, dict) or not isinstance(summary.get("config"), dict):
        e = summary if isinstance(summary, Exception) else ValueError("no 'config' object")
        raise InputError(f"{path} is not a readable summary ({type(e).__name__}: {e}); "
                         "cannot resume, nothing was changed")
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
    if size < 0:
        raise InputError(f"{csv} is missing: the checkpoint's {int(ck['rows'])} rows are "
                         "not there; cannot resume")
    if size < nbytes:
        raise InputError(f"{csv} has {size} bytes, fewer than the {nbytes} of the "
                         f"checkpoint's {int(ck['rows'])} rows; cannot resume")
    if file_crc(csv, nbytes) != int(ck["crc"]):
        raise InputError(f"{csv}: its first {int(ck['rows'])} rows are not the ones the "
                         "checkpoint was written with; cannot resume, nothing was changed")


def _longer(a, b) -> bool:
    return isinstance(a, (int, float)) and isinstance(b, (int, float)) and a > b


def checkpoint_of(run: Run, rows: SeriesFile, used: int) -> dict:
    """The run's state, the rows written, and the saved rows the series has not used yet
    (and one before them): a resumed run computes only what comes after the checkpoint."""
    first = max(0, used - 1)
    keep = run.n // run.save_every + 1
    pending = {f"pending_{k}": getattr(run, k)[first:keep] for k in BUFFERS}
    return {**run.checkpoint(), "rows": rows.rows, "nbytes": rows.nbytes, "crc": rows.crc,
            "used": used, "pending_from": first, **pending, **rows.envelope()}


def restore(run: Run, ck: dict) -> int:
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



def _resume_folder(out) -> Path:
    """The folder of ``--resume``; refused when it is not a run's (no summary.json: a
    checkpoint alone cannot say how to rebuild the run)."""
    out = Path(out)
    if not out.is_dir():        # it said "no summary.json there"
        raise InputError(f"--resume {out}: no such folder")
    if not (out / SUMMARY).is_file():
        why = (f"its {CHECKPOINT} alone cannot say how to rebuild the run"
               if (out / CHECKPOINT).is_file() else "not the folder of a run")
        raise InputError(f"--resume {out}: no {SUMMARY} there: {why}; nothing to resume "
                         "from")
    read_summary(out)       # before its lock: a folder of `modes` is not a run's
    # a read-only one failed at its lock, exit 3, "could not write the results"
    check_writable(out, f"--resume {out}: the folder")
    return out


def has_checkpoint(folder) -> bool:
    """False for a run stopped before its first checkpoint: its resume runs it again from
    step 0 with the configuration its summary.json stores."""
    return (Path(folder) / CHECKPOINT).is_file()
