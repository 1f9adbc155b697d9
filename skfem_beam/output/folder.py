"""An output folder and its summary: checked before anything is written, one status.

Every command writes through :class:`Folder`.  The folder is made only after every
input has been checked (:func:`check_output_dir` is the last check), so bad input leaves
nothing behind.  Its ``summary.json`` says ``"running"`` from the start, and at the end
``"success"`` or ``"unstable"`` (the run's own status), ``"interrupted"`` (SIGINT, SIGTERM),
or ``"failed"`` with the error's message when a solver fails or the disk is full.  A
killed command (SIGKILL, power cut) leaves ``"running"``.

One writer per folder: a run holds an exclusive ``flock`` on ``DIR/.lock`` from before its
first file until it ends (the kernel drops it with the process, so a killed run never
blocks the next one); a second run or resume into the same folder is refused.
"""
from __future__ import annotations

import fcntl
import fnmatch
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import orjson

from .._version import __version__
from ..errors import (EXIT_INPUT, EXIT_SOLVER, EXIT_UNSTABLE,  # noqa: F401 (here too)
                      InputError, Interrupted, SolverError)
from ..lock import LOCK, check_not_busy, lock_folder, release  # noqa: F401 (here too)

SUMMARY = "summary.json"
NO_MEMORY = "not enough memory for this run"     # a MemoryError's line (cli.main_guard)
RESERVE = ".reserve"    # a little disk kept back, freed to write the final summary
OURS = (LOCK, RESERVE)
# atomic writes' temporaries, .NAME.PID.tmp (atomic_write), .NAME.PID.tmp.npz (numpy's
# savez adds .npz: the checkpoint's) and an export's .STEM.PID.tmp.npz or .mat: a process
# killed while writing one leaves it
TEMPORARIES = (".*.tmp", ".*.tmp.npz", ".*.tmp.mat")
# what the project's commands write in a folder, by name, which --overwrite may remove:
# anything else there (a user's notes, a .git, their own CSV, an export's .mat) is named and
# the run refused, not deleted
WRITTEN = (
    "summary.json", "timeseries.csv", "impacts.csv", "checkpoint.npz", "modes.csv",
    "fields.xdmf", "fields.h5", "fields.pvd", "fields_vtu",
    "poincare.csv", "runs.csv", "sweep.json", "runs", "bifurcation.png",      # a sweep's
    "stability_map.csv", "stability_map.png",
    "beam_shapes.png", "contact_force.png", "deflection.png", "displacement.png",  # charts
    "energy.csv", "energy.png", "energy_decay.png", "probes.png", "tip_displacement.png",
    "orbit_[0-9]*.png", "wear_[0-9]*.png",          # per support x: orbit_0.5.png
    *OURS, *TEMPORARIES)
# what the run's own subfolders hold (a user's file in one was deleted with it)
WRITTEN_INSIDE = {"fields_vtu": ("fields_[0-9]*.vtu", *TEMPORARIES),
                  "runs": ("*=*.json", *TEMPORARIES)}
NAME_MAX = 255          # bytes of one file name (Linux, macOS, Windows' NTFS in characters)
OPENED: list[Path] = []         # the folders this process opened (for the interrupt line)


def _make_locked(out: Path) -> None:
    """Create ``out`` (and parents) and lock it.  The parent folder is flock'ed meanwhile,
    so two runs creating the same folder at once are ordered: the second finds it locked."""
    parent = out.resolve().parent
    parent.mkdir(parents=True, exist_ok=True)
    pfd = os.open(parent, os.O_RDONLY)
    try:
        fcntl.flock(pfd, fcntl.LOCK_EX)      # held for a mkdir and a lock only
        out.mkdir(exist_ok=True)
        lock_folder(out)
    finally:
        os.close(pfd)


def check_output_dir(out: str | os.PathLike, overwrite: bool = False) -> Path:
    """Refuse an ``--out`` that cannot be written, or holds another run (unless overwrite)."""
    if not str(out).strip():    # Path("") is ".": the run's files landed in the cwd
        raise InputError(f"--out {str(out)!r} is empty: name the run's folder")
    out = Path(out)
    longest = max((len(p.encode()) for p in out.parts), default=0)
    if longest > NAME_MAX:      # the checks below raised ENAMETOOLONG: exit 3, not 2
        raise InputError(f"--out {out}: a name of {longest} bytes, more than a file name "
                         f"may have ({NAME_MAX})")
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out} exists and is not a folder")
    if out.is_dir():
        check_not_busy(out)
    if out.is_dir() and _holds_files(out):
        _check_replaceable(out, overwrite)
    # missing parents are made when the run starts (after every check); probe the folder
    # itself when it exists (a writable one in a read-only parent is fine, a read-only one
    # failed later with exit 3), else the nearest parent that exists
    parent = out.resolve() if out.is_dir() else out.resolve().parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(f"--out {out}: {parent} is not a folder")
    check_writable(parent, f"--out {out}: folder {parent}")
    return out


