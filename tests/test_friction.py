"""Coulomb friction in round holes (Moreau–Jean): the cone and the dissipation at every
step, the stick/slip threshold of a static analysis, μ = 0, the energy identity with
friction, Archard wear, and Siconos' 2-D friction solver on recorded step problems."""
import json
import shutil
import subprocess
import sys

import numpy as np
import pytest

from conftest import exit_code, resumed
from skfem_beam import methods
from skfem_beam.contact.friction import DRIFT, coulomb, nsgs
from skfem_beam.holes import Hole, HoleAt
from skfem_beam.problem import (Beam, BeamProblem, Damping, Load, Material, Plane, Section)
from skfem_beam.scenefile import example, run_main
from skfem_beam.scheme import Stepping, solve
from skfem_beam.scheme import Run
from skfem_beam.scheme.moreau_jean import MoreauJeanScheme
from skfem_beam.semidiscrete import beam_system
from skfem_beam.timefunctions import Sine

TUBE = Beam.physical(1.5, Material(2e11, 8000.0), Section.tube(0.01905, 0.00165))
R = 4e-4


def flow(mu, J=30, damping=Damping.ratio(0.02, 20.0, 200.0)):
    """The tube in two round holes, buffeted in both planes, μ at both walls."""
    return BeamProblem(TUBE, J=J, ends=("pinned", "pinned"), planes=2, damping=damping,
                       holes=(HoleAt(Hole.round(R), 0.5, friction=mu),
                              HoleAt(Hole.round(R), 1.0, friction=mu)),
                       load=Load.distributed(1.0, Sine(300.0, 2 * np.pi * 30, np.pi / 2)),
                       second=Plane(load=Load.distributed(1.0, Sine(300.0, 2 * np.pi * 23))))


def test_the_cone_holds_and_slip_dissipates_at_every_step():
    mu = 0.3
    run = Run(MoreauJeanScheme(beam_system(flow(mu)), Stepping(1e-4, 0.3)))
    a = run.ops.disks
    stick = slip = 0
    for n in range(2, run.n_steps + 1):
        run.advance(n)
        pn, pt, un, ut = run.st.fc[a, 0], run.st.fc[a, 1], run.st.fc[a, 2], run.st.fc[a, 3]
        # Signorini: a wall that pushes holds the node's outward velocity at 0
        scale = np.abs(run.st.v).max()
        assert (pn >= 0).all() and (np.abs(un[pn > 0]) <= 1e-12 * scale).all()
        assert (np.abs(pt) <= mu * pn * (1 + 1e-12)).all()
        on = pn > 0
        moving = on & (np.abs(ut) > 1e-12 * scale)
        # in slip the friction opposes the sliding at the cone's edge: F_t·v_t = −μ|F_n||v_t|
        assert np.allclose(pt[moving] * ut[moving], -mu * pn[moving] * np.abs(ut[moving]),
                           rtol=1e-12, atol=0)
        stick, slip = stick + int((on & ~moving).sum()), slip + int(moving.sum())
    assert stick > 50 and slip > 50


def test_the_tube_sticks_until_the_pull_reaches_mu_times_the_static_normal_force():
    """P = 60 N presses the node at x = 0.75 on the wall of its hole along +v; from t0 a
    pull along w grows at a N/s from 0.999 T*.  The static analysis of the discrete
    system: with the node on the wall (v = r) the reaction is N = P − ρS·r/f, f = e·K⁻¹e
    the node's flexibility (e its value row, K the plane's stiffness), and a pull T at
    the node is all the wall's while it sticks (w ≡ 0), so it slips at T* = μN."""
    mu, P, t0, a, dt = 0.3, 60.0, 1.0, 0.01, 1e-4

    class Pull:
        def __call__(self, t):
            t = np.asarray(t, dtype=float)
            return np.where(t < t0, 0.0, 0.999 * T_star + a * (t - t0))

    scene = BeamProblem(TUBE, J=10, ends=("pinned", "pinned"), planes=2,
                        damping=Damping(alpha=100.0),
                        holes=(HoleAt(Hole.round(R), 0.75, friction=mu),),
                        load=Load.point(0.75, P),
                        second=Plane(load=Load(points=((0.75, Pull()),))))
    system = beam_system(scene)
    n = system.meta["n_plane"]
    e = system.C[0, :n].toarray().ravel()
    K = system.K[:n, :n].toarray()
    f = e @ np.linalg.solve(K, e)
    T_star = mu * (P - TUBE.rho_S * R / f)
    assert 0 < T_star < mu * P
    # θ = 1: the quasi-static choice (θ = ½ keeps the settling's vibration of the normal
    # force at 3e-6 relative after 2 s, measured: above the threshold's 1e-6)
    run = Run(MoreauJeanScheme(system, Stepping(dt, t0 + 0.002 * T_star / a), theta=1.0))
    first = int(t0 / dt)
    run.advance(first)
    k = run.ops.disks[0]
    for step in range(first + 1, run.n_steps + 1):
        pn, pt = run.st.fc[k, 0], run.st.fc[k, 1]
        ratio = abs(pt) / (mu * pn)
        run.advance(step)
        if abs(run.st.fc[k, 1]) >= mu * run.st.fc[k, 0] * (1 - 1e-12):   # the first slip
            T = float(Pull()(step * dt))   # its load, at t_n + θΔt = t_{n+1}
            break
    else:
        pytest.fail("the tube never slipped")
    assert a * dt <= 1e-6 * T_star
    assert abs(T - T_star) <= a * dt               # the threshold to ≤ 1e-6 relative
    assert ratio == pytest.approx((T - a * dt) / T_star, rel=1e-9)   # the last stick step


