"""Plate scene files (kind = "plate", docs/plate.md "Scene files"): the shipped scenes
run from the command line and write their folder; exact contact at every vertex and the
energy identity, read from the files; the fields read back with meshio; the bad values
refused in one line with nothing written; modes; --resume."""
import csv
import json
import os
import subprocess
import sys

import meshio
import numpy as np
import pytest

from conftest import assert_scene_refused, exit_code
from skfem_beam import InputError, chart_process
from skfem_beam.output.plate import MOMENTS, vertex_fields
from skfem_beam.scenefile import example, load, modes_main, run_main
from skfem_beam.scheme import drive

SHIPPED = ("plate_on_stops", "plate_rattling")
FILES = ("timeseries.csv", "impacts.csv", "summary.json", "fields.xdmf", "fields.h5",
         "fields.pvd", "probes.png", "energy.png", "deflection.png", "checkpoint.npz")


def run_rows(tmp_path, text: str) -> list[dict]:
    """The timeseries.csv rows of the scene ``text`` run without fields (exit 0 asserted)."""
    (tmp_path / "p.toml").write_text(text)
    out = tmp_path / "run"
    assert exit_code(run_main, [str(tmp_path / "p.toml"), "--format", "none", "--out",
                                str(out)]) == 0
    return list(csv.DictReader(open(out / "timeseries.csv")))


def columns(folder) -> dict:
    with open(folder / "timeseries.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    return {name: np.array([float(r[i]) for r in rows[1:]]) for i, name in enumerate(rows[0])}


@pytest.fixture(scope="module", params=SHIPPED)
def shipped(request, tmp_path_factory):
    """(name, output folder) of a shipped scene run by ``python -m skfem_beam run``, its
    charts drawn."""
    out = tmp_path_factory.mktemp(request.param) / "run"
    done = subprocess.run([sys.executable, "-m", "skfem_beam", "run",
                           str(example(request.param)), "--out", str(out)],
                          capture_output=True, text=True, timeout=300,
                          env={**os.environ, chart_process.CHARTS: "1"})
    assert done.returncode == 0, done.stderr
    return request.param, out


def test_shipped_plate_scene_writes_its_folder(shipped):
    name, out = shipped
    for f in FILES:
        assert (out / f).is_file(), f
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "success" and summary["kind"] == "plate"
    assert summary["solver"] == "active-set" and summary["impacts"] > 0
    assert summary["wall_time_s"] > 0 and summary["steps"] == round(summary["T"] /
                                                                    summary["dt"])
    assert summary["max_contact_force_N"] > 0


def test_every_cell_is_counter_clockwise_seen_from_above(shipped):
    """ParaView's normals point along +w: a BFS plate's quads were all clockwise and the
    disk's triangles mixed (91 of 216), so normals and lighting flipped across it."""
    _, out = shipped
    mesh = meshio.read(out / "fields_vtu" / "fields_000000.vtu")
    (block,) = mesh.cells
    x, y = mesh.points[block.data, 0], mesh.points[block.data, 1]
    area = np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)
    assert len(area) > 50 and np.all(area > 0)


def test_exact_contact_at_every_vertex(shipped):
    _, out = shipped
    summary = json.loads((out / "summary.json").read_text())
    gap = summary["smallest_gap_m"]
    assert summary["max_nodal_violation"] <= 1e-12 * gap          # measured ≈ 1e-19 m
    assert summary["max_penetration"] <= 1e-12 * gap


def test_energy_identity_from_the_timeseries(shipped):
    _, out = shipped
    c = columns(out)
    closure = c["energy_J"] - c["energy_J"][0] + c["work_damping_J"] - c["work_input_J"] \
        - c["work_contact_J"]
    assert np.abs(closure).max() <= 1e-9 * np.abs(c["energy_J"]).max()
    assert c["work_contact_J"][-1] < 0                             # impacts lose energy
    assert 0 < c["contact_area_fraction"].max() <= 1
    assert c["contact_force_N"].max() > 0


