"""Results back in Python: read_run against the in-memory result of the same run, the
.npz/.mat export read back, and ``python -m skfem_beam``."""
import json
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest
from scipy.io import loadmat

from conftest import exit_code
from skfem_beam import InputError, read_run
from skfem_beam.__main__ import COMMANDS, listing, main as skfem_main
from skfem_beam.cases import _beam, convex_obstacles, flat_obstacles, impacting_bar, point_stops
from skfem_beam.output.fields import sample_line
from skfem_beam.results import export, export_main, matlab_name, read_csv, variables

MATLAB = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,62}$")


BEAMS = {
    "point_stops": (point_stops.main, ["--T", "0.3", "--frames", "40", "--flush-every", "1000"]),
    "flat_obstacles": (flat_obstacles.main, ["--T", "0.2", "--frames", "20", "--format", "vtu"]),
    "convex_obstacles": (convex_obstacles.main, ["--T", "0.2", "--save-every", "3"]),
}


def _run_case(module, main, monkeypatch, argv):
    kept = {}
    real = module.execute

    def execute(run, options, summary, series, finish):
        def keep(folder, data, run_):
            kept.update(data=data, run=run_)
            return finish(folder, data, run_)
        return real(run, options, summary, series, keep)

    monkeypatch.setattr(module, "execute", execute)
    assert exit_code(main, argv) == 0
    return kept


def _assert_same_series(saved, data):
    assert list(saved.series) == list(data)
    for k, v in data.items():    # exact digits written: bit for bit
        assert saved.series[k].shape == v.shape
        assert np.array_equal(saved.series[k], v, equal_nan=True), k


def _assert_same_frames(saved, run):
    """The field frames read back equal the ones computed from the run's own states."""
    f = saved.fields
    line = sample_line(run.system)
    assert np.array_equal(f.x, line.x)
    res = run.result()
    assert f.t.size >= 2 and f.t[-1] <= res.T + 1e-12
    for j, t in enumerate(f.t):
        k = int(np.argmin(np.abs(res.frames_t - t)))
        assert abs(res.frames_t[k] - t) <= 1e-12
        want = line.fields(t, res.frames_u[k], res.frames_v[k], res.frames_force[k])
        assert set(want) == set(f.arrays)
        for name, v in want.items():
            assert np.array_equal(f[name][j], v, equal_nan=True), (name, t)


@pytest.mark.parametrize("case", list(BEAMS))
def test_beam_run_reads_back_exactly(case, tmp_path, monkeypatch):
    main, argv = BEAMS[case]
    out = tmp_path / case
    kept = _run_case(_beam, main, monkeypatch, argv + ["--out", str(out)])
    saved = read_run(out)
    _assert_same_series(saved, kept["data"])
    res = kept["run"].result()
    assert saved.summary["status"] == "success" and saved.status == "success"
    assert saved.summary["steps"] == res.steps and saved.summary["impacts"] == res.impacts
    assert saved.summary["max_nodal_violation"] == res.max_nodal_violation
    assert saved.summary["case"] == case and saved.summary["config"]["T"] == float(argv[1])
    assert saved.fields.source == ("vtu" if "vtu" in argv else "xdmf")
    _assert_same_frames(saved, kept["run"])
    assert saved.tables == {}
    ev = res.impact_events          # impacts.csv: the run's own events, bit for bit
    assert saved.impacts["t_start"].size == ev["t_start"].size == res.impacts > 0
    for k in ("t_start", "t_end", "x", "velocity", "max_violation"):
        assert np.array_equal(saved.impacts[k], ev[k]), k
    if case == "point_stops":        # rows every step; ũ(L) touches the stops exactly
        assert saved.t.size == 6001 and np.abs(saved["tip_displacement"]).max() == 0.1
        # no stability limit at β = 1/2: JSON's null, not the string "inf"
        assert saved.summary["linear_stability_limit_dt"] is None
        assert '"linear_stability_limit_dt": null' in (out / "summary.json").read_text()


