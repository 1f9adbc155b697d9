"""Moreau–Jean (velocity level, Newton impact law): a rigid mass rebounds at exactly e
times its approach velocity, the energy identity holds to round-off, e = 1 with θ = 1/2
conserves the energy through contact, and on the periodic rod it converges, penetrating
O(Δt)."""
import numpy as np
import pytest
import scipy.sparse as sp

from skfem_beam import InputError, scenes
from skfem_beam.bar import bar_system, l2_time
from skfem_beam.reference import exact_of
from skfem_beam.scheme.solve import moreau_jean
from skfem_beam.semidiscrete import SemiDiscrete


def rigid_mass(v0=-1.0, gap=0.05):
    one = sp.csr_matrix(np.ones((1, 1)))
    return SemiDiscrete(M=one, K=sp.csr_matrix((1, 1)), C=one, lo=np.array([0.0]),
                        hi=np.array([np.inf]), x_contact=np.array([0.0]),
                        loads=np.zeros((1, 0)), load_time=[], u0=np.array([gap]),
                        v0=np.array([v0]), observe={"x": np.ones(1)})


@pytest.mark.parametrize("e", [0.0, 0.3, 1.0])
def test_rigid_mass_rebounds_at_e(e):
    s = rigid_mass()
    r = moreau_jean(s, 0.01, 0.2, restitution=e)
    v = r.velocity["x"]
    v0 = abs(s.v0[0])            # m/s: the approach speed, the scale (e = 0: round-off)
    assert v[-1] == pytest.approx(e * v0, abs=1e-14 * v0)
    assert r.impacts == 1
    # it penetrates at most one step's travel (the index set switches on once the
    # predicted gap closes)
    assert 0 < r.max_penetration <= 0.01 * 1.0 + 1e-15
    assert r.energy[-1] == pytest.approx(0.5 * e * e * v0**2, abs=2e-14 * 0.5 * v0**2)


@pytest.mark.parametrize("theta,e", [(0.5, 0.0), (0.75, 0.0), (0.5, 0.5)])
def test_energy_identity_to_round_off(theta, e):
    bar = scenes.periodic_rod(20)
    r = moreau_jean(bar_system(bar), 0.01, 6.0, theta=theta, restitution=e, frames=5)
    w = r.work
    gap = r.energy - r.energy[0] + w["damping"] - w["input"] - w["contact"]
    assert np.abs(gap).max() < 1e-13
    assert w["contact"][-1] < -1e-4            # impacts lose energy for e < 1
    if theta > 0.5:
        assert w["damping"][-1] > 1e-4         # the θ-scheme's numerical dissipation


@pytest.mark.parametrize("e", [0.0, 1.0])
def test_the_contact_work_is_the_impulses_on_the_mean_velocity_for_any_theta(e):
    """A rigid mass bouncing at θ = 1: the impulse p works on (v⁻ + v⁺)/2, −½(1 − e²)v²
    per impact (0 for e = 1); the θ-scheme's share, p(θ − ½)Δv, is numerical dissipation
    (work_damping).  Counted as pᵀv^θ it was +1 for e = 1 (energy put in by an elastic
    stop) and 0 for e = 0."""
    r = moreau_jean(rigid_mass(), 0.01, 0.2, theta=1.0, restitution=e)
    w = r.work
    assert r.impacts == 1
    assert w["contact"][-1] == pytest.approx(-0.5 * (1 - e * e), abs=1e-14)
    assert w["damping"][-1] >= 0.0
    gap = r.energy - r.energy[0] + w["damping"] - w["input"] - w["contact"]
    assert np.abs(gap).max() < 1e-14


def test_elastic_impacts_conserve_energy():
    bar = scenes.periodic_rod(40)
    r = moreau_jean(bar_system(bar), 0.01, 12.0, restitution=1.0, frames=5)
    assert np.abs(r.energy / 0.125 - 1).max() < 1e-12
    assert r.impacts >= 4


