"""Modified mass (mass redistribution): no inertia at the dofs the constraints act on,
total mass and centre of mass kept; the β-scheme with it: β = 1/2 stable with zero
penetration, β < 1/4 refused with the reason; loads and moving supports; the
quasi-static treatment of the massless rows (equilibrium at t_{n+1})."""
from dataclasses import replace

import numpy as np
import pytest

from skfem_beam import InputError, scenes
from skfem_beam.problem import Damping
from skfem_beam.semidiscrete import beam_system
from skfem_beam.bar import bar_system, run_bar
from skfem_beam.spaces.bspline import BSplineSpace
from skfem_beam.spaces.hermite import HermiteSpace
from skfem_beam.spaces.redistribution import (massless_dofs, redistribute, redistributed,
                                              rigid_modes)


def moments(M, R):
    return np.array([R[:, 0] @ M @ R[:, 0], R[:, 0] @ M @ R[:, 1]])


def check(M, Mr, R, massless):
    assert np.abs(Mr[massless].toarray()).max() == 0
    assert np.abs(Mr[:, massless].toarray()).max() == 0
    assert np.allclose(moments(Mr, R), moments(M, R), rtol=1e-13, atol=0)
    live = np.setdiff1d(np.arange(M.shape[0]), massless)
    assert np.linalg.eigvalsh(Mr[live][:, live].toarray()).min() > 0


@pytest.mark.parametrize("mass", ["average", "consistent", "lumped"])
def test_bar_contact_node_loses_its_mass(mass):
    s0 = bar_system(scenes.periodic_rod(20, mass=mass))
    R = rigid_modes(s0.space)
    Mr = redistribute(s0.M, s0.K, [0], R)
    check(s0.M, Mr, R, [0])


def test_system_of_a_redistributed_bar():
    s = bar_system(scenes.periodic_rod(20, mass="redistributed"))
    assert s.M[0].nnz == 0 and s.M.shape == (20, 20)


@pytest.mark.parametrize("Space", [HermiteSpace, BSplineSpace])
def test_beam_tip_stop(Space):
    space = Space(np.linspace(0, 1.5, 21))
    C = space.point_rows([1.5]) if Space is HermiteSpace else space.C[-1:]
    c = massless_dofs(C)
    if Space is HermiteSpace:     # the tip displacement only: its rotation keeps its inertia
        assert c.tolist() == [space.n - 2]
    else:                         # every coefficient the tip value reads
        assert c.size == np.count_nonzero(C.toarray())
    R = rigid_modes(space)
    check(space.M, redistribute(space.M, space.S, c, R), R, c)


def test_constraints_along_the_span_refused():
    space = HermiteSpace(np.linspace(0, 1, 11))
    with pytest.raises(InputError, match="isolated points"):
        redistribute(space.M, space.S, massless_dofs(space.C), rigid_modes(space))


@pytest.mark.parametrize("beta", [0.0, 0.2])
def test_beta_below_one_quarter_refused(beta):
    with pytest.raises(InputError, match=f"beta={beta:g} with a mass matrix that has no "
                                         "inertia"):
        run_bar(scenes.periodic_rod(20, mass="redistributed"), 0.01, 1.0, beta=beta)


def test_quasi_static_rows_at_zero_beta_refused():
    with pytest.raises(InputError, match="beta=0 with massless='quasi-static': its massless "
                                         "rows are written times beta"):
        run_bar(scenes.periodic_rod(20, mass="redistributed"), 0.01, 1.0, beta=0.0,
                massless="quasi-static")


def test_quasi_static_small_beta_is_stable_up_to_the_limit_of_the_dofs_with_mass():
    """Quasi-static massless rows run at β < 1/4 (the semi-explicit limit at β = 1/100),
    stable below 2/√(κ_h(1−4β)) with κ_h of the dofs with mass: the rod at N = 40 runs
    at 0.98 of it and goes unstable at 1.02, the message naming the limit."""
    from skfem_beam import methods
    from skfem_beam.scheme import solve
    from skfem_beam.stability import kappa_h, linear_limit
    system = bar_system(scenes.periodic_rod(40, mass="redistributed"))
    limit = linear_limit(kappa_h(system), 0.01)
    assert limit * 40 == pytest.approx(0.4808, abs=1e-3)     # Δt/h = 0.48 at c = 1
    method = methods.PositionLevel("auto", 0.0, "quasi-static", beta=0.01)
    runs = {f: solve(system, f * limit, 12.0, frames=2, progress=False, method=method)
            for f in (0.98, 1.02)}
    assert runs[0.98].status == "success" and runs[0.98].max_nodal_violation <= 1e-15
    assert runs[1.02].status == "unstable"
    assert f"= {limit:.4g} s" in runs[1.02].message


