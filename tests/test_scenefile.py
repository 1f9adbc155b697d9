"""Scene files: the TOML keys onto the API's objects, `run` and `modes`, refusals."""
import csv
import json
import math
import shutil

import numpy as np
import pytest

from conftest import assert_refused, exit_code
from skfem_beam import beam_system, scenes
from skfem_beam.cases import flat_obstacles, impacting_bar, point_stops
from skfem_beam.modes import modes
from skfem_beam.problem import Beam, Material, Section
from skfem_beam.scenefile import example, load, modes_main, run_main
from skfem_beam.scheme.solve import drive
from skfem_beam.timefunctions import Table

PIPE = """
kind = "beam"
[mass_normalised]
k2 = 282.84
rho_S = 0.1194
[geometry]
L = 1.501
[[obstacles]]
x = 1.501
g1 = -0.1
g2 = 0.1
[time]
dt = 5e-5
T = 0.01
"""


def write(folder, text, name="scene.toml"):
    p = folder / name
    p.write_text(text)
    return p


def series(folder):
    return (folder / "timeseries.csv").read_text()


@pytest.mark.parametrize("name, case, T", [
    ("point_stops", point_stops, "0.1"),
    ("flat_obstacles", flat_obstacles, "0.1"),
    ("impacting_bar", impacting_bar, "0.1"),
])
def test_shipped_scene_runs_bit_for_bit_as_its_case(tmp_path, name, case, T):
    a, b = tmp_path / "scene", tmp_path / "case"
    assert exit_code(run_main, [str(example(name)), "--set", f"time.T={T}", "--out", str(a),
                                "--format", "none"]) == 0
    assert exit_code(case.main, ["--T", T, "--out", str(b), "--format", "none"]) == 0
    assert series(a) == series(b)          # the same columns, every digit of every row
    sa, sb = (json.loads((d / "summary.json").read_text()) for d in (a, b))
    for key in ("steps", "impacts", "max_nodal_violation", "energy_final"):
        assert sa[key] == sb[key]


def test_convex_obstacles_polynomial_is_the_papers_profile_bit_for_bit():
    scene = load(example("convex_obstacles"))
    ref = scenes.convex_obstacles()
    x = np.linspace(0.0, 10.0, 4001)
    for ours, theirs in zip(scene.problem.obstacles.bounds(x), ref.obstacles.bounds(x)):
        assert np.array_equal(ours, theirs)
    s, r = beam_system(scene.problem), beam_system(ref)
    G = np.linspace(0, 1, 7)
    assert np.array_equal(s.loads, r.loads)
    assert np.array_equal(s.load_time[0](G), r.load_time[0](G))


def test_point_stops_objects_are_the_scenes():
    scene = load(example("point_stops"))
    pb, ref = scene.problem, scenes.point_stops()
    assert pb.beam == ref.beam and pb.support == ref.support and pb.J == ref.J
    s, r = beam_system(pb), beam_system(ref)
    assert np.array_equal(s.u0, r.u0) and np.array_equal(s.v0, r.v0)  # at rest, fixed frame
    assert scene.stepping.dt == 5e-5 and scene.stepping.T == 2.0 and scene.law == "auto"


def test_physical_stepped_and_sections_map_one_to_one(tmp_path):
    text = """
[[segments]]
length = 0.6
material = { E = 2e11, rho = 8000.0 }
section = { tube = { outer_diameter = 0.012, wall = 0.001 } }
[[segments]]
length = 0.9
material = { E = 7e10, rho = 2700.0 }
section = { rect = { b = 0.02, h = 0.005 } }
[ends]
left = "clamped"
right = "pinned"
[[supports]]
x = 0.9
[mesh]
J = 15
[time]
dt = 1e-4
T = 0.01
"""
    pb = load(write(tmp_path, text)).problem
    assert pb.beam == Beam.stepped([(0.6, Material(2e11, 8000.0), Section.tube(0.012, 0.001)),
                                    (0.9, Material(7e10, 2700.0), Section.rect(0.02, 0.005))])
    assert pb.ends == ("clamped", "pinned") and pb.supports == (0.9,)
    rod = load(write(tmp_path, PIPE.replace("[mass_normalised]\nk2 = 282.84\nrho_S = 0.1194",
                                            "[material]\nE = 2e11\nrho = 8000.0\n[section]\n"
                                            "rod = { diameter = 0.01 }"))).problem
    assert rod.beam == Beam.physical(1.501, Material(2e11, 8000.0), Section.rod(0.01))


def test_motion_table_is_relative_to_the_scene_and_stored_for_resume(tmp_path):
    t = np.linspace(0.0, 0.3, 301)
    (tmp_path / "scene").mkdir()
    np.savetxt(tmp_path / "scene" / "phi.csv", np.column_stack([t, 0.2 * np.sin(10 * t)]),
               delimiter=",", header="t,phi", comments="")
    scene_file = write(tmp_path / "scene", PIPE + '[motion]\nend = "left"\ntable = "phi.csv"\n'
                       "[output]\nformat = \"none\"\n")
    scene = load(scene_file)
    motion = scene.problem.support.motion
    assert isinstance(motion, Table) and motion(0.15) == pytest.approx(0.2 * np.sin(1.5), rel=5e-9)
    assert set(scene.files) == {"phi.csv"}
    a, ref = tmp_path / "a", tmp_path / "ref"
    assert exit_code(run_main, [str(scene_file), "--out", str(ref), "--T", "0.02"]) == 0
    assert exit_code(run_main, [str(scene_file), "--out", str(a)]) == 0
    shutil.rmtree(tmp_path / "scene")                  # the stored texts rebuild the run
    assert exit_code(run_main, ["--resume", str(a), "--T", "0.02"]) == 0
    assert series(a) == series(ref)
    config = json.loads((a / "summary.json").read_text())["config"]
    assert 'table = "phi.csv"' in config["scene_text"]
    assert config["scene_files"]["phi.csv"].startswith("t,phi")


def test_set_overrides_nested_keys_and_array_items(tmp_path):
    f = write(tmp_path, PIPE)
    s = load(f, ["time.dt=1e-5", "obstacles.0.g2=0.05", "mesh.element=bspline",
                 "ends.right=sliding", "obstacles[1].x=0.7505", "obstacles.1.g1=-0.01",
                 "mesh.J=20"])     # obstacles[1]: as the refusal lines write an item
    assert s.stepping.dt == 1e-5 and s.problem.element == "bspline"
    assert s.problem.ends == ("clamped", "sliding")
    lo, hi = s.problem.obstacles.bounds(np.array([0.7505, 1.501]))
    assert lo.tolist() == [-0.01, -0.1] and hi.tolist() == [np.inf, 0.05]


def test_initial_mode_is_the_mode_shape_scaled_to_its_amplitude(tmp_path):
    f = write(tmp_path, PIPE + "[initial]\nmode = 2\namplitude = 0.001\n")
    pb = load(f).problem
    m = modes(pb, 2, samples_per_element=50)
    x = np.linspace(0, pb.beam.L, 3001)
    u = pb.initial.u0(x)
    assert np.abs(u).max() == pytest.approx(0.001, rel=1e-3)   # 50 samples per element
    shape = m.space.point_rows(x) @ m.vectors[:, 1]
    assert np.abs(u / 0.001 * np.abs(m.shapes[:, 1]).max() - shape).max() < 1e-12
    # the nodal interpolant of a function of the space is itself: u0 is the mode exactly
    s = beam_system(pb)
    v = m.vectors[:, 1] * 0.001 / np.abs(m.shapes[:, 1]).max()
    assert np.abs(s.u0 - v).max() < 1e-15 and not s.v0.any()


def test_initial_u0_w_v0_w_start_the_second_plane(tmp_path):
    """[initial] u0_w, v0_w are the second plane's start (two planes), read as u0, v0 are:
    the same tables give w the start of v; without them w starts at rest."""
    u0 = "{ x = [0.0, 0.5, 1.0, 1.501], u = [0.0, 0.0001, 0.0003, 0.0002] }"
    v0 = "{ x = [0.0, 0.75, 1.501], v = [0.0, 0.001, 0.002] }"
    two = PIPE.replace('kind = "beam"', 'kind = "beam"\nplanes = 2')
    both = load(write(tmp_path, two + f"[initial]\nu0 = {u0}\nv0 = {v0}\nu0_w = {u0}\n"
                      f"v0_w = {v0}\n")).problem
    s = beam_system(both)
    n = s.meta["n_plane"]
    assert np.abs(s.u0).max() > 0 and np.abs(s.v0).max() > 0
    assert np.array_equal(s.u0[:n], s.u0[n:]) and np.array_equal(s.v0[:n], s.v0[n:])
    first = beam_system(load(write(tmp_path, two + f"[initial]\nu0 = {u0}\nv0 = {v0}\n",
                                   "v_only.toml")).problem)
    assert np.array_equal(first.u0[:n], s.u0[:n]) and not first.u0[n:].any()


def test_modes_command_prints_and_writes_the_cantilever_frequencies(tmp_path, capsys):
    out = tmp_path / "m"
    assert exit_code(modes_main, [str(example("point_stops")), "--n", "3", "--out",
                                  str(out)]) == 0
    text = capsys.readouterr().out
    w1 = 1.8751040687119611 ** 2 * math.sqrt(282.84) / 1.501 ** 2   # clamped–free, exact
    rows = list(csv.reader(open(out / "modes.csv")))
    assert rows[0][:3] == ["mode", "f_Hz", "omega_rad_s"] and len(rows) == 4
    assert abs(float(rows[1][2]) / w1 - 1) < 1e-6                  # J = 19 Hermite
    assert f"{float(rows[1][1]):14.6g}".strip() in text
    x = [float(h[2:-1]) for h in rows[0][3:]]
    assert x[0] == 0.0 and x[-1] == pytest.approx(1.501) and float(rows[1][3]) == 0.0
    # its folder is a run's: --overwrite replaces it
    assert exit_code(modes_main, [str(example("point_stops")), "--n", "2", "--out", str(out),
                                  "--overwrite"]) == 0
    assert len(list(csv.reader(open(out / "modes.csv")))) == 3