def test_mu_zero_is_the_frictionless_run_bit_for_bit():
    zero = solve(beam_system(flow(0.0)), 1e-4, 0.2, method=methods.MoreauJean())
    plain = BeamProblem(TUBE, J=30, ends=("pinned", "pinned"), planes=2,
                        damping=Damping.ratio(0.02, 20.0, 200.0),
                        holes=(HoleAt(Hole.round(R), 0.5), HoleAt(Hole.round(R), 1.0)),
                        load=flow(0.0).load, second=flow(0.0).second)
    ref = solve(beam_system(plain), 1e-4, 0.2, method=methods.MoreauJean())
    assert zero.impacts == ref.impacts > 3 and "friction" not in zero.work
    assert np.array_equal(zero.energy, ref.energy)
    assert np.array_equal(zero.contact_force, ref.contact_force)


@pytest.mark.parametrize("law", ["auto", "moreau-jean"])
def test_energy_identity_closes_with_friction_over_one_second_of_random_flow(tmp_path, law):
    """The shipped friction scene under its default (friction makes "auto" the exact
    position-level law round-hole-friction) and under Moreau–Jean."""
    out = tmp_path / "run"
    assert exit_code(run_main, [str(example("tube_round_holes_friction")), "--out", str(out),
                                "--set", f"contact.law={law}", "--format", "none"]) == 0
    import csv
    with open(out / "timeseries.csv") as fh:
        rows = list(csv.DictReader(fh))
    col = {k: np.array([float(r[k]) for r in rows]) for k in
           ("energy", "work_damping", "work_input", "work_contact", "work_friction",
            "friction_residual")}
    gap = col["energy"] - col["energy"][0] + col["work_damping"] - col["work_input"] \
        - col["work_contact"] - col["work_friction"]
    assert float(rows[-1]["t"]) == pytest.approx(1.0)
    assert np.abs(gap).max() <= 1e-9 * np.abs(col["energy"]).max()
    assert col["work_friction"][-1] < 0 and (col["friction_residual"] <= 1e-12).all()
    summary = json.loads((out / "summary.json").read_text())
    solver = "round-hole-friction" if law == "auto" else law
    assert summary["solver"] == solver and summary["friction"]["coefficients"] == [0.3]
    assert summary["max_penetration"] <= (1e-12 * 4e-4 if law == "auto" else 2e-5)


def test_wear_is_archards_law_linear_in_the_coefficient(tmp_path):
    runs = {}
    for K in ("1e-14", "3e-14"):
        out = tmp_path / K
        assert exit_code(run_main, [str(example("tube_round_holes_friction")), "--set",
                                    "time.T=0.2", "--set", f"wear.coefficient={K}", "--out",
                                    str(out), "--format", "none"]) == 0
        runs[K] = json.loads((out / "summary.json").read_text())
    year = 365.25 * 86400
    for s1, s3 in zip(*(r["impact_statistics"]["supports"] for r in runs.values())):
        w1, w3 = s1["wear"], s3["wear"]
        assert s1["normal_work_rate"] == s3["normal_work_rate"] > 0
        assert w1["volume_rate"] == 1e-14 * s1["normal_work_rate"]
        assert w1["volume"] == pytest.approx(w1["volume_rate"] * 40 * year, rel=1e-15)
        assert w3["volume"] == pytest.approx(3 * w1["volume"], rel=1e-15)
        assert w1["depth_uniform"] == pytest.approx(
            w1["volume"] / (2 * np.pi * 0.01905 / 2 * 0.019), rel=1e-15)
        # the sectors share the volume
        assert sum(k["volume"] for k in w1["sectors"]) == pytest.approx(w1["volume"],
                                                                         rel=1e-12)