def test_bar_half_beta_no_penetration_and_energy_kept():
    bar = scenes.impacting_bar(N=80, mass="redistributed")
    r = run_bar(bar, 0.04 / 80, 3.0, beta=0.5)
    assert r.penetration < 1e-15
    # the energy lost at the impact is O(Δt) (the contact node has no kinetic energy)
    assert abs(r.energy[-1] / 0.5 - 1) < 1e-4          # −0.00 % measured (−0.51 % average mass)


def identity_residual(r):
    """max |energy − energy[0] + damping − input − contact| / max |energy|."""
    w = r.work
    res = r.energy - r.energy[0] + w["damping"] - w["input"] - w["contact"]
    return np.abs(res).max() / np.abs(r.energy).max()


@pytest.mark.parametrize("massless", ["beta", "quasi-static"])
def test_point_stops_with_load_and_moving_support(massless):
    """The papers' pipe (support shaken: two load vectors) with its tip dof massless:
    mass and centre of mass kept, no nodal penetration, the energy identity closed."""
    from skfem_beam.scheme import Run, Stepping, drive
    from skfem_beam.scheme.beta import BetaScheme
    s0 = beam_system(scenes.point_stops())
    s = redistributed(s0)
    R = rigid_modes(s.space)
    assert s.loads.shape[1] == 2
    assert np.allclose(moments(s.M, R), moments(s0.M, R), rtol=1e-14, atol=0)  # 2e-16
    run = Run(BetaScheme(s, Stepping(5e-5, 0.3, massless=massless)))
    drive(run)
    r = run.result()
    assert r.status == "success" and r.impacts > 20                  # 28 / 69 measured
    assert r.max_nodal_violation == 0.0
    assert identity_residual(r) < 1e-11                               # 3e-12 measured
    assert r.work["input"][-1] > 2.0 and r.work["contact"][-1] < 0    # 2.2, −0.59 / −0.16


def test_loaded_bar_runs():
    bar = scenes.impacting_bar(N=40, mass="redistributed", f=-1.0)
    r = run_bar(bar, 0.4 / 40, 3.0, beta=0.5)
    assert r.penetration < 1e-15 and identity_residual(r.result) < 1e-11


@pytest.mark.parametrize("courant", [0.04, 0.4])
def test_quasi_static_massless_node_does_not_oscillate(courant):
    """At β = 1/4 the β-weighted row lets the contact node oscillate (|Δ²u(0)| 1.35 and
    1.26 at N = 40); equilibrium at t_{n+1} keeps it at 0.0125 and 0.0117."""
    bar = scenes.periodic_rod(40, mass="redistributed")
    d2 = {}
    for massless in ("beta", "quasi-static"):
        r = run_bar(bar, courant * bar.h, 12.0, beta=0.25, massless=massless)
        d2[massless] = np.abs(np.diff(r.u0, 2)).max()
        assert r.penetration < 1e-15 and identity_residual(r.result) < 1e-12
    assert d2["beta"] > 1.0 and d2["quasi-static"] < 0.015


@pytest.mark.parametrize("solver, massless, word", [
    ("osqp", "quasi-static", "needs an exact compiled contact law"),
    ("auto", "midpoint", "massless='midpoint' is not one of")])
def test_quasi_static_refusals(solver, massless, word):
    from skfem_beam.scheme import Run, Stepping
    from skfem_beam.scheme.beta import BetaScheme
    s = bar_system(scenes.periodic_rod(20, mass="redistributed"))
    with pytest.raises(InputError, match=word):
        Run(BetaScheme(s, Stepping(0.01, 1.0, massless=massless), solver, 0.25))


