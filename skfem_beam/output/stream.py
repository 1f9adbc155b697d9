"""Running a command's :class:`~skfem_beam.scheme.Run` so that a long run loses nothing.

One pipeline for the beam scenes and the bar.  After every input has been checked the
output :class:`~.folder.Folder` is made (summary "running"); ``timeseries.csv`` grows by
whole rows after every chunk (:mod:`.series`: a run killed at any moment leaves its rows
up to its last flush, and at most a part of one more row without its newline) and the rows are also kept in memory for the charts
and the summary; the field frames are written as they come.  With ``--checkpoint-every
S`` the run's full state is written to ``checkpoint.npz`` (:mod:`.checkpoint`).
``--resume DIR`` rebuilds the same run from ``summary.json``, restores the checkpoint,
cuts the series back to it and continues: the result is identical, bit for bit, to an
uninterrupted run (values are written with the exact shortest digits).  A folder with no
checkpoint (the run stopped before its first) is emptied but for its summary and run
again from step 0: nothing computed was kept, the configuration was.

What a command streams is a :class:`Series`: its columns, computed from the run's saved
buffers, and which field frames to write.
"""
from __future__ import annotations

import errno
import os
import resource
import shlex
import signal
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from .. import chart_process
from ..errors import InputError, SolverError
from ..scheme import Run, drive
from .checkpoint import (CHECKPOINT, _resume_folder, checkpoint_of, has_checkpoint,
                         read_checkpoint, restore, write_checkpoint)
from .fields import FieldWriter
from .folder import (EXIT_SOLVER, NO_MEMORY, Folder, Interrupted, check_clearable,
                     check_output_dir, report)
from .options import OutputOptions
from .series import SeriesFile

FRAMES_AFTER = 1.0        # s: a run's frames stream with its rows from then on (_Stream)


@dataclass
class Series:
    """What a command streams from its run.

    ``columns(run, k0, k1)``: the timeseries rows (a dict of columns; it may keep only some
    of them) for the run's saved rows k0..k1−1; ``ready(run)``: how many saved rows are final
    (default: all computed so far); ``field_every``: steps between field frames, a multiple
    of ``run.frame_every`` (0: every frame the run keeps); ``field_until``: the last step
    with a frame (None: the run's end); ``events(folder, run, last)``: writes impacts.csv
    and returns its summary entries (``last``: the last state the loop computed), on every
    way a run ends: finished, unstable, interrupted, failed; ``writer``: the field
    writer's class, as :class:`~.fields.FieldWriter` is called (the plate's: .plate).
    """
    columns: Callable
    ready: Callable | None = None
    field_every: int = 0
    field_until: int | None = None
    keep_all: bool = False      # finish needs every row (not only what a chart shows)
    events: Callable | None = None
    writer: Callable | None = None   # the field writer's class (None: FieldWriter, a line)

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
        self.make = series.writer or FieldWriter
        threading.Thread(target=_import_writers, args=(fmt,), daemon=True,
                         name="field-imports").start()

    @property
    def writer(self) -> FieldWriter:
        if self._writer is None:
            self._writer = self.make(self.folder, self.run.system, self.fmt)
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


def _import_writers(fmt: str) -> None:
    """The field writers' imports (meshio, h5py: 0.2–0.3 s), made in a thread while the
    loop runs (its kernel releases the GIL), so that they are done by the first frame."""
    try:
        import meshio  # noqa: F401
        if fmt in ("xdmf", "both"):
            from . import xdmf  # noqa: F401
    except Exception:       # noqa: BLE001  (the frame's own import will say what is wrong)
        pass


def prepare(options: OutputOptions) -> Path:
    """Check SKFEM_BEAM_CHARTS and the output folder (or the resumed one) before anything
    is computed (or compiled); return the folder."""
    chart_process.wanted()
    if options.resume:
        return _resume_folder(options.resume)
    return check_output_dir(options.out, options.overwrite)



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
        "energy_final_J": float(data["energy_J"][-1]) if "energy_J" in data
        and data["energy_J"].size else None,      # where ρS (or the plate's units) gives J
        # springs (the penalty law): their compression is the supports' deflection, the
        # physics of an elastic support, not a numerical error; the springs are at the
        # nodes (max_penetration, between them too, read 1.4e-4 against 7.4e-5 m on a span)
        "max_support_deflection": result.max_nodal_violation if result.springs else None,
        "impacts": result.impacts, "contact_fraction": result.contact_fraction,
        "qp_iterations": result.qp_iterations, "status": result.status,
        "message": result.message,
        # the process's peak resident memory so far (Linux: kB): flat in T, see KEEP_ROWS
        "peak_rss_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }


class Signals:
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


def _resume_command(folder) -> str:
    """The command that resumes ``folder``, its path quoted for a shell (spaces, ü)."""
    return f"{_command(folder.summary)} --resume {shlex.quote(str(folder.path))}"


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
    chart_process.wanted()          # a bad SKFEM_BEAM_CHARTS is refused before any file
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
        used = restore(run, ck)
    _note_last_step(run)
    if restart:
        check_clearable(out)            # before anything is written
    run.check_loads(options.flush_every)
    with Signals() as stop:
        folder = Folder.open(out, summary, overwrite=options.overwrite, resume=resume)
        try:
            if ck is not None:
                # the checkpoint is the one truth: a resume that stops before its first new
                # checkpoint leaves a summary that still names it (written after the
                # status, where a run never stopped has it)
                folder.write(checkpoint_step=int(ck["n"]))
            if restart:
                # nothing computed is kept without a checkpoint, and the configuration
                # is in hand (rebuilt from summary.json): the run starts again from step 0
                folder.clear()
                print(f"{out} had no checkpoint: running it again from step 0",
                      file=sys.stderr)
            return _stream(_Stream(run, folder, options, series, stop, used, ck,
                                   can_checkpoint), finish)
        except InputError as e:     # found by the run itself (a load too large for floats)
            folder.fail(e) if resume else folder.discard()
            raise
        finally:
            folder.release()


