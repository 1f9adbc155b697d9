"""``timeseries.csv`` as a run writes it, and the same rows kept in memory for the charts.

The file grows by whole rows after every chunk (flushed and fsynced: a run killed at any
moment leaves its rows up to its last flush, and at most a part of one more row without its
newline, which results.read_csv leaves out: :meth:`SeriesFile._write`); the rows in memory are whole up to
KEEP_ROWS, then each column's extremes per time bin (what a chart shows), so that memory
stays flat however long the run.  A resume reads the rows back block by block
(:func:`read_rows`, :func:`file_crc`; :mod:`.checkpoint`).
"""
from __future__ import annotations

import io
import os
import zlib
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from .folder import csv_rows

PAGE = 4096              # bytes: the largest write (see SeriesFile._write)
BLOCK = 1 << 23          # bytes read at a time on resume (CRC, rows): flat memory
KEEP_ROWS = 1 << 16       # rows kept whole in memory for the charts; beyond, an envelope
BINS = 1000               # time bins of that envelope (a chart is about 1000 pixels wide)


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
    ``keep``: a checkpoint; the file is cut back to its rows (resume).  ``whole``: every
    row held, for a command whose analysis needs them all (else KEEP_ROWS rows, then the
    envelope).
    """
    last_t = None       # the time of the last row this process wrote whole

    def __init__(self, path: Path, names: list[str], keep: dict | None = None,
                 whole: bool = False):
        self.path, self.names = path, names
        self.limit = None if whole else KEEP_ROWS
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
        """Whole rows in writes of at most a page.  A SIGKILL in the middle of a write()
        leaves a part of it: the kernel copies the data page by page of the file and stops
        between two (Linux: generic_perform_write), so a write that crosses a page boundary
        of the file (rows are not page-aligned) can end at it, in a row; the file then
        ends in a part of a row without its newline (seen once in a CI run of
        tests/test_resume.py), which readers leave out and a resume cuts off (the
        checkpoint's byte count).  At most a page: one such part, not a large write's."""
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
        self._write(text.encode())      # a full disk: cut back to the last whole chunk
        self.rows += text.count("\n")
        if "t" in cols and cols["t"].size:    # after the write: a refused chunk is not kept
            self.last_t = float(cols["t"][-1])
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