def test_heat_exchanger_tube_rattles_in_both_baffles(tmp_path):
    scene = load(example("heat_exchanger_tube"))
    pb = scene.problem
    assert pb.ends == ("pinned", "pinned") and pb.damping.alpha > 0
    run = scene.method.build(beam_system(pb), scene.stepping)
    drive(run)
    r = run.result()
    ev = r.impact_events
    assert r.status == "success" and r.max_nodal_violation <= 1e-10
    for x in (0.5, 1.0):
        assert (ev["x"] == x).sum() >= 5, x
    # the command writes the statistics per baffle (N·s, N) and one impacts.csv row each
    out = tmp_path / "hx"
    assert exit_code(run_main, [str(example("heat_exchanger_tube")), "--out", str(out),
                                "--format", "none"]) == 0
    stats = json.loads((out / "summary.json").read_text())["impact_statistics"]
    baffles = {o["where"]: o for o in stats["obstacles"]}
    assert set(baffles) == {"point stops at x=0.5", "point stops at x=1"}
    for o in baffles.values():
        assert o["impacts"] == (ev["x"] == o["x"][0]).sum() and o["max_violation"] <= 1e-10
        assert 0 < o["contact_fraction"] < 1 and o["max_impulse"] > 0
    rows = list(csv.DictReader(open(out / "impacts.csv")))
    assert len(rows) == len(ev["x"]) and stats["units"]["impulse"] == "N·s"


def test_bar_with_elastic_obstacle_and_profile(tmp_path):
    text = example("impacting_bar").read_text().replace("x = 0.0  ", "x = 1.0\nstiffness = 50.0")
    text = text.replace('right = "free"', 'left = "clamped"')
    text = text.replace("u0 = 0.0 ", "u0 = { x = [0.0, 1.0], u = [0.0, 0.0] }")
    bar = load(write(tmp_path, text)).problem
    assert (bar.obstacle, bar.k, bar.obstacle_at, bar.far_end) == ("elastic", 50.0, "right",
                                                                   "clamped")


BAD = {
    "negative E": (PIPE.replace("[mass_normalised]\nk2 = 282.84\nrho_S = 0.1194",
                                "[material]\nE = -2e11\nrho = 8000.0\n[section]\n"
                                "tube = { outer_diameter = 0.01, wall = 0.0005 }"), "E=-2e+11"),
    "wall ≥ radius": (PIPE.replace("[mass_normalised]\nk2 = 282.84\nrho_S = 0.1194",
                                   "[material]\nE = 2e11\nrho = 8000.0\n[section]\n"
                                   "tube = { outer_diameter = 0.01, wall = 0.005 }"), "wall=0.005"),
    "support outside": (PIPE + "[[supports]]\nx = 2.0\n",
                        "[supports.0] x=2 must lie on the beam"),
    # the next four named no key
    "point force outside": (PIPE + "[[loads]]\nx = 2.0\nvalue = 1.0\n",
                            "[loads.0] x=2 must lie on the beam"),
    "damping ratio": (PIPE + "[damping]\nmodal = 2.0\n", "[damping] modal=2 must be below 1"),
    "lifting": (PIPE + '[motion]\nend = "left"\namplitude = 0.1\nomega = 10.0\n'
                'lifting = "maybe"\n', "[motion] lifting='maybe' is not one of"),
    "mesh nodes": (PIPE + "[mesh]\nnodes = [0.0, 1.0, 0.5, 1.501]\n",
                   "[mesh] nodes must be strictly increasing"),
    "carried without motion": (PIPE.replace("g2 = 0.1", "g2 = 0.1\ncarried = true"),
                               "[obstacles.0] carried = true moves the obstacle with the "
                               "support's [motion]: this scene has none"),
    "segment length": (PIPE.replace("[mass_normalised]\nk2 = 282.84\nrho_S = 0.1194", "")
                       .replace("[geometry]\nL = 1.501\n", "") + "[[segments]]\nlength = -0.5"
                       "\nmaterial = { E = 2e11, rho = 8000.0 }\nsection = { rect = { b = "
                       "0.01, h = 0.01 } }\n", "[segments.0] length=-0.5 must be > 0"),
    "support off the nodes": (PIPE + "[mesh]\nJ = 10\n[[supports]]\nx = 0.5\n",
                              "[supports.0] x=0.5: the mesh has no node there (the nearest, "
                              "x=0.4503"),
    "point stop g1 above g2": (PIPE.replace("g2 = 0.1", "g2 = -0.2"),
                               "obstacles.0: g1 ≥ g2 at x=1.501 (g1=-0.1, g2=-0.2)"),
    "span g1 above g2": (PIPE + "[[obstacles]]\nx_from = 0.6004\nx_to = 1.2008\ng1 = 0.2\n"
                         "g2 = 0.1\n[mesh]\nJ = 10\n", "obstacles.1: g1 ≥ g2 at x=0.6004 (g1=0.2, g2=0.1)"),
    "two obstacles crossing": (PIPE + "[[obstacles]]\nx_from = 0.6004\nx_to = 1.501\n"
                               "g1 = 0.2\n[mesh]\nJ = 10\n", "obstacles.1's g1=0.2 ≥ "
                               "obstacles.0's g2=0.1 at x=1.501"),
    "span off the nodes": (PIPE + "[[obstacles]]\nx_from = 0.5\nx_to = 1.501\ng1 = -0.2\n"
                           "[mesh]\nJ = 10\n", "obstacles.1: the mesh has no node at the "
                           "obstacle break point x=0.5"),
    "two supports at one x": (PIPE + "[[supports]]\nx = 0.5\n[[supports]]\nx = 0.5\n",
                              "two supports at x=0.5"),
    "unknown end": (PIPE + '[ends]\nright = "glued"\n', "glued"),
    "unknown key": (PIPE.replace("L = 1.501", "L = 1.501\nwidth = 3"), "'geometry.width'"),
    "unknown section": (PIPE + "[solver]\nx = 1\n", "'solver'"),
    "malformed TOML": (PIPE + "[time\n", "not valid TOML"),
    "second plane's start in one plane": (
        PIPE + "[initial]\nu0_w = { x = [0.0, 1.501], u = [0.0, 0.001] }\n",
        "[initial] u0_w start the second plane: they need planes = 2"),
    "obstacle without bounds": (PIPE + "[[obstacles]]\nx = 0.79\n",
                                "[obstacles.1] needs g1 and/or g2 (m), or a hole"),
    "wear without holes": (PIPE + "[wear]\ncoefficient = 1e-14\nservice_years = 40\n",
                           "error: scene.toml: [wear] needs holes"),
    "table t not increasing": (PIPE + '[motion]\nend = "left"\ntable = "phi.csv"\n',
                               "t is not increasing at row 4"),
}


@pytest.mark.parametrize("what", sorted(BAD))
def test_bad_scene_one_line_exit_2_nothing_written(tmp_path, capsys, what):
    text, word = BAD[what]
    src = tmp_path / "src"
    src.mkdir()
    (src / "phi.csv").write_text("t,phi\n0,0\n0.1,1\n0.1,2\n0.3,0\n0.4,1\n")
    out = tmp_path / "out"
    out.mkdir()
    assert_refused(run_main, [str(write(src, text)), "--out", str(out / "run")], word, capsys,
                   out)


@pytest.mark.parametrize("setting, word", [
    ("time.dtt=1e-5", "unknown key 'dtt'"), ("nosuch.x=1", "unknown key 'nosuch'"),
    ("obstacles.3.g1=0", "index '3'"), ("time", "KEY=VALUE"),
    ("obstacles.1.x=0.79", "[obstacles.1] needs g1 and/or g2"),
])
def test_bad_set_key_is_refused_by_name(tmp_path, capsys, setting, word):
    src = write(tmp_path, PIPE)
    out = tmp_path / "out"
    out.mkdir()
    assert_refused(run_main, [str(src), "--set", setting, "--out", str(out / "run")], word,
                   capsys, out)


def test_set_an_item_of_an_array_of_values():
    """--set replaces or appends an item of an array of numbers by its index, as it does
    an array of tables' (``output.probes.0`` was "unknown key '0'; allows: none")."""
    from skfem_beam.errors import InputError
    from skfem_beam.scenefile.read import apply_set
    data = {"kind": "beam", "output": {"probes": [0.75]}, "loads": [{"direction": [1.0, 0.0]}]}
    for setting in ("output.probes.0=0.5", "output.probes[1]=0.25", "loads.0.direction.1=0.5",
                    "obstacles.0.hole.centre.0=1e-4"):
        assert apply_set(data, setting)[1] == setting.partition("=")[2]
    assert data["output"]["probes"] == [0.5, 0.25]
    assert data["loads"][0]["direction"] == [1.0, 0.5]
    assert data["obstacles"][0]["hole"]["centre"] == [1e-4]   # the pair's check: the scene's
    for setting, word in (("output.probes.3=1.0", "output.probes has 2 item(s); index '3' "
                                                   "must be 0..1 (an item) or 2 (a new one)"),
                          ("output.probes.0.x=1.0", "output.probes.0 is a value, not a table"),
                          ("output.format.0=1.0", "output.format is a value, not a table")):
        with pytest.raises(InputError) as e:
            apply_set(data, setting)
        assert word in str(e.value), str(e.value)
    with pytest.raises(InputError) as e:     # a number where the array goes
        apply_set({"kind": "beam", "output": {"probes": 0.5}}, "output.probes.0=1.0")
    assert "output.probes is not an array in the file" in str(e.value)


def test_unknown_key_message_lists_the_allowed_ones(tmp_path):
    with pytest.raises(Exception) as e:
        load(write(tmp_path, PIPE.replace("dt = 5e-5", "dt = 5e-5\nsteps = 3")))
    assert str(e.value) == ("scene.toml: unknown key 'time.steps'; [time] allows: dt, T, "
                            "beta, load_window")


