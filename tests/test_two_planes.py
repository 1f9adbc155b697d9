"""Two bending planes and holes: the one-plane run as a special case, exact contact in a
round hole (no penetration, the steady whirl's force derived for the discrete system,
Clarabel on recorded step problems), n-gons and stiff springs converging to it, the
energy identity, and what the output says per support."""
import csv
import json

import numpy as np
import pytest

from conftest import assert_refused, compiled, exit_code, resumed
from skfem_beam import methods
from skfem_beam.methods import PositionLevel
from skfem_beam.contact.round_hole import cone_solve, disk_kinds, disk_root
from skfem_beam.holes import Hole, HoleAt
from skfem_beam.errors import InputError
from skfem_beam.problem import (Beam, BeamProblem, Damping, InitialState, Load, Material,
                                Obstacles, Plane, Section)
from skfem_beam.reference import whirl_force
from skfem_beam.scenefile import example, run_main
from skfem_beam.scheme import Run, Stepping, solve
from skfem_beam.scheme.beta import BetaScheme
from skfem_beam.semidiscrete import beam_system
from skfem_beam.timefunctions import Sine

TUBE = Beam.physical(1.5, Material(2e11, 8000.0), Section.tube(0.01905, 0.00165))
R = 4e-4          # the holes' radial clearance (m)


def tube(planes=2, holes=(), load=Load(), second=Plane(), J=30, **kw):
    return BeamProblem(TUBE, load=load, second=second, J=J, ends=("pinned", "pinned"),
                       planes=planes, holes=holes, **kw)


def orbit(result, x):
    return np.column_stack([result.observed[f"hole_{x:g}_displacement_v"],
                            result.observed[f"hole_{x:g}_displacement_w"]])


# ---------------------------------------------------------------- one plane is a special case
@pytest.mark.parametrize("element", ["hermite", "bspline"])
def test_a_square_hole_loaded_in_one_plane_is_the_one_plane_run(element):
    load = Load.distributed(1.0, Sine(300.0, 2 * np.pi * 30))
    one = tube(1, load=load, obstacles=Obstacles.stops([0.5, 1.0], -R, R), element=element)
    two = tube(2, load=load, element=element,
               holes=(HoleAt(Hole.regular(4, R), 0.5), HoleAt(Hole.regular(4, R), 1.0)))
    r1, r2 = solve(beam_system(one), 1e-4, 0.3), solve(beam_system(two), 1e-4, 0.3)
    assert r1.impacts > 100 and r2.impacts == r1.impacts and r2.solver == r1.solver
    v, w = r2.observed["tip_displacement_v"], r2.observed["tip_displacement_w"]
    u = r1.observed["tip_displacement"]
    assert np.abs(w).max() == 0.0
    assert np.abs(v - u).max() <= 1e-12 * np.abs(u).max()
    assert r2.energy[-1] == pytest.approx(r1.energy[-1], rel=1e-12)


def test_the_second_plane_started_as_the_first_moves_as_the_first():
    """A round tube, free of obstacles and support motion, with w started as v (u0 and v0
    given, BeamProblem.second): w(t) is v(t), and both are the one-plane run, to round-off."""
    L = TUBE.L
    start = InitialState(lambda x: 1e-3 * np.sin(np.pi * x / L) * (1 + x),
                         lambda x: 0.05 * np.sin(2 * np.pi * x / L))
    assert TUBE.plane_w().k2 == TUBE.k2
    one = tube(1, initial=start)
    two = tube(2, initial=start, second=Plane(initial=start))
    assert two.plane(1) == (Load(), start)
    r1, r2 = solve(beam_system(one), 1e-4, 0.1), solve(beam_system(two), 1e-4, 0.1)
    u, n = r1.frames_u, r2.system.meta["n_plane"]
    v, w = r2.frames_u[:, :n], r2.frames_u[:, n:]
    scale = np.abs(u).max()
    assert scale > 1e-4 and u.shape == v.shape == w.shape
    assert np.abs(w - v).max() <= 1e-13 * scale         # measured: 0
    assert np.abs(v - u).max() <= 1e-13 * scale         # measured: 0
    assert r2.energy[-1] == pytest.approx(2 * r1.energy[-1], rel=1e-12)
    at_rest = solve(beam_system(tube(2, initial=start)), 1e-4, 0.1)
    assert np.abs(at_rest.frames_u[:, n:]).max() == 0.0    # without second: w at rest