def test_xdmf_and_vtu_give_the_same_frames(tmp_path):
    out = tmp_path / "run"
    assert exit_code(point_stops.main, ["--T", "0.05", "--frames", "10", "--out", str(out)]) == 0
    a, b = read_run(out, fields="xdmf"), read_run(out, fields="vtu")
    assert (a.fields.source, b.fields.source) == ("xdmf", "vtu")
    assert np.array_equal(a.fields.t, b.fields.t) and a.fields.t.size == 11
    assert np.array_equal(a.fields.points, b.fields.points)
    for k in a.fields.arrays:
        assert np.array_equal(a.fields[k], b.fields[k], equal_nan=True), k
    assert a.fields["displacement_vector"].shape == (11, a.fields.x.size, 3)
    assert read_run(out, fields="none").fields is None
    with pytest.raises(InputError, match="fields='h5'"):
        read_run(out, fields="h5")


def test_bar_reads_back_exactly(tmp_path, monkeypatch):
    out = tmp_path / "bar"
    kept = _run_case(impacting_bar, impacting_bar.main, monkeypatch,
                     ["--T", "1", "--N", "40", "--frames", "25", "--out", str(out)])
    saved = read_run(out)
    _assert_same_series(saved, kept["data"])
    assert np.isnan(saved["contact_force"][0])      # R(0) is not defined: written "nan"
    assert {"u_0_exact", "u_L_exact", "contact_force_exact", "energy_exact"} <= set(saved.series)
    assert saved.summary["N"] == 40 and saved.summary["status"] == "success"
    assert saved.fields.t.size >= 20 and "bending_moment" not in saved.fields.arrays


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    out = tmp_path_factory.mktemp("runs") / "pipe"
    assert exit_code(point_stops.main, ["--T", "0.1", "--frames", "8", "--probe", "0.6",
                                        "--out", str(out)]) == 0
    return out


def test_extra_columns_impacts_and_tables_are_read_generically(folder, tmp_path):
    """Columns another command adds (probes) and an impacts.csv come back by name."""
    run = tmp_path / "run"
    shutil.copytree(folder, run)
    lines = (run / "timeseries.csv").read_text().splitlines()
    probe = np.arange(len(lines) - 1) / 3.0
    (run / "timeseries.csv").write_text("\n".join(
        [lines[0] + ",probe_u(0.75)"] + [f"{r},{p:.17g}" for r, p in zip(lines[1:], probe)]) + "\n")
    (run / "impacts.csv").write_text("t,x,side,velocity\n0.0123,1.501,g2,0.5\n"
                                     "0.0456,1.501,g1,-0.25\n")
    (run / "energy.csv").write_text("t,energy_beta_0.5\n0,1.5\n0.001,1.25\n")
    saved = read_run(run)
    assert np.array_equal(saved["probe_u(0.75)"], probe)
    assert list(saved.impacts) == ["t", "x", "side", "velocity"]
    assert saved.impacts["side"].tolist() == ["g2", "g1"]
    assert np.array_equal(saved.impacts["velocity"], [0.5, -0.25])
    assert list(saved.tables) == ["energy"]
    assert np.array_equal(saved.tables["energy"]["energy_beta_0.5"], [1.5, 1.25])
    names = variables(saved)
    assert {"probe_u_0_75_", "impacts_side", "impacts_t", "energy_energy_beta_0_5"} <= set(names)


@pytest.mark.parametrize("files, missing", [
    ((), "no summary.json and no timeseries.csv"),
    (("summary.json",), "no timeseries.csv"),
    (("timeseries.csv", "poincare.csv"), "no summary.json"),
])
def test_not_a_run_is_refused_in_one_line(tmp_path, files, missing):
    for name in files:
        (tmp_path / name).write_text("{}" if name.endswith("json") else "t\n0\n")
    with pytest.raises(InputError) as e:
        read_run(tmp_path)
    assert str(e.value) == f"{tmp_path} is not a run folder: {missing}"
    with pytest.raises(InputError, match="no such folder"):
        read_run(tmp_path / "nothing")


def test_npz_export_reads_back(folder, tmp_path):
    saved = read_run(folder)
    path = export(folder, "npz", tmp_path / "pipe.npz")
    with np.load(path) as z:
        assert json.loads(str(z["summary_json"])) == json.loads(json.dumps(saved.summary))
        assert "probe_0.6_displacement" in saved.series   # under its own name, dots and all
        for k, v in saved.series.items():
            assert np.array_equal(z[k], v)
        assert np.array_equal(z["fields_t"], saved.fields.t)
        assert np.array_equal(z["fields_x"], saved.fields.x) and "fields_y" not in z
        assert np.array_equal(z["fields_g2"], saved.fields["g2"], equal_nan=True)
        assert np.array_equal(z["fields_displacement"], saved.fields["displacement"])