def test_wear_without_a_land_gives_the_volumes_and_no_depth(tmp_path):
    """[wear] with no land: the same volumes and volume rates per support and per sector
    as with one (they need only K and the service years), no depth, and the units say
    that a depth needs the land."""
    text = example("tube_round_holes_friction").read_text()
    assert "land = 0.019" in text
    scenes = {"land": text, "none": text.replace("land = 0.019", "")}
    supports, units = {}, {}
    for name, scene in scenes.items():
        (tmp_path / f"{name}.toml").write_text(scene)
        out = tmp_path / name
        assert exit_code(run_main, [str(tmp_path / f"{name}.toml"), "--set", "time.T=0.2",
                                    "--out", str(out), "--format", "none"]) == 0
        stats = json.loads((out / "summary.json").read_text())["impact_statistics"]
        supports[name], units[name] = stats["supports"], stats["units"]["wear"]
    for with_land, without in zip(supports["land"], supports["none"]):
        w, v = with_land["wear"], without["wear"]
        assert with_land["normal_work_rate"] > 0 and "depth_uniform" in w
        assert set(v) == {"volume_rate", "volume", "sectors"}
        assert v["volume_rate"] == w["volume_rate"] and v["volume"] == w["volume"]
        for a, b in zip(w["sectors"], v["sectors"]):
            assert "depth" in a and "depth" not in b
            assert b == {k: a[k] for k in ("from_rad", "to_rad", "volume_rate", "volume")}
        assert sum(k["volume_rate"] for k in v["sectors"]) == pytest.approx(v["volume_rate"],
                                                                             rel=1e-12)
    assert "depth needs [wear] land" in units["none"] and "depth" in units["land"]


def printed_supports(out: str) -> list[list[str]] | None:
    """The rows (cells) of the supports' table a run printed on stdout, None if none."""
    lines = out.splitlines()
    start = next((i for i, line in enumerate(lines) if line.startswith("supports (")), None)
    if start is None:
        return None
    assert lines[start + 1].split()[:3] == ["x", "(m)", "impacts"]
    assert all(len(line) <= 100 for line in lines[start:])
    return [line.split() for line in lines[start + 2:] if line.strip()]


def is_png(path) -> bool:
    return path.stat().st_size > 0 and path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.usefixtures("charts")
def test_a_tube_run_prints_its_supports_and_draws_their_wear(tmp_path, capsys, monkeypatch):
    """The friction scene prints one row per support whose numbers are summary.json's (to
    the 4 digits printed), and draws wear_<x>.png per support from the same wear entry."""
    from skfem_beam.cases import _beam
    drawn = {}
    real = _beam.draw

    def draw(chart, path, *args, **kwargs):     # the wear entry each chart is drawn from
        if chart.__name__ == "wear_chart":
            drawn[path.name] = args[0]
        real(chart, path, *args, **kwargs)
    monkeypatch.setattr(_beam, "draw", draw)
    out = tmp_path / "run"
    assert exit_code(run_main, [str(example("tube_round_holes_friction")), "--set",
                                "time.T=0.2", "--out", str(out), "--format", "none"]) == 0
    rows = printed_supports(capsys.readouterr().out)
    supports = json.loads((out / "summary.json").read_text())["impact_statistics"]["supports"]
    assert rows is not None and len(rows) == len(supports) == 2
    for row, s in zip(rows, supports):
        depth = max(k["depth"] for k in s["wear"]["sectors"])
        expect = [s["x"], s["contact_fraction"], s["impact_work_rate"], s["normal_work_rate"],
                  s["friction_work_rate"], s["wear"]["volume"] * 1e9, depth * 1e3]
        assert int(row[1]) == s["impacts"] > 0
        cells = [float(c) for c in row[:1] + row[2:]]
        assert cells == pytest.approx(expect, rel=5e-4)
        assert is_png(out / f"wear_{s['x']:g}.png")
        assert drawn[f"wear_{s['x']:g}.png"] == s["wear"]


