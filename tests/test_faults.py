"""Faults a long run meets, and what each leaves on disk (docs/design.md §5).

SIGKILL, SIGINT and SIGTERM at several moments, then --resume: identical, byte for byte,
to an uninterrupted run; two writers on one folder; spoiled checkpoints and summaries
refused in one line, touching nothing; a full disk (a 2 MB tmpfs, as root) leaves whole
rows and resumes once there is room; every output flag checked.
"""
import errno
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time

import meshio
import numpy as np
import pytest

from skfem_beam.methods import PositionLevel

from conftest import exit_code
from skfem_beam.cases import impacting_bar, point_stops
from skfem_beam.contact import ContactLaw
from skfem_beam.errors import InputError, SolverError
from skfem_beam.output import series
from skfem_beam.output.folder import Folder
from skfem_beam.results import read_run
from skfem_beam.scheme import Run
from skfem_beam.scheme.beta import BetaScheme

CASE = [sys.executable, "-m", "skfem_beam.cases.point_stops"]
LONG = ["--dt", "1e-5", "--T", "2", "--flush-every", "2000", "--frames", "10"]
SHORT = ["--dt", "1e-4", "--T", "0.1", "--flush-every", "200", "--format", "none"]


def summary(folder):
    return json.loads((folder / "summary.json").read_text())


def whole_rows(folder, killed_against=None):
    """The rows of timeseries.csv, each one whole (every value a finite number).
    ``killed_against``: the rows of the same run not stopped, for a run stopped by SIGKILL,
    which within a write can leave a part of one more row without its newline
    (output.series): that part must begin the row it would have been, and is left out."""
    text = (folder / "timeseries.csv").read_text()
    if killed_against is not None and not text.endswith("\n"):
        text, torn = text[:text.rfind("\n") + 1], text[text.rfind("\n") + 1:]
        assert killed_against[text.count("\n")].startswith(torn)
    assert text.endswith("\n")
    lines = text.splitlines()
    width = len(lines[0].split(","))
    data = np.array([[float(v) for v in r.split(",")] for r in lines[1:]]).reshape(-1, width)
    assert np.isfinite(data).all()
    return lines


def checkpoint(folder):
    with np.load(folder / "checkpoint.npz", allow_pickle=False) as z:
        return {k: z[k] for k in ("n", "rows")}


def impacts_so_far(folder, reference, last_t):
    """impacts.csv of a stopped run: read back by read_run; its finished rows are the
    reference's first rows, byte for byte; after them only open rows (contacts under way
    at the last state ``last_t``, one per node at most) starting where the reference's
    next ones do.  Returns the number of finished rows."""
    imp, s = read_run(folder).impacts, summary(folder)
    ref = (reference / "impacts.csv").read_text().splitlines()
    lines = (folder / "impacts.csv").read_text().splitlines()
    closed, n = int((imp["open"] == 0).sum()), imp["x"].size
    assert lines[0] == ref[0] and lines[1:closed + 1] == ref[1:closed + 1]
    assert np.all(imp["open"][closed:] == 1) and np.unique(imp["x"][closed:]).size == n - closed
    assert np.array_equal(imp["t_start"][closed:],
                          read_run(reference).impacts["t_start"][closed:n])
    assert imp["t_end"].max() <= last_t + 1e-12
    assert sum(node["impacts"] for node in s["impact_statistics"]["nodes"]) == n
    return closed


def snapshot(folder):
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("ref") / "run"
    assert exit_code(point_stops.main, LONG + ["--out", str(out)]) == 0
    return out


def stop_when(p, csv, nbytes, sig):
    """Send ``sig`` once ``csv`` has ``nbytes``; the exit code and stderr lines."""
    deadline = time.monotonic() + 60
    while p.poll() is None and time.monotonic() < deadline:
        if csv.exists() and csv.stat().st_size >= nbytes and \
                (csv.parent / "checkpoint.npz").exists():
            break
        time.sleep(0.002)
    if p.poll() is not None:
        pytest.skip("the run ended before it could be stopped (machine too fast or slow)")
    os.kill(p.pid, sig)
    _, err = p.communicate(timeout=60)
    return p.returncode, err.strip().splitlines()