def test_fields_read_back_with_the_run_s_deflection(shipped):
    """meshio reads fields.xdmf and the VTU frames; w at every vertex at every frame is
    the run's own (the same run again through the API), bit for bit; the probe
    column of timeseries.csv is w at its vertex."""
    name, out = shipped
    scene = load(example(name))
    system = scene.problem.system
    run = scene.method.build(system, scene.stepping)
    drive(run)
    r = run.result()
    expected = [vertex_fields(system, r.frames_u[k], r.frames_v[k], r.frames_force[k])
                for k in range(r.frames_t.size)]
    with meshio.xdmf.TimeSeriesReader(str(out / "fields.xdmf")) as reader:
        points, cells = reader.read_points_cells()
        assert reader.num_steps == len(expected)
        for k in range(reader.num_steps):
            t, data, _ = reader.read_data(k)
            assert t == r.frames_t[k]
            np.testing.assert_array_equal(data["w"], expected[k]["w"])
            np.testing.assert_array_equal(data["contact_force"], expected[k]["contact_force"])
            for m in MOMENTS:
                np.testing.assert_array_equal(data[m], expected[k][m])
    assert points.shape[0] == system.meta["space"].vertices.shape[1]
    assert cells[0].type == "quad"
    last = meshio.read(out / "fields_vtu" / f"fields_{len(expected) - 1:06d}.vtu")
    np.testing.assert_array_equal(last.point_data["w"], expected[-1]["w"])
    c = columns(out)
    x, y = scene.problem.probes[0]
    i = int(np.argmin(np.hypot(points[:, 0] - x, points[:, 1] - y)))
    step = round(r.frames_t[-1] / scene.stepping.dt)
    assert c[f"w_x{x:g}_y{y:g}"][step] == expected[-1]["w"][i]


GOOD = example("plate_on_stops").read_text()
EDGES = 'left = "clamped"\nright = "clamped"\nbottom = "clamped"\ntop = "clamped"'


@pytest.mark.parametrize("old, new, word", [
    ("nu = 0.3", "nu = 0.6", "nu"),
    ("nu = 0.3", "nu = -1.0", "nu"),
    ("thickness = 0.01 ", "thickness = 0.0 ", "thickness"),
    ("thickness = 0.01 ", "thickness = -0.01 ", "thickness"),
    ('left = "clamped"', 'left = "welded"', "left"),
    ('left = "clamped"', 'middle = "clamped"', "middle"),
    ("g1 = -1.75e-4 ", "g1 = -1.75e-4\nregion = [0.0, 0.0, 0.5, 1.2] ", "region"),
    ("g1 = -1.75e-4 ", "g1 = -1.75e-4\npoints = [[0.2, 1.3]] ", "points"),
    ("g1 = -1.75e-4 ", "g1 = -1.75e-4\npoints = [[0.21, 0.6]] ", "points"),
    ("g1 = -1.75e-4 ", "g1 = \"0.175mm\" ", "g1"),
    ('element = "bfs"', 'element = "hermite"', "element"),
    ("nx = 6", "nx = 0", "nx"),
    ("probes = [[0.2, 0.6], [0.2, 0.2]]", "probes = [[0.2, 0.61]]", "probes"),
    # one column per vertex: a second probe there was an IndexError and a folder "running"
    ("probes = [[0.2, 0.6], [0.2, 0.2]]", "probes = [[0.2, 0.6], [0.2, 0.6000000001]]",
     "output.probes[1] = [0.2, 0.6] is the vertex of output.probes[0]"),
    ('law = "position"', 'law = "springs"', "law"),
    ('law = "position"', 'law = "penalty"', "stiffness"),
    ("static_pressure = 1.0e5 ", "static_pressure = -1.0e5 ", "initial deflection"),
    ("static_pressure = 1.0e5 ", "static_pressure = inf ",
     "[initial] static_pressure=inf must be a finite number"),
    ("g1 = -1.75e-4 ", "g1 = 1.0e-4 ",      # at the clamped edges' vertices
     "is held at w = 0 by its support, outside [0.0001, inf] (g1 of obstacles[0])"),
    # nothing holds the plate: K w = f has no solution (w was −1.9e11 m)
    (EDGES, EDGES.replace('"clamped"', '"free"'), "needs edges that hold the plate"),
    (EDGES, EDGES.replace('"clamped"', '"sliding"'), "rigid body"),
])
def test_bad_plate_scene_one_line_exit_2_nothing_written(tmp_path, capsys, old, new, word):
    assert old in GOOD
    assert_scene_refused(tmp_path, capsys, {"plate.toml": GOOD.replace(old, new)},
                         "plate.toml", word)


