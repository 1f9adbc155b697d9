"""The impacting bar (Do, Raupp & Feijoo): P1 space, exact solutions, accuracy targets,
convergence, energy, Example 2, speed, bad input and the command-line case."""
import csv
import json
import re
import subprocess
import sys

import numpy as np
import pytest

from conftest import SUMMARY_KEYS, assert_refused
from skfem_beam import InputError
from skfem_beam.bar import Bar, bar_system, contact_periods, energy_report, errors, run_bar
from skfem_beam.bench.bar_convergence import study
from skfem_beam.reference import (BarData, BarExact, bar_elastic_paper, bar_rigid_force,
                                  bar_rigid_u0, bar_rigid_uL)
from skfem_beam.spaces.lagrange import LagrangeSpace

# Example 1 at the resolution: N = 100, Δt = 1e-3, T = 3
DT, T = 1e-3, 3.0


@pytest.fixture(scope="module")
def rigid():
    bar = Bar(obstacle="rigid")
    return run_bar(bar, DT, T), BarExact.of(bar, T)


@pytest.fixture(scope="module")
def elastic():
    bar = Bar(obstacle="elastic", k=100.0)
    return run_bar(bar, DT, T), BarExact.of(bar, T)


# --- the P1 space (scikit-fem assembly against the closed forms) -------------------------

@pytest.mark.parametrize("mass", ["consistent", "lumped", "average"])
def test_p1_matrices_equal_closed_forms(mass):
    x = np.array([0.0, 0.1, 0.35, 0.5, 1.2])          # non-uniform on purpose
    sp = LagrangeSpace(x, mass)
    h = np.diff(x)
    Mc, Ml, S = (np.zeros((5, 5)) for _ in range(3))
    for j, hj in enumerate(h):
        Mc[j:j + 2, j:j + 2] += hj / 6 * np.array([[2, 1], [1, 2]])
        Ml[j:j + 2, j:j + 2] += hj / 2 * np.eye(2)
        S[j:j + 2, j:j + 2] += np.array([[1, -1], [-1, 1]]) / hj
    want = {"consistent": Mc, "lumped": Ml, "average": (Mc + Ml) / 2}[mass]
    assert np.abs(sp.M.toarray() - want).max() < 1e-15
    assert np.abs(sp.S.toarray() - S).max() < 1e-13
    L = x[-1]                                         # ∫ z w dz scales as L², z as L
    assert sp.load_vector(lambda z: z) == pytest.approx(Mc @ x, abs=7e-16 * L**2)
    assert sp.project(lambda z: 3 * z - 1) == pytest.approx(3 * x - 1,
                                                            abs=3e-14 * np.abs(3 * x - 1).max())
    assert sp.sampler([0.25]).E0 @ x == pytest.approx(x[:-1] + 0.25 * h, abs=8e-16 * L)


def test_p2_matrices_equal_closed_forms():
    """P2: the element matrices h/30·(4 2 −1; 2 16 2; −1 2 4) and (7 −8 1; −8 16 −8;
    1 −8 7)/(3h), unknowns along x (half band 2), row-sum lumping h(1/6, 2/3, 1/6), and
    quadratics reproduced exactly by interpolation, the sampler and its E2."""
    x = np.array([0.0, 0.1, 0.35, 0.5, 1.2])
    sp = LagrangeSpace(x, "average", element="p2")
    h = np.diff(x)
    Mc, Ml, S = (np.zeros((9, 9)) for _ in range(3))
    for j, hj in enumerate(h):
        i = slice(2 * j, 2 * j + 3)
        Mc[i, i] += hj / 30 * np.array([[4, 2, -1], [2, 16, 2], [-1, 2, 4]])
        Ml[i, i] += hj * np.diag([1 / 6, 2 / 3, 1 / 6])
        S[i, i] += np.array([[7, -8, 1], [-8, 16, -8], [1, -8, 7]]) / (3 * hj)
    assert sp.kd == 2 and np.abs(sp.M.toarray() - (Mc + Ml) / 2).max() < 1e-15
    assert np.abs(sp.S.toarray() - S).max() < 1e-12
    q = sp.interpolate(lambda z: z**2 - z)
    assert (sp.C @ q) == pytest.approx(x**2 - x, abs=1e-15)
    smp = sp.sampler([0.3, 0.8])
    assert smp.E0 @ q == pytest.approx(smp.x**2 - smp.x, abs=1e-14)
    assert smp.E2 @ q == pytest.approx(2.0, abs=1e-11)


def test_a_profile_not_finite_at_a_p2_midpoint_is_refused_by_name():
    """A P2 bar's initial profile is evaluated at its midpoints too: NaN there is refused
    in one line naming the point (it was found by the first step, as a state "too large
    for floating point"); P1 has no dof there and takes it."""
    def u0(x):
        x = np.asarray(x, dtype=float)
        return np.where(np.isclose((x * 4) % 1.0, 0.5), np.nan, 0.0)
    Bar(N=4, element="p1", u0=u0)
    with pytest.raises(InputError, match=r"^u0\(x=0.125\)=nan must be a finite number$"):
        Bar(N=4, element="p2", u0=u0)