def test_kill_interrupt_terminate_then_resume_is_identical(reference, tmp_path):
    """SIGKILL at ~1/5, SIGINT at ~2/5, SIGTERM at ~3/5, each followed by --resume: the
    files are whole at every stop, and the end is the uninterrupted run, byte for byte."""
    out = tmp_path / "run"
    csv = out / "timeseries.csv"
    ref = whole_rows(reference)
    total = (reference / "timeseries.csv").stat().st_size
    popen = dict(stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)

    p = subprocess.Popen(CASE + LONG + ["--checkpoint-every", "0", "--out", str(out)], **popen)
    code, _ = stop_when(p, csv, total // 5, signal.SIGKILL)
    assert code == -signal.SIGKILL and summary(out)["status"] == "running"
    kept = whole_rows(out, killed_against=ref)
    assert kept == ref[:len(kept)]       # whole rows up to the last flush, as computed

    for frac, sig, exit_ in ((2, signal.SIGINT, 130), (3, signal.SIGTERM, 143)):
        p = subprocess.Popen(CASE + ["--resume", str(out)], **popen)
        code, err = stop_when(p, csv, total * frac // 5, sig)
        name = signal.Signals(sig).name
        assert code == exit_ and len(err) == 1, err
        assert err[0].startswith(f"interrupted by {name}: kept ") and f"--resume {out}" in err[0]
        s, ck, kept = summary(out), checkpoint(out), whole_rows(out)
        assert s["status"] == "interrupted" and name in s["message"]
        # the checkpoint is the last state kept: its step and its rows are the files'
        assert s["steps"] == s["checkpoint_step"] == int(ck["n"]) > 0
        assert int(ck["rows"]) == len(kept) - 1 and f"kept {len(kept) - 1} whole rows" in err[0]
        assert kept == ref[:len(kept)]
        assert impacts_so_far(out, reference, s["steps"] * s["dt"]) > 20 * frac   # ~400 in T

    p = subprocess.run(CASE + ["--resume", str(out)], capture_output=True, text=True, timeout=60)
    assert p.returncode == 0, p.stderr
    assert csv.read_bytes() == (reference / "timeseries.csv").read_bytes()
    assert (out / "impacts.csv").read_bytes() == (reference / "impacts.csv").read_bytes()
    a, b = summary(reference), summary(out)
    for key in ("status", "steps", "impacts", "max_nodal_violation", "energy_final",
                "impact_statistics"):
        assert a[key] == b[key]
    # the field frames: the same XDMF and, read back from either file, the same arrays
    # (not fields.h5's size: HDF5 places a resumed file's blocks by where the stops fell)
    assert (out / "fields.xdmf").read_bytes() == (reference / "fields.xdmf").read_bytes()
    for source in ("xdmf", "vtu"):
        got, want = read_run(out, fields=source).fields, read_run(reference, fields=source).fields
        assert got.t.size == want.t.size > 1 and np.array_equal(got.t, want.t)
        for name, values in want.arrays.items():
            assert np.array_equal(got[name], values, equal_nan=True), (source, name)


class GivesUp(ContactLaw):
    """Lemma 4.1's projection solved in Python, failing at its ``calls``-th call (the
    loop calls it on the start step and on the steps in contact)."""
    name = "gives-up"

    def __init__(self, calls):
        self.calls = calls

    def solver(self, step):
        d, calls = np.diag(step.D), [0]

        class Solver:
            def solve(self, x, yf, lo, hi):
                calls[0] += 1
                if calls[0] == self.calls:
                    raise SolverError("gave up on purpose")
                return (np.clip(yf, lo, hi) - yf) / d, 0
        Solver.calls = self.calls
        return Solver()


def test_failed_solver_keeps_the_impacts_so_far(tmp_path, monkeypatch, capsys):
    """A solver failing at its 430th call (a step in contact, 6 tenths into the run):
    exit 3, status "failed", impacts.csv holds the events up to the state before the
    failed step, their rows those of the same run with the compiled projection,
    timeseries.csv the rows up to that state too (it stopped at the last whole chunk), and
    the field series the frames so far (a run's first second keeps its frames in memory:
    the failure writes them, stream._Stream)."""
    argv = ["--dt", "1e-4", "--T", "1", "--flush-every", "200", "--format", "xdmf",
            "--frames", "10"]
    ref = tmp_path / "ref"
    assert exit_code(point_stops.main, argv + ["--out", str(ref)]) == 0
    monkeypatch.setattr(PositionLevel, "build", lambda self, system, stepping:
                        Run(BetaScheme(system, stepping, GivesUp(430))))
    out = tmp_path / "run"
    capsys.readouterr()
    assert exit_code(point_stops.main, argv + ["--out", str(out)]) == 3
    err = [e for e in capsys.readouterr().err.splitlines() if not e.startswith("compiling")]
    assert len(err) == 1 and "gave up on purpose" in err[0], err
    s = summary(out)
    t_fail = int(re.search(r"failed at step (\d+)", s["message"])[1]) * 1e-4
    assert s["status"] == "failed" and s["steps"] * 1e-4 < t_fail and 0.4 < t_fail < 0.8
    t = read_run(out, fields="none").series["t"]
    assert t[-1] == pytest.approx(t_fail - 1e-4) and s["steps"] == round(t[-1] / 1e-4)
    # the run's entries up to there, as an interrupted run's (they were missing)
    series = read_run(out, fields="none").series
    assert s["energy_final"] == series["energy"][-1] and s["solver"] == "gives-up"
    assert s["impacts"] > 10 and 0 < s["contact_fraction"] < 1 and s["wall_time_s"] > 0
    imp = read_run(out).impacts
    assert imp["t_start"].size > 10 and imp["t_end"].max() == pytest.approx(t_fail - 1e-4) \
        or imp["open"].sum() == 0
    assert impacts_so_far(out, ref, t_fail) >= imp["t_start"].size - 1
    frames = []
    with meshio.xdmf.TimeSeriesReader(str(out / "fields.xdmf")) as r:
        r.read_points_cells()
        for k in range(r.num_steps):
            frames.append(r.read_data(k)[0])
    assert frames == pytest.approx([0.1 * k for k in range(s["steps"] // 1000 + 1)])
    assert len(frames) >= 5


HOLD = ("import fcntl, os, sys, time; fd = os.open(sys.argv[1], os.O_RDWR | os.O_CREAT); "
        "fcntl.flock(fd, fcntl.LOCK_EX); print('locked', flush=True); time.sleep(60)")


def test_one_writer_per_folder(tmp_path, capsys):
    """While another process holds the folder, a run into it, an overwrite and a resume
    are refused in one line naming it, touching nothing; once that process is killed its
    lock is gone and the resume goes on."""
    out = tmp_path / "run"
    assert exit_code(point_stops.main, SHORT + ["--out", str(out)]) == 0
    capsys.readouterr()
    before = snapshot(out)
    holder = subprocess.Popen([sys.executable, "-c", HOLD, str(out / ".lock")],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        for argv in (SHORT + ["--out", str(out)], SHORT + ["--out", str(out), "--overwrite"],
                     ["--resume", str(out), "--T", "0.2"]):
            assert exit_code(point_stops.main, argv) == 2
            err = capsys.readouterr().err.splitlines()
            assert len(err) == 1 and f"{out} is being written by another run" in err[0], err
        assert snapshot(out) == before
    finally:
        holder.kill()
        holder.wait()
    assert exit_code(point_stops.main, ["--resume", str(out), "--T", "0.2"]) == 0
    assert summary(out)["steps"] == 2000


def test_two_runs_started_at_once_into_one_folder(tmp_path):
    out = tmp_path / "run"
    argv = CASE + SHORT + ["--out", str(out)]
    ps = [subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
          for _ in range(2)]
    done = [(p.wait(timeout=60), p.stderr.read().strip()) for p in ps]
    codes = sorted(c for c, _ in done)
    assert codes == [0, 2], done
    err = [e for c, e in done if c == 2][0]
    assert err.count("\n") == 0 and str(out) in err and \
        ("another run" in err or "already holds files" in err), err
    ref = tmp_path / "ref"
    assert exit_code(point_stops.main, SHORT + ["--out", str(ref)]) == 0
    assert (out / "timeseries.csv").read_bytes() == (ref / "timeseries.csv").read_bytes()


# ---------------------------------------------------------------- spoiled resumes

@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    out = tmp_path_factory.mktemp("finished") / "run"
    assert exit_code(point_stops.main, SHORT + ["--out", str(out)]) == 0
    return out


def _edit_json(path, edit):
    data = json.loads(path.read_text())
    edit(data)
    path.write_text(json.dumps(data))


def _resave(path, edit):
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    edit(arrays)
    np.savez(path, **arrays)


SPOIL = {
    "truncated checkpoint": ("checkpoint.npz is unreadable", lambda d: (d / "checkpoint.npz")
                             .write_bytes((d / "checkpoint.npz").read_bytes()[:3000])),
    "random checkpoint": ("checkpoint.npz is unreadable", lambda d: (d / "checkpoint.npz")
                          .write_bytes(np.random.default_rng(1).bytes(5000))),
    "pickled checkpoint": ("checkpoint.npz is unreadable", lambda d: np.savez(
        d / "checkpoint.npz", u_cur=np.array([{"x": 1}], dtype=object))),
    "edited checkpoint": ("does not match its sha256", lambda d: _resave(
        d / "checkpoint.npz", lambda a: a["u_cur"].__setitem__(0, 1.0))),
    "edited summary dt": ("summary.json: dt=2e-05 differs from the checkpoint's dt=0.0001",
                          lambda d: _edit_json(d / "summary.json",
                                               lambda s: s["config"].update(dt=2e-5))),
    "random summary": ("summary.json is not a readable summary (UnicodeDecodeError",
                       lambda d: (d / "summary.json").write_bytes(b"\xff\xfe\x00garbage")),
    "cut series": ("fewer than the", lambda d: (d / "timeseries.csv").write_bytes(
        (d / "timeseries.csv").read_bytes()[:-500])),
    "edited series": ("are not the ones the checkpoint was written with",
                      lambda d: edit_row(d / "timeseries.csv", 100)),
    "no series": ("timeseries.csv is missing", lambda d: (d / "timeseries.csv").unlink()),
    "no summary": ("no summary.json there: its checkpoint.npz alone cannot say how",
                   lambda d: (d / "summary.json").unlink()),
}


def edit_row(csv, k):
    """Change the time of row k by one unit in the last place (same length, same shape)."""
    lines = csv.read_text().split("\n")
    t, rest = lines[k].split(",", 1)
    lines[k] = f"{np.nextafter(float(t), 1.0)!r},{rest}"
    csv.write_text("\n".join(lines))


@pytest.mark.parametrize("spoil", list(SPOIL))
def test_spoiled_resume_is_refused_touching_nothing(finished, tmp_path, capsys, spoil):
    out = tmp_path / "run"
    shutil.copytree(finished, out)
    word, spoil_it = SPOIL[spoil]
    spoil_it(out)
    before = snapshot(out)
    assert exit_code(point_stops.main, ["--resume", str(out), "--T", "0.2"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and word in err[0], err
    assert snapshot(out) == before


def test_a_summary_the_disk_refused_after_the_checkpoint_resumes_from_the_checkpoint(
        tmp_path, monkeypatch, capsys):
    """The disk fills between the checkpoint (renamed into place) and the summary's
    checkpoint_step: exit 3, the summary names an older checkpoint (here none) than
    checkpoint.npz holds.  The checkpoint is the one truth: the resume continues from it
    to the uninterrupted run's files (it was refused for good before: a stuck folder)."""
    argv = ["--dt", "5e-5", "--T", "0.4", "--flush-every", "1000", "--checkpoint-every", "0",
            "--format", "none"]
    ref, out = tmp_path / "ref", tmp_path / "run"
    assert exit_code(point_stops.main, argv + ["--out", str(ref)]) == 0
    write, calls = Folder.write, []

    def full_at_the_third(self, **entries):
        if "checkpoint_step" in entries:
            calls.append(entries["checkpoint_step"])
            if len(calls) == 3:
                raise OSError(errno.ENOSPC, "No space left on device")
        return write(self, **entries)
    monkeypatch.setattr(Folder, "write", full_at_the_third)
    assert exit_code(point_stops.main, argv + ["--out", str(out)]) == 3
    monkeypatch.undo()
    assert summary(out)["checkpoint_step"] == calls[1] < int(checkpoint(out)["n"]) == calls[2]
    capsys.readouterr()
    assert exit_code(point_stops.main, ["--resume", str(out)]) == 0
    for name in ("timeseries.csv", "impacts.csv"):
        assert (out / name).read_bytes() == (ref / name).read_bytes()
    assert summary(out)["status"] == "success"


def test_resume_refuses_changed_flags_and_extends_T(finished, tmp_path, capsys):
    out = tmp_path / "run"
    shutil.copytree(finished, out)
    before = snapshot(out)
    for argv, word in ((["--T", "0.2", "--dt", "1e-6"], "--dt 1e-06, where the run had --dt "),
                       (["--frames", "-1"], "--frames -1, where the run had --frames "),
                       (["--T", "0.05"], "--T 0.05 is shorter than the run's T=0.1"),
                       ([], "holds a finished run (status success): nothing to resume")):
        assert exit_code(point_stops.main, ["--resume", str(out)] + argv) == 2
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 1 and word in err[0], err
    assert snapshot(out) == before
    # --T longer: the same rows as a run made that long from the start
    assert exit_code(point_stops.main, ["--resume", str(out), "--T", "0.25"]) == 0
    longer = tmp_path / "longer"
    assert exit_code(point_stops.main, SHORT[:2] + ["--T", "0.25"] + SHORT[4:]
                     + ["--out", str(longer)]) == 0
    assert (out / "timeseries.csv").read_bytes() == (longer / "timeseries.csv").read_bytes()
    assert summary(out)["T"] == summary(longer)["T"] == 0.25


# ---------------------------------------------------------------- a full disk

def tmpfs(tmp_path, size: str):
    disk = tmp_path / "disk"
    disk.mkdir()
    if os.geteuid() != 0:
        pytest.skip(f"mounting a {size} tmpfs needs root")
    p = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(disk)],
                       capture_output=True, text=True)
    if p.returncode:
        pytest.skip(f"cannot mount a tmpfs here: {p.stderr.strip()}")
    return disk


@pytest.fixture
def small_disk(tmp_path):
    disk = tmp_path / "disk"
    yield tmpfs(tmp_path, "2m")
    subprocess.run(["umount", "-l", str(disk)], capture_output=True)


@pytest.fixture
def disk_3m(tmp_path):      # where HDF5's writes, not the CSV's, meet the full disk
    disk = tmp_path / "disk"
    yield tmpfs(tmp_path, "3m")
    subprocess.run(["umount", "-l", str(disk)], capture_output=True)


def test_full_disk_keeps_whole_rows_and_resumes_once_there_is_room(small_disk, tmp_path,
                                                                   capsys):
    argv = ["--dt", "5e-5", "--T", "2", "--flush-every", "1000", "--format", "none"]
    out = small_disk / "run"
    assert exit_code(point_stops.main, argv + ["--checkpoint-every", "0",
                                               "--out", str(out)]) == 3
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and "No space left on device" in err[0], err
    assert "whole rows of timeseries.csv" in err[0] and f"--resume {out}" in err[0]
    s = summary(out)
    assert s["status"] == "failed" and "No space left" in s["message"]
    ref = tmp_path / "ref"
    assert exit_code(point_stops.main, argv + ["--out", str(ref)]) == 0
    kept, full = whole_rows(out), whole_rows(ref)
    assert 1000 < len(kept) < len(full) and kept == full[:len(kept)]
    # the line names the kept rows' last time (it named the refused chunk's)
    assert f"kept {len(kept) - 1} whole rows of timeseries.csv (to t={float(kept[-1].split(',')[0]):.6g} s)" in err[0]
    assert int(checkpoint(out)["rows"]) <= len(kept) - 1
    subprocess.run(["mount", "-o", "remount,size=16m", str(small_disk)], check=True)
    assert exit_code(point_stops.main, ["--resume", str(out)]) == 0
    assert (out / "timeseries.csv").read_bytes() == (ref / "timeseries.csv").read_bytes()
    assert summary(out)["status"] == "success"


def test_a_full_disk_before_any_checkpoint_reports_the_steps_of_its_rows(small_disk):
    """Stopped by a full disk before its first checkpoint, the folder holds its rows only:
    summary.json's steps are the last row's (it said the run's state, 200001 over rows
    to step 160000)."""
    out = small_disk / "run"
    assert exit_code(point_stops.main, ["--dt", "5e-5", "--T", "2", "--flush-every", "1000",
                                        "--format", "none", "--checkpoint-every", "1e6",
                                        "--out", str(out)]) == 3
    s, kept = summary(out), whole_rows(out)
    assert s["status"] == "failed" and not (out / "checkpoint.npz").exists()
    assert s["steps"] * 5e-5 == pytest.approx(float(kept[-1].split(",")[0]), abs=1e-12)


def test_a_run_stopped_before_its_first_frame_has_no_field_files_until_resumed(
        small_disk, tmp_path, capsys):
    """The field files are made with the first frames (after the loop, in a run this
    short): a full disk before them leaves none, the folder reads back with no fields,
    and its resume writes the frames a run never stopped writes."""
    argv = ["--dt", "5e-5", "--T", "2", "--flush-every", "1000", "--format", "both"]
    out = small_disk / "run"
    assert exit_code(point_stops.main, argv + ["--checkpoint-every", "0",
                                               "--out", str(out)]) == 3
    assert "No space left on device" in capsys.readouterr().err
    assert not list(out.glob("fields*")) and read_run(out).fields is None
    ref = tmp_path / "ref"
    assert exit_code(point_stops.main, argv + ["--out", str(ref)]) == 0
    subprocess.run(["mount", "-o", "remount,size=64m", str(small_disk)], check=True)
    assert exit_code(point_stops.main, ["--resume", str(out)]) == 0
    for source in ("xdmf", "vtu"):
        got, want = read_run(out, fields=source).fields, read_run(ref, fields=source).fields
        assert got.t.size == want.t.size == 201 and np.array_equal(got.t, want.t)
        for name, values in want.arrays.items():
            assert np.array_equal(got[name], values, equal_nan=True), (source, name)


def test_immutable_checkpoint_fails_in_one_line_and_resumes_once_writable(tmp_path, capsys):
    """A resume that cannot replace its checkpoint (``chattr +i checkpoint.npz``) exits 3
    with one line naming the cause, not "once there is room", and leaves the folder as it
    was: once the file is writable the resume gives the uninterrupted run's files."""
    argv = ["--dt", "5e-5", "--checkpoint-every", "0.02", "--format", "none"]
    ref, out = tmp_path / "ref", tmp_path / "run"
    assert exit_code(point_stops.main, argv + ["--T", "0.2", "--out", str(ref)]) == 0
    assert exit_code(point_stops.main, argv + ["--T", "0.1", "--out", str(out)]) == 0
    capsys.readouterr()
    ck = out / "checkpoint.npz"
    p = subprocess.run(["chattr", "+i", str(ck)], capture_output=True, text=True)
    if p.returncode:
        pytest.skip(f"chattr +i needs root and an ext4/xfs folder: {p.stderr.strip()}")
    try:
        assert exit_code(point_stops.main, ["--resume", str(out), "--T", "0.2"]) == 3
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 1 and "Operation not permitted" in err[0], err
        assert "chattr -i" in err[0] and "room" not in err[0]
        assert summary(out)["checkpoint_step"] == 2000
    finally:
        subprocess.run(["chattr", "-i", str(ck)], check=True)
    assert exit_code(point_stops.main, ["--resume", str(out), "--T", "0.2"]) == 0
    for name in ("timeseries.csv", "impacts.csv"):
        assert (out / name).read_bytes() == (ref / name).read_bytes()
    assert summary(out)["status"] == "success"


# ---------------------------------------------------------------- output flags

@pytest.mark.parametrize("main", [point_stops.main, impacting_bar.main])
@pytest.mark.parametrize("flag, value", [
    ("--frames", "-1"), ("--frames", "0"), ("--save-every", "0"), ("--flush-every", "0"),
    ("--flush-every", "-5"), ("--checkpoint-every", "nan"), ("--checkpoint-every", "-1"),
    ("--checkpoint-every", "inf"), ("--format", "png")])
def test_output_flags_are_checked(tmp_path, capsys, main, flag, value):
    argv = ["--T", "0.1", flag, value, "--out", str(tmp_path / "run")]
    assert exit_code(main, argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and value in err and \
        flag.lstrip("-") in err.replace("_", "-"), err
    assert not list(tmp_path.iterdir())


@pytest.mark.usefixtures("charts")
def test_resume_of_a_long_run_reads_no_row(tmp_path, monkeypatch):
    """A run longer than the rows kept whole (KEEP_ROWS, made 1,000 here) checkpoints its
    chart envelope: --resume checks the rows on disk (CRC, block by block) and parses
    none of them, and ends with the same files, charts included, as one run to the end."""
    monkeypatch.setattr(series, "KEEP_ROWS", 1000)
    argv = ["--dt", "1e-4", "--flush-every", "500", "--format", "none"]
    whole, part = tmp_path / "whole", tmp_path / "part"
    assert exit_code(point_stops.main, argv + ["--T", "1", "--out", str(whole)]) == 0
    assert exit_code(point_stops.main, argv + ["--T", "0.5", "--out", str(part)]) == 0
    with np.load(part / "checkpoint.npz", allow_pickle=False) as z:
        envelope = z["envelope"]
    header = (part / "timeseries.csv").read_text().splitlines()[0].split(",")
    # 5,001 rows reduced to each column's first extremes per time bin (at most 2,000 bins)
    assert envelope.shape[1] == len(header) and 1000 < envelope.shape[0] < 5001

    def parse(*a):
        raise AssertionError("a resume parsed the rows on disk")
    monkeypatch.setattr(series, "read_rows", parse)
    assert exit_code(point_stops.main, ["--resume", str(part), "--T", "1"]) == 0
    for name in ("timeseries.csv", "impacts.csv", "tip_displacement.png", "energy.png",
                 "contact_force.png"):
        assert (part / name).read_bytes() == (whole / name).read_bytes(), name


def test_a_full_disk_with_hdf5_fields_exits_3_in_one_line_every_time(disk_3m):
    """A fresh run writing XDMF/HDF5 fields onto a full disk: exit 3 and one line, 8 of
    8 times (the .h5 left open after a failed write used to make HDF5 crash at exit:
    tracebacks and a segmentation fault, 4 runs of 5 on a 3 MiB disk; 8 clean runs in a
    row at that rate: 2.6e-6)."""
    for i in range(8):
        out = disk_3m / f"run{i}"
        p = subprocess.run(CASE + ["--dt", "2e-6", "--T", "1", "--format", "xdmf",
                                   "--save-every", "10", "--checkpoint-every", "0.3",
                                   "--out", str(out)], capture_output=True, text=True)
        err = [e for e in p.stderr.splitlines() if not e.startswith("compiling")]
        assert p.returncode == 3 and len(err) == 1 and "No space left" in err[0], (i, p.stderr)
        assert summary(out)["status"] == "failed"
        shutil.rmtree(out)


def test_a_finished_run_of_someone_else_can_be_checked_for_a_writer(tmp_path, monkeypatch):
    """export reads a folder: its busy probe opened .lock to write, and a user without
    write permission got "could not write the results: Permission denied", exit 3."""
    import os
    from skfem_beam.lock import LOCK, check_not_busy
    (tmp_path / LOCK).write_text("")
    real = os.open

    def read_only(path, flags, *args):
        if flags & (os.O_WRONLY | os.O_RDWR):
            raise PermissionError(13, "Permission denied", str(path))
        return real(path, flags, *args)
    monkeypatch.setattr(os, "open", read_only)
    check_not_busy(tmp_path)


def test_a_long_legal_folder_name_is_taken(tmp_path):
    """The writability probe was named after the folder: a legal name of 250 bytes passed
    the file system's 255 with the probe's prefix and was refused 'File name too long'."""
    from skfem_beam.output.folder import check_output_dir
    out = tmp_path / ("ü" * 125)        # 250 bytes in UTF-8
    assert check_output_dir(out) == out
    out.mkdir()
    assert check_output_dir(out) == out     # probed inside itself when it exists
    # one over the file system's limit: refused (exit 2), where the checks raised
    # ENAMETOOLONG (exit 3, "could not write the results")
    with pytest.raises(InputError, match="a name of 300 bytes, more than a file name may"):
        check_output_dir(tmp_path / ("a" * 300))


def test_a_penalty_failure_says_why(tmp_path, capsys):
    """Springs of 1e20 N/m cycle on and off: the line said only "the penalty contact solver
    failed at step 191", with no reason and no hint."""
    out = tmp_path / "run"
    assert exit_code(point_stops.main, ["--law", "penalty", "--stiffness", "1e20", "--T",
                                        "0.5", "--format", "none", "--out", str(out)]) == 3
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "the penalty contact solver failed at step" in err and \
        "its set of compressed springs did not settle" in err, err


def test_a_friction_failure_says_why(tmp_path, capsys):
    """μ = 50 on the friction tube: the line said only "the round-hole-friction contact
    solver failed at step 3003"."""
    from skfem_beam.scenefile import example as example_scene, run_main
    out = tmp_path / "run"
    assert exit_code(run_main, [str(example_scene("tube_round_holes_friction")), "--set",
                                "contact.friction=50", "--T", "0.35", "--format", "none",
                                "--out", str(out)]) == 3
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "the round-hole-friction contact solver failed at step" in err and \
        "its block Gauss–Seidel sweeps did not converge" in err, err


def test_a_run_beyond_the_memory_is_one_line_and_no_folder(tmp_path):
    """A 600 × 600 plate in 1.5 GB of address space: numpy's _ArrayMemoryError was a
    traceback; it is one line, exit 3, and no folder."""
    import resource
    import sys
    from skfem_beam.scenefile import example as example_scene

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (1_500_000_000, 1_500_000_000))
    out = tmp_path / "run"
    p = subprocess.run([sys.executable, "-m", "skfem_beam", "run",
                        str(example_scene("plate_on_stops")), "--set", "mesh.nx=600", "--set",
                        "mesh.ny=600", "--T", "0.001", "--out", str(out)],
                       capture_output=True, text=True, preexec_fn=limit,
                       env={**os.environ, "SKFEM_BEAM_CHARTS": "0",
                            "OPENBLAS_NUM_THREADS": "1"})   # its threads' buffers need more
    assert p.returncode == 3 and p.stderr.startswith("error: not enough memory for this run")
    assert p.stderr.count("\n") == 1 and not out.exists(), p.stderr


def test_memory_running_out_after_the_folder_is_made_marks_it_failed(tmp_path, monkeypatch,
                                                                     capsys):
    """The folder's summary.json stayed "running" (and read_run then said a run was writing
    it): it is "failed", with the one line's reason."""
    from skfem_beam.output import series
    from skfem_beam.scenefile import example as example_scene, run_main

    def no_memory(self, columns):
        raise MemoryError
    monkeypatch.setattr(series.SeriesFile, "append", no_memory)
    out = tmp_path / "run"
    assert exit_code(run_main, [str(example_scene("flat_obstacles")), "--T", "0.05",
                                "--format", "none", "--out", str(out)]) == 3
    assert "error: not enough memory for this run" in capsys.readouterr().err
    assert summary(out)["status"] == "failed"
    assert summary(out)["message"] == "not enough memory for this run"


WHIRL = """kind = "beam"
planes = 2
[material]
E = 2.0e11
rho = 8000.0
[section]
tube = { outer_diameter = 0.01905, wall = 0.00165 }
[geometry]
L = 1.5
[ends]
left = "pinned"
right = "pinned"
[[obstacles]]
x = 0.5
hole = { sides = 128, radius = 0.0004 }
[[obstacles]]
x = 1.0
hole = { sides = 128, radius = 0.0004 }
[[loads]]
distributed = true
rotating = { amplitude = 20.0, omega = 94.24777960769379 }
[contact]
friction = 0.3
[damping]
alpha = 30.0
alpha_K = 1e-4
[mesh]
J = 30
[time]
dt = 1e-4
T = 0.05
"""


def test_a_many_sided_polygon_with_friction_says_so_when_it_fails(tmp_path, capsys):
    """A whirl in 128-gons at μ = 0.3 stops at t ≈ 0.025 s (16 to 64 sides run, within 1 %
    of the round hole's forces): the line blamed a very large μ only."""
    from skfem_beam.scenefile import run_main
    scene = tmp_path / "whirl.toml"
    scene.write_text(WHIRL)
    assert exit_code(run_main, [str(scene), "--format", "none", "--out",
                                str(tmp_path / "run")]) == 3
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "a polygon hole of 128 sides or more fails so at μ = 0.3 already: give it as " \
           "the round hole it approaches, or 64 sides" in err, err
