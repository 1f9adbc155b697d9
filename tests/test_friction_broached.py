"""Coulomb friction in broached holes at position level (contact.round_hole_friction's
coulomb_lands: the arc as a round hole's contact, a lobe's line as a face, a lobe's corner
as two faces): one contact's exact local solve, full lands as the round hole with
friction, μ = 0 as the frictionless broached run, no node out of K, the cone and the
dissipation at every step, and the energy identity with the friction's work."""
import json
import math
from dataclasses import replace

import numpy as np
import pytest

from conftest import assert_exact_with_friction, exit_code, random_broached
from skfem_beam import methods
from skfem_beam.contact.lands import land_split
from skfem_beam.contact.round_hole_friction import (CORNER, FALLBACK, FRICTIONLESS, SEPARATE,
                                                    RoundHoleFriction, coulomb_lands)
from skfem_beam.holes import Hole, HoleAt, land_excess
from skfem_beam.problem import Beam, BeamProblem, Damping, Load, Material, Plane, Section
from skfem_beam.scenefile import example, load, run_main
from skfem_beam.scheme import Run, Stepping, solve
from skfem_beam.scheme.beta import BetaScheme
from skfem_beam.semidiscrete import beam_system
from skfem_beam.timefunctions import Sine

TUBE = Beam.physical(1.5, Material(2e11, 8000.0), Section.tube(0.01905, 0.00165))
R = 4e-4
FRICTION_LAW = methods.PositionLevel("round-hole-friction")
TREFOIL = Hole.broached(3, math.radians(40), R)


def whirl(mu, hole):
    """test_friction_faces' rotating force (J = 10) with ``hole`` at x = 0.75, μ at its
    wall."""
    return BeamProblem(TUBE, J=10, ends=("pinned", "pinned"), planes=2, damping=Damping(),
                       holes=(HoleAt(hole, 0.75, friction=mu),),
                       load=Load.distributed(20.0, Sine(1.0, 2 * np.pi * 15, np.pi / 2)),
                       second=Plane(load=Load.distributed(20.0, Sine(1.0, 2 * np.pi * 15))))


def orbit(result, x=0.75):
    return np.column_stack([result.observed[f"hole_{x:g}_displacement_v"],
                            result.observed[f"hole_{x:g}_displacement_w"]])


def excess(hole, p):
    return np.array([land_excess(a, b, hole.radius, *hole.land_row()) for a, b in p])


def contacts(mu2, p, slip, f, hole):
    """land_split's contacts as rows (λ_n, λ_t, s)."""
    out = land_split(mu2, p, slip, hole.radius, f, hole.land_row())
    return np.array(out[1:]).reshape(2, 3)[:out[0]]


# ---------------------------------------------------------------- one contact
def test_one_contact_is_in_k_on_its_wall_in_the_cone_and_slips_against_the_force():
    """Random SPD blocks, lands, z beyond K: the point lies on ∂K (to 1e-13 r), each of its
    contacts in the Coulomb cone, a slipping one at the cone's edge against its slip;
    arcs, lines and corners all occur and no case falls back."""
    rng = np.random.default_rng(3)
    out = np.empty(4)
    seen = {"arc": 0, "line": 0, "corner": 0, "stick": 0}
    for _ in range(3000):
        hole, D = random_broached(rng, (0.05, 0.9), 0.3)
        f = rng.uniform(0.05, 0.5)
        z, q = rng.normal(size=2) * 2.0, rng.normal(size=2) * 0.5
        case = coulomb_lands((D[0, 0], D[0, 1], D[1, 1]), z, q, 1.0, f, hole.land_row(), out)
        if excess(hole, [z])[0] <= 0:
            assert case == SEPARATE and not out[:2].any()
            continue
        assert case != FALLBACK
        mu = out[:2].copy()
        p = z + D @ mu
        assert abs(excess(hole, [p])[0]) <= 1e-13
        rows = contacts(mu, p, p - q, f, hole)
        kind = "corner" if case == CORNER else \
            "arc" if abs(np.hypot(*p) - 1.0) <= 1e-12 else "line"
        seen[kind] += 1
        assert len(rows) == (2 if kind == "corner" else 1)
        for ln, lt, s in rows:
            assert ln >= 0 and abs(lt) <= f * ln * (1 + 1e-12)
            if abs(s) > 1e-12:
                assert lt * s == pytest.approx(-f * ln * abs(s), rel=1e-10)
            else:
                seen["stick"] += 1
    assert min(seen.values()) > 20, seen


# ---------------------------------------------------------------- its limits
def test_full_lands_with_friction_are_the_round_hole_before_the_second_impact():
    """Lands 360/n wide are the drilled circle: the rough run (μ = 0.3) is the round hole's
    to round-off until the second impact (measured: 0.0 over the 73 states before it)."""
    round_ = solve(beam_system(whirl(0.3, Hole.round(R))), 1e-4, 0.1)
    full = solve(beam_system(whirl(0.3, Hole.broached(3, 2 * math.pi / 3, R))), 1e-4, 0.1)
    assert full.solver == round_.solver == "round-hole-friction"
    times = np.unique(round_.impact_events["t_start"])
    k = int(np.searchsorted(round_.t, times[1]))
    assert k > 10
    assert np.abs(orbit(full)[:k] - orbit(round_)[:k]).max() <= 1e-12 * R
    assert round_.work["friction"][k] < 0