def test_command_line_massless_reaches_the_run(tmp_path):
    """--mass redistributed --massless quasi-static runs the bar (exit 0) with the run the
    API gives for massless="quasi-static", which is not the default rows' run."""
    import json
    from conftest import exit_code
    from skfem_beam.cases import impacting_bar
    base = ["--mass", "redistributed", "--T", "0.5", "--format", "none"]
    qs, beta = tmp_path / "qs", tmp_path / "beta"
    assert exit_code(impacting_bar.main, base + ["--massless", "quasi-static",
                                                 "--out", str(qs)]) == 0
    assert exit_code(impacting_bar.main, base + ["--out", str(beta)]) == 0
    s = json.loads((qs / "summary.json").read_text())
    assert s["status"] == "success" and s["config"]["massless"] == "quasi-static"
    assert s["max_penetration"] < 1e-15
    force = {k: np.genfromtxt(d / "timeseries.csv", delimiter=",", skip_header=1, usecols=3)
             for k, d in (("qs", qs), ("beta", beta))}      # the reaction R(0, t)
    api = run_bar(scenes.impacting_bar(mass="redistributed"), 1e-3, 0.5, beta=0.25,
                  massless="quasi-static")
    np.testing.assert_array_equal(force["qs"], api.force)
    assert np.nanmax(np.abs(force["qs"] - force["beta"])) > 0.05      # 0.099 measured


@pytest.mark.parametrize("args, word", [
    (["--mass", "redistributed", "--massless", "foo"], "--massless='foo' is not one of"),
    (["--massless", "quasi-static"], "--massless 'quasi-static' applies to a redistributed mass only"),
    (["--mass", "redistributed", "--massless", "beta", "--law", "moreau-jean"],
     "--law moreau-jean"),
])
def test_command_line_massless_refusals(args, word, tmp_path, capsys):
    """A bad value, or --massless without a redistributed mass (or with Moreau–Jean): one
    stderr line naming it, exit 2, nothing written."""
    from conftest import assert_refused
    from skfem_beam.cases import impacting_bar
    assert_refused(impacting_bar.main, args + ["--T", "0.1", "--out", str(tmp_path / "run")],
                   word, capsys, tmp_path)


@pytest.mark.parametrize("beta, dt, gains", [(0.25, 5e-5, True), (0.5, 5e-5, False),
                                             (0.25, 1e-5, False)])
def test_quasi_static_quarter_can_gain_energy_on_the_chattering_pipe(beta, dt, gains):
    """The papers' pipe (point stops, forced, chattering at the tip), tip dof massless,
    quasi-static rows, T = 0.3: at β = 1/4, Δt = 5e-5 the contact does work +32.8 and ½E_β
    goes 1.38 → 36.5 (the three-step β-average of the force is not sign-definite); at
    β = 1/2, or at Δt = 1e-5, the contact work is ≤ 0 (−0.16, −0.07 measured).  The
    energy identity closes in every case, so the work columns show it."""
    from skfem_beam.scheme import Run, Stepping, drive
    from skfem_beam.scheme.beta import BetaScheme
    s = redistributed(beam_system(scenes.point_stops()))
    run = Run(BetaScheme(s, Stepping(dt, 0.3, massless="quasi-static"), beta=beta))
    drive(run, progress=False)
    r = run.result()
    assert r.status == "success" and r.max_nodal_violation == 0.0
    assert identity_residual(r) < 1e-11
    if gains:
        assert r.work["contact"][-1] > 30.0 and r.energy[-1] > 20 * r.energy[0]
        assert r.energy[0] == pytest.approx(1.378, abs=1e-3)
        assert r.energy[-1] == pytest.approx(36.5, rel=0.01)    # chaotic: a loose pin
    else:
        assert r.work["contact"][-1] < 0.0 and r.energy[-1] < 3 * r.energy[0]


def test_a_case_reports_the_limit_of_the_dofs_with_mass(tmp_path, capsys):
    """point_stops --mass redistributed: the warning and summary.json named the limit of the
    beam before its mass was redistributed (1.265e-5 s), while the run's own was 1.485e-5
    s; both are now the run's, and Δt = 1.4e-5 is not warned."""
    import json
    from skfem_beam.cases import point_stops
    from skfem_beam.stability import kappa_h, linear_limit
    from skfem_beam.spaces.redistribution import redistributed
    args = ["--mass", "redistributed", "--massless", "quasi-static", "--beta", "0.01",
            "--T", "0.01", "--format", "none"]
    limit = linear_limit(kappa_h(redistributed(beam_system(scenes.point_stops()))), 0.01)
    assert limit == pytest.approx(1.485e-5, rel=1e-3)
    for dt, warned in (("1.4e-5", False), ("1.5e-5", True)):
        out = tmp_path / dt
        assert point_stops.main(args + ["--dt", dt, "--out", str(out)]) == 0
        summary = json.loads((out / "summary.json").read_text())
        assert summary["linear_stability_limit_dt"] == pytest.approx(limit, rel=1e-12)
        assert ("above the linear stability limit" in capsys.readouterr().err) == warned


