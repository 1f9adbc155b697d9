"""The β-scheme against exact references: rates in Δt, energy identity, constraints."""
import numpy as np
import pytest
import scipy.linalg

from conftest import rate
from skfem_beam import (Beam, BeamProblem, InitialState, Load, Obstacles, beam_system, solve)
from skfem_beam.stability import kappa_h, linear_limit
from skfem_beam.reference import cantilever_mode

L, K2 = 1.501, 282.84


def free_system(obstacles=Obstacles(), J=8):
    ini = InitialState(u0=lambda x: 0.01 * cantilever_mode(x, L, 0) + 0.002 * cantilever_mode(x, L, 1),
                       v0=lambda x: 0.3 * cantilever_mode(x, L, 0))
    return beam_system(BeamProblem(Beam(L, K2), obstacles, initial=ini, J=J))


def modal_tip(system, T):
    """Exact solution of the semi-discrete system M ü + K u = 0 at t = T."""
    w2, V = scipy.linalg.eigh(system.K.toarray(), system.M.toarray())
    w = np.sqrt(w2)
    a, b = V.T @ (system.M @ system.u0), V.T @ (system.M @ system.v0) / w
    return system.observe["tip_displacement"] @ (V @ (a * np.cos(w * T) + b * np.sin(w * T)))


@pytest.mark.parametrize("beta", [0.5, 0.25])
def test_second_order_in_dt_free_vibration(beta):
    system, T = free_system(), 0.2
    exact = modal_tip(system, T)
    dts = np.array([2e-4, 1e-4, 5e-5, 2.5e-5])
    errors = [abs(solve(system, dt, T, beta, frames=1).observed["tip_displacement"][-1] - exact)
              for dt in dts]
    assert errors[-1] < 1e-6
    assert 1.9 <= rate(errors, dts) <= 2.1


def test_load_window_orders():
    """The papers' forward average lags f by Δt/2 (order 1); the centred one is order 2."""
    system = beam_system(BeamProblem(Beam(L, K2), load=Load.uniform(lambda t: np.sin(10 * t)), J=8))
    T = 0.5
    exact = solve(system, 2.5e-6, T, 0.5, frames=1, load_window="centered").observed["tip_displacement"][-1]
    dts = np.array([4e-4, 2e-4, 1e-4, 5e-5])
    rates = {}
    for window in ("forward", "centered"):
        e = [abs(solve(system, dt, T, 0.5, frames=1, load_window=window)
                 .observed["tip_displacement"][-1] - exact) for dt in dts]
        rates[window] = rate(e, dts)
    assert 0.9 <= rates["forward"] <= 1.1
    assert rates["centered"] >= 1.9


@pytest.mark.parametrize("beta", [0.5, 0.25, 0.1, 0.0])
def test_energy_conserved_to_round_off_without_contact(beta):
    # J = 8: evaluating uᵀKu cancels terms of size κ_h|u|² ≫ E, so the round-off of E
    # itself grows like κ_h ~ J⁴ (≈ 5e-9·E at J = 19 near the β = 0.1 limit)
    system = free_system(J=8)
    dt = 0.5 * linear_limit(kappa_h(system), beta) if beta < 0.25 else 1e-4
    r = solve(system, dt, 2000 * dt, beta)
    E = r.energy
    assert np.abs(E - E[0]).max() <= 1e-10 * E[0]   # 2000 steps of round-off


@pytest.mark.parametrize("beta", [0.5, 0.25])
def test_energy_never_increases_with_contact(beta):
    """f = 0, stops at the tip: E_β^{n+1} ≤ E_β^n at every step, and it does drop."""
    system = free_system(Obstacles.point_stops(L, -0.013, 0.013), J=19)
    r = solve(system, 1e-4, 0.5, beta)
    dE = np.diff(r.energy)
    assert r.impacts > 3
    assert dE.max() <= 1e-10 * r.energy[0]   # round-off of evaluating E at J = 19
    assert r.energy[-1] < 0.9 * r.energy[0]


def test_stops_hold_to_round_off(pipe):
    r = solve(beam_system(pipe), 5e-5, 0.5, 0.5)
    tip = r.observed["tip_displacement"]
    assert r.impacts >= 10
    assert np.abs(tip).max() <= 0.1 * (1 + 1e-15)
    assert r.max_nodal_violation <= 1e-15
    assert (np.abs(r.contact_force).max()) > 0


def test_unstable_run_is_detected_and_truncated(pipe):
    system = beam_system(pipe)
    limit = linear_limit(kappa_h(system), 0.1)
    r = solve(system, 1.2 * limit, 0.1, 0.1)
    assert r.status == "unstable" and "linear stability limit" in r.message
    assert np.isfinite(r.energy).all() and r.energy.max() < 100 * r.energy[0]
    ok = solve(system, 0.9 * limit, 0.1, 0.1)
    assert ok.status == "success"


def test_a_name_not_in_a_result_s_table_says_which_are():
    r = solve(free_system(), 1e-3, 0.01)
    with pytest.raises(KeyError, match="'tip_velocity' is not in this run's table; it holds: "
                                       "tip_displacement"):
        r.observed["tip_velocity"]
    assert r.velocity["tip_displacement"].shape == r.t.shape and "contact" in r.work