@pytest.mark.usefixtures("charts")
def test_without_land_or_wear_the_table_says_so_and_without_wear_no_wear_chart(
        tmp_path, capsys):
    """No land: the depth column is "—", the chart draws volumes; no [wear]: "—" for the
    volume too and no wear chart (the orbits are drawn on their own, as without friction)."""
    text = example("tube_round_holes_friction").read_text()
    start = text.index("[wear]")
    scenes = {"no_land": text.replace("land = 0.019", ""),
              "no_wear": text[:start] + text[text.index("[mesh]"):]}
    for name, scene in scenes.items():
        (tmp_path / f"{name}.toml").write_text(scene)
        out = tmp_path / name
        assert exit_code(run_main, [str(tmp_path / f"{name}.toml"), "--set", "time.T=0.05",
                                    "--out", str(out), "--format", "none"]) == 0
        rows = printed_supports(capsys.readouterr().out)
        assert [r[-1] for r in rows] == ["—", "—"]
        assert (rows[0][-2] == "—") == (name == "no_wear")
        assert (out / "wear_0.5.png").exists() == (name == "no_land")
        # one picture per support: the wear chart draws the orbit beside the wear
        assert is_png(out / ("wear_0.5.png" if name == "no_land" else "orbit_0.5.png"))
        assert (out / "orbit_0.5.png").exists() == (name == "no_wear")


def test_a_run_without_supports_prints_no_table_and_draws_no_wear_chart(tmp_path, capsys):
    from skfem_beam.cases import point_stops
    out = tmp_path / "run"
    assert exit_code(point_stops.main, ["--T", "0.05", "--out", str(out),
                                        "--format", "none"]) == 0
    printed = capsys.readouterr().out
    assert "steps in" in printed and printed_supports(printed) is None
    assert not list(out.glob("wear_*"))


# ---------------------------------------------------------------- Siconos
def recorded(count=30):
    """Moreau–Jean step problems with both holes in contact: nsgs's inputs and result."""
    run = Run(MoreauJeanScheme(beam_system(flow(0.3)), Stepping(1e-4, 0.5)))
    ops, st = run.ops, run.st
    out = []
    for n in range(2, run.n_steps + 1):
        # the inputs of step n as mj_holes builds them (free velocity: advance, then undo)
        run.advance(n)
        fc = st.fc[ops.disks]
        if (fc[:, 0] > 0).all() and (np.abs(fc[:, 1]) > 0).all():
            out.append(n)
        if len(out) == count:
            break
    return out


def problems(steps):
    """Re-run to each recorded step and rebuild its local problem in Siconos' form."""
    system = beam_system(flow(0.3))
    run = Run(MoreauJeanScheme(system, Stepping(1e-4, 0.5)))
    ops, st = run.ops, run.st
    found = []
    for n in steps:
        run.advance(n - 1)
        # the free velocity of step n, as mj_steps computes it before the impulses
        saved = {k: getattr(st, k).copy() for k in st._fields}
        run.advance(n)
        wf, yp, yv = st.wf.copy(), st.yp.copy(), saved["yv"]
        p, fc = np.zeros(st.p.size), np.zeros(st.fc.shape)
        lo_e, hi_e = np.zeros(st.p.size), np.zeros(st.p.size)
        its, res = nsgs(ops.D, (ops.pair, ops.fric, saved["lo"], saved["hi"]),
                        (wf, yv, yp, saved["y_cur"], ops.e, 1e-14, ops.theta * ops.dt),
                        (p, fc, lo_e, hi_e))
        assert its > 0 and np.allclose(fc[ops.disks, :2], st.fc[ops.disks, :2], rtol=1e-10)
        # Siconos: u = W r + q, r = (p_n, p_t) per contact, u_n ≥ 0 ⟂ r_n ≥ 0
        D, a = ops.D, ops.disks
        frames = []
        for c in a:
            b = ops.pair[c]
            n_, t_ = fc[c, 4:6], np.array([-fc[c, 5], fc[c, 4]])
            frames.append((c, b, n_, t_))
        W = np.zeros((2 * len(a), 2 * len(a)))
        q = np.zeros(2 * len(a))
        for i, (c, b, n_, t_) in enumerate(frames):
            y = saved["y_cur"]
            gap = max(np.hypot(y[c] - 0.5 * (saved["lo"][c] + saved["hi"][c]),
                               y[b] - 0.5 * (saved["lo"][b] + saved["hi"][b]))
                      - 0.5 * (saved["hi"][c] - saved["lo"][c]), 0.0) * DRIFT / (ops.theta
                                                                                 * ops.dt)
            q[2 * i] = -(n_ @ wf[[c, b]] + gap)
            q[2 * i + 1] = t_ @ wf[[c, b]]
            for k, (c2, b2, n2, t2) in enumerate(frames):
                Dk = D[np.ix_([c, b], [c2, b2])]
                W[2 * i, 2 * k] = n_ @ Dk @ n2
                W[2 * i, 2 * k + 1] = -(n_ @ Dk @ t2)
                W[2 * i + 1, 2 * k] = -(t_ @ Dk @ n2)
                W[2 * i + 1, 2 * k + 1] = t_ @ Dk @ t2
        ours = np.ravel(fc[a, :2])
        found.append((W, q, ours))
    return found


