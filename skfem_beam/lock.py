"""One writer per run folder: an exclusive ``flock`` on ``DIR/.lock``, held by the one
process writing the folder from before its first file until it ends (the kernel drops it
with the process, so a killed run never blocks the next one).  Apart from the output
package so that reading a folder (skfem_beam.results) can ask without loading the
scheme."""
from __future__ import annotations

import errno
import fcntl
import os
from pathlib import Path

from .errors import InputError

LOCK = ".lock"          # flock'ed by the one process writing the folder
_HELD: dict[Path, int] = {}     # folder → descriptor of its locked .lock, in this process


def _busy(out: Path) -> InputError:
    return InputError(f"{out} is being written by another run (its {LOCK} is locked); "
                      "wait for it to end or choose another folder")


def _flock(fd: int, out: Path) -> None:
    """Take ``fd``'s exclusive flock without waiting; refuse ``out`` as busy (closing
    ``fd``) when another process holds it."""
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as e:
        os.close(fd)
        if e.errno in (errno.EWOULDBLOCK, errno.EAGAIN):
            raise _busy(out) from None
        raise


def lock_folder(out: Path) -> None:
    """Take the exclusive lock of folder ``out`` (which exists) for this process, or refuse
    (InputError naming the folder) when another process holds it.  Held until
    :func:`release`, or the process ends."""
    key = Path(out).resolve()
    if key in _HELD:
        return
    fd = os.open(key / LOCK, os.O_RDWR | os.O_CREAT, 0o644)
    _flock(fd, out)
    _HELD[key] = fd


def release(out=None) -> None:
    """Drop the lock of ``out`` (every lock this process holds when None)."""
    keys = list(_HELD) if out is None else [Path(out).resolve()]
    for key in keys:
        fd = _HELD.pop(key, None)
        if fd is not None:
            os.close(fd)     # closing the descriptor releases the flock


def check_not_busy(out: Path) -> None:
    """Refuse a folder another process is writing (probe its lock, hold nothing).  The
    probe opens the lock read-only: a reader without write permission (a colleague's
    finished run, exported) was refused "Permission denied" on opening it to write."""
    if Path(out).resolve() in _HELD or not (Path(out) / LOCK).exists():
        return
    try:
        fd = os.open(Path(out) / LOCK, os.O_RDONLY)
    except OSError:
        return          # cannot be read: nobody's lock this process can see
    _flock(fd, out)
    os.close(fd)