def test_a_second_plane_needs_two_planes():
    with pytest.raises(InputError, match="second plane.s load or initial state need planes = 2"):
        tube(1, second=Plane(initial=InitialState(lambda x: 0 * x)))


# ---------------------------------------------------------------- the whirl in a round hole
def whirl_problem(q=20.0, omega=2 * np.pi * 15, damping=Damping(alpha=60.0, alpha_K=2e-4)):
    """A rotating distributed force q·(cos ωt, sin ωt) N/m on the tube, one round hole
    at mid-span (J = 10): it reaches the wall three times over and whirls on it."""
    return tube(holes=(HoleAt(Hole.round(R), 0.75),), J=10, damping=damping,
                load=Load.distributed(q, Sine(1.0, omega, np.pi / 2)),
                second=Plane(load=Load.distributed(q, Sine(1.0, omega))))


def test_a_round_hole_is_never_penetrated_under_a_rotating_force():
    result = solve(beam_system(whirl_problem(damping=Damping())), 1e-4, 0.5)
    p = orbit(result, 0.75)
    assert result.contact_fraction > 0.9 and result.solver == "round-hole"
    assert (np.hypot(p[:, 0], p[:, 1]) - R).max() <= 1e-12 * R
    assert result.max_nodal_violation <= 1e-12 * R


def test_the_steady_whirl_has_the_contact_force_of_the_discrete_steady_state():
    dt, omega = 1e-4, 2 * np.pi * 15
    system = beam_system(whirl_problem(omega=omega))
    result = solve(system, dt, 2.0, save_every=10)
    lam = np.hypot(result.contact_force[:, 0], result.contact_force[:, 1])
    n = system.meta["n_plane"]
    Lam = whirl_force((system.M[:n, :n], system.K[:n, :n], system.B[:n, :n]),
                      system.loads[:n, 0], system.C[0, :n].toarray(), R, omega, dt, 0.5)
    assert result.contact_fraction > 0.99
    assert np.abs(lam[-100:] / Lam - 1).max() <= 1e-6        # measured 1.2e-13
    assert np.ptp(np.hypot(*orbit(result, 0.75)[-100:].T)) <= 1e-15   # on the circle


def test_energy_identity_closes_with_impacts_in_both_planes():
    scene = tube(holes=(HoleAt(Hole.round(R), 0.5), HoleAt(Hole.regular(3, R), 1.0)),
                 load=Load.distributed(1.0, Sine(300.0, 2 * np.pi * 30)),
                 second=Plane(load=Load.distributed(1.0, Sine(200.0, 2 * np.pi * 23))),
                 damping=Damping.ratio(0.02, 20.0, 200.0))
    r = solve(beam_system(scene), 1e-4, 0.5)
    ev = r.impact_events
    assert r.impacts > 50 and np.ptp(ev["angle"][np.isfinite(ev["angle"])]) > 3.0
    w = r.work
    gap = r.energy - r.energy[0] + w["damping"] - w["input"] - w["contact"]
    assert np.abs(gap).max() <= 1e-11 * np.abs(r.energy).max()
    assert w["contact"][-1] < 0                    # exact contact dissipates


# ---------------------------------------------------------------- the step problem
def recorded_problems(count=40):
    """Step problems (D, y_f, lo, hi, disks) of a rectangular bar (k2_w ≠ k2: each disk's
    2×2 block is anisotropic) in a round hole over three nodes and one at x = 1."""
    beam = Beam.physical(1.5, Material(2e11, 8000.0), Section.rect(0.012, 0.02))
    scene = BeamProblem(beam, ends=("pinned", "pinned"), J=30, planes=2,
                        holes=(HoleAt(Hole.round(R), 0.45, 0.55), HoleAt(Hole.round(R), 1.0)),
                        load=Load.distributed(1.0, Sine(900.0, 2 * np.pi * 30, np.pi / 2)),
                        second=Plane(load=Load.distributed(1.0, Sine(900.0, 2 * np.pi * 30))))
    run = Run(BetaScheme(beam_system(scene), Stepping(1e-4, 0.2)))
    kind = disk_kinds(run.st.yf.size, run.scheme.step.disks)
    out = []
    for n in range(2, 2000):
        run.advance(n)
        yf, lo, hi = run.st.yf.copy(), run.st.lo.copy(), run.st.hi.copy()
        pairs = run.scheme.step.disks
        outside = np.hypot(yf[pairs[:, 0]], yf[pairs[:, 1]]) > R
        if outside.sum() >= 2:
            out.append((run.ops.D, yf, lo, hi, kind, pairs))
        if len(out) == count:
            break
    return out


