"""The scheme's energy identity with damping and loads, bounds that move with a support,
and the impact events the loop records."""
from dataclasses import replace

import numpy as np
import pytest

from skfem_beam import beam_system, scenes, solve
from skfem_beam.bar import Bar, bar_system
from skfem_beam.methods import Penalty
from skfem_beam.scheme import Run, Stepping
from skfem_beam.scheme.kernels import EVENT_COLUMNS
from skfem_beam.scheme.solve import drive


def closure(r):
    """energy − energy[0] + damping work − input work − contact work (0 by the identity)."""
    w = r.work
    return r.energy - r.energy[0] + w["damping"] - w["input"] - w["contact"]


@pytest.mark.parametrize("make, dt, T, kw", [
    (lambda: beam_system(scenes.point_stops()), 5e-5, 0.5, {}),              # support load
    (lambda: beam_system(scenes.flat_obstacles()), 1e-3, 1.0, {}),           # f = sin 10t
    (lambda: bar_system(Bar(b=0.02, f=-1.0)), 1e-3, 3.0, {"beta": 0.25}),    # Kelvin–Voigt
    (lambda: bar_system(Bar(obstacle="elastic")), 1e-3, 3.0,
     {"beta": 0.25, "method": Penalty(100.0, equation_units=True)}),         # spring
])
def test_energy_identity_closes_to_round_off(make, dt, T, kw):
    r = solve(make(), dt, T, **kw)
    scale = max(np.abs(r.energy).max(), np.abs(r.work["input"]).max())
    assert np.abs(closure(r)).max() <= 2e-11 * scale
    assert r.work["contact"][-1] <= 1e-12 * scale or "method" in kw  # impacts lose energy


def test_damping_work_is_what_the_energy_loses():
    """The energy-decay beam with stiffness-proportional damping B = 1e-2 K, before its
    first impact and with no load: the energy it loses is the damping work."""
    system = beam_system(scenes.energy_decay())
    r = solve(replace(system, B=1e-2 * system.K), 1e-3, 0.05)
    assert r.impacts == 0 and r.work["input"][-1] == 0.0
    assert r.work["damping"][-1] > 1e-3 * r.energy[0]
    assert r.energy[0] - r.energy[-1] == pytest.approx(r.work["damping"][-1], rel=1e-10)


def test_bounds_that_move_hold_exactly_at_every_step():
    """The pipe's tip stops shaken as 0.02 sin 30t (in the lifted variable): the tip sits on
    the moving bound to round-off whenever it is in contact, never beyond it."""
    system = beam_system(scenes.point_stops())
    phi = lambda t: 0.02 * np.sin(30 * np.asarray(t))  # noqa: E731
    moving = replace(system, bound_motion=phi, bound_shift=np.ones(1),
                     sample_shift=np.ones(system.sample_lo.size))
    r = solve(moving, 5e-5, 0.6)
    tip, t = r.observed["tip_displacement"], r.t
    lo, hi = -0.1 + phi(t), 0.1 + phi(t)
    assert r.impacts > 3
    assert (tip >= lo[...] - 1e-15).all() and (tip <= hi + 1e-15).all()
    on = r.contact_force[:, 0] != 0
    assert np.abs(np.where(r.contact_force[on, 0] > 0, tip[on] - lo[on], hi[on] - tip[on])).max() \
        <= 1e-15
    still = solve(replace(system, bound_motion=lambda t: 0 * np.asarray(t),
                          bound_shift=np.ones(1), sample_shift=np.ones(system.sample_lo.size)),
                  5e-5, 0.2)
    assert np.array_equal(still.observed["tip_displacement"],
                          solve(system, 5e-5, 0.2).observed["tip_displacement"])


def test_impact_events_add_up_and_survive_a_full_buffer():
    system = beam_system(scenes.flat_obstacles())
    r = solve(system, 1e-3, 1.0)
    ev = r.impact_events
    assert len(ev["t_start"]) == r.impacts > 50
    assert (np.diff(ev["t_start"]) >= 0).all() and (ev["t_end"] >= ev["t_start"]).all()
    # the impulses are the saved contact forces summed over each contact
    assert ev["impulse"].sum() == pytest.approx(r.contact_force.sum() * r.dt, rel=1e-12)
    assert (ev["max_violation"] <= 1e-12).all()
    assert set(ev["x"]) <= set(system.x_contact) and (ev["x"] >= 5.0).all()
    # a loop whose event buffer fills every few impacts gives the same table
    run = Run(system, Stepping(1e-3, 1.0), "auto")
    run.out = run.out._replace(events=np.zeros((run.st.active.size + 3, len(EVENT_COLUMNS))))
    drive(run)
    small = run.impact_events()
    for k in ev:
        assert np.array_equal(ev[k], small[k], equal_nan=True), k