def check_writable(folder: Path, what: str) -> None:
    """Refuse, in one line ("``what`` is not writable"), a folder nothing can be written
    in: tried, since permission bits say little (root, read-only mounts, /proc)."""
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".probe.", dir=folder))   # not out's name: a long
        # name of 250 bytes, legal, passed 255 with the probe's prefix and was refused
    except OSError as e:
        raise InputError(f"{what} is not writable ({e.strerror})") from None


def _holds_files(out: Path) -> bool:
    return any(p.name not in OURS for p in out.iterdir())


def _check_replaceable(out: Path, overwrite: bool) -> None:
    """Refuse a folder holding files, unless ``overwrite`` and an earlier run wrote it
    (its summary.json says so): --overwrite empties the folder, and must not take a
    user's own files with it (``--out .`` in a folder of notes)."""
    if not overwrite:
        raise InputError(f"--out {out} already holds files; pass --overwrite to replace them")
    try:
        ours = "package_version" in json.loads((out / SUMMARY).read_text())
    except (OSError, ValueError, TypeError):
        ours = False
    if not ours:
        raise InputError(f"--out {out} holds files no run wrote ({_shown(out, OURS)}); "
                         f"--overwrite replaces only a run's folder (one with its {SUMMARY}): "
                         f"choose a new or empty folder")
    foreign = _shown(out)
    if foreign:
        raise InputError(f"--out {out} holds files besides the run's ({foreign}): --overwrite "
                         "replaces only what a run writes; move them out or choose another "
                         "folder")


def check_clearable(out: Path) -> None:
    """A stopped run's folder to be started again from step 0 (``Folder.clear``) holds
    only what runs write: files of the user's (an export's .mat, notes) are named and the
    resume refused, as --overwrite does (they went with the run's)."""
    foreign = _shown(out)
    if foreign:
        raise InputError(f"--resume {out}: it has no checkpoint, so the run starts again "
                         f"from step 0 and replaces what a run writes; the folder also "
                         f"holds files of yours ({foreign}): move them out first")


def _shown(out: Path, ours=None) -> str:
    """The first three names in ``out`` that are not ``ours`` (None: not a name a run
    writes, WRITTEN, nor in the run's subfolders WRITTEN_INSIDE), for an error line (""
    when there is none)."""
    def theirs(name: str, written=WRITTEN) -> bool:
        return name not in ours if ours is not None else \
            not any(fnmatch.fnmatch(name, w) for w in written)
    names = [p.name for p in out.iterdir() if theirs(p.name)]
    if ours is None:
        for sub, written in WRITTEN_INSIDE.items():
            if (out / sub).is_dir() and not (out / sub).is_symlink():
                names += [f"{sub}/{p.name}" for p in (out / sub).iterdir()
                          if p.is_dir() or theirs(p.name, written)]
    names = sorted(names)
    return ", ".join(names[:3]) + (", …" if len(names) > 3 else "")


def _remove_temporaries(out: Path) -> None:
    """Remove the temporaries a killed process left in ``out`` (TEMPORARIES): a resumed
    run then ends with the files of a run never stopped."""
    for p in out.iterdir():
        if p.is_file() and any(fnmatch.fnmatch(p.name, t) for t in TEMPORARIES):
            p.unlink(missing_ok=True)


def _empty(out: Path, keep: tuple[str, ...]) -> None:
    """Remove everything in folder ``out`` but the names in ``keep``."""
    for p in out.iterdir():
        if p.name not in keep:
            shutil.rmtree(p) if p.is_dir() and not p.is_symlink() else p.unlink()


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