SICONOS = """
import sys, numpy as np, siconos.numerics as sn
d = np.load(sys.argv[1])
out = []
for W, q in zip(d["W"], d["q"]):
    nc = q.size // 2
    fcp = sn.FrictionContactProblem(2, nc, np.ascontiguousarray(W), q, np.full(nc, 0.3))
    r, u = np.zeros(q.size), np.zeros(q.size)
    so = sn.SolverOptions(sn.SICONOS_FRICTION_2D_NSGS)
    so.dparam[sn.SICONOS_DPARAM_TOL] = 1e-14
    so.iparam[sn.SICONOS_IPARAM_MAX_ITER] = 100000
    assert sn.fc2d_driver(fcp, r, u, so) == 0
    out.append(r)
np.save(sys.argv[2], np.array(out))
"""


def siconos_python():
    """A Python with Siconos (Debian's python3-siconos), or None."""
    for exe in ("/usr/bin/python3", shutil.which("python3"), sys.executable):
        if exe and subprocess.run([exe, "-c", "import siconos.numerics"],
                                  capture_output=True).returncode == 0:
            return exe
    return None


def test_siconos_friction_solver_agrees_on_recorded_problems(tmp_path):
    exe = siconos_python()
    if exe is None:
        pytest.skip("Siconos is not installed (Debian: apt-get install python3-siconos)")
    found = problems(recorded(20))
    assert len(found) == 20
    np.savez(tmp_path / "p.npz", W=np.array([w for w, _, _ in found]),
             q=np.array([q for _, q, _ in found]))
    script = tmp_path / "s.py"
    script.write_text(SICONOS)
    subprocess.run([exe, str(script), str(tmp_path / "p.npz"), str(tmp_path / "r.npy")],
                   check=True)
    theirs = np.load(tmp_path / "r.npy")
    for (_, _, ours), r in zip(found, theirs):
        assert np.abs(ours - r).max() <= 1e-9 * np.abs(ours).max()


def test_one_contact_is_solved_exactly_in_each_case():
    out = np.empty(4)
    W = (2.0, 0.1, 1.5)
    assert coulomb(*W, -1.0, 0.3, 0.3, out) == 0 and out[0] == 0          # separating
    assert coulomb(*W, 1.0, 0.01, 0.3, out) == 1                           # stick
    assert abs(out[2]) < 1e-15 and abs(out[3]) < 1e-15 and abs(out[1]) <= 0.3 * out[0]
    case = coulomb(*W, 1.0, 0.8, 0.3, out)                                 # slip forward
    assert case == 2 and out[3] > 0 and out[1] == pytest.approx(-0.3 * out[0], rel=1e-15)
    assert abs(out[2]) < 1e-15


def test_a_step_that_misses_the_tolerance_stops_the_run_with_one_line():
    from skfem_beam.errors import SolverError
    run = Run(MoreauJeanScheme(beam_system(flow(0.3)), Stepping(1e-4, 0.3)))
    run.scheme.ops = run.ops._replace(tol=-1.0)       # no sweep can meet it
    with pytest.raises(SolverError, match="did not reach .*residual"):
        run.advance(run.n_steps)


@pytest.mark.parametrize("extra, word", [
    ("[contact]\nfriction = 0.3\n", "no tangential direction"),
    ("planes = 2\n[[obstacles]]\nx = 0.5\nhole = { radius = 4e-4 }\nfriction = 0.3\n"
     "[contact]\nlaw = \"round-hole\"\n", "velocity-level"),
    ("planes = 2\n[[obstacles]]\nx = 0.5\nhole = { lands = 4, land_width = 30, radius = 4e-4 }"
     "\nfriction = 0.3\n[contact]\nlaw = \"moreau-jean\"\n", "round-hole-friction"),
    ("planes = 2\n[[obstacles]]\nx = 0.5\nhole = { sides = 3, radius = 4e-4 }\nfriction = 0.3\n"
     "[contact]\nlaw = \"moreau-jean\"\n", "round-hole-friction"),
])
def test_friction_where_it_cannot_act_is_refused(tmp_path, capsys, extra, word):
    from conftest import assert_refused
    top = "planes = 2\n" if extra.startswith("planes") else ""
    rest = extra[len(top):]
    base = """kind = "beam"
{top}[material]
E = 2.0e11
rho = 8000.0
[section]
tube = {{ outer_diameter = 0.01905, wall = 0.00165 }}
[geometry]
L = 1.5
[ends]
left = "pinned"
right = "pinned"
{rest}
[mesh]
J = 30
[time]
dt = 1e-4
T = 0.01
""".format(top=top, rest=rest)
    scene = tmp_path / "s.toml"
    scene.write_text(base)
    bad = tmp_path / "bad"
    bad.mkdir()
    assert_refused(run_main, [str(scene), "--out", str(bad / "run")], word, capsys, bad)