def test_scene_files_are_package_data():
    import tomllib
    from pathlib import Path
    pyproject = tomllib.loads((Path(__file__).parent.parent / "pyproject.toml").read_text())
    assert "scene_files/*.toml" in pyproject["tool"]["setuptools"]["package-data"]["skfem_beam"]
    for name in ("point_stops", "flat_obstacles", "convex_obstacles", "impacting_bar",
                 "heat_exchanger_tube"):
        load(example(name))


def test_penalty_law_runs_as_the_case_penalty_method(tmp_path):
    a, b = tmp_path / "scene", tmp_path / "case"
    assert exit_code(run_main, [str(example("point_stops")), "--out", str(a), "--T", "0.05",
                                "--format", "none", "--set", 'contact.law="penalty"',
                                "--set", "contact.stiffness=1e8", "--set", "time.beta=0.25"]) == 0
    assert exit_code(point_stops.main, ["--T", "0.05", "--out", str(b), "--format", "none",
                                        "--method", "penalty"]) == 0
    assert series(a) == series(b)


def test_restitution_runs_as_the_case_flag(tmp_path):
    """[contact] restitution = 0.5 is the case command's --restitution 0.5, bit for bit."""
    f = write(tmp_path, PIPE + '[contact]\nlaw = "auto"\nrestitution = 0.5\n')
    assert load(f).method.restitution == 0.5
    a, b = tmp_path / "a", tmp_path / "b"
    assert exit_code(run_main, [str(example("point_stops")), "--out", str(a), "--T", "0.3",
                                "--format", "none", "--set", "contact.restitution=0.5"]) == 0
    assert exit_code(point_stops.main, ["--T", "0.3", "--out", str(b), "--format", "none",
                                        "--restitution", "0.5"]) == 0
    assert series(a) == series(b)
    assert json.loads((a / "summary.json").read_text())["solver"] == "restitution"


def test_massless_key_is_the_case_flag(tmp_path, capsys):
    """[mesh] massless = "quasi-static" with mass = "redistributed" is the bar command's
    --mass redistributed --massless quasi-static, bit for bit; an unknown value, or the
    key without mass = "redistributed", is refused in one line naming it."""
    a, b = tmp_path / "scene", tmp_path / "case"
    mesh = ["--set", "mesh.mass=redistributed", "--set", "mesh.massless=quasi-static"]
    assert load(example("impacting_bar"), mesh[1::2]).stepping.massless == "quasi-static"
    assert exit_code(run_main, [str(example("impacting_bar")), "--set", "time.T=0.5", *mesh,
                                "--out", str(a), "--format", "none"]) == 0
    assert exit_code(impacting_bar.main, ["--T", "0.5", "--mass", "redistributed",
                                          "--massless", "quasi-static", "--out", str(b),
                                          "--format", "none"]) == 0
    assert series(a) == series(b)
    bad = tmp_path / "bad"
    bad.mkdir()
    for sets, word in ((["mesh.mass=redistributed", "mesh.massless=midpoint"],
                        "[mesh] massless='midpoint' is not one of: beta, quasi-static"),
                       (["mesh.massless=quasi-static"], "[mesh] massless 'quasi-static' applies to a redistributed mass only")):
        assert_refused(run_main, [str(example("impacting_bar")), "--out", str(bad / "run"),
                                  *[x for s in sets for x in ("--set", s)]], word, capsys, bad)


def test_bar_element_and_mass_are_named_when_refused(tmp_path, capsys):
    """A bar's keys are named in its refusals (they named Bar's fields: N=0, k=-100,
    b=-0.1): one line with the key, the value and what is allowed; nothing written.  A P2
    run's summary.json says p2 (it said p1 whatever the element)."""
    bad = tmp_path / "bad"
    bad.mkdir()
    for key, word in (("element=p3", "[mesh] element='p3' is not one of: p1, p2"),
                      ("mass=heavy", "[mesh] mass='heavy' is not one of: consistent, lumped"),
                      ("J=0", "[mesh] J=0 must be a whole number ≥ 1"),
                      ("obstacles.0.stiffness=-100", "[obstacles.0] stiffness=-100 must be"),
                      ("damping.viscosity=-0.1", "[damping] viscosity=-0.1 must be ≥ 0")):
        key = key if "." in key.split("=")[0] else f"mesh.{key}"
        assert_refused(run_main, [str(example("impacting_bar")), "--out", str(bad / "run"),
                                  "--set", key], word, capsys, bad)
    out = tmp_path / "p2"
    assert exit_code(run_main, [str(example("impacting_bar")), "--set", "mesh.element=p2",
                                "--set", "time.T=0.1", "--format", "none",
                                "--out", str(out)]) == 0
    assert json.loads((out / "summary.json").read_text())["element"] == "p2"


@pytest.mark.parametrize("scene, sets, flags", [
    ("impacting_bar", ["contact.law=moreau-jean", "time.T=0.5"],
     (impacting_bar.main, ["--T", "0.5", "--law", "moreau-jean"])),
    ("impacting_bar", ["mesh.element=p2", "time.beta=0.09", "time.T=0.5"],
     (impacting_bar.main, ["--T", "0.5", "--element", "p2", "--beta", "0.09"])),
    ("point_stops", ["contact.law=moreau-jean", "time.T=0.3"],
     (point_stops.main, ["--T", "0.3", "--law", "moreau-jean"])),
    ("point_stops", ["mesh.mass=redistributed", "mesh.massless=quasi-static", "time.T=0.3"],
     (point_stops.main, ["--T", "0.3", "--mass", "redistributed", "--massless",
                         "quasi-static"])),
])
def test_law_and_mass_keys_are_the_case_flags(tmp_path, scene, sets, flags):
    """[contact] law = "moreau-jean" and a beam's [mesh] mass / massless run as the case
    command's --law, --mass, --massless, bit for bit (issue: scene files name every class)."""
    a, b = tmp_path / "scene", tmp_path / "case"
    assert exit_code(run_main, [str(example(scene)), *[x for s in sets for x in ("--set", s)],
                                "--out", str(a), "--format", "none"]) == 0
    main, argv = flags
    assert exit_code(main, [*argv, "--out", str(b), "--format", "none"]) == 0
    assert series(a) == series(b)
    assert json.loads((a / "summary.json").read_text())["status"] == "success"


@pytest.mark.parametrize("sets, word", [
    (["mesh.mass=lumped"], "[mesh] mass='lumped' is not one of: consistent, redistributed"),
    (["contact.law=bogus"], "[contact] law='bogus' is not one of: position, moreau-jean"),
    (["contact.law=position", "contact.stiffness=1e6"], "law = 'position' does not take it"),
    (["contact.law=moreau-jean", "mesh.mass=redistributed", "mesh.massless=beta"],
     '[mesh] massless = beta applies to the β-scheme'),
])
def test_bad_law_and_mass_keys_are_refused(tmp_path, capsys, sets, word):
    assert_refused(run_main, [str(example("point_stops")), "--out", str(tmp_path / "run"),
                              *[x for s in sets for x in ("--set", s)]], word, capsys, tmp_path)


def test_modes_need_no_time_step(tmp_path):
    """`modes` on a scene without [time] gives the frequencies and shapes of the same
    scene with [time] (which it ignores, with [contact] and [output])."""
    text = example("heat_exchanger_tube").read_text()
    lines, skip = [], False
    for line in text.splitlines():
        skip = line.startswith("[time]") or (skip and not line.startswith("["))
        if not skip:
            lines.append(line)
    bare = write(tmp_path, "\n".join(lines) + "\n", "bare.toml")
    assert "[time]" not in bare.read_text()
    a, b = tmp_path / "a", tmp_path / "b"
    assert exit_code(modes_main, [str(bare), "--n", "3", "--out", str(a)]) == 0
    assert exit_code(modes_main, [str(example("heat_exchanger_tube")), "--n", "3",
                                  "--out", str(b)]) == 0
    assert (a / "modes.csv").read_text() == (b / "modes.csv").read_text()


BAR = """kind = "bar"
[geometry]
L = 1.0
[material]
E = 1.0
rho = 1.0
[[obstacles]]
x = 0
[initial]
v0 = -1.0
[time]
dt = 1e-3
T = 1.5
"""


def test_a_bar_section_is_its_area(tmp_path, capsys):
    """[section] A = 2 (no I: a bar does not bend) runs, its forces A times the
    per-section ones; a bar's section with I is refused in one line."""
    per, area = tmp_path / "per", tmp_path / "area"
    assert exit_code(run_main, [str(write(tmp_path, BAR, "per.toml")), "--out", str(per),
                                "--format", "none"]) == 0
    assert exit_code(run_main, [str(write(tmp_path, BAR + "[section]\nA = 2.0\n", "a.toml")),
                                "--out", str(area), "--format", "none"]) == 0
    f1 = np.genfromtxt(per / "timeseries.csv", delimiter=",", names=True)["contact_force"]
    f2 = np.genfromtxt(area / "timeseries.csv", delimiter=",", names=True)["contact_force"]
    assert np.nanmax(np.abs(f1)) > 0.5
    # two runs' round-off: 2.6e-12 N measured at a 2.0 N force (peak 2.18 N); rtol alone
    # would not hold it, so an atol of 1e-12 × the peak force
    np.testing.assert_allclose(f2, 2.0 * f1, rtol=1e-12, atol=1e-12 * np.nanmax(np.abs(f2)))
    assert json.loads((area / "summary.json").read_text())["units"]["contact_force"] == "N"
    bad = tmp_path / "bad"
    bad.mkdir()
    assert_refused(run_main, [str(write(tmp_path, BAR + "[section]\nI = 1e-8\nA = 2.0\n",
                                        "i.toml")), "--out", str(bad / "run")],
                   "a bar has no I", capsys, bad)