def atomic_write(path: Path, write, binary: bool = False) -> None:
    """``write(fh)`` into a hidden sibling of ``path``, then rename it into place (a reader,
    or a run killed meanwhile, sees the old file or the new one, never half of one)."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with (open(tmp, "wb") if binary else open(tmp, "w", newline="")) as fh:
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


def csv_rows(columns: dict, names: list[str], integers: tuple[str, ...] = ()) -> str:
    """Rows of equal-length columns as CSV text, every value in the shortest digits that
    read back to the same double (exact round trip); the columns named in ``integers``
    as integers (a short table's flags: through Python lists, not one float array).

    orjson formats floats with Ryu, ten times faster than Python's "%.17g" (0.10 s against
    0.97 s for 200,000 rows of 13 values, measured): formatting, not computing, set the
    time of a long run.  JSON has no NaN or ±inf: NaN comes out as null (turned back into
    nan); a chunk holding ±inf is formatted by Python instead."""
    data = np.column_stack([np.asarray(columns[k], dtype=float) for k in names])
    if not data.size:
        return ""
    if integers and np.isfinite(data).all():
        cols = [np.asarray(columns[k]).astype(int).tolist() if k in integers
                else data[:, i].tolist() for i, k in enumerate(names)]
        text = orjson.dumps([list(row) for row in zip(*cols)])
        return text[2:-2].replace(b"],[", b"\n").decode() + "\n"
    if np.isinf(data).any():
        row = ",".join(["%r"] * len(names)) + "\n"
        return (row * data.shape[0]) % tuple(data.ravel().tolist())
    text = orjson.dumps(np.ascontiguousarray(data), option=orjson.OPT_SERIALIZE_NUMPY)
    return text[2:-2].replace(b"],[", b"\n").replace(b"null", b"nan").decode() + "\n"


def write_timeseries(folder: Path, columns: dict[str, np.ndarray],
                     name: str = "timeseries.csv") -> None:
    """One CSV with a header row; columns of equal length."""
    with open(Path(folder) / name, "w") as fh:
        fh.write(",".join(columns) + "\n" + csv_rows(columns, list(columns)))


class Folder:
    """The output folder of one command and the status in its ``summary.json``.

    ``Folder.open(out, summary, overwrite)`` after every check: makes and locks the folder
    (emptying it with ``overwrite``) and writes the summary with status "running";
    ``resume=True`` reopens a folder a stopped command left.  Used as a context manager, a
    solver error or an OSError inside marks it "failed" (and propagates), and the lock is
    released on any exit; :meth:`close` writes the final summary.
    """

    def __init__(self, path: Path, summary: dict):
        self.path, self.summary = Path(path), dict(summary)

    @classmethod
    def open(cls, out, summary: dict, overwrite: bool = False, resume: bool = False) -> "Folder":
        out = Path(out)
        _make_locked(out)
        try:
            if not resume and _holds_files(out):   # filled since the checks: a race lost
                _check_replaceable(out, overwrite)
                _empty(out, keep=(LOCK,))   # the lock file: it is what others lock
            _remove_temporaries(out)        # a killed run's: locked, no writer is left
            folder = cls(out, summary)
            OPENED.append(out)
            folder.reserve()
            folder.write(status="running", **stamp())
        except BaseException:
            release(out)
            raise
        return folder

    def clear(self) -> None:
        """Remove what a stopped run left (rows, frames, charts, tables, temporary files),
        so that a run started again from step 0 here writes what it would into an empty
        folder.  The summary stays: it holds the run's configuration, and a run killed
        in the middle of this must still find it (:func:`check_clearable` first)."""
        _empty(self.path, keep=(*OURS, SUMMARY))

    def discard(self) -> None:
        """Remove the folder this command made or emptied, with all it wrote: a run
        refused once it started (bad input found by the run itself) leaves no folder."""
        _empty(self.path, keep=())
        try:
            self.path.rmdir()
        except OSError:
            pass

    def reserve(self, size: int = 1 << 16) -> None:
        """Keep ``size`` bytes of disk, so that the final summary fits when the disk fills."""
        try:
            with open(self.path / RESERVE, "wb") as fh:
                fh.write(b"\0" * size)
        except OSError:
            (self.path / RESERVE).unlink(missing_ok=True)

    def unreserve(self) -> None:
        (self.path / RESERVE).unlink(missing_ok=True)

    def release(self) -> None:
        self.unreserve()
        release(self.path)

    def __truediv__(self, name: str) -> Path:
        return self.path / name

    def write(self, **entries) -> None:
        self.summary.update(entries)
        write_summary(self.path, self.summary)

    def fail(self, error: BaseException, **entries) -> None:
        """Mark the folder "failed" (the reserve freed first, so that it fits on a full disk;
        quietly, if even that cannot be written)."""
        self.unreserve()
        try:
            self.write(**{"status": "failed", "message": str(error), **entries, **stamp()})
        except OSError:
            pass

    def close(self, status: str = "success", **entries) -> dict:
        """The final summary: ``entries`` and the status, with the version stamp."""
        self.unreserve()
        self.write(**{"status": status, **entries, **stamp()})
        return self.summary

    def __enter__(self):
        return self

    def __exit__(self, kind, error, tb):
        if isinstance(error, (SolverError, OSError)):
            self.fail(error)
        elif isinstance(error, MemoryError):    # main_guard's one line
            self.fail(MemoryError(NO_MEMORY))
        elif isinstance(error, KeyboardInterrupt):
            self.fail(error, status="interrupted", message=f"interrupted ({error or 'SIGINT'})")
        self.release()
        return False


def report(summary: dict, out, last_t: float) -> int:
    """One line for a finished run (stdout, or stderr when it went unstable, with
    ``last_t`` the time of its last row: with save_every, before the stop); the exit code."""
    steps, wall = summary["steps"], summary["wall_time_s"]
    if summary["status"] != "success":
        print(f"error: {summary['message']}; results up to t={last_t:.6g} s written to "
              f"{out}", file=sys.stderr)
        return EXIT_UNSTABLE
    print(f"{steps} steps in {wall:.3g} s ({1e6 * wall / max(1, steps):.3g} µs/step), "
          f"{summary['impacts']} impacts, max nodal violation "
          f"{summary['max_nodal_violation']:.2e} m -> {out}")
    return 0