@pytest.mark.parametrize("element, order", [("p1", 2), ("p2", 4)])
def test_clamped_free_frequencies_converge_at_the_element_rate(element, order):
    """u_tt = u_xx, u(1) = 0, u_x(0) = 0: ω_k = (k − ½)π; the consistent mass's first
    three frequencies converge at h², h⁴ (measured 2.00, 4.00)."""
    import scipy.linalg as sl
    errs = []
    for N in (8, 16):
        sp = LagrangeSpace(np.linspace(0.0, 1.0, N + 1), "consistent", (N,), element)
        w = np.sqrt(sl.eigh(sp.S.toarray(), sp.M.toarray(), eigvals_only=True)[:3])
        errs.append(np.abs(w / ((np.arange(3) + 0.5) * np.pi) - 1))
    rates = np.log2(errs[0] / errs[1])
    assert rates == pytest.approx(order, abs=0.1)


def test_bar_system_units():
    """M carries ρ, K = a·S, B = b·S; constraint u(0) ≥ 0; uniform data."""
    bar = Bar(a=3.0, b=0.2, rho=2.0, L=2.0, f=-1.5, v0=-0.5, u0=0.1, N=4, mass="lumped")
    s = bar_system(bar)
    assert s.M.sum() == pytest.approx(bar.rho * bar.L)           # total mass ρL
    assert s.K.toarray()[0, :2] == pytest.approx([3.0 / 0.5, -3.0 / 0.5])
    assert s.B.toarray()[0, 0] == pytest.approx(0.2 / 0.5)
    assert s.C.toarray().tolist() == [[1, 0, 0, 0, 0]] and s.lo[0] == 0 and s.hi[0] == np.inf
    assert (s.loads[:, 0] * s.load_time[0](np.array([0.3]))).sum() == pytest.approx(-3.0)
    assert s.u0 == pytest.approx(0.1) and s.v0 == pytest.approx(-0.5)
    assert s.observe["mean_u"] @ np.linspace(0, 2, 5) == pytest.approx(1.0)


# --- exact solutions ---------------------------------------------------------------------

def test_exact_rigid_equals_the_closed_forms():
    ex = BarExact(BarData(1, 1, 1, -1, "rigid"), 4.0)
    t = np.linspace(0, 4, 4001)
    assert np.abs(ex.u(0, t) - bar_rigid_u0(t)).max() < 1e-15
    assert np.abs(ex.u(1, t) - bar_rigid_uL(t)).max() < 1e-15
    assert np.abs(ex.contact_force(t[1:]) - bar_rigid_force(t[1:])).max() == 0.0
    assert ex.contact_intervals() == [(0.0, 2.0)]


@pytest.mark.parametrize("k", [100.0, 7.0, 1.0])
def test_exact_elastic_equals_the_papers_regions(k):
    """R_I, R_II, R_III of the paper, wherever they hold (t ≤ 2 + x)."""
    ex = BarExact(BarData(1, 1, 1, -1, "elastic", k), 3.0)
    X, Tm = np.meshgrid(np.linspace(0, 1, 101), np.linspace(0, 3, 301))
    ref = bar_elastic_paper(X, Tm, k)
    known = np.isfinite(ref)
    assert known.mean() > 0.8
    assert np.abs(ex.u(X, Tm) - ref)[known].max() < 1e-14


@pytest.mark.parametrize("kw", [dict(obstacle="elastic", k=100.0), dict(obstacle="elastic", k=3.0),
                                dict(obstacle="rigid"),
                                dict(obstacle="elastic", k=50.0, a=4.0, rho=2.0, L=1.5, v0=-0.3)])
def test_exact_conserves_energy(kw):
    """b = 0, f = 0: ½∫ρu_t² + ½∫a u_x² + ½k(U⁻)² is constant (quadrature error only)."""
    kw = {"a": 1.0, "rho": 1.0, "L": 1.0, "v0": -1.0, **kw}
    ex = BarExact(BarData(**kw), T=6.0)
    E = ex.energy(np.linspace(0, 6, 25), points=20001)["total"]
    E0 = 0.5 * kw["rho"] * kw["v0"] ** 2 * kw["L"]
    assert np.abs(E - E0).max() < 2e-5 * E0


@pytest.mark.parametrize("obstacle", ["rigid", "elastic"])
def test_exact_example2_long_horizon_conserves_energy(obstacle):
    """f = −1 over 15 round trips (7 and 18 contacts): E − ∫f u dx stays constant."""
    ex = BarExact(BarData(1, 1, 1, -1, obstacle, k=100.0, f=-1.0), 30.0)
    assert len(ex.contact_intervals()) == {"rigid": 7, "elastic": 18}[obstacle]
    t, x = np.linspace(0, 30, 13), np.linspace(0, 1, 8001)
    X, Tm = np.meshgrid(x, t)
    u = ex.u(X, Tm)
    total = ex.energy(t, points=8001)["total"] + (u[:, 1:] + u[:, :-1]).sum(axis=1) / 2 * (x[1])
    # the rigid bar carries velocity jumps: the trapezoid rule is first order there
    assert np.ptp(total) < {"rigid": 1e-3, "elastic": 1e-5}[obstacle]