def test_the_round_hole_law_agrees_with_clarabel_on_recorded_steps():
    clarabel = pytest.importorskip("clarabel")
    import scipy.sparse as sp
    problems = recorded_problems()
    assert len(problems) == 40
    worst, gap, outside = 0.0, -np.inf, -np.inf
    for D, yf, lo, hi, kind, pairs in problems:
        mu, active = np.zeros(yf.size), np.zeros(yf.size, bool)
        assert cone_solve(D, yf, lo, hi, kind, mu, active) > 0
        y = yf + D @ mu
        # KKT of ours: on or inside every circle, forces inward and only on the wall
        rho = np.hypot(y[pairs[:, 0]], y[pairs[:, 1]])
        assert (rho <= R * (1 + 1e-14)).all()
        push = mu[pairs[:, 0]] * y[pairs[:, 0]] + mu[pairs[:, 1]] * y[pairs[:, 1]]
        assert (push <= 0).all() and (np.abs(push) * (R - rho) <= 1e-16 * R * np.abs(mu).max()).all()
        # Clarabel: min ½(y − y_f)ᵀD⁻¹(y − y_f), (r, y_p) in the second-order cone, in
        # units of r and of D's scale (its tolerances are absolute)
        Dinv = np.linalg.inv(D / np.abs(D).max())
        rows, b = [], []
        for a, c in pairs:
            for k in (None, a, c):
                row = np.zeros(yf.size)
                if k is not None:
                    row[k] = -1.0
                rows.append(row)
                b.append(1.0 if k is None else 0.0)
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        for tol in ("tol_gap_abs", "tol_gap_rel", "tol_feas"):
            setattr(settings, tol, 1e-10)
        sol = clarabel.DefaultSolver(sp.csc_matrix(np.triu(Dinv)), -Dinv @ yf / R,
                                     sp.csc_matrix(np.array(rows)), np.array(b),
                                     [clarabel.SecondOrderConeT(3)] * len(pairs),
                                     settings).solve()
        assert str(sol.status) in ("Solved", "AlmostSolved")
        yc = np.array(sol.x) * R

        def f(v):
            return 0.5 * (v - yf) @ np.linalg.solve(D, v - yf)
        # the same optimum to Clarabel's accuracy (its points may lie outside by its
        # feasibility tolerance, so a little below ours)
        gap = max(gap, (f(y) - f(yc)) / f(yc))
        outside = max(outside, (np.hypot(yc[pairs[:, 0]], yc[pairs[:, 1]]) / R - 1).max())
        worst = max(worst, np.abs(yc - y).max() / R)
    # measured: gap 1.7e-10, worst 1.1e-6, Clarabel's points up to ~1e-10 r outside
    assert gap <= 1e-8 and worst <= 1e-5, (gap, worst)


def test_one_disk_is_the_secular_equations_root():
    out = np.empty(3)
    for a, b, d in ((2.0, 0.3, 1.5), (1.0, 0.0, 4.0), (3.0, 0.0, 3.0), (1e-3, 2e-4, 5e-4)):
        z = np.array([1.3, -0.7])
        compiled(disk_root)(a, b, d, z[0], z[1], 0.4, out)
        p, t = out[:2], out[2]
        assert np.hypot(*p) == pytest.approx(0.4, rel=1e-15)
        assert np.abs((np.eye(2) + t * np.array([[a, b], [b, d]])) @ p - z).max() <= 1e-15
        assert t > 0