def test_a_held_beam_observes_its_largest_first_mode_amplitude(tmp_path):
    """A pinned–pinned tube's default series is not identically zero: it observes the
    node of largest first-mode amplitude (mid-span, by symmetry of the shipped tube), and
    summary.json says where and why."""
    out = tmp_path / "hx"
    assert exit_code(run_main, [str(example("heat_exchanger_tube")), "--set", "time.T=0.05",
                                "--out", str(out), "--format", "none"]) == 0
    s = json.loads((out / "summary.json").read_text())
    pb = load(example("heat_exchanger_tube")).problem
    m = modes(pb, 1)
    nodes = pb.nodes
    x_peak = nodes[np.argmax(np.abs(np.interp(nodes, m.x, m.shapes[:, 0])))]
    assert s["observed_x"] == pytest.approx(x_peak) == pytest.approx(pb.beam.L / 2)
    assert "the end at L is held" in s["units"]["tip_displacement"]
    tip = np.genfromtxt(out / "timeseries.csv", delimiter=",", names=True)["tip_displacement"]
    assert np.abs(tip).max() > 1e-4


def test_a_free_tip_is_still_observed_at_the_tip(tmp_path):
    out = tmp_path / "ps"
    assert exit_code(run_main, [str(example("point_stops")), "--set", "time.T=0.01",
                                "--out", str(out), "--format", "none"]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["observed_x"] == pytest.approx(1.501) and "held" not in s["units"]["tip_displacement"]


TUBE = """
[material]
E = 2.0e11
rho = 7850.0
[section]
tube = { outer_diameter = 0.01905, wall = 0.00124 }
[geometry]
L = 1.2
[ends]
left = "pinned"
right = "pinned"
[mass]
added = 0.3
[mesh]
J = 30
"""


def test_added_mass_gives_the_textbook_first_frequency(tmp_path):
    """A pinned–pinned steel tube carrying 0.3 kg/m of fluid ([mass] added): its first
    frequency is (π/2L²)√(EI/(ρA + m_a)) to 1e-6, and forces in N use ρA + m_a."""
    from skfem_beam.modes import modes
    scene = load(write(tmp_path, TUBE), dynamic=False)
    D, d = 0.01905, 0.01905 - 2 * 0.00124
    EI, rhoA = 2.0e11 * np.pi * (D**4 - d**4) / 64, 7850.0 * np.pi * (D**2 - d**2) / 4
    f1 = np.pi / (2 * 1.2**2) * np.sqrt(EI / (rhoA + 0.3))
    assert modes(scene.problem, 1).f[0] == pytest.approx(f1, rel=1e-6)
    assert scene.problem.beam.rho_S == pytest.approx(rhoA + 0.3, rel=1e-15)
    dry = load(write(tmp_path, TUBE.replace("added = 0.3", "added = 0.0"), "dry.toml"),
               dynamic=False)
    assert modes(dry.problem, 1).f[0] / f1 == pytest.approx(np.sqrt(1 + 0.3 / rhoA), rel=1e-6)


@pytest.mark.parametrize("change, sets, line", [
    (("g1 = -0.0004", 'g1 = "-0.25mm"'), [], "hx.toml: obstacles.0.g1 = '-0.25mm': must be a "
                                             "number"),
    (("E = 2.0e11", 'E = "200GPa"'), [], "hx.toml: material.E = '200GPa': must be a number"),
    (("zeta = 0.02", "zeta = 2"), [], "hx.toml: [damping] zeta=2 must be below 1: it is a "
                                      "ratio of critical damping (0.02 for 2 %)"),
    (('left = "pinned"', 'left = "glued"'), [], "hx.toml: ends.left='glued' is not one of: "
                                                "clamped, pinned, sliding, free"),
    ((), ["obstacles.0.x=0.6m"], "hx.toml: --set obstacles.0.x=0.6m: must be a number, in "
                                 "SI units (m, s, kg, N, Pa; e.g. 0.25 mm is 0.00025)"),
    ((), ["obstacles.0.g1=-0.25mm"], "hx.toml: --set obstacles.0.g1=-0.25mm: must be a number"),
    ((), ["mass.added=0.3kg"], "hx.toml: --set mass.added=0.3kg: must be a number"),
    (("frames = 200", 'frames = 200\nprobes = [0.5, "1m"]'), [],
     "hx.toml: output.probes[1] = '1m': must be a number, in SI units"),
    (("frames = 200", "frames = 200\nprobes = 0.5"), [],
     "hx.toml: output.probes = 0.5: must be an array of numbers"),
    ((), ['output.probes=[0.5, "1m"]'],
     "hx.toml: --set output.probes=[0.5, \"1m\"]: output.probes[1] = '1m': must be a number"),
])
def test_unit_mistakes_are_one_line_naming_the_file_and_key(tmp_path, capsys, change, sets,
                                                            line):
    text = example("heat_exchanger_tube").read_text()
    src = write(tmp_path, text.replace(*change) if change else text, "hx.toml")
    out = tmp_path / "out"
    out.mkdir()
    argv = [str(src), *[a for x in sets for a in ("--set", x)], "--out", str(out / "run")]
    assert_refused(run_main, argv, line, capsys, out)


def toml_text(data: dict) -> str:
    """``data`` as TOML, each top-level key on one line (inline tables and arrays), so
    that a test can write back a scene file with one value changed."""
    return "".join(f"{key} = {toml_value(value)}\n" for key, value in data.items())


def toml_value(value) -> str:
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {toml_value(v)}" for k, v in value.items()) + "}"
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    return json.dumps(value) if isinstance(value, str) else repr(value)


def numbers_in(value, schema, name="", where=()):
    """(key path as error lines write it, path into the data) of every number in
    ``value``, list entries included, walking the key table ``schema`` beside it; a number
    where the table checks no number fails: "0.5m" there would reach the objects."""
    from skfem_beam.scenefile import N, ListOf, NumberOr, NumberOrWord
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        assert schema is N or isinstance(schema, (NumberOr, NumberOrWord)), \
            f"{name} = {value!r}: the key table does not mark it as a number"
        yield name, where
    elif isinstance(value, list):
        assert isinstance(schema, (ListOf, list)), f"{name}: the key table has no array"
        for i, item in enumerate(value):
            inner = f"{name}[{i}]" if isinstance(schema, ListOf) else f"{name}.{i}"
            yield from numbers_in(item, schema.item if isinstance(schema, ListOf)
                                  else schema[0], inner, where + (i,))
    elif isinstance(value, dict):
        for key, item in value.items():
            yield from numbers_in(item, schema[key], f"{name}.{key}" if name else key,
                                  where + (key,))


SHIPPED = sorted(p.name for p in example("point_stops").parent.glob("*.toml"))
# the arrays of numbers the shipped files do not use (they run as they are)
ARRAYS = {"arrays.toml": """kind = "beam"
planes = 2
[mass_normalised]
k2 = 282.84
rho_S = 0.1194
[geometry]
L = 1.5
[motion]
end = "left"
direction = [0.6, 0.8]
sines = [[0.001, 10.0, 0.0], [0.002, 20.0]]
[[obstacles]]
x = 0.5
hole = { radius = 0.001, centre = [0.0001, 0.0] }
[[obstacles]]
x = 0.75
hole = { polygon = [[0.001, 0.0], [0.0, 0.001], [-0.001, 0.0], [0.0, -0.001]] }
[[obstacles]]
x = 1.0
hole = { faces = [[1.0, 0.0, 0.001], [-1.0, 0.0, 0.001]], centre = [0.0, 0.0] }
[[obstacles]]
x_from = 1.25
x_to = 1.5
g1 = { x = [1.25, 1.5], g = [-0.01, -0.02] }
g2 = { poly = [0.01, 0.001], about = 1.25 }
[initial]
u0 = { x = [0.0, 0.5, 1.0, 1.5], u = [0.0, 0.0001, 0.0002, 0.0003] }
v0 = { x = [0.0, 0.75, 1.5], v = [0.0, 0.001, 0.002] }
u0_w = { x = [0.0, 0.75, 1.5], u = [0.0, -0.0001, 0.0] }
v0_w = { x = [0.0, 0.5, 1.0, 1.5], v = [0.0, 0.001, 0.0, 0.0] }
[mesh]
nodes = [0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5]
[time]
dt = 1e-4
T = 0.01
[output]
probes = [0.3, 0.6]
""", "bar_tables.toml": """kind = "bar"
[material]
E = 1.0
rho = 1.0
[geometry]
L = 1.0
[[obstacles]]
x = "left"
[initial]
u0 = { x = [0.0, 1.0], u = [0.0, 0.0] }
v0 = { x = [0.0, 0.5, 1.0], v = [-1.0, -1.0, -1.0] }
[time]
dt = 1e-3
T = 0.01
"""}


@pytest.mark.parametrize("bad", ["0.5m", float("nan")])
@pytest.mark.parametrize("name", SHIPPED + sorted(ARRAYS))
def test_a_unit_string_for_any_number_of_a_scene_file_is_one_line(tmp_path, capsys, name,
                                                                   bad):
    """Every number of the shipped scene files (and of ARRAYS), in arrays too, written
    "0.5m" or nan: exit code 2, one stderr line naming the file, the key path and the
    value, nothing written."""
    import copy
    import tomllib
    from skfem_beam.scenefile import KINDS
    text = ARRAYS[name] if name in ARRAYS else example(name).read_text()
    if name in ARRAYS:      # a valid scene: the refusals below are the changed value's
        assert exit_code(run_main, [str(write(tmp_path, text, name)), "--format", "none",
                                    "--out", str(tmp_path / "valid")]) == 0
        capsys.readouterr()     # its lines (a cold cache's compile notice) are not the refusals'
    data = tomllib.loads(text)
    assert tomllib.loads(toml_text(data)) == data          # the writer loses nothing
    found = list(numbers_in(data, KINDS[data.get("kind", "beam")]))
    assert len(found) >= 10
    out = tmp_path / "out"
    out.mkdir()
    for key, where in found:
        changed = copy.deepcopy(data)
        node = changed
        for part in where[:-1]:
            node = node[part]
        node[where[-1]] = bad
        src = write(tmp_path, toml_text(changed), name)
        assert_refused(run_main, [str(src), "--out", str(out / "run")],
                       f"error: {name}: {key} = {bad!r}: must be ", capsys, out)