def test_mat_export_reads_back_with_names_matlab_accepts(folder, tmp_path):
    saved = read_run(folder)
    assert exit_code(export_main, [str(folder), "--to", "mat", "--out",
                                   str(tmp_path / "pipe.mat")]) == 0
    m = loadmat(tmp_path / "pipe.mat")
    names = [k for k in m if not k.startswith("__")]
    assert all(MATLAB.match(k) for k in names), names
    for k, v in saved.series.items():        # column vectors, as MATLAB users expect
        k = k.replace(".", "_")                # probe_0.6_... is probe_0_6_... in MATLAB
        assert m[k].shape == (v.size, 1) and np.array_equal(m[k][:, 0], v)
    assert np.array_equal(m["fields_displacement"], saved.fields["displacement"])
    assert m["fields_displacement_vector"].shape == saved.fields["displacement_vector"].shape
    s = m["summary"][0, 0]
    assert all(MATLAB.match(k) for k in s.dtype.names)
    assert s["impacts"][0, 0] == saved.summary["impacts"]
    assert str(s["case"][0]) == "point_stops" and s["linear_stability_limit_dt"].size == 0
    config = s["config"][0, 0]
    assert config["J"][0, 0] == 19 and config["mesh"].size == 0      # None: empty matrix
    # default file: inside the run folder, named after it
    assert exit_code(export_main, [str(folder), "--to", "npz"]) == 0
    assert (folder / "pipe.npz").is_file()
    (folder / "pipe.npz").unlink()


def test_matlab_names():
    taken = {}
    for raw, want in [("u(L, t)", "u_L__t_"), ("1st", "x1st"), ("_x", "x_x"),
                      ("energy_beta_0.5", "energy_beta_0_5"), ("ũ", "x_")]:
        assert matlab_name(raw) == want
    long = "a" * 80
    assert matlab_name(long) == "a" * 63
    for _ in range(3):
        taken[matlab_name("u(L)", taken)] = 1
    assert list(taken) == ["u_L_", "u_L__2", "u_L__3"]