# ---------------------------------------------------------------- n-gons and springs
def push_problem(hole):
    """A 10 Hz push at 0.35 rad on the tube, one hole at mid-span (J = 10)."""
    th = 0.35
    return tube(holes=(HoleAt(hole, 0.75),), J=10,
                load=Load.distributed(30.0 * np.cos(th), Sine(1.0, 2 * np.pi * 10)),
                second=Plane(load=Load.distributed(30.0 * np.sin(th), Sine(1.0, 2 * np.pi * 10))))


def test_ngons_converge_to_the_round_hole_at_second_order():
    """The n-gon with a corner on the push (the worst case) before the second impact:
    the corner is r(sec(π/n) − 1) ≈ rπ²/(2n²) beyond the circle, so the rate is 2."""
    dt, T = 1e-4, 0.013
    ref = solve(beam_system(push_problem(Hole.round(R))), dt, T)
    ev = ref.impact_events
    assert ev["angle"][0] == pytest.approx(0.35, abs=1e-12)
    k = int(round(ev["t_start"][1] / dt)) - 2           # before the second impact
    errors = []
    for n in (8, 16, 32, 64):
        r = solve(beam_system(push_problem(Hole.regular(n, R, angle=0.35 - np.pi / n))), dt, T)
        errors.append(np.abs(orbit(r, 0.75)[:k] - orbit(ref, 0.75)[:k]).max() / R)
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert ((rates > 1.8) & (rates < 2.2)).all(), rates     # measured 1.92, 2.04, 2.00
    assert errors[-1] < 2e-3


def test_stiffer_springs_converge_to_the_exact_round_hole_run():
    """Radial springs taken at t_{n+1} (Penalty(implicit=True): the Moreau–Yosida
    regularisation of the exact step) converge to the exact run at the same Δt and mesh,
    at rate 1 in 1/κ, before the second impact; the β-weighted springs come within ~1 %
    of the clearance and stay there (docs/design.md §1, *Springs → exact contact*)."""
    dt, T = 1e-4, 0.013
    ref = solve(beam_system(push_problem(Hole.round(R))), dt, T)
    k = int(round(ref.impact_events["t_start"][1] / dt)) - 2
    errors = []
    for stiffness in (1e7, 1e8, 1e9, 1e10):
        r = solve(beam_system(push_problem(Hole.round(R))), dt, T, beta=0.5,
                  method=methods.Penalty(stiffness, implicit=True))
        assert r.solver == "penalty" and r.max_nodal_violation > 0
        errors.append(np.abs(orbit(r, 0.75)[:k] - orbit(ref, 0.75)[:k]).max() / R)
    rates = np.log10(np.array(errors[:-1]) / np.array(errors[1:]))
    assert (rates > 0.85).all() and errors[-1] < 5e-5, errors   # 0.88, 0.98, 1.00; 2.4e-5
    # the β-weighted springs (normal compliance in the dynamics), Δt = 1e-5
    ref = solve(beam_system(push_problem(Hole.round(R))), 1e-5, 0.0098)
    weighted = [np.abs(orbit(solve(beam_system(push_problem(Hole.round(R))), 1e-5, 0.0098,
                                   method=methods.Penalty(s)), 0.75) - orbit(ref, 0.75))
                .max() / R for s in (1e6, 1e8)]
    assert weighted[0] > 4 * weighted[1] and weighted[1] < 0.02, weighted  # 0.113, 0.0127


def test_a_push_lands_where_it_points_and_says_so():
    r = solve(beam_system(push_problem(Hole.round(R))), 1e-4, 0.02)
    ev = r.impact_events
    first = 0
    assert ev["angle"][first] == pytest.approx(0.35, abs=1e-12)
    assert ev["normal_velocity"][first] > 0.01
    assert abs(ev["tangential_velocity"][first]) <= 1e-9 * ev["normal_velocity"][first]