def _last_row_t(run, rows) -> float:
    """The time of the last row kept (a bar's rows are decimated by its writer, not its
    run: their own time)."""
    t = getattr(rows, "last_t", None) if rows is not None and rows.rows else 0.0
    return (rows.rows - 1) * run.save_every * run.dt if t is None else t


def _note_last_step(run) -> None:
    """One line when T is not a whole number of steps: the run ends at the first step at
    or after T (Stepping.steps), which a user reading the last row should not wonder at."""
    s = getattr(run, "stepping", None)
    if s is not None and abs(s.steps * s.dt - s.T) > 1e-9 * s.T:
        print(f"note: T={s.T:g} s is not a whole number of steps dt={s.dt:g} s: the run "
              f"ends at t={s.steps * s.dt:.9g} s ({s.steps} steps)", file=sys.stderr)
    note_last_row(getattr(run, "save_every", 1), getattr(run, "n_steps", 0), run.dt)


def note_last_row(every: int, steps: int, dt: float) -> None:
    """One line when the rows, and energy_final, stop short of the run's last state."""
    if steps % every:
        last = steps // every * every
        print(f"note: a row saved every {every} states does not divide the {steps} steps: "
              f"the last saved row is state {last} (t={last * dt:.9g} s), not the last "
              "state", file=sys.stderr)


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


def _stream(s: _Stream, finish) -> int:
    """The body of :func:`execute`, in the open folder: the run to its end, or what a
    stop (signal, failed solver, failed write) leaves and says."""
    run, folder, stop = s.run, s.folder, s.stop
    try:
        entries = s.to_the_end(finish)
    except Interrupted as e:
        return s.interrupted(e)
    except SolverError as e:
        # the loop stopped inside a chunk: its events reach the state before the failed step;
        # the summary has the run's entries up to there, as an interrupted run's
        kept = {k: v for k, v in outcome(run.result(), s.rows.data()).items()
                if k not in ("status", "message")}
        folder.fail(e, **{**kept, "steps": run.n, **s.write_events(run.stopped_at - 1)})
        raise
    except OSError as e:
        return s.failed_write(e)
    except MemoryError:         # main_guard's one line; the folder said "running"
        folder.fail(MemoryError(NO_MEMORY))
        raise
    phase("summary")
    final = folder.close(**entries)
    code = report(final, folder.path, _last_row_t(run, s.rows))
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
        write_checkpoint(folder / CHECKPOINT, checkpoint_of(run, self.rows, self.used),
                         folder.summary["config"])
        self.kept = run.n
        folder.write(checkpoint_step=run.n)

    def write_rows(self, run) -> None:
        """The saved rows up to the run's state n not written yet."""
        k1 = self.series.rows_ready(run)
        if k1 > self.used:
            self.rows.append(self.series.columns(run, self.used, k1))
            self.used = k1
            run.release(self.used - 1)   # written: memory stays flat (one row kept before)

    def on_chunk(self, run) -> None:
        self.write_rows(run)
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
                                   whole=series.keep_all)
            self.fields = _Fields(self.folder.path, run, fmt, series) if fmt != "none" else None
            self.on_chunk(run)              # state 1's row (on resume: the rows so far)
            try:
                drive(run, chunk=self.options.flush_every, on_chunk=self.on_chunk)
            except (SolverError, InputError):   # a failed step (not a write refused: no
                self.write_rows(run)            # more writes) keeps the rows and frames up
                self.write_frames()             # to the last good saved state
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
        t = _last_row_t(run, rows)
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
        again = _resume_command(folder)
        resume = f"continue with: {again}" if self.kept is not None else \
            f"no checkpoint: run it again from step 0 with: {again}"
        print(f"interrupted by {name}: {self.what_is_kept()}{why}; {resume}", file=sys.stderr)
        return e.code

    def failed_write(self, e: OSError) -> int:
        """A write refused (full disk, ...): status "failed", what is kept, exit 3."""
        run, folder = self.run, self.folder
        # with no checkpoint the folder holds the rows only: its steps are theirs (it said
        # 200001 over rows to step 160000)
        steps = run.n if self.kept is not None else int(round(_last_row_t(run, self.rows)
                                                               / run.dt))
        folder.fail(e, steps=steps, kept=self.what_is_kept(), **self.write_events(run.n))
        again = _resume_command(folder)
        resume = (f"{_once_fixed(e)}, continue with: {again}" if self.kept is not None else
                  f"{_once_fixed(e)}, with no checkpoint (--checkpoint-every) run it again "
                  f"from step 0 with: {again}")
        print(f"error: could not write the results: {e}; {self.what_is_kept()}; {resume}",
              file=sys.stderr)
        return EXIT_SOLVER