def test_a_restored_friction_run_goes_on_bit_for_bit():
    system = beam_system(flow(0.3))
    a, c = resumed(lambda: Run(MoreauJeanScheme(system, Stepping(1e-4, 0.2))), 777)
    assert np.array_equal(a.st.sectors, c.st.sectors)
    # the saved rows after the checkpoint (those before it are the caller's)
    assert np.array_equal(a.result().work["friction"][778:], c.result().work["friction"][778:])


def test_moreau_jean_reports_its_penetration_beyond_the_circle(tmp_path):
    """Moreau–Jean's summary took the round hole's box (|v|, |w| ≤ r) for its bound and
    said 1.02e-5 m where the node stood 1.71e-5 m beyond the circle: its headline now
    measures the circle, as the β-scheme's and its own impacts.csv do."""
    from skfem_beam.results import read_run
    out = tmp_path / "mj"
    assert exit_code(run_main, [str(example("tube_round_holes_friction")), "--set",
                                "time.T=0.4", "--set", "contact.law=moreau-jean", "--out",
                                str(out), "--format", "none"]) == 0
    run = read_run(out)
    beyond = max(np.hypot(run.series[f"hole_{x}_displacement_v"],
                          run.series[f"hole_{x}_displacement_w"]).max() - 0.0004
                 for x in ("0.5", "1"))
    assert beyond > 1.5e-5                       # measured 1.707e-5 at t = 0.3997
    assert run.summary["max_nodal_violation"] == pytest.approx(beyond, rel=1e-9)
    assert run.summary["max_nodal_violation"] == max(run.impacts["max_violation"])


@pytest.mark.parametrize("mu, word", [("-0.3", "[contact] friction=-0.3 must be ≥ 0"),
                                      ("nan", "contact.friction = nan: must be a number")])
def test_a_bad_scene_friction_is_refused_where_every_hole_sets_its_own(tmp_path, capsys,
                                                                      mu, word):
    """[contact] friction is checked where a hole takes it; with every hole's own μ it was
    taken by none and a negative or NaN μ ran without a word."""
    from conftest import assert_scene_refused
    text = example("tube_round_holes_friction").read_text()
    text = text.replace("hole = { radius = 0.0004 }", "hole = { radius = 0.0004 }\nfriction = 0.2")
    text = text.replace("friction = 0.3 ", f"friction = {mu} ")
    assert text.count("friction = 0.2") == 2 and f"friction = {mu} " in text
    assert_scene_refused(tmp_path, capsys, {"t.toml": text}, "t.toml", word)


PUSHED = """kind = "beam"
planes = 2
material = { E = 2.0e11, rho = 8000.0 }
section = { tube = { outer_diameter = 0.01905, wall = 0.00165 } }
geometry = { L = 1.5 }
ends = { left = "pinned", right = "pinned" }
mesh = { J = 30 }
time = { dt = 1e-4, T = 0.2 }
[[obstacles]]
x = 0.75
hole = { sides = 4, radius = 0.0004, angle = 0.1 }
[[loads]]
distributed = true
direction = [-1.0, 0.0]
value = 200.0
[[loads]]
distributed = true
direction = [0.0, 1.0]
amplitude = 300.0
omega = 300.0
[contact]
friction = 0.3
[wear]
coefficient = 1e-14
service_years = 40
land = 0.019
"""