# ---------------------------------------------------------------- the command
@pytest.mark.usefixtures("charts")
def test_the_round_hole_scene_writes_orbits_angles_and_work_rates(tmp_path):
    out = tmp_path / "run"
    assert exit_code(run_main, [str(example("tube_round_holes")), "--set", "time.T=0.3",
                                "--out", str(out), "--format", "vtu"]) == 0
    for name in ("orbit_0.5.png", "orbit_1.png", "tip_displacement.png", "impacts.csv"):
        assert (out / name).is_file()
    summary = json.loads((out / "summary.json").read_text())
    supports = summary["impact_statistics"]["supports"]
    assert [s["x"] for s in supports] == [0.5, 1.0]
    with open(out / "timeseries.csv") as fh:
        rows = list(csv.DictReader(fh))
    T = float(rows[-1]["t"])
    # the supports' impact work is the run's contact work, in W
    total = sum(s["impact_work_rate"] for s in supports) * T
    assert total == pytest.approx(-float(rows[-1]["work_contact_J"]), rel=1e-9)
    assert all(s["normal_work_rate"] > 0 and sum(s["impact_angle_histogram"]["counts"])
               == s["impacts"] for s in supports)
    with open(out / "impacts.csv") as fh:
        head = fh.readline().strip().split(",")
    assert head[-4:] == ["angle", "normal_velocity", "tangential_velocity", "open"]
    v = np.array([float(r_["hole_0.5_displacement_v"]) for r_ in rows])
    w = np.array([float(r_["hole_0.5_displacement_w"]) for r_ in rows])
    assert (np.hypot(v, w) - R).max() <= 1e-12 * R
    import meshio
    last = sorted((out / "fields_vtu").glob("*.vtu"))[-1]
    mesh = meshio.read(last)
    vec = mesh.point_data["displacement_vector"]
    assert np.array_equal(vec[:, 1], mesh.point_data["displacement_v"])
    assert np.array_equal(vec[:, 2], mesh.point_data["displacement_w"])
    assert np.abs(vec[:, 0]).max() == 0.0