def test_exact_scaling_gap_and_stiff_limit():
    # a gap u0: free flight for u0/|v0|, then contact for 2L/c (c = √(a/ρ) = 2)
    Tx = 5.0                                        # s: the times' scale, 2e-15 Tx = 1e-14
    ex = BarExact(BarData(a=8.0, rho=2.0, L=1.5, v0=-0.5, obstacle="rigid", u0=0.1),
                  T=Tx)
    (t0, t1), = ex.contact_intervals()
    assert t0 == pytest.approx(0.2, abs=2e-15 * Tx) and t1 == pytest.approx(0.2 + 1.5,
                                                                          abs=2e-15 * Tx)
    assert ex.contact_force(1.0) == pytest.approx(np.sqrt(8.0 * 2.0) * 0.5)   # ρc|v0|
    # a stiff spring tends to the rigid obstacle, with U ≈ −ρc|v0|/k in contact
    t = np.linspace(0, 3, 601)
    stiff = BarExact(BarData(1, 1, 1, -1, "elastic", k=1e6), 3.0)
    assert np.abs(stiff.u(0, t) - bar_rigid_u0(t)).max() < 3e-6     # O(1/k)
    assert stiff.u(0, 1.0) == pytest.approx(-1e-6, rel=1e-9)
    # moving away: no contact, rigid translation
    away = BarExact(BarData(1, 1, 1, +0.7, "rigid"), 3.0)
    assert away.contact_intervals() == [] and away.u(0.3, 2.0) == pytest.approx(1.4)


def test_exact_elastic_against_a_very_fine_numerical_solution():
    """The characteristics solution and the scheme agree, better and better with h."""
    bar = Bar(obstacle="elastic", k=100.0, N=400)
    e = errors(run_bar(bar, 0.1 * bar.h, T), BarExact.of(bar, T))
    assert e["l2_u0"] < 1.5e-3 and e["l2_uL"] < 3e-4 and e["l2_force"] < 0.05


def test_exact_example2_second_impact():
    """f = −1: separation at t = 3, a second impact at 3 + √2 (rigid; the scheme finds
    it too, test_example2_second_impact)."""
    Tx = 6.0                                        # the times' scale: 1.5e-13 Tx = 9e-13
    ex = BarExact(BarData(1, 1, 1, -1, "rigid", f=-1.0), Tx)
    iv = ex.contact_intervals()
    assert iv[0] == pytest.approx((0.0, 3.0), abs=1.5e-13 * Tx)
    assert iv[1][0] == pytest.approx(3 + np.sqrt(2), abs=1.5e-13 * Tx)


# --- the accuracy targets (rigid obstacle, Example 1) ------------------------------

def test_rigid_targets_no_penetration_and_errors(rigid):
    run, ex = rigid
    assert run.t.size == 3001 and run.t[-1] == pytest.approx(3.0)
    assert run.u0.min() >= -1e-12                      # at every step
    e = errors(run, ex)
    assert e["l2_u0"] <= 8e-3 and e["l2_u0"] < 1.38e-2      # Siconos: 1.38e-2
    assert e["l2_uL"] <= 2.5e-3 and e["l2_uL"] < 4.09e-3    # Siconos: 4.09e-3


def test_consistent_mass_misses_the_target():
    """Why ``average`` is the default: consistent mass has Siconos' dispersion error."""
    bar = Bar(mass="consistent")
    e = errors(run_bar(bar, DT, T), BarExact.of(bar, T))
    assert e["l2_u0"] > 1.2e-2 and e["l2_uL"] > 3.5e-3


def test_rigid_convergence_rates_positive_and_stable():
    rows = study("rigid", Ns=(25, 50, 100, 200))
    for key, low in (("l2_u0", 0.6), ("l2_uL", 0.9), ("l2_force", 0.3)):
        rates = np.array([r[f"rate_{key}"] for r in rows[1:]])
        assert rates.min() > low, (key, rates)
        assert np.ptp(rates) < 0.1, (key, rates)                 # stable under refinement
    assert all(r["penetration"] <= 1e-12 for r in rows)


def test_elastic_convergence_rates_positive():
    rows = study("elastic", Ns=(50, 100, 200, 400))
    for key in ("l2_u0", "l2_uL", "l2_force"):
        assert min(r[f"rate_{key}"] for r in rows[1:]) > 0.5, key


# --- energy ----------------------------------------------------------------------------------

def test_rigid_energy_loss_is_the_contact_node(rigid):
    """The Signorini step stops the contact node: it loses ½ m₀ v0² (m₀ = 5h/12 with the
    average mass), nothing else; conserved (to round-off) before and after."""
    run, _ = rigid
    rep = energy_report(run)
    assert rep["energy_before_contact"] == pytest.approx(0.5, rel=2e-15)
    assert rep["energy_loss"] == pytest.approx(0.5 * 5 * run.bar.h / 12, rel=0.02)
    assert np.ptp(run.energy[1:]) < 1e-9


def test_elastic_energy_report(elastic):
    """The exact solution conserves energy; the discrete loss is reported and small.  The
    scheme's energy (with the spring's β-form) is exactly conserved while the spring
    stays compressed and while it is idle: it changes only on the switching steps."""
    run, _ = elastic
    rep = energy_report(run)
    assert abs(rep["energy_loss_relative"]) < 5e-3
    for a, b in ((0.1, 1.9), (2.05, 3.0)):       # in contact; free flight
        phase = (run.t > a) & (run.t < b)
        assert np.ptp(run.energy[phase]) < 1e-10
    # the split adds up to the scheme's own ½E_β
    n = run.t.size
    assert np.abs(run.kinetic[1:] + run.strain[1:] - run.result.energy[1:n]).max() < 1e-12