def test_a_square_hole_wears_on_the_face_the_tube_is_pushed_onto(tmp_path):
    """A face row bounds two opposite faces (lo ≤ n·p ≤ hi): its wear goes to the face
    touched, n's or −n's.  Pushed along −v onto the face at 180° + 5.7°, the wear fell in
    the opposite sector, [0°, 30°), before."""
    (tmp_path / "push.toml").write_text(PUSHED)
    out = tmp_path / "out"
    assert exit_code(run_main, [str(tmp_path / "push.toml"), "--out", str(out),
                                "--format", "none"]) == 0
    sup, = json.loads((out / "summary.json").read_text())["impact_statistics"]["supports"]
    sectors = sup["wear"]["sectors"]
    worst = max(sectors, key=lambda k: k["volume"])
    assert worst["from_rad"] == pytest.approx(-np.pi) and worst["volume"] > 0.9 * sum(
        k["volume"] for k in sectors)
    assert sectors[6]["volume"] == 0.0          # [0°, 30°): no face is touched there


@pytest.mark.parametrize("change, word", [
    # [contact] friction over flat stops only: it ran frictionless without a word
    (lambda t: (t[:t.index("[wear]")] + t[t.index("[mesh]"):])
     .replace("hole = { radius = 0.0004 }", "g1 = -0.0004\ng2 = 0.0004"),
     "[contact] friction=0.3 acts at a hole's wall: this scene has no hole"),
    # [wear] on a beam known by k² alone: K × W per kg/m was printed as mm³ and mm
    (lambda t: t.replace('[material]\nE = 2.0e11               # Pa\nrho = 8000.0             '
                         '# kg/m³\n', '[mass_normalised]\nk2 = 282.84\n')
     .replace("[section]\ntube = { outer_diameter = 0.01905, wall = 0.00165 }\n", "")
     .replace("distributed = true", "per_mass = true")
     .replace("land = 0.019 ", "radius = 0.0095\nland = 0.019 "),
     "[wear] needs forces in newtons, so the beam's mass per length"),
])
def test_friction_without_a_hole_and_wear_without_newtons_are_refused(tmp_path, capsys,
                                                                      change, word):
    from conftest import assert_scene_refused
    text = example("tube_round_holes_friction").read_text()
    new = change(text)
    assert new != text
    assert_scene_refused(tmp_path, capsys, {"t.toml": new}, "t.toml", word)


def test_a_stepped_tube_of_one_outer_diameter_gives_wear_its_radius(tmp_path):
    """[wear] land on [[segments]] of one tube: "radius is needed ... when [section] is not a
    tube" was said though every segment is one."""
    from skfem_beam.scenefile import load
    from skfem_beam.scenefile.build import wear
    text = example("tube_round_holes_friction").read_text()
    one = "{ E = 2.0e11, rho = 8000.0 }", "{ tube = { outer_diameter = 0.01905, wall = 0.00165 } }"
    segments = "".join(f"[[segments]]\nlength = 0.75\nmaterial = {one[0]}\nsection = {one[1]}\n"
                       for _ in range(2))
    start, end = text.index("[material]"), text.index("[ends]")
    (tmp_path / "s.toml").write_text(text[:start] + segments + text[end:])
    assert wear(load(tmp_path / "s.toml")).radius == 0.01905 / 2


def test_a_support_worn_past_the_tube_wall_is_said_with_when():
    """The shipped friction scene's deepest sector passes its 1.65 mm wall in 40 years
    (2.19 mm): the table printed that depth without a word."""
    from skfem_beam.output.supports import Wear, worn_through
    wear = Wear(1e-14, 40.0, 0.019, 0.0095, wall=0.00165)
    sectors = [{"depth": 1e-3}, {"depth": 2.2e-3}]
    lines = worn_through([{"x": 0.5, "wear": {"sectors": sectors}},
                          {"x": 1.0, "wear": {"sectors": sectors[:1]}}], wear)
    assert lines == ["the support at x=0.5 wears 2.2 mm deep in 40 years, more than the "
                     "tube's wall (1.65 mm): it wears through in about 30 years (the depth "
                     "past the wall is Archard's law extrapolated)"]
    assert worn_through([{"x": 0.5, "wear": {"sectors": sectors}}],
                        Wear(1e-14, 40.0, 0.019, 0.0095)) == []     # not a tube: no wall


@pytest.mark.parametrize("law", ["auto", "moreau-jean"])
def test_the_wear_work_rate_is_the_friction_work_over_mu(tmp_path, law):
    """Archard's |F_n||v_t| where friction acts is the friction work over μ (the slip's
    share of the force), under either scheme.  Moreau–Jean's counted, at an impact that
    sticks, the velocity before it: at μ = 3 it read 0.0378 W against a friction work
    rate of 0.016 W (0.0053 W over μ), and it did not fall from μ = 3 to 30."""
    out = tmp_path / "r"
    assert exit_code(run_main, [str(example("tube_round_holes_friction")), "--format",
                                "none", "--out", str(out), "--set", "time.T=0.3", "--set",
                                f"contact.law={law}", "--set", "contact.friction=3"]) == 0
    supports = json.loads((out / "summary.json").read_text())["impact_statistics"]["supports"]
    for s in supports:
        assert s["friction_work_rate"] > 0
        assert s["normal_work_rate"] == pytest.approx(s["friction_work_rate"] / 3, rel=1e-9)