@pytest.mark.parametrize("sets, warning", [
    (["material.E=200"], "[material] E = 200 Pa is outside engineering materials"),
    (["material.rho=7.85"], "[material] rho = 7.85 kg/m³ is outside engineering materials"),
    ([f"obstacles.{i}.{g}={s}0.25" for i in (0, 1) for g, s in (("g1", "-"), ("g2", ""))],
     "no contact in 2000 steps: the largest displacement at the obstacles was"),
])
def test_implausible_values_warn_in_one_line_and_the_run_goes_on(tmp_path, capsys, sets,
                                                                 warning):
    argv = [str(example("heat_exchanger_tube")), "--set", "time.T=0.2", "--format", "none",
            "--out", str(tmp_path / "run")]
    assert exit_code(run_main, argv + [a for s in sets for a in ("--set", s)]) == 0
    err = [e for e in capsys.readouterr().err.splitlines() if e.startswith("warning")]
    assert len(err) == 1 and warning in err[0], err


@pytest.mark.parametrize("k", [1, 2, 3])
def test_modal_damping_gives_every_mode_its_log_decrement(tmp_path, k):
    """[damping] modal = 0.02: the tube released from its k-th mode shape decays as that
    mode alone, with the log decrement 2πζ/√(1 − ζ²) to 1e-3 (peaks of 6 periods,
    each refined by a parabola through the three samples around it)."""
    text = TUBE.replace("added = 0.3", "added = 0.0") + \
        f"[damping]\nmodal = 0.02\n[initial]\nmode = {k}\namplitude = 0.001\n"
    scene = load(write(tmp_path, text + "[time]\ndt = 1e-5\nT = 0.1\n"), dynamic=False)
    f = modes(scene.problem, k).f[k - 1]
    system = beam_system(scene.problem)
    x = 0.5 / k * 1.2 if k > 1 else 0.6      # a crest of mode k
    from skfem_beam.semidiscrete import add_probes
    add_probes(system, [x])
    steps_per_period = 400
    from skfem_beam import Stepping, methods
    run = methods.PositionLevel("auto").build(system, Stepping(1 / (f * steps_per_period), 6.5 / f,
                                                    frames=10))
    drive(run, progress=False)
    u = run.result().observed[f"probe_{x:g}_displacement"]
    i = np.flatnonzero((u[1:-1] > u[:-2]) & (u[1:-1] >= u[2:])) + 1
    a, b, c = u[i - 1], u[i], u[i + 1]
    peaks = b - (a - c) ** 2 / (8 * (a - 2 * b + c))
    delta = np.log(peaks[:-1] / peaks[1:])
    assert peaks.size >= 5
    want = 2 * np.pi * 0.02 / np.sqrt(1 - 0.02**2)
    assert np.abs(delta / want - 1).max() < 1e-3, delta / want