@pytest.mark.parametrize("args, word", [
    (["--mass", "redistributed", "--beta", "0.2"], "error: beta=0.2 with a mass matrix that"),
    (["--mass", "redistributed", "--massless", "quasi-static", "--beta", "0"],
     "error: beta=0 with massless='quasi-static'"),
])
def test_a_refused_method_is_one_line_without_the_limits_warning(tmp_path, capsys, args,
                                                                  word):
    """The stability warning came first: two lines on stderr for one refusal."""
    from conftest import assert_refused
    from skfem_beam.cases import point_stops
    assert_refused(point_stops.main, args + ["--T", "0.01", "--out", str(tmp_path / "run")],
                   word, capsys, tmp_path)


@pytest.mark.parametrize("damping", [Damping.ratio(0.02, 20.0, 200.0), Damping(modal=0.03)])
def test_damping_is_built_from_the_mass_the_run_uses(damping):
    """Rayleigh and modal damping with a redistributed mass give each mode of the run's
    own dynamics (the massless dofs condensed: quasi-static) the ratio asked.  Built from
    the consistent mass, they gave the massless dof damping it cannot have, and the
    ratios were off by up to 2.5 % (Rayleigh) and 11 % (modal) in the first 8 modes."""
    import scipy.linalg as sla
    s = beam_system(replace(scenes.point_stops(), damping=damping, J=20),
                    mass="redistributed")
    M, K, B = s.M.toarray(), s.K.toarray(), s.B.toarray()
    m = np.flatnonzero(np.abs(M).sum(axis=1) == 0)
    keep = np.setdiff1d(np.arange(M.shape[0]), m)
    T = np.eye(M.shape[0])[:, keep]            # u = T u_l: the massless dofs in equilibrium
    T[m] = -np.linalg.solve(K[np.ix_(m, m)], K[np.ix_(m, keep)])
    w2, V = sla.eigh(T.T @ K @ T, T.T @ M @ T)
    w = np.sqrt(w2[:8])
    ratio = np.einsum("ik,ij,jk->k", V[:, :8], T.T @ B @ T, V[:, :8]) / (2 * w)
    asked = damping.alpha / (2 * w) + damping.alpha_K * w / 2 + damping.modal
    assert m.size == 1 and np.abs(ratio / asked - 1).max() < 1e-8


def test_a_redistributed_mass_is_for_one_plane():
    with pytest.raises(InputError, match="one plane"):
        beam_system(replace(scenes.point_stops(), planes=2), mass="redistributed")
    with pytest.raises(InputError, match="'lumped' is not one of: consistent, redistributed"):
        beam_system(scenes.point_stops(), mass="lumped")


def test_a_quasi_static_massless_run_that_gains_energy_says_so(tmp_path, capsys):
    """The first paper's pipe with its tip stops' mass redistributed, quasi-static, β = 1/4:
    ½E_β 1.38 → 36.5 through its impacts (the energy sees the contact force averaged over
    three steps), a run that ended "success" without a word; β = 1/2 keeps it: no line."""
    from conftest import exit_code
    from skfem_beam.cases import point_stops
    base = ["--mass", "redistributed", "--T", "0.3", "--format", "none"]
    assert exit_code(point_stops.main, base + ["--massless", "quasi-static", "--beta",
                                               "0.25", "--out", str(tmp_path / "a")]) == 0
    err = capsys.readouterr().err
    line = "warning: the contact at the redistributed mass's massless rows did "
    assert line in err and float(err.split(line)[1].split()[0]) > 20      # 32.84 here
    assert exit_code(point_stops.main, base + ["--out", str(tmp_path / "b")]) == 0
    assert "massless rows did" not in capsys.readouterr().err
