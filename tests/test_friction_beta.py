"""Coulomb friction in the β-scheme at position level (contact.round_hole_friction): one
contact's exact local solve (circle, cone, slip against the force, the stick/slip
threshold), μ = 0 as the frictionless round-hole run bit for bit, the shipped friction
scene (no penetration, the energy identity with friction work, dissipation at every
step), the whirl on a rough wall and the static stick/slip threshold."""
import numpy as np
import pytest

from conftest import assert_exact_with_friction, resumed
from skfem_beam import methods
from skfem_beam.contact.round_hole_friction import (SEPARATE, SLIP_BACKWARD, SLIP_FORWARD,
                                                    STICK, RoundHoleFriction, coulomb_disk)
from skfem_beam.holes import Hole, HoleAt
from skfem_beam.problem import Beam, BeamProblem, Damping, Load, Material, Plane, Section
from skfem_beam.scenefile import example, load
from skfem_beam.scheme import Run, Stepping, solve
from skfem_beam.scheme.beta import BetaScheme
from skfem_beam.semidiscrete import beam_system
from skfem_beam.timefunctions import Sine

TUBE = Beam.physical(1.5, Material(2e11, 8000.0), Section.tube(0.01905, 0.00165))
R = 4e-4
FRICTION_LAW = methods.PositionLevel("round-hole-friction")


def local(D, z, q, r, f):
    out = np.empty(4)
    case = coulomb_disk((D[0, 0], D[0, 1], D[1, 1]), (z[0], z[1]), (q[0], q[1]), r, f, out)
    mu = out[:2].copy()
    p = z + D @ mu                       # the block's value after the step, as the law's
    n = p / np.linalg.norm(p)
    t = np.array([-n[1], n[0]])
    return case, mu, p, -n @ mu, t @ mu, t @ (p - q)


def test_one_contact_is_exact_on_the_circle_in_the_cone_and_slips_against_the_force():
    rng = np.random.default_rng(7)
    r, cases = 1e-3, {STICK: 0, SLIP_FORWARD: 0, SLIP_BACKWARD: 0}
    for _ in range(3000):
        A = rng.normal(size=(2, 2))
        D = A @ A.T + 0.3 * np.eye(2)
        f = rng.uniform(0.05, 0.8)
        z = rng.normal(size=2)
        z *= r * rng.uniform(1.001, 2.0) / np.linalg.norm(z)
        q = rng.normal(size=2) * r * rng.uniform(0.3, 1.0)
        case, mu, p, ln, lt, s = local(D, z, q, r, f)
        cases[case] += 1
        assert np.linalg.norm(p) - r <= 1e-14 * r          # no penetration
        assert abs(np.linalg.norm(p) - r) <= 1e-13 * r     # on the wall: contact
        assert ln > 0 and abs(lt) <= f * ln * (1 + 1e-12)  # the cone
        if case == STICK:
            assert abs(s) <= 1e-13 * r
        else:   # slip: the friction at the cone's edge, against the slip
            assert lt * s == pytest.approx(-f * ln * abs(s), rel=1e-12)
            assert (s > 0) == (case == SLIP_FORWARD)
    assert min(cases.values()) > 100, cases
    # free point inside: no force
    assert local(np.eye(2), np.array([0.5e-3, 0.0]), np.array([0.9e-3, 0.0]), r, 0.3)[0] \
        == SEPARATE


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_a_force_just_inside_the_cone_sticks_and_just_outside_slips(side):
    """z made from a stick point p_s and a force whose tangential part is (1 ∓ 1e-6)μλ_n:
    inside, the solve returns that force and p_s; outside, it slips at the cone's edge,
    by a slip of the order of the excess, in the direction the excess pushes."""
    rng = np.random.default_rng(3)
    r, f, ln = 1e-3, 0.3, 2e-4
    for _ in range(50):
        A = rng.normal(size=(2, 2))
        D = 0.3 * A @ A.T + np.eye(2)
        angle = rng.uniform(0, 2 * np.pi)
        n = np.array([np.cos(angle), np.sin(angle)])
        t = np.array([-n[1], n[0]])
        q, p_s = 0.8 * r * n, r * n
        for excess, expect in ((1 - 1e-6, STICK), (1 + 1e-6, None)):
            mu = -ln * n + side * excess * f * ln * t
            z = p_s - D @ mu
            case, mu_got, p, ln_got, lt_got, s = local(D, z, q, r, f)
            if expect == STICK:
                assert case == STICK and np.allclose(mu_got, mu, rtol=0, atol=1e-12 * ln)
                assert np.allclose(p, p_s, rtol=0, atol=1e-14 * r)
            else:   # the force pushed along side·t: the node slips that way, −side·s > 0?
                assert case == (SLIP_BACKWARD if side > 0 else SLIP_FORWARD)
                assert abs(lt_got) == pytest.approx(f * ln_got, rel=1e-12)
                assert 0 < abs(s) <= 1e-5 * r