def test_mu_zero_is_the_frictionless_broached_run_bit_for_bit():
    system = beam_system(whirl(0.0, TREFOIL))
    assert system.friction is None
    zero = solve(system, 1e-4, 0.1, method=FRICTION_LAW, frames=50)
    plain = solve(system, 1e-4, 0.1, method=methods.PositionLevel("round-hole"), frames=50)
    assert zero.solver == "round-hole-friction" and zero.impacts > 5
    for name in ("energy", "contact_force", "frames_u", "frames_v", "frames_force"):
        assert np.array_equal(getattr(zero, name), getattr(plain, name))
    assert np.array_equal(zero.work["contact"], plain.work["contact"])
    rough = solve(beam_system(whirl(0.3, TREFOIL)), 1e-4, 0.02, method=methods.PositionLevel())
    assert rough.solver == "round-hole-friction"   # auto with μ > 0 in a broached hole


# ---------------------------------------------------------------- runs
@pytest.mark.parametrize("hole", [TREFOIL, Hole.broached(4, math.radians(30), R, 0.3)])
def test_a_rough_broached_hole_under_a_rotating_force_at_every_step(hole):
    """Every step of 0.3 s (μ = 0.3): each contact (land_split: an arc's, a line's, a
    corner's two) has |λ_t| ≤ μλ_n, a slipping one λ_t s = −μλ_n|s| (friction work ≤ 0);
    no node beyond K; the friction's work never grows.  Measured: trefoil 303 arc, 1270
    line, 49 corner steps (220 sticking contacts), 4 lands 355, 1110, 17 (176); slip at
    the cone's edge to 4.5e-15, excess ≤ 1.2e-15 R."""
    mu = 0.3
    system = beam_system(whirl(mu, hole))
    run = Run(BetaScheme(system, Stepping(1e-4, 0.3), RoundHoleFriction()))
    count = {"arc": 0, "line": 0, "corner": 0, "stick": 0}
    worst = {"cone": -np.inf, "dissipation": 0.0, "excess": -np.inf}
    for n in range(2, run.n_steps + 1):
        run.advance(n)
        st = run.st
        p = st.y_cur[:2] - 0.5 * (st.lo[:2] + st.hi[:2])
        worst["excess"] = max(worst["excess"], excess(hole, [p])[0])
        if not st.mu[:2].any():
            continue
        rows = contacts(st.mu[:2], p, st.dy[:2], mu, hole)
        count["corner" if len(rows) == 2 else
              "arc" if abs(np.hypot(*p) - R) <= 1e-12 * R else "line"] += 1
        for ln, lt, s in rows:
            worst["cone"] = max(worst["cone"], abs(lt) - mu * ln * (1 + 1e-9))
            if abs(s) > 1e-12 * R:
                edge = mu * ln * abs(s)
                worst["dissipation"] = max(worst["dissipation"], (lt * s + edge) / edge)
            else:
                count["stick"] += 1
    assert count["arc"] > 200 and count["line"] > 800 and count["corner"] > 10, count
    assert worst["cone"] <= 0.0
    assert worst["dissipation"] <= 1e-9
    assert worst["excess"] <= 1e-12 * R
    result = run.result()
    assert result.max_nodal_violation <= 1e-12 * R
    assert excess(hole, orbit(result)).max() <= 1e-12 * R
    w = result.work["friction"]
    assert w[-1] < 0 and np.diff(w).max() <= 1e-15 * abs(w[-1])


def test_the_friction_scene_in_broached_holes_closes_its_energy_identity():
    """The shipped friction scene (random loads, two baffles, J = 30) with trefoil holes
    (μ = 0.3): auto runs the position-level law, no node beyond K, the energy identity
    with the friction's work to round-off, friction that dissipates at every step
    (measured over 0.2 s: 38 impacts, violation 6.8e-16 R, identity 9.0e-13 relative,
    friction work −0.0246 J, contact −0.0318 J)."""
    scene = load(example("tube_round_holes_friction"))
    problem = replace(scene.problem, holes=tuple(replace(h, hole=TREFOIL)
                                                 for h in scene.problem.holes))
    r = solve(beam_system(problem), scene.stepping.dt, 0.2, method=methods.PositionLevel())
    assert_exact_with_friction(r, R)
    for x in (0.5, 1.0):
        assert excess(TREFOIL, orbit(r, x)).max() <= 1e-12 * R
        assert np.hypot(*orbit(r, x).T).max() > 1.01 * R       # into a lobe


def test_a_broached_hole_wears_where_its_lands_are(tmp_path):
    """The wear per sector follows the wall's normal: in a trefoil hole (three 40° lands at
    0°, 120°, 240°) the tube bears on a land's arc or, from a lobe's corner, on a land's
    edge; the lobes have no metal.  Binned by the node's angle, 70 % of the volume fell in
    sectors wholly inside the lobes (the deepest one too)."""
    out = tmp_path / "tref"
    assert exit_code(run_main, [str(example("tube_trefoil_holes")), "--set", "time.T=0.2",
                                "--set", "wear.coefficient=1e-14", "--set",
                                "wear.service_years=40", "--set", "wear.land=0.019",
                                "--out", str(out), "--format", "none"]) == 0
    supports = json.loads((out / "summary.json").read_text())["impact_statistics"]["supports"]
    lands = [(np.radians(c - 20), np.radians(c + 20)) for c in (0, 120, -120)]
    for s in supports:
        sectors = s["wear"]["sectors"]
        on_land = [any(k["from_rad"] < b and k["to_rad"] > a for a, b in lands)
                   for k in sectors]
        assert all(k["volume"] == 0.0 for k, land in zip(sectors, on_land) if not land)
        assert sum(k["volume"] for k in sectors) == pytest.approx(s["wear"]["volume"],
                                                                  rel=1e-12)
        assert s["wear"]["volume"] > 0 and sum(on_land) == 6