def test_bad_value_line_names_the_file(tmp_path, capsys):
    (tmp_path / "plate.toml").write_text(GOOD.replace("nu = 0.3", "nu = 0.6"))
    assert exit_code(run_main, [str(tmp_path / "plate.toml"), "--out",
                                str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert "plate.toml" in err and "[material] nu=0.6" in err and "(-1, 0.5)" in err
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("sets, warning", [
    (["material.E=210"], "[material] E = 210 Pa is outside engineering materials"),
    (["material.rho=7.77"], "[material] rho = 7.77 kg/m³ is outside engineering materials"),
    (["obstacles.0.g1=-0.175"], "no contact in 500 steps: the largest displacement at the "
                                "obstacles was"),
])
def test_implausible_values_warn_in_one_line_and_the_run_goes_on(tmp_path, capsys, sets,
                                                                 warning):
    """As a beam's: a value in the wrong unit (GPa, g/cm³, mm) warns and the run goes on."""
    argv = [str(example("plate_on_stops")), "--format", "none", "--out", str(tmp_path / "r")]
    assert exit_code(run_main, argv + [a for s in sets for a in ("--set", s)]) == 0
    err = [e for e in capsys.readouterr().err.splitlines() if e.startswith("warning")]
    assert len(err) == 1 and warning in err[0], err


def test_modes_lists_the_plate_frequencies(tmp_path, capsys):
    assert exit_code(modes_main, [str(example("plate_rattling")), "--n", "3", "--out",
                                  str(tmp_path / "m")]) == 0
    text = capsys.readouterr().out
    # simply supported 1 × 1 m, h = 5 mm: ω₁₁ = 2π² √(D/(ρh)) = 154.5 rad/s (BFS 8 × 8)
    assert "154.4" in text or "154.5" in text
    rows = list(csv.reader(open(tmp_path / "m" / "modes.csv")))
    assert len(rows) == 4 and rows[1][0] == "1"


def test_resume_extends_a_plate_run_bit_for_bit(tmp_path):
    """A finished run keeps its last checkpoint: --resume DIR --T longer continues it, and
    its timeseries.csv and impacts.csv are the uninterrupted longer run's, byte for byte."""
    scene = str(example("plate_rattling"))
    short, whole = tmp_path / "short", tmp_path / "whole"
    assert exit_code(run_main, [scene, "--T", "0.05", "--out", str(short)]) == 0
    assert exit_code(run_main, ["--resume", str(short), "--T", "0.1"]) == 0
    assert exit_code(run_main, [scene, "--T", "0.1", "--out", str(whole)]) == 0
    assert (short / "timeseries.csv").read_bytes() == (whole / "timeseries.csv").read_bytes()
    assert (short / "impacts.csv").read_bytes() == (whole / "impacts.csv").read_bytes()


def test_every_plate_key_is_in_docs_plate_md():
    from pathlib import Path
    from skfem_beam.scenefile.schema import PLATE_KEYS
    text = (Path(__file__).parents[1] / "docs" / "plate.md").read_text()
    text = text[text.index("## Scene files"):]
    for section, sub in PLATE_KEYS.items():
        sub = sub[0] if isinstance(sub, list) else sub
        keys = [k for k in sub if k not in ("amplitude", "omega", "phase", "value", "sines",
                                            "table", "random", "psd")] \
            if isinstance(sub, dict) else [section]
        for key in keys:
            assert f"`{key}`" in text, f"[{section}] {key}"


def test_an_obstacle_region_may_be_a_line_of_vertices(tmp_path):
    """docs/plate.md: an obstacle's region may have one side of zero length (a load's may
    not): [0.2, 0.0, 0.2, 1.2] is the grid line x = 0.2 (nx = 6 on a = 0.4), whose 19
    vertices less the 2 the clamped edges hold get a row each."""
    text = GOOD.replace("g1 = -1.75e-4 ", "g1 = -1.75e-4\nregion = [0.2, 0.0, 0.2, 1.2] ")
    (tmp_path / "line.toml").write_text(text)
    system = load(tmp_path / "line.toml").problem.system
    assert system.C.shape[0] == 17
    assert np.allclose(system.x_contact, 0.2) and np.allclose(system.lo, -1.75e-4)


SHAPED = """
[[obstacles]]
g1 = { poly = [[-5e-4, 0.0, 1e-3], [0.0], [1e-3]], about = [0.2, 0.6] }
[[obstacles]]
g2 = { x = [0.0, 0.2, 0.4], y = [0.0, 1.2], g = [[1e-3, 2e-3, 4e-3], [1e-3, 2e-3, 4e-3]] }
region = [0.0, 0.0, 0.4, 1.2]
"""


def test_plate_obstacles_as_polynomials_and_tables(tmp_path):
    """docs/plate.md: g1, g2 of a plate's obstacle may be Σ c_ij (x − x0)^i (y − y0)^j
    ({poly, about}) or a table on an x, y grid, bilinear ({x, y, g}), as a beam's are
    polynomials and tables of x; at every vertex with a row, the bounds are those
    functions (a paraboloid's bowl under the plate, a ramp above it)."""
    text = GOOD.replace("[[obstacles]]\ng1 = -1.75e-4", SHAPED + "[[obstacles]]\ng1 = -1.75e-4")
    assert text != GOOD
    (tmp_path / "shaped.toml").write_text(text)
    system = load(tmp_path / "shaped.toml").problem.system
    x, y = system.x_contact, system.meta["y_contact"]
    bowl = -5e-4 + 1e-3 * (y - 0.6) ** 2 + 1e-3 * (x - 0.2) ** 2
    assert np.array_equal(system.lo, np.maximum(bowl, -1.75e-4))
    assert np.allclose(system.hi, np.interp(x, [0.0, 0.2, 0.4], [1e-3, 2e-3, 4e-3]),
                       rtol=0, atol=1e-18)
    assert np.ptp(system.hi) > 2e-3 and system.C.shape[0] == 85


@pytest.mark.parametrize("g2, word", [
    ("{ x = [0.0, 0.2], y = [0.0, 1.2], g = [[1e-4, 2e-4], [1e-4, 2e-4]] }",
     "lies outside its table's x [0, 0.2]"),
    ("{ x = [0.0, 0.2, 0.4], y = [0.0, 1.2], g = [[1e-4, 2e-4], [1e-4, 2e-4]] }",
     "g needs one row per y (2) of one value per x (3)"),
    ("{ x = [0.0, 0.4, 0.2], y = [0.0, 1.2], g = [[1, 2, 3], [1, 2, 3]] }", "must increase"),
    ("{ poly = [[1e-4]], about = [0.5] }", "about a point [x0, y0]"),
    ("{ poly = [[nan]], about = [0.2, 0.6] }", "g2.poly[0][0] = nan: must be a number"),
    ("{ x = [0.0, 0.4], y = [0.0, 1.2], g = [[nan, 1e-3], [1e-3, 1e-3]] }",
     "g2.g[0][0] = nan: must be a number"),
    ("{ x = [0.0, 0.4], g = [1e-4, 2e-4] }", "obstacles.0.g2.g[0] = 0.0001"),
    ('"1e-4 + x"', "must be a number or a table ({ poly"),
])
def test_bad_plate_obstacle_shape_one_line(tmp_path, capsys, g2, word):
    shaped = SHAPED.replace(SHAPED.splitlines()[4], f"g2 = {g2}")
    text = GOOD.replace("[[obstacles]]\ng1 = -1.75e-4", shaped + "[[obstacles]]\ng1 = -1.75e-4")
    assert_scene_refused(tmp_path, capsys, {"plate.toml": text}, "plate.toml",
                         word.replace("obstacles.0", "obstacles.1"))


def test_the_largest_contact_force_counts_an_obstacle_above_the_plate(tmp_path):
    """plate_on_stops mirrored (pressed up, released onto an obstacle above it, w ≤ g2): its
    forces are negative, and summary.json's max_contact_force_N (a signed maximum: 0 N
    with 69 impacts) is the largest |contact_force_N|."""
    out = tmp_path / "run"
    assert exit_code(run_main, [str(example("plate_on_stops")), "--T", "0.004", "--out",
                                str(out), "--format", "none", "--set",
                                "initial.static_pressure=-1e5", "--set",
                                "obstacles.0.g2=1.75e-4", "--set", "obstacles.0.g1=-1"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    force = np.genfromtxt(out / "timeseries.csv", delimiter=",", names=True)["contact_force_N"]
    assert summary["impacts"] > 0 and force.min() < -1e3 and force.max() <= 0.0
    assert summary["max_contact_force_N"] == np.abs(force).max()


@pytest.mark.parametrize("sets, n, line", [
    (["mesh.nx=1", "mesh.ny=1"], "1", "plate_on_stops.toml: the plate has no free dofs"),
    (["mesh.nx=2", "mesh.ny=2"], "5", "plate_on_stops.toml: n=5 must be a whole number in "
                                      "[1, 4] (the plate has 4 free dofs)"),
])
def test_modes_of_a_plate_with_few_free_dofs_say_what_is_allowed(capsys, sets, n, line):
    """(they printed [1, -1] and [1, 0]; a dense solve gives all the free dofs' modes)"""
    from skfem_beam.scenefile import modes_main
    argv = [str(example("plate_on_stops")), "--n", n] + [a for s in sets for a in ("--set", s)]
    assert exit_code(modes_main, argv) == 2
    assert line in capsys.readouterr().err
    argv[2] = "4"
    if sets[0] == "mesh.nx=2":       # all four
        assert exit_code(modes_main, argv) == 0
        assert len(capsys.readouterr().out.strip().splitlines()) == 5


def test_cells_too_small_for_the_elements_basis_are_one_line(capsys):
    """A 200 × 600 BFS plate: skfem's global monomials made the cells' matrices singular,
    a LinAlgError traceback."""
    from skfem_beam.scenefile import modes_main
    argv = [str(example("plate_on_stops")), "--n", "1", "--set", "mesh.nx=200", "--set",
            "mesh.ny=600"]
    assert exit_code(modes_main, argv) == 2
    assert "the bfs element's matrices (global monomials in x, y) are singular on this " \
        "mesh: a cell too small (smallest 0.002 m across) or too flat" in capsys.readouterr().err


def test_a_plate_file_without_its_kind_is_told_so(tmp_path, capsys):
    """A plate's file without kind = "plate" is read as a beam's; its line said only
    "[geometry] allows: L", and now says which kind its keys fit."""
    from conftest import assert_refused
    from skfem_beam.scenefile import example, run_main
    text = example("plates/plate_rattling").read_text()
    path, out = tmp_path / "nokind.toml", tmp_path / "out"
    path.write_text("\n".join(l for l in text.splitlines() if not l.startswith("kind")))
    out.mkdir()
    assert_refused(run_main, [str(path), "--out", str(out / "r")],
                   "no kind is written, so it is read as a beam; a plate's file says "
                   "kind = \"plate\"", capsys, out)


def test_a_plate_above_its_step_limit_is_warned_of_before_it_runs(tmp_path, capsys):
    """β = 0 with Δt above the plate's linear limit: a beam warned before the run, a
    plate did not (it went unstable at step 7 without a word before)."""
    from conftest import exit_code
    from skfem_beam.scenefile import example, run_main
    code = exit_code(run_main, [str(example("plates/plate_rattling")), "--set",
                                "time.beta=0", "--format", "none",
                                "--out", str(tmp_path / "r")])
    err = capsys.readouterr().err
    assert code == 4 and "is above the linear stability limit 2/√(κ_h(1−4β))" in err


def test_a_plate_too_thick_for_kirchhoff_love_is_warned_of(tmp_path, capsys):
    """A thickness of half the shorter side ran without a word; the thin-plate model's
    limit (about 1/10) is now said in one line, and the shipped plates stay quiet."""
    from conftest import exit_code
    from skfem_beam.scenefile import example, run_main
    for thickness, warned in ((0.5, "Kirchhoff–Love plates are thin"), (None, None),
                              # a 1 m plate 5e-5 m thick, as a mesh file in mm makes one
                              (5e-5, "is the plate (its mesh file) in mm? Every length")):
        sets = ["--set", f"section.thickness={thickness}"] if thickness else []
        out = tmp_path / str(thickness)
        assert exit_code(run_main, [str(example("plates/plate_rattling")), *sets, "--T",
                                    "0.0005", "--format", "none", "--out", str(out)]) == 0
        err = capsys.readouterr().err
        assert (warned in err) if warned else "thickness=" not in err


@pytest.mark.parametrize("velocity, warned", [(0.1, True), (0.0, False)])
def test_a_start_that_overfills_the_stiff_modes_says_so(tmp_path, capsys, velocity, warned):
    """A uniform initial velocity on a simply supported plate: its projection has content in
    modes the step does not resolve, which the start step gives Δt·v0 instead of v0/ω: the
    run's energy 2.46 times the data's ½v0ᵀMv0 at 8 × 8, Δt = 1e-4, carried through the
    run without a word.  At rest (a static start) no line."""
    scene = tmp_path / "v.toml"
    scene.write_text(VELOCITY_START.format(velocity=velocity))
    assert exit_code(run_main, [str(scene), "--format", "none", "--out",
                                str(tmp_path / "run")]) == 0
    err = [e for e in capsys.readouterr().err.splitlines() if "initial data" in e]
    assert err == (["warning: the start holds 2.46 times the initial data's energy (½v0ᵀMv0 "
                    "+ ½u0ᵀKu0): the initial velocity has content in modes that dt does not "
                    "resolve, which the start step overfills; a smoother initial velocity, "
                    "or a smaller dt"] if warned else [])


# a simply supported a × b steel plate, n × n BFS: the scenes of the tests below
PLATE = """kind = "plate"
[geometry]
a = {a}
b = {b}
[section]
thickness = 0.01
[material]
E = 2.1e11
rho = 7850.0
nu = 0.3
[edges]
"""     # a steel plate a × b, 1 cm thick: its edges follow
SS_PLATE = PLATE + """left = "simply_supported"
right = "simply_supported"
bottom = "simply_supported"
top = "simply_supported"
[mesh]
nx = {n}
ny = {n}
"""
VELOCITY_START = SS_PLATE.format(a=1.0, b=0.6, n=8) + """[initial]
velocity = {velocity}
[time]
dt = 1e-4
T = 0.002
"""


def test_a_plate_scene_takes_the_centered_load_window(tmp_path):
    """[time] load_window was refused for a plate: its loads lagged by ΩΔt/2 (the phase
    of a damped forced plate 2.0e-2 rad off at Δt = 1e-4, against 3e-4 centred)."""
    text = example("plate_rattling").read_text().replace("beta = 0.5", 'beta = 0.5\nload_window = "centered"')
    scene = load(tmp_path / "p.toml") if (tmp_path / "p.toml").write_text(text) else None
    assert scene.stepping.load_window == "centered"


@pytest.mark.parametrize("damping", [dict(modal=0.05), dict(alpha=40.0)])
def test_a_damped_plate_released_from_its_first_mode_decays_as_its_oscillator(damping):
    """A plate had no damping (issue 41 asks Rayleigh or modal): released from the static
    deflection under sin·sin, the first mode alone, its centre follows
    w0 e^{−ζωt}(cos ω_d t + ζω/ω_d sin ω_d t), ζ = the modal ratio or α/(2ω)."""
    from skfem_beam import solve
    from skfem_beam.plate import Plate, natural_frequencies, plate_space, plate_system
    from skfem_beam.plate.system import PlateInitial, Pressure
    from skfem_beam.problem import Damping
    a, b = 1.0, 0.6
    space = plate_space(Plate(a=a, b=b, h=0.01, E=2.1e11, rho=7850.0, nu=0.3, nx=8, ny=8))
    sinsin = Pressure(lambda x, y: 1e4 * np.sin(np.pi * x / a) * np.sin(np.pi * y / b))
    system = plate_system(space, initial=PlateInitial(static=sinsin), observe=[(0.5, 0.3)],
                          damping=Damping(**damping))
    omega = natural_frequencies(space, 1)[0][0]
    zeta = damping.get("modal", damping.get("alpha", 0.0) / (2 * omega))
    r = solve(system, 2.5e-5, 0.05)
    w = r.observed["w(0.5,0.3)"]
    wd = omega * np.sqrt(1 - zeta**2)
    exact = w[0] * np.exp(-zeta * omega * r.t) * (np.cos(wd * r.t)
                                                   + zeta * omega / wd * np.sin(wd * r.t))
    assert np.abs(w - exact).max() < 1e-3 * abs(w[0])     # 3.3e-4, 4.7e-4 (undamped 1.2e-3)
    assert abs(w[-1]) < 0.3 * abs(w[0])            # 0.16, 0.24 (undamped 0.62) at 4.6 periods
    assert r.work["damping"][-1] > 0


def test_a_plate_scene_takes_damping(tmp_path):
    """[damping] in a plate scene (refused as an unknown section before): the system's B is
    the Rayleigh or modal damping asked, and the run's damping work is positive."""
    text = example("plate_rattling").read_text() + "\n[damping]\nmodal = 0.02\n"
    (tmp_path / "p.toml").write_text(text)
    out = tmp_path / "run"
    assert exit_code(run_main, [str(tmp_path / "p.toml"), "--format", "none", "--out",
                                str(out)]) == 0
    rows = list(csv.DictReader(open(out / "timeseries.csv")))
    assert float(rows[-1]["work_damping_J"]) > 1e-6
    bad = text.replace("modal = 0.02", "modal = 2.0")
    (tmp_path / "bad.toml").write_text(bad)
    assert exit_code(run_main, [str(tmp_path / "bad.toml"), "--out", str(tmp_path / "b")]) == 2


def test_a_point_force_at_the_centre_deflects_the_plate_as_navier(tmp_path, capsys):
    """[[loads]] point = [x, y], force = P (N) (issue 41's point forces; a plate had none):
    a simply supported square, P = 1000 N at the centre, held by a heavy damping until at
    rest: w = 0.0116 P a²/D (Navier, ν = 0.3) to BFS's error at 16 × 16.  A point off the
    vertices is refused naming the nearest."""
    text = SS_PLATE.format(a=1.0, b=1.0, n=16) + """[[loads]]
point = [0.5, 0.5]
force = 1000.0
[damping]
modal = 0.9
[time]
dt = 5e-4
T = 0.5
[output]
probes = [[0.5, 0.5]]
"""
    D = 2.1e11 * 0.01**3 / (12 * (1 - 0.3**2))
    w = float(run_rows(tmp_path, text)[-1]["w_x0.5_y0.5"])
    assert w == pytest.approx(0.0116 * 1000.0 / D, rel=3e-3)     # Navier's 3 digits
    (tmp_path / "bad.toml").write_text(text.replace("point = [0.5, 0.5]", "point = [0.52, 0.5]"))
    assert exit_code(run_main, [str(tmp_path / "bad.toml"), "--out", str(tmp_path / "b")]) == 2
    assert "[loads.0] point: (0.52, 0.5) is not a vertex of the plate's mesh; the nearest " \
           "is (0.5, 0.5)" in capsys.readouterr().err


def test_a_plate_released_from_its_first_mode_follows_it(tmp_path):
    """[initial] mode = 1, amplitude = 1 mm (issue 41's start from a mode shape; a plate had
    none): the centre starts at 1 mm and follows A cos ωt, ω the plate's first (undamped),
    to the time step's error."""
    text = VELOCITY_START.format(velocity=0.0).replace(
        "velocity = 0.0", "mode = 1\namplitude = 1e-3").replace("dt = 1e-4", "dt = 2.5e-5") \
        .replace("T = 0.002", "T = 0.05") + "[output]\nprobes = [[0.5, 0.3]]\n"
    (tmp_path / "m.toml").write_text(text)
    out = tmp_path / "run"
    assert exit_code(run_main, [str(tmp_path / "m.toml"), "--format", "none", "--out",
                                str(out)]) == 0
    rows = list(csv.DictReader(open(out / "timeseries.csv")))
    t = np.array([float(r["t"]) for r in rows])
    w = np.array([float(r["w_x0.5_y0.3"]) for r in rows])
    scene = load(tmp_path / "m.toml")
    from skfem_beam.plate import natural_frequencies
    omega = natural_frequencies(scene.problem.space, 1)[0][0]
    assert w[0] == pytest.approx(1e-3, rel=1e-12)
    assert np.abs(w - 1e-3 * np.cos(omega * t)).max() < 2e-3 * 1e-3


def test_an_obstacle_over_a_disk_acts_at_the_vertices_within_it(tmp_path, capsys):
    """[[obstacles]] disk = [xc, yc, r] (issue 41's disk region; a plate had rectangles and
    points only): the constrained vertices are those within r of the centre, counted
    here from the grid; a disk off the plate or holding no vertex is one line."""
    text = example("plate_rattling").read_text().replace(
        "points = [[0.25, 0.25], [0.75, 0.25], [0.25, 0.75], [0.75, 0.75]]",
        "disk = [0.5, 0.5, 0.3]")
    (tmp_path / "d.toml").write_text(text)
    system = load(tmp_path / "d.toml").problem.system
    k = np.arange(9) / 8                                      # the 8 × 8 grid's vertices
    X, Y = np.meshgrid(k, k)
    inside = np.hypot(X - 0.5, Y - 0.5) <= 0.3
    assert system.C.shape[0] == inside.sum() == 21
    assert np.all(np.hypot(system.x_contact - 0.5, system.meta["y_contact"] - 0.5) <= 0.3)
    for disk, line in (("[1.5, 0.5, 0.1]", "obstacles.0.disk centre = [1.5, 0.5] is off"),
                       ("[0.55, 0.55, 0.01]", "obstacles.0.disk = [0.55, 0.55, 0.01] holds "
                                               "no vertex of the mesh"),
                       ("[0.5, 0.5, -0.1]", "obstacles.0.disk r=-0.1 must be > 0")):
        (tmp_path / "bad.toml").write_text(text.replace("[0.5, 0.5, 0.3]", disk))
        assert exit_code(run_main, [str(tmp_path / "bad.toml"), "--out",
                                    str(tmp_path / "b")]) == 2
        assert line in capsys.readouterr().err


def test_render_plate_draws_the_deflected_plate_and_its_contacts(tmp_path):
    """A plate's render (issue 41: "a render with the [render] extra"; the beam's refused
    a plate): the frame with the most vertices in contact shows red points, the start's
    none; a beam's Result is refused in one line."""
    pytest.importorskip("pyvista")
    from skfem_beam import solve
    from skfem_beam.output.render_plate import render_plate
    scene = load(example("plate_on_stops"))
    r = solve(scene.problem.system, scene.stepping.dt, 0.004, frames=40)
    contacts = (np.asarray(r.frames_force) != 0).sum(axis=1)
    k = int(np.argmax(contacts))
    assert contacts[k] > 0 and contacts[0] == 0

    def red(img):
        R, G, B = (img[..., i].astype(int) for i in range(3))
        return ((R > G + 80) & (R > B + 80)).mean()
    hit = render_plate(tmp_path / "hit.png", r, time=r.frames_t[k])
    start = render_plate(tmp_path / "start.png", r, time=0.0)
    assert (tmp_path / "hit.png").stat().st_size > 5000
    assert hit.mean(axis=2).std() > 15 and red(hit) > 1e-4 and red(start) == 0.0
    with pytest.raises(InputError, match="render_plate needs the Result of a plate's"):
        render_plate(tmp_path / "x.png", object())


FREE_PLATE = PLATE.format(a=1.0, b=0.5) + 'left = "free"\n[mesh]\nnx = 8\nny = 4\n'   # 8 × 4 BFS


def test_a_free_plate_at_rest_in_a_rigid_mode_stays_there(tmp_path):
    """All edges free, [initial] mode = 1 (a rigid motion) at rest, no load: nothing moves.
    Its ½E_β is ±1e-17 (round-off of sums whose terms are not zero) against an a-priori
    bound of 0, which stopped the run as unstable at step 2 (exit 4) before the energy's
    floor and bound took the terms' size (scheme.watch.Watch._terms)."""
    text = FREE_PLATE + """[initial]
mode = 1
amplitude = 1e-4
[time]
dt = 1e-4
T = 0.05
[output]
probes = [[0.0, 0.0]]
"""
    rows = run_rows(tmp_path, text)
    w = np.array([float(r["w_x0_y0"]) for r in rows])
    assert len(rows) == 501 and abs(w[0]) > 1e-6
    assert np.abs(w - w[0]).max() < 1e-10 * abs(w[0])       # round-off drift
    assert max(abs(float(r["energy_J"])) for r in rows) < 1e-12


@pytest.mark.parametrize("extra, line", [
    # dropped: the plate started flat, exit 0
    ("[initial]\namplitude = 1e-3\n", "[initial] amplitude = 0.001 scales a mode shape: "
                                      "give the mode too"),
    # dropped: the force went into the support's fixed dof, nothing moved, exit 0
    ("[[loads]]\npoint = [0.0, 0.5]\nforce = 1000.0\n",
     "[loads.0] point: (0, 0.5) is a vertex the edges hold at w = 0"),
    # named "n", the modes command's flag, not the key written
    ("[initial]\nmode = 145\namplitude = 1e-3\n",
     "[initial] mode=145 must be a whole number in [1, 144] (the plate has 144 free dofs)"),
])
def test_a_plate_value_that_would_be_dropped_is_one_line(tmp_path, capsys, extra, line):
    text = SS_PLATE.format(a=1.0, b=1.0, n=6) + extra + "[time]\ndt = 1e-4\nT = 0.001\n"
    assert_scene_refused(tmp_path, capsys, {"p.toml": text}, "p.toml", line)


def test_the_nearest_vertex_named_can_be_pasted_back(tmp_path, capsys):
    """A point off the vertices is refused naming the nearest in full: its %g form (six
    digits, 0.333333 on a grid of thirds) was refused again when pasted back."""
    base = SS_PLATE.format(a=1.0, b=1.0, n=3) + "[time]\ndt = 1e-4\nT = 0.001\n"
    (tmp_path / "p.toml").write_text(base + "[[loads]]\npoint = [0.333333, 0.6]\nforce = 1.0\n")
    assert exit_code(run_main, [str(tmp_path / "p.toml"), "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err
    nearest = err.split("the nearest is (")[1].split(")")[0]
    assert nearest == "0.3333333333333333, 0.6666666666666666"
    (tmp_path / "q.toml").write_text(
        base + f"[[loads]]\npoint = [{nearest}]\nforce = 1.0\n[output]\nformat = \"none\"\n")
    assert exit_code(run_main, [str(tmp_path / "q.toml"), "--out", str(tmp_path / "b")]) == 0


@pytest.mark.parametrize("e, warned", [(1.0, True), (0.0, False)])
def test_a_contact_that_gains_energy_is_warned_of(tmp_path, capsys, e, warned):
    """A free plate falling flat at 0.1 m/s onto an obstacle under every vertex: with
    Newton restitution e = 1 at position level its energy went from 0.196 to 0.365 J in
    one impact (the contact's work +0.169 J), a run like any other, its units saying the
    contact's work is ≤ 0.  e = 0 loses energy, as exact contact does: no line."""
    text = FREE_PLATE + """[[obstacles]]
g1 = -1e-3
[initial]
velocity = -0.1
[time]
dt = 1e-4
T = 0.02
[output]
format = "none"
[contact]
restitution = {e}
""".format(e=e)
    (tmp_path / "p.toml").write_text(text)
    out = tmp_path / "run"
    assert exit_code(run_main, [str(tmp_path / "p.toml"), "--out", str(out)]) == 0
    rows = list(csv.DictReader(open(out / "timeseries.csv")))
    gain = float(rows[-1]["work_contact_J"])
    err = capsys.readouterr().err
    line = f"warning: the contact with restitution e = 1 did {gain:.4g} J of work, " \
           f"{100 * gain / float(rows[0]['energy_J']):.0f} % of the energy given to the plate"
    assert (gain > 0.5 * float(rows[0]["energy_J"])) is warned
    assert (line in err) is warned and ("restitution" in err) is warned