def whirl(mu, damping=Damping()):
    """The rotating force of tests/test_two_planes.py's whirl (J = 10, one hole at
    mid-span) with Coulomb's μ at the hole."""
    return BeamProblem(TUBE, J=10, ends=("pinned", "pinned"), planes=2, damping=damping,
                       holes=(HoleAt(Hole.round(R), 0.75, friction=mu),),
                       load=Load.distributed(20.0, Sine(1.0, 2 * np.pi * 15, np.pi / 2)),
                       second=Plane(load=Load.distributed(20.0, Sine(1.0, 2 * np.pi * 15))))


def test_mu_zero_is_the_frictionless_round_hole_run_bit_for_bit():
    system = beam_system(whirl(0.0))
    zero = solve(system, 1e-4, 0.1, method=FRICTION_LAW, frames=50)
    plain = solve(system, 1e-4, 0.1, method=methods.PositionLevel("round-hole"), frames=50)
    assert zero.solver == "round-hole-friction" and zero.contact_fraction > 0.5
    assert "friction" not in zero.work
    for name in ("energy", "contact_force", "frames_u", "frames_v", "frames_force"):
        assert np.array_equal(getattr(zero, name), getattr(plain, name))
    assert np.array_equal(zero.work["contact"], plain.work["contact"])


def test_the_shipped_friction_scene_at_position_level():
    """No penetration at the nodes, the energy identity with the friction's work, and
    friction that dissipates at every step (½λ_t s ≤ 0 with s the step's slip)."""
    scene = load(example("tube_round_holes_friction"))
    r = solve(beam_system(scene.problem), scene.stepping.dt, 0.2, method=methods.PositionLevel())
    assert_exact_with_friction(r, R)


def test_a_rough_round_hole_is_never_penetrated_under_a_rotating_force():
    """On a rough wall (μ = 0.3) the whirl chatters (0.46 of the steps in contact, 191
    impacts in 0.5 s; Moreau–Jean: 0.35, 391, measured) where the smooth one rolls
    round (0.94): still no penetration at the node, and friction dissipates."""
    rough = solve(beam_system(whirl(0.3)), 1e-4, 0.5, method=methods.PositionLevel())
    assert rough.solver == "round-hole-friction" and rough.contact_fraction > 0.3
    assert rough.impacts > 50
    assert rough.max_nodal_violation <= 1e-12 * R
    p = np.column_stack([rough.observed["hole_0.75_displacement_v"],
                         rough.observed["hole_0.75_displacement_w"]])
    assert (np.hypot(p[:, 0], p[:, 1]) - R).max() <= 1e-12 * R
    w = rough.work["friction"]
    assert w[-1] < 0 and np.diff(w).max() <= 1e-15 * abs(w[-1])


def test_the_tube_sticks_until_the_pull_reaches_mu_times_the_static_normal_force():
    """tests/test_friction.py's static threshold at position level: P = 60 N presses the
    node at x = 0.75 on its wall along +v, a pull along w grows from 0.999 T* (T* = μN of
    the discrete static analysis); the node sticks (|λ_t| < μλ_n) until the pull reaches
    T* to within the settling's vibration (β = ½ damps none of it: 2.3e-6, measured)."""
    mu, P, t0, a, dt = 0.3, 60.0, 1.0, 0.01, 1e-4

    class Pull:
        def __call__(self, t):
            t = np.asarray(t, dtype=float)
            return np.where(t < t0, 0.0, 0.999 * T_star + a * (t - t0))

    system = beam_system(BeamProblem(TUBE, J=10, ends=("pinned", "pinned"), planes=2,
                                     damping=Damping(alpha=100.0),
                                     holes=(HoleAt(Hole.round(R), 0.75, friction=mu),),
                                     load=Load.point(0.75, P),
                                     second=Plane(load=Load(points=((0.75, Pull()),)))))
    n = system.meta["n_plane"]
    e = system.C[0, :n].toarray().ravel()
    T_star = mu * (P - TUBE.rho_S * R / (e @ np.linalg.solve(system.K[:n, :n].toarray(), e)))
    run = Run(BetaScheme(system, Stepping(dt, t0 + 0.002 * T_star / a), RoundHoleFriction()))
    run.advance(int(t0 / dt))

    def cone_ratio():
        y, m, c = run.st.y_cur, run.st.mu, 0.5 * (run.st.lo + run.st.hi)
        nv = np.array([y[0] - c[0], y[1] - c[1]]) / R
        return abs(-nv[1] * m[0] + nv[0] * m[1]) / (mu * -(nv[0] * m[0] + nv[1] * m[1]))

    for step in range(int(t0 / dt) + 1, run.n_steps + 1):
        run.advance(step)
        if cone_ratio() >= 1 - 1e-12:        # the first slip
            T = float(Pull()(step * dt))
            break
    else:
        pytest.fail("the tube never slipped")
    assert abs(T / T_star - 1) <= 1e-5


def test_a_restored_position_level_friction_run_goes_on_bit_for_bit():
    system = beam_system(whirl(0.3))
    a, c = resumed(lambda: Run(BetaScheme(system, Stepping(1e-4, 0.1), RoundHoleFriction())), 555)
    assert np.array_equal(a.st.rowwork, c.st.rowwork)
    assert np.array_equal(a.result().work["friction"][556:], c.result().work["friction"][556:])