def test_periodic_rod_converges_and_penetrates_order_dt():
    errs, pens = [], []
    for N in (20, 40, 80):
        bar = scenes.periodic_rod(N)
        dt = 0.04 * bar.h
        r = moreau_jean(bar_system(bar), dt, 12.0, frames=5)
        errs.append(l2_time(r.observed["u0"] - exact_of(bar, 12.0).u(0.0, r.t), dt))
        pens.append(r.max_penetration)
        assert pens[-1] <= 0.5 * dt + 1e-15        # |u_t| ≤ 1/2 on this rod
    assert errs[0] > errs[1] > errs[2] and errs[2] < 1.4e-2       # 1.30e-2 measured
    assert pens[2] > 0


@pytest.mark.parametrize("kw,msg", [(dict(theta=0.3), "theta=0.3"),
                                    (dict(restitution=1.5), "restitution=1.5")])
def test_bad_input_refused(kw, msg):
    with pytest.raises(InputError, match=msg):
        moreau_jean(rigid_mass(), 0.01, 0.1, **kw)


@pytest.mark.parametrize("args, word", [
    (["--restitution", "1.5"], "--restitution 1.5"), (["--restitution", "-0.1"], "-0.1"),
    (["--mass", "foo"], "foo"), (["--law", "bogus"], "bogus"),
    (["--law", "moreau-jean", "--solver", "osqp"], "osqp"),
])
def test_command_line_refuses_laws_and_masses_that_do_not_apply(args, word, tmp_path, capsys):
    """One line naming the value, exit 2, nothing written (the issue's bad-input list)."""
    from conftest import assert_refused
    from skfem_beam.cases import point_stops
    assert_refused(point_stops.main, args + ["--T", "0.01", "--out", str(tmp_path / "run")],
                   word, capsys, tmp_path)


def test_command_line_moreau_jean_and_restitution_run(tmp_path):
    """--law moreau-jean and --restitution run the bar end to end and say so."""
    import json
    from conftest import exit_code
    from skfem_beam.cases import impacting_bar
    for args in (["--law", "moreau-jean"], ["--restitution", "0.5"]):
        out = tmp_path / args[1]
        assert exit_code(impacting_bar.main, args + ["--T", "0.5", "--out", str(out),
                                                     "--format", "none"]) == 0
        s = json.loads((out / "summary.json").read_text())
        assert s["status"] == "success" and s["solver"] == {"moreau-jean": "moreau-jean",
                                                              "0.5": "restitution"}[args[1]]


def test_a_beta_given_to_moreau_jean_is_refused(tmp_path, capsys):
    """Moreau–Jean has θ, no β: a β given to it was checked and not used (β = 0 ran, as
    stable as any, after a warning of the β-scheme's stability limit)."""
    from conftest import assert_refused, exit_code
    from skfem_beam.cases import flat_obstacles
    from skfem_beam.scenefile import example, run_main
    assert_refused(flat_obstacles.main, ["--law", "moreau-jean", "--beta", "0", "--out",
                                         str(tmp_path / "a")],
                   "--beta 0 is the β-scheme's β; --law moreau-jean has none (its θ: --theta)",
                   capsys, tmp_path)
    # a scene file's [time] beta is the file's (a --set of the law keeps it): not used,
    # and no warning of the β-scheme's stability limit
    out = tmp_path / "b"
    assert exit_code(run_main, [str(example("flat_obstacles.toml")), "--set",
                                "contact.law=moreau-jean", "--set", "time.beta=0", "--T", "0.1",
                                "--format", "none", "--out", str(out)]) == 0
    assert "stability limit" not in capsys.readouterr().err


@pytest.mark.parametrize("args, line", [
    (["--stiffness", "nan"], "--stiffness nan is the penalty law's spring (N/m); --law "
     "position has none (give --law penalty)"),
    (["--law", "moreau-jean", "--stiffness", "-1"], "--law moreau-jean has none"),
    (["--method", "penalty", "--law", "position"],
     "--method penalty and --law position name two laws: give one of them"),
    (["--method", "contact", "--law", "penalty"], "name two laws"),
])
def test_a_flag_of_another_law_is_refused(tmp_path, capsys, args, line):
    """--stiffness without the penalty law, and --method and --law naming two laws, were
    accepted and not used (nan and −1 ran exact contact, stored in summary.json)."""
    from conftest import assert_refused
    from skfem_beam.cases import point_stops
    assert_refused(point_stops.main, [*args, "--T", "0.01", "--out", str(tmp_path / "a")],
                   line, capsys, tmp_path)