@pytest.mark.parametrize("argv, word", [
    (["--to", "xls"], "--to 'xls' is not one of: npz, mat"),
    (["--to", "mat", "--out", "x.npz"], "must end in .mat"),
    (["--to", "mat", "--out", "/no/such/folder/x.mat"], "does not exist"),
])
def test_export_bad_input_one_line(folder, capsys, argv, word):
    assert exit_code(export_main, [str(folder)] + argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and word in err, err


def test_python_m_skfem_beam(tmp_path):
    text = listing()
    for module in ("skfem_beam.cases.point_stops", "skfem_beam.cases.impacting_bar",
                   "skfem_beam.cases.stability_map", "skfem_beam.sweep",
                   "skfem_beam.bench.work_precision", "skfem_beam.bench.speed",
                   # the docs send users to these three, which the listing left out
                   "skfem_beam.plate.bench", "skfem_beam.plate.convergence",
                   "skfem_beam.meshes"):
        line = next(x for x in text.splitlines() if f"python -m {module} " in x)
        assert len(line.split(None, 3)[3]) > 20        # with its one-line description
    assert "cases._beam" not in text and "bench._floor" not in text
    assert all(f"python -m skfem_beam {name} " in text for name in COMMANDS)
    p = subprocess.run([sys.executable, "-m", "skfem_beam"], capture_output=True, text=True)
    assert p.returncode == 0 and p.stdout == text
    p = subprocess.run([sys.executable, "-m", "skfem_beam", "plot"], capture_output=True,
                       text=True)
    assert p.returncode == 2 and p.stdout == "" and p.stderr.count("\n") == 1
    assert "unknown command 'plot'" in p.stderr
    p = subprocess.run([sys.executable, "-m", "skfem_beam", "export", str(tmp_path),
                        "--to", "mat"], capture_output=True, text=True)
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "not a run folder" in p.stderr
    assert not list(tmp_path.iterdir())
    assert skfem_main(["nope"]) == 2


@pytest.mark.parametrize("tail", ["", "0.3,2.5", "0.3,", "0.3,2.5e-1", "0.3,x"])
def test_a_part_of_a_row_without_its_newline_is_left_out(tmp_path, tail):
    """A run killed within a write() of timeseries.csv can end in a part of a row without
    its newline (output.series): read_csv reads the whole rows and leaves that part out,
    numbers and mixed columns alike."""
    whole = "t,u\n0.1,0.5\n0.2,-1.25e-7\n"
    text_column = whole.replace("0.5", "a").replace("-1.25e-7", "b")
    for text, second in ((whole, -1.25e-7), (text_column, "b")):
        path = tmp_path / "timeseries.csv"
        path.write_text(text + tail)
        cols = read_csv(path)
        assert list(cols) == ["t", "u"] and cols["t"].tolist() == [0.1, 0.2]
        assert cols["u"].tolist()[1] == second


def test_a_word_among_a_columns_numbers_is_a_damaged_file(tmp_path):
    """It came back as a column of text (dtype <U3), and export wrote it so."""
    path = tmp_path / "timeseries.csv"
    path.write_text("t,u\n0.1,0.5\n0.2,abc\n0.3,0.25\n")
    with pytest.raises(InputError, match=r"timeseries.csv: row 3, column u: 'abc' is not a "
                                         r"number, as the column's other values are"):
        read_csv(path)



def test_export_of_a_folder_that_does_not_exist_names_it(tmp_path, capsys):
    """Not the --out the user never gave (it defaults to a file inside the folder)."""
    assert exit_code(export_main, [str(tmp_path / "nosuch"), "--to", "npz"]) == 2
    assert capsys.readouterr().err == f"error: {tmp_path / 'nosuch'} is not a run folder: " \
        "no such folder\n"


def test_a_field_not_in_the_folder_says_which_are(folder):
    run = read_run(folder)
    with pytest.raises(KeyError, match="'displacement_v' is not a field of this run; it "
                                       "holds: displacement, "):
        run.fields["displacement_v"]


def test_export_does_not_overwrite_the_checkpoint(folder, tmp_path, capsys):
    """`--out DIR/checkpoint.npz` replaced what --resume reads (a stopped run could no
    longer be resumed): refused, the checkpoint as it was."""
    before = (folder / "checkpoint.npz").read_bytes()
    argv = [str(folder), "--to", "npz", "--out", str(folder / "checkpoint.npz")]
    assert exit_code(export_main, argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is a run's checkpoint" in err, err
    assert (folder / "checkpoint.npz").read_bytes() == before
    # another run's checkpoint is as precious (it was replaced, exit 0)
    other = tmp_path / "other"
    shutil.copytree(folder, other)
    argv = [str(folder), "--to", "npz", "--out", str(other / "checkpoint.npz")]
    assert exit_code(export_main, argv) == 2
    assert (other / "checkpoint.npz").read_bytes() == before


def test_export_of_a_folder_a_run_is_writing_is_refused(folder, tmp_path, capsys):
    """A run holds DIR/.lock while it writes: its files are half there, so export waits
    for it as a resume does."""
    run = tmp_path / "live"
    shutil.copytree(folder, run)
    holder = subprocess.Popen(
        [sys.executable, "-c", "import fcntl, os, sys, time; fd = os.open(sys.argv[1], "
         "os.O_RDWR | os.O_CREAT); fcntl.flock(fd, fcntl.LOCK_EX); print('held', flush=True);"
         " time.sleep(60)", str(run / ".lock")], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        assert exit_code(export_main, [str(run), "--to", "npz"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "is being written by another run" in err, err
        assert not (run / "live.npz").exists()
    finally:
        holder.kill()
        holder.wait()
    assert exit_code(export_main, [str(run), "--to", "npz"]) == 0     # once it has ended


def test_a_plate_export_places_its_fields(tmp_path):
    """A plate's field arrays are per vertex: the export gives the vertices' x and y."""
    from skfem_beam.scenefile import example, run_main
    out = tmp_path / "plate"
    assert exit_code(run_main, [str(example("plate_on_stops")), "--out", str(out),
                                "--T", "0.002", "--format", "xdmf"]) == 0
    saved = read_run(out)
    with np.load(export(out, "npz")) as z:
        assert np.array_equal(z["fields_x"], saved.fields.points[:, 0])
        assert np.array_equal(z["fields_y"], saved.fields.points[:, 1])
        assert z["fields_w"].shape == (saved.fields.t.size, z["fields_y"].size)


@pytest.mark.parametrize("module, argv, word", [
    # tracebacks before (ValueError from int()/float()/min()), or a run of -1 cycles
    ("skfem_beam.bench.bar_convergence", ["--N", "abc"], "--N: 'abc' is not a whole number"),
    ("skfem_beam.bench.rod_study", ["--courant", "x"], "--courant: 'x' is not a finite"),
    ("skfem_beam.bench.qp_solvers", ["--repeat", "0"], "--repeat: '0' is not a whole number"),
    ("skfem_beam.bench.qp_solvers", ["--J", "40,-5"], "--J: '-5' is not a whole number"),
    ("skfem_beam.bench.soak", ["--cycles", "-1"], "--cycles: '-1' is not a whole number"),
    ("skfem_beam.meshes", ["--out", "FILE"], "cannot make the folder (File exists)"),
    # these two checked --out only once their study was done: exit 3, the work lost
    ("skfem_beam.bench.rod_study", ["--out", "FILE"], "cannot make the folder (File exists)"),
    ("skfem_beam.bench.friction_study", ["--out", "FILE"], "cannot make the folder"),
])
def test_study_commands_refuse_bad_flags_in_one_line(tmp_path, module, argv, word):
    (tmp_path / "FILE").write_text("")
    argv = [str(tmp_path / "FILE") if a == "FILE" else a for a in argv]
    p = subprocess.run([sys.executable, "-m", module, *argv], capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and word in p.stderr, p.stderr


def test_the_speed_benchmark_checks_its_out_before_it_measures(tmp_path, capsys):
    """It wrote --out after minutes of measuring: a folder failed there ("Is a directory")
    and the run was lost.  A file in a missing folder is refused at once."""
    from skfem_beam.bench import speed
    assert exit_code(speed.main, ["--quick", "--out", str(tmp_path / "no" / "s.json")]) == 2
    assert "is not a writable folder" in capsys.readouterr().err


def test_fields_read_while_a_run_writes_them_say_so(folder, tmp_path, monkeypatch):
    """A read during a flush found a dataset the XML names not yet in the .h5: the line
    said the data "cannot be read", as if damaged (1 read in 20 of a running run)."""
    import skfem_beam.results as results
    from skfem_beam.errors import InputError
    running = tmp_path / "running"
    shutil.copytree(folder, running)
    summary = json.loads((running / "summary.json").read_text())
    (running / "summary.json").write_text(json.dumps({**summary, "status": "running"}))

    def mid_flush(path):
        raise InputError(f"{path}: its .h5 data cannot be read (object 'data46' doesn't exist)")
    monkeypatch.setattr(results, "read_xdmf", mid_flush)
    with pytest.raises(InputError, match="a run is writing its fields now .*: read it again"):
        read_run(running)
    assert read_run(running, fields="none").series        # the rows read
    with pytest.raises(InputError, match="cannot be read"):
        read_run(folder)                                  # a finished run's: as it was


def test_export_does_not_replace_a_file_it_did_not_write(tmp_path, capsys):
    """--out thesis.mat, a file of the user's, was replaced; an earlier export is."""
    run = tmp_path / "r"
    assert exit_code(point_stops.main, ["--T", "0.01", "--format", "none", "--out",
                                        str(run)]) == 0
    mine = tmp_path / "thesis.mat"
    mine.write_text("my thesis\n")
    assert exit_code(export_main, [str(run), "--to", "mat", "--out", str(mine)]) == 2
    assert "exists and is not an export of a run" in capsys.readouterr().err
    assert mine.read_text() == "my thesis\n"
    for _ in range(2):      # the second replaces the first
        assert exit_code(export_main, [str(run), "--to", "mat", "--out",
                                       str(tmp_path / "e.mat")]) == 0