def test_viscosity_dissipates():
    run = run_bar(Bar(obstacle="elastic", b=0.01), DT, T)
    assert BarExact.of(run.bar, T) is None
    assert np.all(np.diff(run.energy[2200:]) <= 1e-12)      # free flight: damped vibration
    assert run.energy[-1] < run.energy[0] - 1e-3


def test_penalty_penetrates_the_rigid_obstacle():
    """Normal compliance stands in for the rigid obstacle: it penetrates, at least by the
    continuum spring's compression ρc|v0|/k (the contact node's own rebound adds to it),
    less as k grows; the contact method has no penetration at all."""
    pen = {k: run_bar(Bar(obstacle="rigid", k=k), DT, T, method="penalty").penetration
           for k in (1e4, 1e6)}
    assert pen[1e4] > 0.5e-4 and pen[1e6] > 0.5e-6
    assert pen[1e6] < pen[1e4] / 10


# --- Example 2 (f = −1): the bar separates and hits again ---------------------------------

@pytest.mark.parametrize("obstacle", ["rigid", "elastic"])
def test_example2_second_impact(obstacle):
    bar = Bar(obstacle=obstacle, f=-1.0)
    run, ex = run_bar(bar, DT, 6.0), BarExact.of(bar, 6.0)
    periods = contact_periods(run.t, run.force, merge=0.1)
    assert len(periods) == 2
    assert periods[1][0] == pytest.approx(ex.contact_intervals()[1][0], abs=3e-3)
    e = errors(run, ex)
    assert e["l2_u0"] < 5e-3 and e["l2_uL"] < 5e-3


# --- β = 0, lumped mass, Courant number 1 ---------------------------------------------------

def test_explicit_courant_one_equals_a_plain_leapfrog():
    """At its stability limit the explicit scheme keeps every state it is given: the run
    reaches T with E_β constant, equals a ten-line leapfrog with the contact node clamped
    (to round-off), and so reproduces the exact u(L,t) and reaction, while
    the released end node steps in pairs (0, 2h, 2h, 4h, …) after t = 2."""
    bar = Bar(obstacle="rigid", mass="lumped")
    dt, T3 = bar.h / bar.c, 3.0
    run = run_bar(bar, dt, T3, beta=0.0)
    assert run.result.status == "success" and run.t[-1] == pytest.approx(T3)
    assert np.ptp(run.result.energy) < 1e-12

    s = bar_system(bar)
    m, K = s.M.diagonal(), s.K
    U = [s.u0, s.u0 + dt * s.v0 - 0.5 * dt**2 * (K @ s.u0) / m]
    U[1][0] = max(U[1][0], 0.0)
    for _ in range(run.t.size - 2):
        x = 2 * U[-1] - U[-2] - dt**2 * (K @ U[-1]) / m
        x[0] = max(x[0], 0.0)          # Signorini at x = 0: a clamp, as M is diagonal
        U.append(x)
    U = np.array(U)
    assert np.abs(run.u0 - U[:, 0]).max() < 1e-13
    assert np.abs(run.uL - U[:, -1]).max() < 1e-13

    e = errors(run, BarExact.of(bar, T3))
    assert e["l2_uL"] < 1e-12 and e["l2_force"] < 1e-12
    assert e["max_u0"] == pytest.approx(bar.h, rel=1e-9)
    assert np.all(np.abs(run.u0 - BarExact.of(bar, T3).u(0.0, run.t))[run.t < 2.0 - dt / 2] < 1e-13)


# --- bad input ---------------------------------------------------------------------------

@pytest.mark.parametrize("kw, word", [
    (dict(N=0), "N=0"), (dict(N=2.5), "N=2.5"), (dict(a=0), "a=0"), (dict(a=-1), "a=-1"),
    (dict(rho=0), "rho=0"), (dict(L=-2), "L=-2"), (dict(b=-0.1), "b=-0.1"),
    (dict(k=-5), "k=-5"), (dict(obstacle="elastic", k=0), "k=0"), (dict(u0=-0.01), "u0=-0.01"),
    (dict(obstacle="soft"), "obstacle='soft'"), (dict(mass="diag"), "mass='diag'"),
    (dict(v0=float("nan")), "v0=nan"), (dict(a=float("inf")), "a=inf"),
])
def test_bar_refuses_bad_input(kw, word):
    with pytest.raises(InputError, match=word.replace("(", r"\(")) as e:
        Bar(**kw)
    assert "\n" not in str(e.value)


def test_run_refuses_bad_steps():
    with pytest.raises(InputError, match="dt"):
        run_bar(Bar(), 0.0, 1.0)
    with pytest.raises(InputError, match="T"):
        run_bar(Bar(), 1e-3, -1.0)
    with pytest.raises(InputError, match="method"):
        run_bar(Bar(), 1e-3, 1.0, method="magic")


# --- the command-line case -------------------------------------------------------------------

CASE = [sys.executable, "-m", "skfem_beam.cases.impacting_bar"]