def test_the_trefoil_scene_runs_in_its_lands(tmp_path):
    out = tmp_path / "run"
    assert exit_code(run_main, [str(example("tube_trefoil_holes")), "--set", "time.T=0.2",
                                "--out", str(out), "--format", "none"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["max_nodal_violation"] <= 1e-15 and summary["impacts"] > 10


@pytest.mark.parametrize("extra, word", [
    ('[[obstacles]]\nx = 0.5\nhole = { radius = 4e-4 }\n', "planes = 2"),
    ('planes = 3\n', "planes"),
    ('planes = 2\n[[obstacles]]\nx = 0.5\nhole = { radius = 4e-4, angle = 1 }\n', "angle"),
    ('planes = 2\n[[obstacles]]\nx = 0.5\nhole = { polygon = [[0, 1], [1, 0], [1, 1], [-1, 0]] }\n',
     "convex"),
    # a pentagram: every turn to the left, but twice round (it ran as its inner pentagon)
    ('planes = 2\n[[obstacles]]\nx = 0.5\nhole = { polygon = [[0.0, 4e-4], [-2.35e-4, -3.24e-4], '
     '[3.8e-4, 1.24e-4], [-3.8e-4, 1.24e-4], [2.35e-4, -3.24e-4]] }\n', "crosses itself"),
    ('planes = 2\n[[obstacles]]\nx = 0.5\nhole = { radius = 4e-4, centre = [1e-3, 0] }\n',
     "rest position"),
    ('planes = 2\n[[obstacles]]\nx = 0.0\nhole = { radius = 4e-4 }\n', "held there"),
    ('planes = 2\n[[obstacles]]\nx = 0.5\nhole = { radius = 4e-4 }\n[contact]\n'
     'law = "active-set"\n', "round holes"),
    ('[[loads]]\ndistributed = true\ndirection = [0, 1]\nvalue = 1.0\n', "planes = 2"),
    ('planes = 2\n[[loads]]\ndistributed = true\ndirection = [0, 0]\nvalue = 1.0\n',
     "no direction"),
])
def test_bad_two_plane_scenes_are_refused_in_one_line(tmp_path, capsys, extra, word):
    base = example("heat_exchanger_tube").read_text().replace("kind = \"beam\"\n", "")
    scene = tmp_path / "s.toml"
    scene.write_text("kind = \"beam\"\n" + extra.split("[[")[0].split("[contact]")[0]
                     if extra.startswith("planes") and "[[" not in extra else "")
    text = "kind = \"beam\"\n"
    top = extra.split("\n[")[0] if extra.startswith("planes") else ""
    rest = extra[len(top):]
    scene.write_text(text + top + "\n" + base.replace("[time]", rest + "\n[time]"))
    bad = tmp_path / "bad"
    bad.mkdir()
    assert_refused(run_main, [str(scene), "--out", str(bad / "run")], word, capsys, bad)


def test_a_restored_two_plane_run_goes_on_bit_for_bit():
    from skfem_beam.scenefile import load
    system = beam_system(load(example("tube_round_holes")).problem)
    a, c = resumed(lambda: Run(BetaScheme(system, Stepping(1e-4, 0.3))), 1234)
    assert np.array_equal(a.st.rowwork, c.st.rowwork) and a.result().impacts > 20


def test_modes_of_two_planes_list_each_planes_own(tmp_path, capsys):
    from skfem_beam.scenefile import modes_main
    assert exit_code(modes_main, [str(example("tube_round_holes")), "--n", "4", "--set",
                                  "section={ rect = { b = 0.01, h = 0.02 } }", "--out",
                                  str(tmp_path / "m")]) == 0
    with open(tmp_path / "m" / "modes.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["plane"] for r in rows] == ["w", "v", "w", "v"]
    f = [float(r["f_Hz"]) for r in rows]
    # h = 2b: the first plane is four times stiffer, so twice the frequency
    assert f[1] / f[0] == pytest.approx(2.0, rel=1e-12)
    assert f[0] == pytest.approx(np.pi / (2 * 1.5**2) * np.sqrt(2e11 * 0.02 * 0.01**3 / 12
                                                                / (8000 * 2e-4)), rel=1e-6)


@pytest.mark.parametrize("setting, word", [
    ("mesh.mass=redistributed", "one plane"),
    ("contact.law=osqp", "round holes"),
    ("obstacles.0.damping=30.0", "stiffness"),
])
def test_what_two_planes_do_not_take_is_refused(tmp_path, capsys, setting, word):
    bad = tmp_path / "bad"
    bad.mkdir()
    assert_refused(run_main, [str(example("tube_round_holes")), "--set", setting,
                              "--out", str(bad / "run")], word, capsys, bad)


def test_a_carried_round_hole_moves_with_its_support_and_is_never_penetrated():
    """A cantilever whose clamp shakes along d = (0.6, 0.8), its tip in a round hole
    carried by the shaken frame: relative to the hole (ũ − φ(t)·d at the tip, i.e.
    u − (1 − h)φ(t)·d in the lifted u) the tip stays in the disk to round-off, and it
    does touch the wall."""
    from skfem_beam.problem import Support
    d = (0.6, 0.8)
    scene = BeamProblem(TUBE, J=10, planes=2, support=Support(0.002, 2 * np.pi * 30,
                                                              direction=d),
                        holes=(HoleAt(Hole.round(R), 1.5, carried=True),))
    system = beam_system(scene)
    r = solve(system, 1e-4, 0.3)
    assert r.impacts > 5 and r.max_nodal_violation <= 1e-12 * R
    h = float(system.view.lift.h(np.array([1.5]))[0])
    phi = scene.support.phi(r.t)
    rel = orbit(r, 1.5) - np.outer((1 - h) * phi, d)
    assert (np.hypot(rel[:, 0], rel[:, 1]) - R).max() <= 1e-12 * R
    # fixed to the ground instead, the same shaking reaches far beyond the clearance
    fixed = solve(beam_system(BeamProblem(TUBE, J=10, planes=2, support=scene.support,
                                          holes=(HoleAt(Hole.round(R), 1.5),))), 1e-4, 0.3)
    assert fixed.impacts != r.impacts


def test_the_linear_laws_take_a_polygons_faces():
    """Triangular holes (three faces a node: rows that depend on one another; the shipped
    trefoil scene's tube, its broached holes made the triangle of its lands): OSQP gives
    the active set's run, springs and Moreau–Jean run, daqp (which inverts D) refuses."""
    from dataclasses import replace

    from skfem_beam.errors import InputError
    from skfem_beam.scenefile import load
    problem = load(example("tube_trefoil_holes")).problem
    system = beam_system(replace(problem, holes=tuple(replace(h, hole=Hole.regular(3, R))
                                                      for h in problem.holes)))
    ref = solve(system, 1e-4, 0.2)
    osqp = solve(system, 1e-4, 0.2, method=PositionLevel("osqp"))
    assert ref.solver == "active-set" and osqp.impacts == ref.impacts > 20
    k = int(round(ref.impact_events["t_start"][2] / 1e-4))     # before the second impact
    assert np.abs(orbit(osqp, 0.5)[:k] - orbit(ref, 0.5)[:k]).max() <= 1e-12 * R
    for method in (methods.Penalty(1e7), methods.MoreauJean()):
        r = solve(system, 1e-4, 0.2, method=method)
        assert r.success and r.impacts > 20
    with pytest.raises(InputError, match="independent constraint rows"):
        solve(system, 1e-4, 0.2, method=PositionLevel("daqp"))


def test_a_face_is_the_half_plane_written_whatever_its_normals_length():
    """faces = [[2, 0, 4e-4], ...] is 2v ≤ 4e-4 (docs: n·(v, w) ≤ gap): the normal was
    made a unit vector and the gap kept, a hole twice as wide as written."""
    from skfem_beam.holes import Hole
    scaled = Hole.faces([[2.0, 0.0, 4e-4], [-2.0, 0.0, 4e-4], [0.0, 1.0, 4e-4]])
    unit = Hole.faces([[1.0, 0.0, 2e-4], [-1.0, 0.0, 2e-4], [0.0, 1.0, 4e-4]])
    assert scaled.faces_ == unit.faces_
    assert Hole.regular(4, 4e-4).faces_[0][2] == 4e-4        # unit normals: the gap exact
    rows = np.array([[2.0, 0.0, 4e-4], [-1.0, 0.0, 2e-4], [0.0, 1.0, 4e-4]])
    assert Hole.faces(rows).faces_ == Hole.faces(rows).faces_ == unit.faces_
    assert rows[0, 2] == 4e-4         # the caller's array as it was (its gaps were halved)


def test_a_polygon_closed_by_its_first_vertex_or_with_one_mid_edge_is_the_same_hole():
    """As CAD writes an outline (the first vertex again at the end), or with a vertex in the
    middle of an edge: the same faces, where "not convex ... at vertex 4" refused them."""
    from skfem_beam.holes import Hole
    square = [[1e-3, 0.0], [0.0, 1e-3], [-1e-3, 0.0], [0.0, -1e-3]]
    plain = Hole.polygon(square).faces_
    assert Hole.polygon(square + [square[0]]).faces_ == plain
    assert Hole.polygon(square[:1] + [[5e-4, 5e-4]] + square[1:]).faces_ == plain
    with pytest.raises(InputError, match="not convex and counter-clockwise at vertex 4"):
        Hole.polygon(square + [[5e-4, -2e-4]])
    with pytest.raises(InputError, match=r"at vertex 3 \(\[0.2, 0.2\]\)"):   # as given
        Hole.polygon([[0, 0], [0, 0], [1, 0], [0.2, 0.2], [0, 1]])


def test_an_open_holes_chart_wall_is_its_faces_not_a_closing_corner():
    """Three faces open on one side were drawn as a closed triangle whose third corner broke
    a face by the clearance; flat bars had no wall at all.  Every wall point is on a face
    and inside the others; a bounded hole's outline is still closed."""
    from skfem_beam.holes import Hole
    r = 4e-4
    for rows, closed in (([[0, 1, r], [0, -1, r]], False),
                         ([[1, 0, r], [0.5, 0.866, r], [-0.5, 0.866, r]], False),
                         ([[1, 0, r], [0, 1, r], [-1, 0, r], [0, -1, r]], True)):
        hole = Hole.faces(rows)
        o = hole.outline()
        p = o[~np.isnan(o[:, 0])]
        f = np.asarray(hole.faces_)
        d = p @ f[:, :2].T - f[:, 2]
        assert len(p) >= 3 and (d <= 1e-12 * r).all() and (np.abs(d) <= 1e-12 * r).any(axis=1).all()
        assert np.array_equal(o[0], o[-1]) == closed