SHAKEN = """kind = "beam"
planes = 2
material = {{ E = 2.0e11, rho = 8000.0 }}
section = {{ tube = {{ outer_diameter = 0.01905, wall = 0.00165 }} }}
geometry = {{ L = 1.0 }}
ends = {{ left = "clamped", right = "free" }}
[motion]
end = "left"
direction = [0.0, 1.0]
amplitude = 0.0002
omega = 31.41592653589793
lifting = "{lifting}"
[[obstacles]]
x = 0.5
hole = {{ {hole} }}
carried = {carried}
[[loads]]
distributed = true
direction = [1.0, 0.0]
value = 50.0
[damping]
zeta = 0.05
f1 = 10.0
f2 = 200.0
[mesh]
J = 20
[time]
dt = 1e-4
T = {T}
[output]
format = "none"
"""


@pytest.mark.parametrize("carried", ["true", "false"])
def test_the_wear_slip_is_relative_to_a_moving_hole(tmp_path, carried):
    """A cantilever pressed onto a round hole while its clamp shakes along z: the wear's
    slip and the impacts' velocities are the tube's relative to the hole, whatever the
    lifting (its frame is the run's own, not the physics').  They were the lifted u's:
    the wear work rate read 3.5× (carried hole, the paper's lifting), 3.1× and 5.0× (a
    fixed hole) its value."""
    rates, first = [], []
    for lifting in ("paper", "static"):
        (tmp_path / f"{lifting}.toml").write_text(SHAKEN.format(
            lifting=lifting, carried=carried, hole="radius = 0.0004", T=0.3))
        out = tmp_path / lifting
        assert exit_code(run_main, [str(tmp_path / f"{lifting}.toml"), "--out", str(out)]) == 0
        sup, = json.loads((out / "summary.json").read_text())["impact_statistics"]["supports"]
        rates.append(sup["normal_work_rate"])
        impacts = np.genfromtxt(out / "impacts.csv", delimiter=",", names=True)
        first.append(impacts["tangential_velocity"][0])
    # the two liftings' runs differ by their time discretisation alone (1e-4 here)
    assert rates[0] > 0 and rates[0] == pytest.approx(rates[1], rel=1e-3)
    assert first[0] == pytest.approx(first[1], rel=1e-3)


def test_a_face_s_impact_velocity_points_into_the_face_touched(tmp_path):
    """A face row bounds two opposite faces (lo ≤ n·p ≤ hi): an impact on the lower one
    (outward normal −n) approaches it with normal_velocity > 0, as on the upper one.  The
    lower face's were written along n, negative (81 of 83 in a hexagon, 34 of 43 here)."""
    (tmp_path / "p.toml").write_text(PUSHED)
    out = tmp_path / "out"
    assert exit_code(run_main, [str(tmp_path / "p.toml"), "--out", str(out),
                                "--format", "none"]) == 0
    impacts = np.genfromtxt(out / "impacts.csv", delimiter=",", names=True)
    for bound in (1, 2):        # the approach > 0 on either face (it slides too: ~0 there)
        v = impacts["normal_velocity"][impacts["bound"] == bound]
        assert (v > 1e-9).sum() > 2 * (v < -1e-9).sum() > 0     # lower faces: 34 to 9,
        #                                                          were 9 to 34


@pytest.mark.parametrize("carried", ["true", "false"])
def test_friction_at_a_hole_that_moves_with_the_support_is_refused(tmp_path, capsys, carried):
    """The friction law takes its slip from the lifted u, not relative to a hole that moves
    in the run's frame (carried, or fixed while the support moves): a carried hole's
    friction work was 3,700× apart between two liftings.  Refused, nothing written."""
    from conftest import assert_refused
    scene = tmp_path / "s.toml"
    scene.write_text(SHAKEN.format(lifting="auto", carried=carried, hole="radius = 0.0004",
                                   T=0.01) + "[contact]\nfriction = 0.3\n")
    bad = tmp_path / "bad"
    bad.mkdir()
    assert_refused(run_main, [str(scene), "--out", str(bad / "run")],
                   "Coulomb friction at the hole at x=0.5, which moves with the support's "
                   "motion", capsys, bad)
