"""Long runs lose nothing: streamed series, SIGKILL + --resume gives identical results."""
import errno
import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import skfem_beam
from conftest import exit_code
from skfem_beam.output import series, stream
from skfem_beam.cases import point_stops
from skfem_beam.results import read_csv
from skfem_beam.scenefile import run_main

ARGS = ["--dt", "1e-5", "--T", "1.0", "--flush-every", "2000", "--frames", "10"]
CASE = [sys.executable, "-m", "skfem_beam.cases.point_stops"]


def rows(path):
    return (path / "timeseries.csv").read_text().splitlines()


def test_sigkill_then_resume_is_bit_identical(tmp_path):
    ref, killed = tmp_path / "ref", tmp_path / "killed"
    assert subprocess.run(CASE + ARGS + ["--out", str(ref)], capture_output=True).returncode == 0
    total = len(rows(ref)) - 1
    stop_after = random.Random().randint(total // 10, total * 7 // 10)
    p = subprocess.Popen(CASE + ARGS + ["--out", str(killed), "--checkpoint-every", "0"],
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and p.poll() is None:
        csv = killed / "timeseries.csv"
        if (killed / "checkpoint.npz").exists() and csv.exists() and \
                csv.stat().st_size > 70 * stop_after:
            break
        time.sleep(0.002)
    os.kill(p.pid, signal.SIGKILL)
    p.wait()
    if (json.loads((killed / "summary.json").read_text())["status"]) != "running":
        pytest.skip("the run finished before it could be killed")
    # the killed run's series is readable, whole rows up to its last flush; killed within
    # a write, a part of one more row without its newline (output.series, SeriesFile._write)
    text = (killed / "timeseries.csv").read_text()
    partial = text.splitlines()
    if not text.endswith("\n"):
        assert rows(ref)[len(partial) - 1].startswith(partial.pop())
        assert len(read_csv(killed / "timeseries.csv")["t"]) == len(partial) - 1
    data = np.array([[float(v) for v in r.split(",")] for r in partial[1:]])
    assert data.shape[0] >= 1 and np.isfinite(data).all()
    assert partial == rows(ref)[:len(partial)]
    res = subprocess.run(CASE + ["--resume", str(killed)], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert rows(killed) == rows(ref)                    # every digit of every row
    a, b = (json.loads((d / "summary.json").read_text()) for d in (ref, killed))
    for key in ("steps", "impacts", "max_nodal_violation", "energy_final", "contact_fraction"):
        assert a[key] == b[key]
    assert list(a) == list(b)           # in one order (checkpoint_step had moved)
    # the field series is rewritten from the checkpoint's frames: the same, frame for frame
    fa, fb = (fields(d) for d in (ref, killed))
    assert len(fa) == len(fb) == 11
    for (ta, da), (tb, db) in zip(fa, fb):
        assert ta == tb and np.array_equal(da, db)


def fields(folder):
    import meshio
    with meshio.xdmf.TimeSeriesReader(str(folder / "fields.xdmf")) as r:
        r.read_points_cells()
        return [(t, d["displacement"]) for t, d, _ in
                (r.read_data(k) for k in range(r.num_steps))]


def test_disk_full_mid_run_stops_clearly_and_checkpoint_resumes(tmp_path, monkeypatch, capsys):
    out = tmp_path / "run"
    base = ["--dt", "5e-5", "--T", "0.5", "--flush-every", "1000", "--frames", "5"]
    argv = base + ["--checkpoint-every", "0", "--out", str(out)]
    real = series.SeriesFile.append
    calls = {"n": 0}

    def full(self, columns):
        calls["n"] += 1
        if calls["n"] > 4:
            raise OSError(errno.ENOSPC, "No space left on device")
        real(self, columns)

    monkeypatch.setattr(series.SeriesFile, "append", full)
    code = exit_code(point_stops.main, argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 3 and len(err) == 1 and "No space left" in err[0]
    assert json.loads((out / "summary.json").read_text())["status"] == "failed"
    monkeypatch.setattr(series.SeriesFile, "append", real)
    assert exit_code(point_stops.main, ["--resume", str(out)]) == 0
    ref = tmp_path / "ref"
    exit_code(point_stops.main, base + ["--out", str(ref)])
    assert rows(out) == rows(ref)


def test_resume_needs_a_run_folder(tmp_path, capsys):
    """A folder no run made (no summary.json) is refused in one line, changing nothing."""
    assert exit_code(point_stops.main, ["--resume", str(tmp_path)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and "no summary.json there: not the folder of a run" in err[0], err
    assert not list(tmp_path.iterdir())
    # a folder that is not there (a run killed before it made it) is named so
    assert exit_code(point_stops.main, ["--resume", str(tmp_path / "gone")]) == 2
    assert capsys.readouterr().err == f"error: --resume {tmp_path / 'gone'}: no such folder\n"


def test_resume_of_a_folder_that_cannot_be_written_is_refused_first(tmp_path, monkeypatch,
                                                                    capsys):
    """A run's folder on a read-only mount: --resume failed at its lock, exit 3, "could not
    write the results"; now one line, exit 2, as --out there is (the mount is played by
    the write probe failing: mounting needs root)."""
    from skfem_beam.output import folder
    out = tmp_path / "run"
    assert exit_code(point_stops.main, ["--T", "0.01", "--format", "none", "--out",
                                        str(out)]) == 0
    before = snapshot(out)

    def read_only(**_):
        raise OSError(errno.EROFS, os.strerror(errno.EROFS))
    monkeypatch.setattr(folder.tempfile, "mkdtemp", read_only)
    capsys.readouterr()
    assert exit_code(point_stops.main, ["--resume", str(out), "--T", "0.02"]) == 2
    assert capsys.readouterr().err == f"error: --resume {out}: the folder is not writable " \
                                      "(Read-only file system)\n"
    assert snapshot(out) == before


def test_summary_records_configuration_and_version(tmp_path):
    out = tmp_path / "run"
    exit_code(point_stops.main, ["--T", "0.01", "--gap", "0.05", "--out", str(out)])
    s = json.loads((out / "summary.json").read_text())
    assert s["config"]["gap"] == 0.05 and s["config"]["T"] == 0.01
    assert s["package_version"] and s["status"] == "success"


def test_a_run_killed_after_its_last_checkpoint_resumes_at_once(tmp_path):
    """Killed after the final checkpoint but before summary.json said "success" (here:
    its status set back to "running"): --resume finishes at once (no loop), with the
    uninterrupted run's files and status "success"."""
    ref, out = tmp_path / "ref", tmp_path / "out"
    base = CASE + ["--T", "0.1", "--format", "none"]
    subprocess.run(base + ["--out", str(ref)], check=True, capture_output=True)
    subprocess.run(base + ["--out", str(out)], check=True, capture_output=True)
    path = out / "summary.json"
    path.write_text(json.dumps({**json.loads(path.read_text()), "status": "running"}))
    t0 = time.monotonic()
    p = subprocess.run(CASE + ["--resume", str(out)], capture_output=True, text=True,
                       timeout=60)
    assert p.returncode == 0, p.stderr
    assert time.monotonic() - t0 < 30
    for name in ("timeseries.csv", "impacts.csv"):
        assert (out / name).read_bytes() == (ref / name).read_bytes(), name
    assert json.loads(path.read_text())["status"] == "success"


def test_a_failed_resume_of_a_moved_folder_leaves_it_resumable(tmp_path, monkeypatch, capsys):
    """A stopped run copied to another folder (its config names the old one), resumed
    there, the resume failing before its first checkpoint (a full disk): the folder still
    resumes, to the files of the uninterrupted run.  The checkpoint is the one truth and
    the output path is no part of a run's identity."""
    ref, a = tmp_path / "ref", tmp_path / "a"
    base = ["--T", "0.1", "--format", "none", "--flush-every", "500"]
    assert exit_code(point_stops.main, base + ["--out", str(ref)]) == 0
    subprocess.run(CASE + base + ["--out", str(a), "--checkpoint-every", "0"], check=True,
                   capture_output=True)
    path = a / "summary.json"
    path.write_text(json.dumps({**json.loads(path.read_text()), "status": "running"}))
    b = tmp_path / "moved" / "b"
    b.parent.mkdir()
    os.rename(a, b)

    def full_disk(run, *args, **kw):
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(stream, "drive", full_disk)
    assert exit_code(point_stops.main, ["--resume", str(b)]) == 3
    s = json.loads((b / "summary.json").read_text())
    assert s["status"] == "failed" and s["checkpoint_step"] == 2000
    monkeypatch.undo()
    capsys.readouterr()
    assert exit_code(point_stops.main, ["--resume", f"{b}/"]) == 0, capsys.readouterr().err
    for name in ("timeseries.csv", "impacts.csv"):
        assert (b / name).read_bytes() == (ref / name).read_bytes(), name


@pytest.mark.usefixtures("charts")
@pytest.mark.parametrize("sig, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_a_signal_during_the_charts_gives_its_exit_code(tmp_path, monkeypatch, capsys, sig,
                                                        code):
    """SIGTERM/SIGINT while the charts are drawn (after the last step): the files are
    complete (status "success"), and the exit code is the signal's, with one line."""
    from skfem_beam.cases import _beam
    chart = _beam.trajectory_chart

    def signalled(*args, **kw):
        os.kill(os.getpid(), sig)
        return chart(*args, **kw)
    monkeypatch.setattr(_beam, "trajectory_chart", signalled)
    out = tmp_path / "run"
    capsys.readouterr()
    assert exit_code(point_stops.main, ["--T", "0.05", "--format", "none", "--out",
                                        str(out)]) == code
    err = [e for e in capsys.readouterr().err.splitlines() if not e.startswith("compiling")]
    assert len(err) == 1 and "results are complete" in err[0], err
    assert json.loads((out / "summary.json").read_text())["status"] == "success"


@pytest.mark.parametrize("phase", stream.PHASES)
def test_killed_at_each_phase_of_its_end_a_run_resumes_to_the_same_files(tmp_path, phase):
    """SIGKILL at every boundary of a run's end (after the last chunk, after the final
    checkpoint, after the charts, after impacts.csv, before the final summary), then
    --resume: the uninterrupted run's timeseries.csv and impacts.csv, byte for byte, and
    "success", each resume under a timeout (no loop)."""
    base = CASE + ["--T", "0.1", "--format", "xdmf", "--frames", "5", "--flush-every", "300",
                   "--checkpoint-every", "0"]
    ref, out = tmp_path / "ref", tmp_path / "out"
    subprocess.run(base + ["--out", str(ref)], check=True, capture_output=True)
    killed = subprocess.run(base + ["--out", str(out)], capture_output=True,
                            env={**os.environ, "SKFEM_BEAM_KILL_AT": phase})
    assert killed.returncode == -signal.SIGKILL
    assert json.loads((out / "summary.json").read_text())["status"] == "running"
    p = subprocess.run(CASE + ["--resume", str(out)], capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 0, p.stderr
    for name in ("timeseries.csv", "impacts.csv"):
        assert (out / name).read_bytes() == (ref / name).read_bytes(), name
    assert json.loads((out / "summary.json").read_text())["status"] == "success"
    assert h5_datasets(out / "fields.h5") == h5_datasets(ref / "fields.h5")


def h5_datasets(path):
    """Every dataset of an HDF5 file, name → bytes of its values."""
    import h5py
    found = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: found.update({name: obj[()].tobytes()})
                     if isinstance(obj, h5py.Dataset) else None)
    return found


# ------------------------------------------------ a run stopped before its first checkpoint

SHORT = ["--T", "0.1", "--flush-every", "300", "--frames", "5", "--format", "xdmf"]
SCENE = [str(Path(skfem_beam.__file__).parent / "scene_files" / "point_stops.toml"),
         "--set", "time.T=0.1", "--flush-every", "300", "--frames", "5", "--format", "xdmf"]
# what differs between two runs of one command: the clock, the memory, the folder's name
VOLATILE = {"wall_time_s", "us_per_step", "peak_rss_MB", "written"}


def kill_before_the_first_checkpoint(command, out):
    """``command`` (writing folder ``out``) SIGKILLed in its loop's first chunk
    (SKFEM_BEAM_KILL_AT), with no --checkpoint-every: a folder "running" with a few rows
    and no checkpoint.  Returns the lines of its timeseries.csv."""
    p = subprocess.run(command, capture_output=True,
                       env={**os.environ, "SKFEM_BEAM_KILL_AT": stream.FIRST_CHUNK})
    assert p.returncode == -signal.SIGKILL, p.stderr
    assert json.loads((out / "summary.json").read_text())["status"] == "running"
    assert not (out / "checkpoint.npz").exists()
    return len(rows(out))


def run_again_from_step_0(main, out, capsys):
    """``--resume out`` in process (from another folder: nothing but the folder is used):
    exit 0 and one line saying the run started again."""
    capsys.readouterr()
    assert exit_code(main, ["--resume", str(out)]) == 0
    err = [e for e in capsys.readouterr().err.splitlines() if not e.startswith("compiling")]
    assert err == [f"{out} had no checkpoint: running it again from step 0"], err


def assert_same_run(out, ref):
    """The files of a run never stopped: the tables byte for byte, the summary's numbers,
    the field frames value for value (an HDF5 file's bytes hold times of writing)."""
    for name in ("timeseries.csv", "impacts.csv"):
        assert (out / name).read_bytes() == (ref / name).read_bytes(), name
    a, b = (json.loads((d / "summary.json").read_text()) for d in (out, ref))
    assert a["status"] == "success" and a["checkpoint_step"] == b["steps"]
    a["config"].pop("out"), b["config"].pop("out")
    assert {k: v for k, v in a.items() if k not in VOLATILE} == \
        {k: v for k, v in b.items() if k not in VOLATILE}
    assert h5_datasets(out / "fields.h5") == h5_datasets(ref / "fields.h5")


@pytest.mark.parametrize("flags", [[], ["--law", "moreau-jean"], ["--solver", "osqp"]],
                         ids=["beta", "moreau-jean", "osqp"])
def test_a_case_stopped_before_its_first_checkpoint_runs_again_on_resume(
        tmp_path, monkeypatch, capsys, flags):
    """Killed before any checkpoint, --resume runs the stored configuration again from step
    0, to the files of a run never stopped: the β-scheme, Moreau–Jean, OSQP."""
    ref, out = tmp_path / "ref", tmp_path / "out"
    assert exit_code(point_stops.main, flags + SHORT + ["--out", str(ref)]) == 0
    command = CASE + flags + SHORT + ["--out", str(out)]
    assert 1 < kill_before_the_first_checkpoint(command, out) < len(rows(ref))
    monkeypatch.chdir(tmp_path)
    run_again_from_step_0(point_stops.main, out, capsys)
    assert_same_run(out, ref)


def test_a_scene_file_run_stopped_before_its_first_checkpoint_runs_again_on_resume(
        tmp_path, monkeypatch, capsys):
    """The same for python -m skfem_beam run FILE.toml --set ...: its resume rebuilds the
    scene from the text and the --set stored in summary.json."""
    ref, out = tmp_path / "ref", tmp_path / "out"
    assert exit_code(run_main, SCENE + ["--out", str(ref)]) == 0
    command = [sys.executable, "-m", "skfem_beam", "run"] + SCENE + ["--out", str(out)]
    assert 1 < kill_before_the_first_checkpoint(command, out) < len(rows(ref))
    monkeypatch.chdir(tmp_path)
    # a file of the user's there (an export's .mat): named and kept, the resume refused
    # (starting again from step 0 deleted it), then run once it is moved out
    (out / "out.mat").write_bytes(b"mine")
    before = sorted(p.name for p in out.iterdir())
    assert exit_code(run_main, ["--resume", str(out)]) == 2
    assert "holds files of yours (out.mat)" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == before
    (out / "out.mat").unlink()
    # what a kill during a write leaves: its temporaries (the checkpoint's ends .tmp.npz),
    # taken for the user's, so the resume was refused; now they go, as a run never
    # stopped has none
    for name in (".checkpoint.npz.99999.tmp.npz", ".timeseries.csv.99999.tmp"):
        (out / name).write_bytes(b"half")
    run_again_from_step_0(run_main, out, capsys)
    assert_same_run(out, ref)
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in ref.iterdir())


def test_overwrite_and_resume_remove_a_killed_writes_temporaries(tmp_path, capsys):
    """A temporary left by a kill during a checkpoint's write (.checkpoint.npz.PID.tmp.npz)
    made --overwrite refuse the folder ("holds files besides the run's"), and stayed after
    a resume; an export's (.NAME.PID.tmp.mat) too."""
    out = tmp_path / "run"
    argv = ["--T", "0.01", "--format", "none", "--checkpoint-every", "0.005", "--out",
            str(out)]
    assert exit_code(point_stops.main, argv) == 0
    left = (".checkpoint.npz.4242.tmp.npz", ".run.4242.tmp.mat")
    for name in left:
        (out / name).write_bytes(b"half")
    assert exit_code(point_stops.main, argv + ["--overwrite"]) == 0
    assert not any((out / name).exists() for name in left)
    for name in left:
        (out / name).write_bytes(b"half")
    assert exit_code(point_stops.main, ["--resume", str(out), "--T", "0.02"]) == 0
    assert not any((out / name).exists() for name in left)


def test_a_folder_without_checkpoint_is_still_refused_when_unreadable_or_locked(
        tmp_path, capsys):
    """No checkpoint, and a summary.json that cannot be read, or a folder another process
    holds: refused in one line, changing nothing."""
    out = tmp_path / "run"
    assert exit_code(point_stops.main, ["--T", "0.01", "--format", "none", "--out",
                                        str(out)]) == 0
    (out / "checkpoint.npz").unlink()       # as a run killed before its first checkpoint
    summary = out / "summary.json"
    summary.write_text(json.dumps({**json.loads(summary.read_text()), "status": "running"}))
    good = summary.read_bytes()
    summary.write_bytes(b"{\"status\": \"running\"")
    before = snapshot(out)
    assert exit_code(point_stops.main, ["--resume", str(out)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and "summary.json is not a readable summary" in err[0], err
    assert snapshot(out) == before
    summary.write_bytes(good)
    before = snapshot(out)
    holder = subprocess.Popen([sys.executable, "-c", HOLD, str(out / ".lock")],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        assert exit_code(point_stops.main, ["--resume", str(out)]) == 2
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 1 and "is being written by another run" in err[0], err
        assert snapshot(out) == before
    finally:
        holder.kill()
        holder.wait()


HOLD = ("import fcntl, os, sys, time; fd = os.open(sys.argv[1], os.O_RDWR | os.O_CREAT); "
        "fcntl.flock(fd, fcntl.LOCK_EX); print('locked', flush=True); time.sleep(60)")


def snapshot(folder):
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def test_a_run_again_from_step_0_keeps_nothing_of_the_stopped_run(tmp_path, capsys):
    """Killed after its last chunk (every row, its field files and charts, no checkpoint
    yet), then its resume killed in its first chunk: the folder holds only what that new
    start wrote (rows, no field file, no chart), never frames of the first attempt beyond
    its rows; resumed again, the files of a run never stopped."""
    ref, out = tmp_path / "ref", tmp_path / "out"
    assert exit_code(point_stops.main, SHORT + ["--out", str(ref)]) == 0
    p = subprocess.run(CASE + SHORT + ["--out", str(out)], capture_output=True,
                       env={**os.environ, "SKFEM_BEAM_KILL_AT": "last-chunk"})
    assert p.returncode == -signal.SIGKILL
    assert (out / "fields.h5").exists() and not (out / "checkpoint.npz").exists()
    assert len(rows(out)) == len(rows(ref))
    assert kill_before_the_first_checkpoint(CASE + ["--resume", str(out)], out) < len(rows(ref))
    assert sorted(p.name for p in out.iterdir()) == [".lock", ".reserve", "summary.json",
                                                      "timeseries.csv"]
    run_again_from_step_0(point_stops.main, out, capsys)
    assert_same_run(out, ref)


def test_a_folder_another_command_wrote_names_the_command_that_resumes_it(tmp_path,
                                                                           capsys):
    """A case's --resume took a scene-file run's folder (or another case's) and failed on
    a flag the user never gave ("--massless 'beta' applies to ..."): now one line naming
    the command that wrote it, the folder untouched."""
    from skfem_beam.cases import flat_obstacles
    scene, case = tmp_path / "scene", tmp_path / "case"
    assert exit_code(run_main, [str(skfem_beam.scenefile.example("point_stops")), "--out",
                                str(scene), "--set", "time.T=0.01"]) == 0
    assert exit_code(point_stops.main, ["--T", "0.01", "--out", str(case)]) == 0
    capsys.readouterr()
    for main, folder, how in (
            (point_stops.main, scene, f"python -m skfem_beam run --resume {scene}"),
            (flat_obstacles.main, case,
             f"python -m skfem_beam.cases.point_stops --resume {case}")):
        before = {f.name: f.read_bytes() for f in folder.iterdir() if f.is_file()}
        assert exit_code(main, ["--resume", str(folder), "--T", "0.02"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.rstrip().endswith(how), err
        assert {f.name: f.read_bytes() for f in folder.iterdir() if f.is_file()} == before


def test_a_sweep_folder_given_to_resume_names_the_sweep_command(tmp_path, capsys):
    """A sweep's folder is resumed by running the sweep again (there is no cases.sweep)."""
    from skfem_beam.sweep import main as sweep_main
    out = tmp_path / "sw"
    assert exit_code(sweep_main, ["--values", "8", "--transient", "0.2", "--periods", "3",
                                  "--workers", "0", "--no-progress", "--out", str(out)]) == 0
    capsys.readouterr()
    assert exit_code(point_stops.main, ["--resume", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "python -m skfem_beam.sweep, the same values" in err, err


def test_resume_of_a_modes_folder_says_it_is_not_a_run(tmp_path, capsys):
    """`modes` writes a summary.json without a run's config: --resume of its folder said
    "not a readable summary (ValueError: no 'config' object)"."""
    from skfem_beam.__main__ import main as skfem_main
    scene = Path(point_stops.__file__).parents[1] / "scene_files" / "point_stops.toml"
    out = tmp_path / "modes"
    assert exit_code(skfem_main, ["modes", str(scene), "--out", str(out)]) == 0
    capsys.readouterr()
    before = snapshot(out)
    for main, argv in ((point_stops.main, ["--resume", str(out)]),
                       (skfem_main, ["run", str(scene), "--resume", str(out)])):
        assert exit_code(main, argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert err == [f"error: {out} holds the results of `python -m skfem_beam modes`, not a "
                       "run: there is nothing to resume, nothing was changed"], err
    assert snapshot(out) == before


@pytest.mark.parametrize("scene, law, T", [
    ("point_stops", "law=\"osqp\"", 0.8), ("plate_on_stops", "law=\"osqp-sparse\"", 0.004)])
def test_an_osqp_run_extended_by_resume_takes_the_same_admm_iterations(tmp_path, scene, law,
                                                                       T):
    """OSQP's own warm start (its x, y, ρ) is in the checkpoint: without it a resumed run's
    ADMM started cold and summary.json's qp_iterations differed (56,290 against 56,280;
    the plate's 935 against 910), though every row was the same."""
    from skfem_beam.scenefile import example
    argv = [str(example(scene)), "--set", f"contact.{law}", "--format", "none"]
    whole, half = tmp_path / "whole", tmp_path / "half"
    assert exit_code(run_main, argv + ["--T", str(T), "--out", str(whole)]) == 0
    assert exit_code(run_main, argv + ["--T", str(T / 2), "--out", str(half)]) == 0
    assert exit_code(run_main, ["--resume", str(half), "--T", str(T)]) == 0
    a, b = (json.loads((d / "summary.json").read_text()) for d in (whole, half))
    assert a["qp_iterations"] == b["qp_iterations"] > 0
    assert rows(whole) == rows(half)