def test_a_psd_load_over_part_of_the_span(tmp_path):
    """[[loads]] psd = { table, seed, df } over x_from..x_to: the force per length is the
    table's synthesis with that seed (timefunctions.from_psd, whose realised spectrum
    test_psd holds to its 95 % band) on the span and 0 off it; the run stores the table,
    so it resumes without the file."""
    from skfem_beam.timefunctions import psd_from_csv
    (tmp_path / "psd.csv").write_text("f,S\n5,0.0\n10,4.0\n100,4.0\n150,0.0\n")
    text = TUBE + """[[obstacles]]
x = 0.6
g1 = -0.0003
g2 = 0.0003
[[loads]]
distributed = true
x_from = 0.4
x_to = 0.8
psd = { table = "psd.csv", seed = 3, df = 0.5 }
[time]
dt = 1e-4
T = 0.2
"""
    src = write(tmp_path, text)
    scene = load(src)
    (profile, time), = scene.problem.load.forces
    t = np.linspace(0.0, 0.2, 999)
    np.testing.assert_array_equal(time(t), psd_from_csv(tmp_path / "psd.csv", 3, 0.5)(t))
    np.testing.assert_array_equal(profile(np.array([0.0, 0.39, 0.4, 0.6, 0.8, 0.81, 1.2])),
                                  [0, 0, 1, 1, 1, 0, 0])
    out = tmp_path / "run"
    assert exit_code(run_main, [str(src), "--format", "none", "--checkpoint-every", "0",
                                "--out", str(out)]) == 0
    (tmp_path / "psd.csv").unlink()
    assert exit_code(run_main, ["--resume", str(out), "--T", "0.3"]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "success" and s["impacts"] > 0


def test_elastic_supports_give_peak_forces_that_converge_with_dt(tmp_path):
    """The heat-exchanger tube with baffles of stiffness 1e6 N/m ([[obstacles]] stiffness,
    the penalty law's springs) and the load averaged about each step ([time] load_window
    = "centered"): the first impact's peak force with Δt = 1e-4, 5e-5, 2.5e-5 s moves by
    1.3 % then 0.2 % (converged within 1 % at 5e-5: not a number of Δt, unlike rigid
    baffles, whose units say so)."""
    text = example("heat_exchanger_tube").read_text().replace(
        "g2 = 0.0004", "g2 = 0.0004\nstiffness = 1e6").replace(
        "T = 1.0", 'T = 0.04\nload_window = "centered"')
    src = write(tmp_path, text, "hx.toml")
    peaks = []
    for dt in (1e-4, 5e-5, 2.5e-5):
        out = tmp_path / f"dt{dt:g}"
        assert exit_code(run_main, [str(src), "--set", f"time.dt={dt}", "--format", "none",
                                    "--out", str(out)]) == 0
        first = np.genfromtxt(out / "impacts.csv", delimiter=",", names=True)[0]
        peaks.append(first["peak_force"])
        s = json.loads((out / "summary.json").read_text())
        assert s["method"] == "penalty" and s["penalty_stiffness_N_per_m"] == 1e6
        assert "rigid" not in s["impact_statistics"]["units"]["peak_force"]
        assert 1e-6 < s["max_support_deflection"] == s["max_nodal_violation"] < 1e-4
    change = np.abs(np.diff(peaks)) / peaks[1:]
    assert 0.005 < change[0] < 0.03 and change[1] < 0.01, (peaks, change)
    rigid = tmp_path / "rigid"
    assert exit_code(run_main, [str(example("heat_exchanger_tube")), "--set", "time.T=0.04",
                                "--format", "none", "--out", str(rigid)]) == 0
    units = json.loads((rigid / "summary.json").read_text())["impact_statistics"]["units"]
    assert "grows as dt shrinks: quote the impulse" in units["peak_force"]


def test_damped_supports_dissipate_what_their_dashpots_do(tmp_path):
    """Baffles of 1e6 N/m and 30 N·s/m ([[obstacles]] stiffness, damping: Kelvin–Voigt).
    Over the first impact the contact work equals −Σ c ẏ² Δt, the dashpot's dissipation
    summed from the probes' displacement series at the baffles (ẏ central, on the steps
    compressed at tₙ), up to the springs' own defect where they switch on and off, which
    falls at second order: 5.5 % at Δt = 5e-5 s, 1.3 % at 2.5e-5 s.  The energy identity
    holds to round-off and the peak force moves by under 1 % between the two."""
    from skfem_beam import read_run
    text = example("heat_exchanger_tube").read_text().replace(
        "g2 = 0.0004", "g2 = 0.0004\nstiffness = 1e6\ndamping = 30.0").replace(
        "T = 1.0", 'T = 0.04\nload_window = "centered"')
    src = write(tmp_path, text, "hx.toml")
    errors, peaks = [], []
    for dt in (5e-5, 2.5e-5):
        out = tmp_path / f"dt{dt:g}"
        assert exit_code(run_main, [str(src), "--set", f"time.dt={dt}", "--probe", "0.5",
                                    "--probe", "1.0", "--format", "none",
                                    "--out", str(out)]) == 0
        run = read_run(out)
        s, imp = run.series, run.impacts
        assert run.summary["penalty_damping_N_s_per_m"] == 30.0
        end = int(round(imp["t_end"][0] / dt)) + 2       # the first impact is over
        dissipated = 0.0
        for x in ("0.5", "1"):
            y = s[f"probe_{x}_displacement"][:end + 1]
            n = np.flatnonzero(np.abs(y[1:-1]) > 0.0004) + 1     # compressed at tₙ
            dissipated += 30.0 * np.sum((y[n + 1] - y[n - 1]) ** 2) / (4 * dt)
        errors.append(abs(s["work_contact_J"][end] / -dissipated - 1))
        peaks.append(imp["peak_force"][0])
        balance = s["energy_J"] - s["energy_J"][0] + s["work_damping_J"] \
            - s["work_input_J"] - s["work_contact_J"]
        assert np.abs(balance).max() < 1e-11 * np.abs(s["energy_J"]).max()
    assert errors[1] < 0.02 and errors[0] / errors[1] > 3, errors
    assert abs(peaks[1] / peaks[0] - 1) < 0.01


def test_a_shipped_scene_runs_by_its_name_from_any_folder(tmp_path, monkeypatch, capsys):
    """`run point_stops.toml` (as the scene-file page writes it) finds the shipped file when
    the folder has none of that name, and runs what `example` gives; a --set of the kind is
    one line (it used to end in a KeyError)."""
    monkeypatch.chdir(tmp_path)
    a, b = tmp_path / "a", tmp_path / "b"
    argv = ["--T", "0.01", "--format", "none"]
    assert exit_code(run_main, ["point_stops.toml", "--out", str(a), *argv]) == 0
    assert exit_code(run_main, [str(example("point_stops")), "--out", str(b), *argv]) == 0
    assert (a / "timeseries.csv").read_bytes() == (b / "timeseries.csv").read_bytes()
    out = tmp_path / "refused"
    out.mkdir()
    capsys.readouterr()
    assert_refused(run_main, ["point_stops.toml", "--set", "kind=foo", "--out",
                              str(out / "x")], "a scene's kind is its file's", capsys, out)


def test_resume_names_a_changed_set_or_scene_as_written(tmp_path, capsys):
    """A resumed run keeps its scene and --set: the refusal shows both as a user writes
    them (not Python lists or None)."""
    src = write(tmp_path, PIPE + '[output]\nformat = "none"\n')
    other = write(tmp_path, PIPE, name="other.toml")
    out = tmp_path / "run"
    assert exit_code(run_main, [str(src), "--out", str(out)]) == 0
    capsys.readouterr()
    for argv, line in (
            (["--set", "time.dt=2e-5"], "--set time.dt=2e-5, where the run had no --set"),
            ([str(other)], f"scene file {other}, where the run had scene file {src}")):
        assert exit_code(run_main, ["--resume", str(out), *argv]) == 2
        assert capsys.readouterr().err == (
            f"error: --resume {out}: {line}; a resumed run keeps its scene and flags (only "
            "--T may grow: extend it with --T)\n")


def test_resume_takes_the_run_s_set_however_written(tmp_path, capsys):
    """--resume with the run's own --set written another way (indexed, 0.30, another
    order) is the same run (it was refused as a change); one that changes a value, or
    reorders a table and a key inside it (order decides), is not."""
    from skfem_beam.parser import same_sets
    src = write(tmp_path, PIPE + '[output]\nformat = "none"\nprobes = [0.5]\n')
    out = tmp_path / "run"
    run = ["--set", "time.T=0.02", "--set", "output.probes.0=0.3"]
    assert exit_code(run_main, [str(src), "--out", str(out), *run]) == 0
    capsys.readouterr()
    again = ["--set", "output.probes[0]=0.30", "--set", "time.T=0.02", "--T", "0.03"]
    assert exit_code(run_main, ["--resume", str(out), *again]) == 0
    assert same_sets(["a.b=1", "c=[1, 2]"], ["c = [1.0, 2]", "a.b=1.0"])
    assert not same_sets(["a.b=1"], ["a.b=2"]) and not same_sets(["a=1"], ["a=1", "b=2"])
    assert not same_sets(["a={b=1}", "a.b=2"], ["a.b=2", "a={b=1}"])


def test_a_T_between_steps_says_where_the_run_ends(tmp_path, capsys):
    """The run ends at the first step at or after T (⌈T/Δt⌉ steps): one line says so."""
    argv = [str(write(tmp_path, PIPE)), "--format", "none", "--set", "time.dt=3e-5"]
    assert exit_code(run_main, argv + ["--out", str(tmp_path / "a")]) == 0
    notes = [e for e in capsys.readouterr().err.splitlines() if e.startswith("note")]
    assert notes == ["note: T=0.01 s is not a whole number of steps dt=3e-05 s: the run "
                     "ends at t=0.01002 s (334 steps)"]
    assert exit_code(run_main, argv[:-1] + ["time.dt=2.5e-5", "--out", str(tmp_path / "b")]) == 0
    assert "note" not in capsys.readouterr().err


SUMMARY_ONLY = ("displacement", "energy_balance", "linear_stability_limit_dt",
                "max_support_deflection", "rho_S", "probes")


@pytest.mark.parametrize("name", ["point_stops", "heat_exchanger_tube",
                                  "tube_round_holes_friction"])
def test_units_name_each_column_written_and_no_other(tmp_path, name):
    """summary.json's units: one entry per timeseries column under its own name (a
    plane's suffix, a hole's x as <x>), and none for a column the run did not write."""
    out = tmp_path / name
    assert exit_code(run_main, [str(example(name)), "--set", "time.T=0.01", "--format",
                                "none", "--out", str(out)]) == 0
    units = json.loads((out / "summary.json").read_text())["units"]
    columns = (out / "timeseries.csv").read_text().splitlines()[0].split(",")
    named = {c if not c.startswith("hole_") else f"hole_<x>_displacement{c[-2:]}"
             for c in columns}
    assert named - set(units) == set()
    assert set(units) - named - set(SUMMARY_ONLY) == set()
    if name == "tube_round_holes_friction":
        assert units["tip_velocity_w"].endswith("; the second plane's, along z")
        assert "work_friction_J" in units and "tip_velocity" not in units


def test_a_hole_radius_like_the_hole_s_own_warns(tmp_path, capsys):
    """A hole's radius is the clearance round the tube's axis: one as large as the tube
    (the hole's own radius, written there) warns in one line and runs."""
    argv = [str(example("tube_round_holes")), "--set", "obstacles.0.hole.radius=0.013",
            "--set", "time.T=0.005", "--format", "none", "--out", str(tmp_path / "r")]
    assert exit_code(run_main, argv) == 0
    err = [e for e in capsys.readouterr().err.splitlines() if e.startswith("warning")]
    assert err == ["warning: [obstacles.0] hole radius = 0.013 m is 1.4× the tube's outer "
                   "radius 0.009525 m: it is the radial clearance round the tube's axis "
                   "(0.0004 for 0.4 mm), not the hole's own radius"]


@pytest.mark.parametrize("setting, line", [
    ("wear.land=19.0", "warning: [wear] land = 19 m is longer than the beam (L = 1.5 m): it "
                       "is the baffle's thickness in m (0.019 for 19 mm)"),
    ("wear.radius=9.525", "warning: [wear] radius = 9.525 m is 1000× the section's outer "
                          "radius 0.009525 m: it is the tube's outer radius in m (0.009525 "
                          "for 9.525 mm)"),
    ("wear.land=0.019", None)])
def test_a_wear_size_in_mm_written_as_m_warns(tmp_path, capsys, setting, line):
    """A [wear] land or radius in mm written as m made the depth 1000 times too small
    and dropped the wear-through warning, silently: one line, and it runs."""
    argv = [str(example("tube_round_holes_friction")), "--set", setting,
            "--set", "time.T=0.005", "--format", "none", "--out", str(tmp_path / "r")]
    assert exit_code(run_main, argv) == 0
    err = [e for e in capsys.readouterr().err.splitlines() if e.startswith("warning: [wear]")]
    assert err == ([line] if line else []), err


def test_a_hole_off_the_mesh_is_named_and_modes_write_no_minus_zero(tmp_path, capsys):
    """A hole at no node was refused without its key (a flat obstacle's line has it); a
    mode's shape at a held node was written -0."""
    out = tmp_path / "out"
    out.mkdir()
    assert_refused(run_main, [str(example("tube_round_holes")), "--set", "obstacles.0.x=0.52",
                              "--out", str(out / "r")],
                   "tube_round_holes.toml: obstacles.0: the mesh has no node at the obstacle "
                   "break point x=0.52", capsys, out)
    assert exit_code(modes_main, [str(example("tube_round_holes")), "--out",
                                  str(tmp_path / "m")]) == 0
    text = (tmp_path / "m" / "modes.csv").read_text()
    assert ",-0," not in text and not text.count(",-0\n"), text[:300]


def test_a_hole_in_a_one_plane_scene_asks_for_planes_first(tmp_path, capsys):
    """A hole beside g1, g2 in a one-plane file was told to leave out g1, g2, and then
    that it needs planes = 2: the planes first."""
    src = example("heat_exchanger_tube").read_text()
    assert "planes" not in src and "g1 = " in src
    out = tmp_path / "out"
    out.mkdir()
    assert_refused(run_main, [str(example("heat_exchanger_tube")), "--set",
                              "obstacles.0.hole={radius=0.0004}", "--out", str(out / "r")],
                   "it needs planes = 2 at the top of the file", capsys, out)


@pytest.mark.parametrize("angle, warned", [(30.0, True), (-7.0, True), (0.5236, False)])
def test_a_polygon_angle_beyond_a_turn_warns(tmp_path, capsys, angle, warned):
    """A regular polygon's angle is in rad (a broached hole's in degrees): 30 meant as
    degrees ran as 30 rad, another polygon, silently; beyond a turn it warns and runs."""
    argv = [str(example("tube_round_holes")), "--set",
            f"obstacles.0.hole={{sides=6,radius=0.0004,angle={angle}}}",
            "--set", "time.T=0.005", "--format", "none", "--out", str(tmp_path / "r")]
    assert exit_code(run_main, argv) == 0
    err = [e for e in capsys.readouterr().err.splitlines() if e.startswith("warning")]
    line = (f"warning: [obstacles.0] hole angle = {angle:g} is in rad for sides = n (a turn is "
            f"6.283): {angle:g}° would be angle = {np.radians(angle):.6g}")
    assert err == ([line] if warned else []), err



@pytest.mark.parametrize("argv, line", [
    (["--set", "time.dt=-1e-5"], "error: scene.toml: [time] dt=-1e-05 must be > 0"),
    (["--set", "output.frames=0"], "error: scene.toml: [output] frames=0 must be a whole "
                                   "number ≥ 1"),
    (["--T", "1e-6"], "error: --T 1e-06: dt=5e-05 must be less than T=1e-06"),
])
def test_a_bad_time_grid_names_its_key_or_flag(tmp_path, capsys, argv, line):
    out = tmp_path / "out"
    out.mkdir()
    assert_refused(run_main, [str(write(tmp_path, PIPE)), *argv, "--out", str(out / "r")],
                   line, capsys, out)


@pytest.mark.parametrize("setting, written", [
    # read as truthy before: "false" ran as true (6 impacts, not 9), 0 as a load
    ('initial.fixed_frame="false"', "--set initial.fixed_frame=\"false\""),
    ("loads.0.distributed=0", "--set loads.0.distributed=0"),
    ('loads.0.per_mass="no"', "--set loads.0.per_mass=\"no\""),
])
def test_a_flag_is_true_or_false(tmp_path, capsys, setting, written):
    scene = example("flat_obstacles.toml")
    assert_refused(run_main, [str(scene), "--set", setting, "--out", str(tmp_path / "x")],
                   f"{written}: must be true or false (no quotes)", capsys, tmp_path)


def test_a_beam_obstacle_table_must_cover_where_it_acts(tmp_path, capsys):
    """{x, g} over the span [5, 10] given on [6, 8] only was extended flat beyond its
    points (np.interp), silently; a plate's table is refused the same way."""
    scene = example("flat_obstacles.toml")
    assert_refused(run_main, [str(scene), "--set", "obstacles.0.g1={x=[6,8],g=[-0.01,-0.02]}",
                              "--out", str(tmp_path / "x")],
                   "obstacles.0.g1 = {x, g}: the obstacle acts at x=5, outside its table's x "
                   "[6, 8]", capsys, tmp_path)
    covered = tmp_path / "ok"
    assert exit_code(run_main, [str(scene), "--set", "obstacles.0.g1={x=[5,10],g=[-0.01,-0.02]}",
                                "--T", "0.2", "--format", "none", "--out", str(covered)]) == 0


def test_a_load_span_off_the_beam_is_refused(tmp_path, capsys):
    """x_from, x_to = [11, 12] on the 10 m beam ran as no load at all (a point force off
    the beam is refused, and a plate's load region off the plate)."""
    assert_refused(run_main, [str(example("flat_obstacles.toml")), "--set",
                              "loads=[{distributed=true,x_from=11.0,x_to=12.0,value=1000.0}]",
                              "--out", str(tmp_path / "x")],
                   "[loads.0] x_from, x_to = [11, 12] must lie on the beam [0, L=10]",
                   capsys, tmp_path)


@pytest.mark.parametrize("setting, word", [
    ("contact.friction=0.3", "unknown key 'friction'; [contact] allows: law, stiffness"),
    ("output.probes=[0.5]", "unknown key 'probes'; [output] allows: format"),
])
def test_the_bar_refuses_keys_it_ignored(tmp_path, capsys, setting, word):
    """A bar's [contact] friction and [output] probes were read and ignored (the same
    files with and without them)."""
    assert_refused(run_main, [str(example("impacting_bar.toml")), "--set", setting, "--out",
                              str(tmp_path / "x")], word, capsys, tmp_path)


@pytest.mark.parametrize("scene, setting, word", [
    # tracebacks before: TypeError (unhashable, a missing argument), ValueError (ragged)
    ("tube_round_holes.toml", "motion.end=[1]", "--set motion.end=[1]: must be a word in quotes"),
    ("tube_round_holes.toml", "mesh.element=1", "--set mesh.element=1: must be a word in quotes"),
    ("tube_round_holes.toml", "loads.0.random={rms=10.0}",
     "[loads.0.random] needs rms, f_low, f_high (missing f_low, f_high)"),
    ("tube_round_holes.toml",
     "obstacles.0.hole={polygon=[[0.001,0.0,1.0],[0.0,0.001],[-0.001,0.0]]}",
     "hole polygon must be [[y1, z1], [y2, z2], ...]"),
    ("tube_round_holes.toml", "obstacles.0.hole={faces=[[1.0,0.0],[-1.0,0.0,0.0004]]}",
     "obstacles.0.hole: hole faces must be [[ny, nz, gap], ...]"),
    # a zero load, silently
    ("flat_obstacles.toml", "loads=[{per_mass=true,omega=10.0}]",
     "[loads.0] amplitude and omega go together"),
    ("flat_obstacles.toml", "loads=[{per_mass=true,amplitude=1.0}]",
     "[loads.0] amplitude and omega go together"),
    ("point_stops.toml", "motion={end=\"left\",omega=10.0}",
     "[motion] amplitude and omega go together"),
    # the time function's own refusal, named by its table (it named no key)
    ("tube_round_holes.toml", "loads.0.random={rms=1.0,f_low=100.0,f_high=10.0}",
     "tube_round_holes.toml: [loads.0] f_high=10 must exceed f_low=100"),
    # a phase without its sine, ignored silently
    ("flat_obstacles.toml", "loads=[{per_mass=true,phase=1.5}]",
     "[loads.0] phase belongs to amplitude · sin(omega t + phase): give amplitude and omega"),
    ("flat_obstacles.toml", "loads=[{per_mass=true,value=1.0,phase=1.5}]",
     "[loads.0] phase belongs to amplitude · sin(omega t + phase): not to value"),
])
def test_malformed_values_are_one_line(tmp_path, capsys, scene, setting, word):
    assert_refused(run_main, [str(example(scene)), "--set", setting, "--out",
                              str(tmp_path / "x")], word, capsys, tmp_path)


def test_modes_over_a_run_folder_replaces_it_whole(tmp_path, capsys):
    """modes --out DIR --overwrite on a run's folder wrote modes.csv and its summary
    beside the run's series, fields and checkpoint (a resume then refused, read_run mixed
    them); it now empties the folder as a run does, and locks it while it writes."""
    out = tmp_path / "run"
    assert exit_code(point_stops.main, ["--T", "0.01", "--format", "none", "--out",
                                        str(out)]) == 0
    assert exit_code(modes_main, [str(example("point_stops.toml")), "--out", str(out),
                                  "--overwrite"]) == 0
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == \
        ["modes.csv", "summary.json"]
    assert json.loads((out / "summary.json").read_text())["modes"] == 6


@pytest.mark.parametrize("setting, word", [
    # amplitude without mode was read and ignored: the beam started at rest
    ("initial.amplitude=0.001", "[initial] amplitude scales a mode shape: it needs mode = k"),
    # mode without amplitude started the beam 1 m out
    ("initial.mode=1", "[initial] mode = 1 needs amplitude (m)"),
    # over half the beam, extrapolated: the tip started at 4.4 times the largest value
    ("initial.u0={x=[0,2.5,5],u=[0,1e-4,5e-4]}", "[initial.u0] x runs from 0 to 5 m: the "
                                                 "table must cover the beam, 0 to L = 10 m"),
    ("initial.v0={x=[-1,0,10],v=[0,0,0]}", "[initial.v0] x runs from -1 to 10 m"),
    # J was read and ignored: the nodes' 2 elements ran
    ("mesh.nodes=[0,5,10]", "[mesh] give J (a uniform mesh) or nodes, not both"),
])
def test_values_read_and_not_used_are_refused(tmp_path, capsys, setting, word):
    assert_refused(run_main, [str(example("flat_obstacles.toml")), "--set", setting,
                              "--out", str(tmp_path / "x")], word, capsys, tmp_path)


@pytest.mark.parametrize("setting, word", [
    # named a flag the user never gave (--format, --flush-every), and no file
    ('output.format="vtk"', "flat_obstacles.toml: [output] format 'vtk' is not one of"),
    ("output.flush_every=0", "flat_obstacles.toml: [output] flush_every=0 must be"),
])
def test_an_output_value_of_the_file_is_named_as_the_file_has_it(tmp_path, capsys, setting,
                                                                word):
    assert_refused(run_main, [str(example("flat_obstacles.toml")), "--set", setting, "--out",
                              str(tmp_path / "x")], word, capsys, tmp_path)


@pytest.mark.parametrize("scene, setting, word", [
    # numpy's "Maximum allowed size exceeded", skfem's "Newton iteration didn't converge"
    ("flat_obstacles.toml", "mesh.J=99999999999999999999999", "must be at most 10,000,000"),
    ("plate_rattling.toml", "mesh.nx=100000", "[mesh] nx=100000 must be at most 2,000"),
    # and a refused value names its key
    ("plate_rattling.toml", "loads.0.pressure=inf", "loads.0.pressure=inf must be a finite"),
    ("plate_rattling.toml", "mesh.nx=2.5", "[mesh] nx=2.5 must be a whole number ≥ 1"),
    ("flat_obstacles.toml", "mesh.J=40.5", "[mesh] J=40.5 must be a whole number ≥ 1"),
])
def test_a_mesh_beyond_memory_is_one_line(tmp_path, capsys, scene, setting, word):
    assert_refused(run_main, [str(example(scene)), "--set", setting, "--out",
                              str(tmp_path / "x")], word, capsys, tmp_path)


@pytest.mark.parametrize("setting, word", [
    ("obstacles.1.hole.radius=-0.0004", "obstacles.1.hole: radius=-0.0004 must be > 0"),
    ("obstacles.1.friction=-1", "obstacles.1: friction=-1 must be ≥ 0"),
    ("obstacles.1.x=2.0", "obstacles.1: hole at x=2 lies outside the beam [0, L=1.5]"),
    ("obstacles.1.hole.sides=2", "obstacles.1.hole: sides=2 must be a whole number ≥ 3"),
])
def test_a_hole_refused_names_its_obstacle(tmp_path, capsys, setting, word):
    """With two baffles, "radius=-0.0004 must be > 0" did not say which."""
    assert_refused(run_main, [str(example("tube_round_holes")), "--set", setting, "--out",
                              str(tmp_path / "x")], word, capsys, tmp_path)


def test_a_whole_number_written_as_a_float_is_taken():
    """TOML's 1e3 and 40.0 are floats: they were refused as "J=40.0 must be a whole
    number", which they are."""
    a, b = (load(example("flat_obstacles"), [f"mesh.J={j}"]) for j in ("40", "40.0"))
    assert a.problem.J == b.problem.J == 40 and isinstance(b.problem.J, int)
    plate = load(example("plate_rattling"), ["mesh.nx=2e1", "mesh.ny=2e1"])
    assert plate.problem.space.plate.nx == 20


def test_a_kind_that_is_no_word_is_one_line(tmp_path, capsys):
    path = tmp_path / "src" / "k.toml"
    path.parent.mkdir()
    path.write_text('kind = ["beam"]\n')
    (tmp_path / "out").mkdir()
    assert_refused(run_main, [str(path), "--out", str(tmp_path / "out" / "x")],
                   "kind=['beam'] must be one of: beam, bar, plate", capsys, tmp_path / "out")


def test_the_bar_refuses_a_probe_flag(tmp_path, capsys):
    """`run impacting_bar.toml --probe 0.5` took the probe and wrote no column for it."""
    assert_refused(run_main, [str(example("impacting_bar.toml")), "--probe", "0.5", "--out",
                              str(tmp_path / "x")],
                   "--probe X is a beam's: the bar writes u(0) and u(L) only", capsys, tmp_path)


@pytest.mark.parametrize("scene, settings", [
    # skfem's "Transforming over 1000 elements to C_CONTIGUOUS." (a transposed array of ours)
    ("flat_obstacles.toml", ["mesh.J=1200", "time.T=0.002"]),
    # matplotlib's "No artists with labels found to put in legend."
    ("plate_rattling.toml", ["output.probes=[]", "time.T=0.002"]),
])
def test_no_library_chatter_on_stderr(tmp_path, scene, settings):
    """As a user runs it (a process of its own: pytest captures logging and warnings)."""
    import os
    import subprocess
    import sys
    argv = [sys.executable, "-m", "skfem_beam", "run", str(example(scene)), "--format",
            "none", "--out", str(tmp_path / "x")]
    for s in settings:
        argv += ["--set", s]
    p = subprocess.run(argv, capture_output=True, text=True,
                       env={**os.environ, "SKFEM_BEAM_CHARTS": "1"})
    assert p.returncode == 0, p.stderr
    assert "C_CONTIGUOUS" not in p.stderr and "Warning" not in p.stderr, p.stderr


SEGMENT_E0 = """kind = "beam"
[[segments]]
length = 0.75
material = { E = 2.0e11, rho = 8000.0 }
section = { rod = { diameter = 0.01 } }
[[segments]]
length = 0.75
material = { E = 0.0, rho = 8000.0 }
section = { rod = { diameter = 0.01 } }
[[obstacles]]
x = 1.5
g1 = -0.01
g2 = 0.01
[time]
dt = 1e-4
T = 0.01
"""


@pytest.mark.parametrize("scene, args, line", [
    ("point_stops", ["--set", "output.probes=[0.5, 5.0]"],
     "error: point_stops.toml: [output] probes[1] = 5.0: outside the beam [0, L = 1.501] m"),
    ("point_stops", ["--probe", "7"], "error: --probe 7: outside the beam [0, L = 1.501] m"),
    ("point_stops", ["--set", "obstacles.0.g1=0.05"],
     "error: point_stops.toml: u0 violates the obstacles at x=1.501"),
    ("tube_round_holes", ["--set", "obstacles.0.x=0.0"],
     "error: tube_round_holes.toml: hole 0 at x=0: the beam is held there"),
    ("heat_exchanger_tube", ["--set", "material.E=0"],
     "error: heat_exchanger_tube.toml: [material] E=0 must be > 0"),
    ("heat_exchanger_tube", ["--set", "section.tube.wall=0.1"],
     "error: heat_exchanger_tube.toml: [section.tube] wall=0.1 must be less than"),
    ("segments", [], "error: segments.toml: [segments.1.material] E=0 must be > 0"),
    ("point_stops", ["--set", "time.beta=-0.5"],
     "error: point_stops.toml: [time] beta=-0.5 must lie in [0, 1/2]"),
    ("plate_on_stops", ["--set", "time.beta=-0.5"],
     "error: plate_on_stops.toml: [time] beta=-0.5 must lie in [0, 1/2]"),
])
def test_a_refusal_found_after_the_file_is_read_names_the_file_and_key(tmp_path, capsys,
                                                                        scene, args, line):
    """Errors the system's own checks find (a probe, the start against the obstacles, a
    hole at a held node, a segment's E, β) name the file, and the key where it is one."""
    src = write(tmp_path, SEGMENT_E0, "segments.toml") if scene == "segments" \
        else example(scene)
    out = tmp_path / "out"
    out.mkdir()
    assert_refused(run_main, [str(src), "--out", str(out / "run"), *args], line, capsys, out)


def test_dt_is_checked_against_the_t_that_runs(tmp_path):
    """--T overrides [time] T before Δt is checked: Δt = 0.01 s is refused against the
    file's T = 0.01 s and runs its 10 steps under --T 0.1 (it was checked against the
    file's T while --set time.T=0.1 ran)."""
    scene, out = example("plate_on_stops"), tmp_path / "run"
    argv = [str(scene), "--set", "time.dt=0.01", "--format", "none", "--out", str(out)]
    assert exit_code(run_main, argv) == 2
    assert exit_code(run_main, argv + ["--T", "0.1"]) == 0
    assert json.loads((out / "summary.json").read_text())["steps"] == 10


@pytest.mark.parametrize("sets, T, line", [
    (["time.dt=-2"], "1", "error: plate_on_stops.toml: [time] dt=-2 must be > 0"),
    ([], "nan", "error: --T nan: T must be a positive number of seconds"),
    ([], "1e300", "error: --T 1e+300: T/dt = "),
    ([], "1e-6", "error: --T 1e-06: dt=2e-05 must be less than T=1e-06"),
])
def test_errors_about_t_name_the_flag_and_others_the_file(tmp_path, capsys, sets, T, line):
    """Only T and Δt against it are the flag's: a bad dt of the file's was blamed on --T,
    and --T nan named a --set the user never typed."""
    out = tmp_path / "out"
    out.mkdir()
    assert_refused(run_main, [str(example("plate_on_stops")), "--T", T, "--out",
                              str(out / "run")] + [a for s in sets for a in ("--set", s)],
                   line, capsys, out)


def test_a_driver_above_the_nyquist_frequency_warns_and_runs(tmp_path, capsys):
    """A random band at 6–9 kHz with dt = 1e-4 s (Nyquist 5 kHz) ran without a word, its
    response 14 times that at dt = 1e-5 s."""
    sets = ["time.T=0.002", "loads.0.random.f_low=6000", "loads.0.random.f_high=9000"]
    argv = [str(example("tube_round_holes")), "--format", "none", "--out", str(tmp_path / "r")]
    assert exit_code(run_main, argv + [a for s in sets for a in ("--set", s)]) == 0
    err = [e for e in capsys.readouterr().err.splitlines() if "Nyquist" in e]
    assert err == ["warning: loads.0: its highest frequency, 9000 Hz, lies above the steps' "
                   "Nyquist frequency 1/(2 dt) = 5000 Hz: the steps alias it to a lower one; "
                   "dt ≤ 5.56e-05 s resolves it (about 10 steps a period: 1.11e-05 s)"]


@pytest.mark.parametrize("T, warned", [(0.5, True), (0.4, False)])
def test_a_time_table_ending_before_T_warns(tmp_path, capsys, T, warned):
    """A table is held at its last value past its last row: a support motion cut short by
    mistake stopped there without a word (a beam's motion and load, a plate's pressure)."""
    (tmp_path / "phi.csv").write_text("t,phi\n0,0\n0.1,0.001\n0.2,0.002\n0.3,0.001\n0.4,0\n")
    beam = PIPE.replace("T = 0.01", f"T = {T}") + \
        '[motion]\nend = "left"\ntable = "phi.csv"\n[[loads]]\ntable = "phi.csv"\nper_mass = true\n'
    plate = example("plate_rattling").read_text().replace("T = 0.2 ", f"T = {T} ") \
        .replace("omega = 150.0 ", 'table = "phi.csv"')
    load(write(tmp_path, beam))
    load(write(tmp_path, plate, "plate.toml"))
    err = capsys.readouterr().err.splitlines()
    held = f"table = 'phi.csv' ends at t=0.4 s, before T={T:g} s: from there on it is held " \
           "at its last value"
    assert err == ([f"warning: [loads.0] {held}", f"warning: [motion] {held}",
                    f"warning: [loads.0] {held}"] if warned else [])


def test_a_time_table_whose_spline_overshoots_its_rows_warns(tmp_path, capsys):
    """A ramp then a hold (0, 0, 1, 1, 1): the spline through it went to −0.103 where the
    rows say 0, and a plate on a stop under that load lifted off it by 0.25 mm without a
    word; a smooth table (the bump of the test above) says nothing."""
    (tmp_path / "ramp.csv").write_text("t,f\n0,0\n0.1,0\n0.3,1\n0.4,1\n0.6,1\n")
    beam = PIPE.replace("T = 0.01", "T = 0.6") + '[[loads]]\ntable = "ramp.csv"\nper_mass = true\n'
    load(write(tmp_path, beam))
    assert capsys.readouterr().err.splitlines() == [
        "warning: [loads.0] table = 'ramp.csv': the cubic spline through its rows reaches "
        "-0.103 between t=0 and 0.1 s, outside the rows' values there: give rows closer "
        "together where it bends (a spline gives the acceleration a support's motion needs)"]


def test_a_beam_at_rest_on_a_shaken_support_is_not_a_rough_start(tmp_path, capsys):
    """No [initial] under a moving mid support: the beam starts at rest in its static shape
    (in the moving frame), its data's energy round-off; the start's first step takes in the
    support's motion, which warned "the start holds 5.77e+23 times the initial data's
    energy".  The rough-start line is for initial velocities, not for a support's motion."""
    (tmp_path / "m.toml").write_text("""kind = "beam"
[material]
E = 2.0e11
rho = 8000.0
[section]
rect = { b = 0.02, h = 0.01 }
[geometry]
L = 1.0
[ends]
left = "pinned"
right = "pinned"
[[supports]]
x = 0.5
[motion]
at = 0.5
amplitude = 0.01
omega = 1.0
phase = 1.5707963267948966
[mesh]
J = 20
[time]
dt = 1e-4
T = 0.01
[output]
format = "none"
""")
    assert exit_code(run_main, [str(tmp_path / "m.toml"), "--out", str(tmp_path / "r")]) == 0
    assert "warning" not in capsys.readouterr().err