@pytest.mark.usefixtures("charts")
def test_case_end_to_end(tmp_path):
    out = tmp_path / "run"
    p = subprocess.run(CASE + ["--T", "2.5", "--out", str(out)], capture_output=True,
                       text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    files = {f.name for f in out.iterdir()}
    assert {"summary.json", "timeseries.csv", "displacement.png"} <= files
    s = json.loads((out / "summary.json").read_text())
    assert SUMMARY_KEYS <= set(s), SUMMARY_KEYS - set(s)
    assert s["steps"] == 2500 and s["max_penetration"] <= 1e-12
    assert s["errors"]["l2_uL"] < 2.5e-3
    rows = list(csv.DictReader(open(out / "timeseries.csv")))
    assert len(rows) == 2501
    uL = np.array([float(r["u_L"]) for r in rows])
    uL_ex = np.array([float(r["u_L_exact"]) for r in rows])
    assert np.abs(uL - uL_ex).max() < 1e-2
    assert {"t", "u_0", "contact_force", "energy", "energy_kinetic", "energy_strain",
            "energy_obstacle", "contact_force_exact"} <= set(rows[0])


@pytest.mark.parametrize("args, word", [
    (["--N", "0"], "--N=0"), (["--rho", "-1"], "--rho=-1"),
    # named by the flag given, not by Bar's field (it said a=0)
    (["--a", "0"], "--E=0 must be > 0"), (["--E", "-1"], "--E=-1 must be > 0"),
    (["--far-end", "glued"], "--far-end='glued' is not one of"),
    (["--L", "0"], "L=0"), (["--dt", "0"], "dt=0"), (["--T", "-1"], "T=-1"),
    (["--b", "-1"], "b=-1"), (["--obstacle", "elastic", "--k", "-1"], "k=-1"),
    (["--u0", "-0.1"], "u0=-0.1"), (["--obstacle", "soft"], "soft"),
    (["--mass", "x"], "mass='x'"),
    # a spring of the other obstacle: read and not used
    (["--k", "50"], "--k 50 is the elastic obstacle's stiffness: with --obstacle rigid it "
                    "is not used"),
    (["--obstacle", "elastic", "--law", "penalty", "--stiffness", "5"],
     "--stiffness 5 is the penalty springs' at a rigid obstacle"),
    (["--v0", "-1e-1", "--dt", "-1e-3"], "dt=-0.001 must be > 0"),    # -1e-3: a value
])
def test_case_bad_input_one_line_no_output(tmp_path, capsys, args, word):
    """In-process through the same guard as ``python -m`` (a subprocess each is slow)."""
    from skfem_beam.cases import impacting_bar
    assert_refused(impacting_bar.main, args + ["--out", str(tmp_path / "run")], word, capsys,
                   tmp_path)


def test_case_bad_input_subprocess(tmp_path):
    out = tmp_path / "run"
    p = subprocess.run(CASE + ["--N", "0", "--out", str(out)], capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 2 and p.stderr.strip() == "error: --N=0 must be a whole number ≥ 1"
    assert p.stdout == "" and not out.exists()


def test_case_honours_save_every_and_frames(tmp_path):
    """The bar streams through the same pipeline as the beams: --save-every keeps every
    n-th row, --frames about that many field frames (not one per step)."""
    from conftest import exit_code
    from skfem_beam.cases import impacting_bar
    out = tmp_path / "run"
    assert exit_code(impacting_bar.main, ["--T", "1", "--save-every", "10", "--frames", "20",
                                          "--format", "vtu", "--out", str(out)]) == 0
    rows = list(csv.DictReader(open(out / "timeseries.csv")))
    assert len(rows) == 101 and float(rows[1]["t"]) == pytest.approx(0.01)
    assert len(list((out / "fields_vtu").iterdir())) == 21
    full = run_bar(Bar(), DT, 1.0)
    assert np.array([float(r["u_L"]) for r in rows]) == \
        pytest.approx(full.uL[::10], abs=1e-15 * np.abs(full.uL).max())
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "success" and s["steps"] == 1000


def test_case_disk_full_then_resume_is_bit_identical(tmp_path, monkeypatch, capsys):
    """Checkpoints and --resume work for the bar as for the beams."""
    from conftest import exit_code
    from skfem_beam.cases import impacting_bar
    from skfem_beam.output import series
    out, ref = tmp_path / "run", tmp_path / "ref"
    base = ["--T", "3", "--flush-every", "250", "--format", "xdmf", "--obstacle", "elastic"]
    real = series.SeriesFile.append
    calls = {"n": 0}

    def full(self, columns):
        calls["n"] += 1
        if calls["n"] > 5:
            raise OSError(28, "No space left on device")
        real(self, columns)

    monkeypatch.setattr(series.SeriesFile, "append", full)
    assert exit_code(impacting_bar.main, base + ["--checkpoint-every", "0", "--out", str(out)]) == 3
    assert json.loads((out / "summary.json").read_text())["status"] == "failed"
    monkeypatch.setattr(series.SeriesFile, "append", real)
    assert exit_code(impacting_bar.main, ["--resume", str(out)]) == 0
    assert exit_code(impacting_bar.main, base + ["--out", str(ref)]) == 0
    assert (out / "timeseries.csv").read_text() == (ref / "timeseries.csv").read_text()
    a, b = (json.loads((d / "summary.json").read_text()) for d in (out, ref))
    for key in ("steps", "impacts", "errors", "energy", "max_penetration", "status"):
        assert a[key] == b[key], key


# --- profiles, either end, clamped far end, cross-section (issue "own beam and bar") -------

def test_profiles_equal_the_uniform_numbers():
    """A table or a function that is the uniform value gives the same run, bit for bit."""
    ref = run_bar(Bar(obstacle="elastic", u0=0.05, N=20), 5e-3, 1.5)
    for u0, v0 in (([(0, 0.05), (1, 0.05)], [(0, -1.0), (1, -1.0)]),
                   (lambda x: 0 * x + 0.05, lambda x: np.full_like(x, -1.0))):
        got = run_bar(Bar(obstacle="elastic", u0=u0, v0=v0, N=20), 5e-3, 1.5)
        assert np.array_equal(got.u0, ref.u0) and np.array_equal(got.uL, ref.uL)
        assert np.array_equal(got.energy, ref.energy)


def test_profile_is_interpolated_at_the_nodes():
    bar = Bar(u0=[(0, 0.2), (0.5, 0.0), (1, 0.3)], v0=lambda x: x**2, N=4, obstacle="elastic")
    s = bar_system(bar)
    u0, v0 = [0.2, 0.1, 0.0, 0.15, 0.3], [0.0, 1 / 16, 1 / 4, 9 / 16, 1.0]
    assert s.u0 == pytest.approx(u0, abs=3e-16 * max(u0))
    assert s.v0 == pytest.approx(v0, abs=1e-16 * max(v0))


def test_obstacle_at_the_right_end_is_the_mirror_image():
    """Elastic Example 1 mirrored (obstacle at x = L, v0 = +1): u(L) = −u(0) of the original,
    the same reaction R ≥ 0 and energy, and the same errors against the mirrored exact."""
    left = run_bar(Bar(obstacle="elastic", N=50), 2e-3, 2.5)
    right = run_bar(Bar(obstacle="elastic", obstacle_at="right", v0=1.0, N=50), 2e-3, 2.5)
    # equal to round-off (the other end's sums run in the other order): 1.6e-13 measured
    assert np.abs(right.uL + left.u0).max() < 1e-12 and np.abs(right.u0 + left.uL).max() < 1e-12
    assert np.nanmax(np.abs(right.force - left.force)) < 1e-10 and np.nanmax(right.force) > 0.5
    assert np.abs(right.energy - left.energy).max() < 1e-12
    assert right.penetration == pytest.approx(left.penetration, rel=1e-9)
    el, er = errors(left, BarExact.of(left.bar, 2.5)), errors(right, BarExact.of(right.bar, 2.5))
    assert er["l2_uL"] == pytest.approx(el["l2_u0"], rel=1e-9)
    assert er["l2_force"] == pytest.approx(el["l2_force"], rel=1e-9)
    s = bar_system(right.bar)
    assert s.lo[0] == -np.inf and s.hi[0] == 0.0 and s.x_contact[0] == 1.0
    assert Bar(obstacle_at=1.0).obstacle_at == "right" and Bar(obstacle_at=0).obstacle_at == "left"


def test_clamped_far_end_drops_its_node_and_reflects_with_a_sign_change():
    """u0 = 0, v0 = −1 towards the obstacle at x = 0, the far end x = L clamped: the node
    at L is gone, u(L, t) ≡ 0, and ½E_β is conserved until the first impact."""
    bar = Bar(far_end="clamped", u0=0.0, v0=-1.0, obstacle="rigid", N=40)
    s = bar_system(bar)
    assert s.n == 40 and np.all(s.observe["uL"] == 0) and s.observe["u0"][0] == 1.0
    # ρL less the clamped node's row and column: 2h/3 (consistent), h/2 (lumped), mean 7h/12
    assert s.M.sum() == pytest.approx(1.0 - 7 / 12 / 40, rel=1e-15)
    run = run_bar(bar, 0.01, 1.0)
    assert np.all(run.uL == 0.0) and run.penetration <= 1e-15
    assert BarExact.of(bar, 1.0) is None                         # no exact solution known


def test_cross_section_gives_newtons_and_joules():
    """A multiplies M, K and the load: u is unchanged, forces (N) and energies (J) scale by A;
    the spring k is then in N/m, i.e. k/A per unit section."""
    A = 2e-4
    per = run_bar(Bar(obstacle="elastic", f=-1.0, N=30), 5e-3, 3.0)
    phys = run_bar(Bar(obstacle="elastic", f=-1.0, N=30, A=A, k=100.0 * A), 5e-3, 3.0)
    assert np.abs(phys.u0 - per.u0).max() < 1e-13
    assert np.nanmax(np.abs(phys.force - A * per.force)) < 1e-12
    assert np.abs(phys.energy + phys.load_potential - A * (per.energy + per.load_potential)
                  ).max() < 1e-15
    e_per, e_phys = errors(per, BarExact.of(per.bar, 3.0)), errors(phys, BarExact.of(phys.bar, 3.0))
    assert e_phys["l2_u0"] == pytest.approx(e_per["l2_u0"], rel=1e-8)
    assert e_phys["l2_force"] == pytest.approx(A * e_per["l2_force"], rel=1e-8)
    assert Bar(a=3.0).E == 3.0


@pytest.mark.parametrize("kw, word", [
    (dict(u0=[(0, 0.1), (0.5, 0.2), (0.5, 0.3), (1, 0)]), "x must increase"),
    (dict(u0=[(0, 0.1), (0.9, 0.1)]), "covers [0, 0.9]"),
    (dict(u0=[(0, 0.1)]), "at least two"),
    (dict(u0="abc"), "u0='abc'"),
    (dict(v0=lambda x: np.where(x < 0.5, np.nan, x)), "v0(x=0)=nan"),
    (dict(v0=lambda x: float(x)), "function failed"),
    (dict(u0=[(0, -0.1), (1, 0.2)]), "u(0,0)=-0.1 < 0"),
    (dict(obstacle_at="right", u0=0.1), "u(L,0)=u0=0.1 > 0"),
    (dict(far_end="clamped", u0=0.1), "u0=0.1 at the clamped end x=1"),
    (dict(far_end="pinned"), "far_end='pinned'"), (dict(obstacle_at="top"), "obstacle_at='top'"),
    (dict(obstacle_at=0.5), "obstacle_at=0.5"), (dict(A=0), "A=0"), (dict(A=-1e-4), "A=-0.0001"),
])
def test_bar_refuses_bad_new_input(kw, word):
    with pytest.raises(InputError, match=re.escape(word)) as e:
        Bar(**kw)
    assert "\n" not in str(e.value)


def test_case_periodic_rod_from_a_csv(tmp_path):
    """The rod through the command line: the exact solution is found and written beside."""
    from conftest import exit_code
    from skfem_beam.cases import impacting_bar
    csv_path = tmp_path / "rod.csv"
    csv_path.write_text("x,u\n0,0.5\n1,0\n")
    out = tmp_path / "run"
    assert exit_code(impacting_bar.main, [
        "--far-end", "clamped", "--v0", "0", "--u0-csv", str(csv_path), "--N", "40",
        "--dt", "0.01", "--T", "3", "--format", "none", "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert SUMMARY_KEYS <= set(s) and s["exact_solution"] is True
    assert s["exact_contact_periods"] == [[1.0, 2.0]] and s["impacts"] == 1
    assert s["max_penetration"] <= 1e-15 and s["errors"]["l2_u0"] < 0.04
    assert s["bar"]["u0"] == {"x": [0.0, 1.0], "value": [0.5, 0.0]}
    rows = list(csv.DictReader(open(out / "timeseries.csv")))
    assert float(rows[0]["energy"]) == pytest.approx(0.125, rel=8e-13)
    assert float(rows[0]["energy_exact"]) == pytest.approx(0.125, rel=8e-13)


def test_case_right_obstacle_and_cross_section(tmp_path):
    from conftest import exit_code
    from skfem_beam.cases import impacting_bar
    out = tmp_path / "run"
    assert exit_code(impacting_bar.main, [
        "--obstacle-at", "right", "--v0", "1", "--A", "1e-4", "--E", "2", "--N", "40",
        "--dt", "0.005", "--T", "2", "--format", "none", "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["units"]["contact_force"] == "N" and s["bar"]["a"] == 2.0
    assert s["max_penetration"] <= 1e-15 and s["impacts"] == 1
    rows = list(csv.DictReader(open(out / "timeseries.csv")))
    R = np.array([float(r["contact_force_exact"]) for r in rows])
    assert R.max() == pytest.approx(1e-4 * np.sqrt(2.0))       # A·ρc|v0|


@pytest.mark.parametrize("content, word", [("0,0.5\n0,0\n", "x must increase"),
                                           ("0,0.5\n1,zero\n", "line 2"), (None, "cannot read")])
def test_case_bad_csv_one_line_no_output(tmp_path, capsys, content, word):
    from skfem_beam.cases import impacting_bar
    path = tmp_path / "in" / "u0.csv"
    if content is not None:
        path.parent.mkdir()
        path.write_text(content)
    folder = tmp_path / "outs"
    folder.mkdir()
    assert_refused(impacting_bar.main, ["--far-end", "clamped", "--v0", "0", "--u0-csv",
                                        str(path), "--out", str(folder / "run")], word, capsys,
                   folder)


def test_a_restitution_that_cannot_act_on_the_first_impact_is_warned_of(tmp_path, capsys):
    """Example 1 touches the obstacle at t = 0: the position-level restitution needs the
    state before the first step, so e = 0 and e = 1 ran the same, without a word; one
    warning line now (none with a gap the bar takes more than a step to close)."""
    from conftest import exit_code
    from skfem_beam.cases import impacting_bar
    for args, warned in ((["--restitution", "1"], True),
                         (["--restitution", "1", "--u0", "0.1"], False),
                         (["--restitution", "1", "--law", "moreau-jean"], False)):
        out = tmp_path / str(len(list(tmp_path.iterdir())))
        assert exit_code(impacting_bar.main, [*args, "--T", "0.2", "--format", "none",
                                              "--out", str(out)]) == 0
        err = capsys.readouterr().err
        assert ("restitution 1 does not act on the first impact" in err) == warned, args


def test_a_row_every_k_states_keeps_the_runs_T_and_says_where_the_rows_end(tmp_path, capsys):
    """--save-every 7 of 3000 steps: summary.json's T is the run's 3.0 s (it was the last
    row's 2.996 s) and one note says the last row is state 2996, as a beam run says."""
    from conftest import exit_code
    from skfem_beam.cases import impacting_bar
    out = tmp_path / "r"
    assert exit_code(impacting_bar.main, ["--save-every", "7", "--format", "none",
                                          "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["T"] == 3.0 and s["steps"] == 3000
    assert "the last saved row is state 2996 (t=2.996 s)" in capsys.readouterr().err


def test_a_run_too_long_for_the_energy_split_says_its_columns_are_nan(tmp_path, capsys):
    """Past 4,000,000 stored values the β split is not computed: energy_kinetic and
    energy_strain were NaN in every row without a word; one warning line now."""
    from conftest import exit_code
    from skfem_beam.cases import impacting_bar
    from skfem_beam.results import read_run
    out = tmp_path / "long"
    assert exit_code(impacting_bar.main, ["--N", "1000", "--dt", "1e-3", "--T", "5",
                                          "--format", "none", "--out", str(out)]) == 0
    assert "energy_kinetic and energy_strain are NaN in this run" in capsys.readouterr().err
    s = read_run(out).series
    assert np.isnan(s["energy_kinetic"]).all() and np.isfinite(s["energy"]).all()


def test_a_viscous_bar_from_a_non_uniform_start_follows_its_damped_mode():
    """ρu_tt = Eu_xx + bu_xxt, free in flight: u = 5 + Vt + q(t)cos(πx/L) with q the damped
    oscillator's (ζ = bω/2E).  The start step left out Δt/2·B u⁰ that the step's factor
    carries: a velocity −½M⁻¹Bu⁰ at every N and Δt, the mode 6.5e-4 off (3 % of its
    amplitude) at N = 100, 400 and 1000 alike; now 8.7e-9 (N = 100, Δt = 1e-3)."""
    from skfem_beam.bar import run_bar
    E, L, b, a, V = 1.3, 2.0, 0.05, 0.02, -0.5
    bar = Bar(a=E, b=b, L=L, v0=V, u0=lambda x: 5 + a * np.cos(np.pi * np.asarray(x) / L),
              N=100)
    r = run_bar(bar, 1e-3, 1.0)
    om = np.sqrt(E) * np.pi / L
    z = b * om / (2 * E)
    wd = om * np.sqrt(1 - z * z)
    q = a * np.exp(-z * om * r.t) * (np.cos(wd * r.t) + z * om / wd * np.sin(wd * r.t))
    assert np.abs((r.u0 + r.uL) / 2 - (5 + V * r.t)).max() < 1e-10
    assert np.abs((r.u0 - r.uL) / 2 - q).max() < 1e-6 * a       # 8.7e-9 = 4.4e-7 a


def test_a_bar_released_from_a_compressed_spring_runs_and_matches_its_exact_force():
    """u0 = −0.05 against an elastic obstacle (k = 20), at rest: the spring's 0.025 J goes
    into the bar, R = e^{−kt/Z} until the wave returns (Z = ρc = 1).  The a-priori energy
    bound began at the first state's energy without the spring's (3e-5): "unstable at step
    3" at every N and Δt."""
    bar = Bar(obstacle="elastic", k=20.0, u0=-0.05, v0=0.0, N=200)
    r = run_bar(bar, 1e-4, 0.5)
    assert r.result.status == "success", r.result.message
    t = r.t
    early = (t > 0.0) & (t < 0.3)
    R = np.exp(-20.0 * t[early])
    assert np.abs(r.force[early] - R).max() < 3e-2        # measured 2.05e-2 (P1, N = 200)
    assert np.abs(r.energy / 0.025 - 1).max() < 1e-3      # the spring's energy, kept


@pytest.mark.parametrize("N, warned", [(400, True), (100, False)])
def test_a_spring_stiff_for_the_mesh_says_so(tmp_path, capsys, N, warned):
    """k = 1e4 at N = 400 (E = ρ = 1): the contact node alone on the spring rings at 3.87
    times the mesh's highest frequency, the force between 0 and 4.3 against the exact 1 and
    the node off the spring 63 % of the contact at any Δt, without a word (the warning on
    √(k/m₀)Δt stays silent at Δt = 2.5e-5); at N = 100 the default k = 100 is 0.77 times
    it: no line."""
    from conftest import exit_code
    from skfem_beam.cases import impacting_bar
    k = "1e4" if warned else "100"
    argv = ["--obstacle", "elastic", "--k", k, "--N", str(N), "--dt", "2.5e-5", "--T",
            "0.01", "--format", "none", "--out", str(tmp_path / "run")]
    assert exit_code(impacting_bar.main, argv) == 0
    err = [e for e in capsys.readouterr().err.splitlines() if "for the mesh" in e]
    assert err == (["warning: stiff spring for the mesh: the contact node alone on it rings "
                    "at √(k/m₀) = 3.87 × the mesh's highest frequency 2c/h, which the bar "
                    "cannot carry away: its contact force oscillates about the exact one "
                    "(±32 % at 1.1 ×, ±13 % at 0.87 ×) and from about 2 × the node lifts off "
                    "the spring; a finer mesh (the ratio goes as 1/√N: N = 6000 for 1 ×) or a "
                    "softer --k"] if warned else [])
