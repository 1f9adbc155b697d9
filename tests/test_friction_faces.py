"""Coulomb friction on a hole's flat faces at position level (contact.round_hole_friction,
a face's row and its tangent row): one face's exact local solve (on its bound, in the
cone, slip against the force, the stick/slip threshold), a tube in a square and a
hexagonal hole under a rotating force (cone, dissipation at every contact step, corners,
no penetration), the energy identity with the friction's work, μ = 0 as the frictionless
run bit for bit, the static threshold, a restored run, and Moreau–Jean refused."""
from dataclasses import replace

import numpy as np
import pytest

from conftest import assert_exact_with_friction, assert_refused, resumed
from skfem_beam import methods
from skfem_beam.contact.round_hole_friction import (FALLBACK, SEPARATE, SLIP_BACKWARD,
                                                    SLIP_FORWARD, STICK, RoundHoleFriction,
                                                    coulomb_face)
from skfem_beam.errors import InputError
from skfem_beam.holes import Hole, HoleAt
from skfem_beam.problem import Beam, BeamProblem, Damping, Load, Material, Plane, Section
from skfem_beam.scenefile import example, load, run_main
from skfem_beam.scheme import Run, Stepping, solve
from skfem_beam.scheme.beta import BetaScheme
from skfem_beam.scheme.moreau_jean import MoreauJeanScheme
from skfem_beam.semidiscrete import beam_system
from skfem_beam.timefunctions import Sine

TUBE = Beam.physical(1.5, Material(2e11, 8000.0), Section.tube(0.01905, 0.00165))
R = 4e-4
FRICTION_LAW = methods.PositionLevel("round-hole-friction")


def face(D, yj, yt, qt, lo, hi, f):
    """coulomb_face's case, (μ_j, μ_T), the block's values after the step, and the
    outward (λ_n, λ_t, s) of the bound it touches (module docstring's signs)."""
    out = np.empty(2)
    case = coulomb_face((D[0, 0], D[0, 1], D[1, 1]), yj, yt, qt, lo, hi, f, out)
    y = np.array([yj, yt]) + D @ out
    sg = 1.0 if yj > hi else -1.0
    return case, out, y, -sg * out[0], sg * out[1], sg * (y[1] - qt)


def test_one_face_is_exact_on_its_bound_in_the_cone_and_slips_against_the_force():
    rng = np.random.default_rng(11)
    g, cases = 1e-3, {STICK: 0, SLIP_FORWARD: 0, SLIP_BACKWARD: 0}
    for _ in range(3000):
        A = rng.normal(size=(2, 2))
        D = A @ A.T + 0.3 * np.eye(2)
        f = rng.uniform(0.05, 0.8)
        lo, hi = -g * rng.uniform(0.5, 1.5), g * rng.uniform(0.5, 1.5)
        side = rng.choice([-1.0, 1.0])
        yj = (hi if side > 0 else lo) + side * g * rng.uniform(1e-3, 1.0)
        yt, qt = rng.normal(size=2) * g
        case, mu, y, ln, lt, s = face(D, yj, yt, qt, lo, hi, f)
        assert case != FALLBACK
        cases[case] += 1
        bound = hi if side > 0 else lo
        assert abs(y[0] - bound) <= 1e-14 * g                # on the face: contact, exact
        assert ln > 0 and abs(lt) <= f * ln * (1 + 1e-14)     # the cone
        if case == STICK:
            assert abs(s) <= 1e-14 * g
        else:   # slip: the friction at the cone's edge, against the slip
            assert lt * s == pytest.approx(-f * ln * abs(s), rel=1e-14)
            assert (s > 0) == (case == SLIP_FORWARD)
    assert min(cases.values()) > 300, cases
    assert face(np.eye(2), 0.5e-3, 0.0, 1e-4, -1e-3, 1e-3, 0.3)[0] == SEPARATE


@pytest.mark.parametrize("side", [1.0, -1.0])
@pytest.mark.parametrize("push", [1.0, -1.0])
def test_a_push_just_inside_the_cone_sticks_and_just_outside_slips(side, push):
    """z made from a stick point (on the face, y_T = y_T^{n−1}) and a force whose
    tangential part is (1 ∓ 1e-6)μλ_n: inside, the solve returns that force and point;
    outside, it slips at the cone's edge, by a slip of the order of the excess, the way
    the excess pushes."""
    rng = np.random.default_rng(5)
    g, f, ln = 1e-3, 0.3, 2e-4
    for _ in range(50):
        A = rng.normal(size=(2, 2))
        D = 0.3 * A @ A.T + np.eye(2)
        lo, hi = -g, g
        qt = rng.normal() * g
        stick = np.array([hi if side > 0 else lo, qt])
        for excess, expect in ((1 - 1e-6, STICK), (1 + 1e-6, None)):
            lam = np.array([-side * ln, side * push * excess * f * ln])   # (μ_j, μ_T)
            z = stick - D @ lam
            case, mu, y, ln_got, lt_got, s = face(D, z[0], z[1], qt, lo, hi, f)
            if expect == STICK:
                assert case == STICK and np.allclose(mu, lam, rtol=0, atol=1e-12 * ln)
                assert np.allclose(y, stick, rtol=0, atol=1e-14 * g)
            else:   # λ_t along +push: the slip goes the other way, s of sign −push
                assert case == (SLIP_BACKWARD if push > 0 else SLIP_FORWARD)
                assert abs(lt_got) == pytest.approx(f * ln_got, rel=1e-14)
                assert 0 < abs(s) <= 1e-5 * g


def whirl(mu, sides=4, damping=Damping()):
    """The rotating force of test_friction_beta's whirl (J = 10) with a regular polygon
    of ``sides`` (inscribed radius R) at x = 0.75 and Coulomb's μ on its faces."""
    return BeamProblem(TUBE, J=10, ends=("pinned", "pinned"), planes=2, damping=damping,
                       holes=(HoleAt(Hole.regular(sides, R), 0.75, friction=mu),),
                       load=Load.distributed(20.0, Sine(1.0, 2 * np.pi * 15, np.pi / 2)),
                       second=Plane(load=Load.distributed(20.0, Sine(1.0, 2 * np.pi * 15))))


@pytest.mark.parametrize("sides", [4, 6])
def test_a_rough_polygon_under_a_rotating_force_at_every_contact_step(sides):
    """Every step of 0.3 s (μ = 0.3): each face in contact has |λ_t| ≤ μλ_n, a slipping
    one λ_t s = −μλ_n|s| (its friction work ≤ 0), a sticking one s = 0 to round-off; no
    node beyond a face; corners (two faces of the node at once) occur and converge.
    Measured: square 226 stick, 969 slip, 44 corner steps, ≤ 27 sweeps; hexagon 172,
    1363, 35, ≤ 40; cone and dissipation exact (0.0), stick slip ≤ 1.5e-15 R."""
    mu = 0.3
    system = beam_system(whirl(mu, sides))
    tangents = system.tangents
    assert tangents.shape == (sides // 2, 2) and system.C.shape[0] == sides
    run = Run(BetaScheme(system, Stepping(1e-4, 0.3), RoundHoleFriction()))
    stick = slip = corners = 0
    worst = {"cone": 0.0, "dissipation": 0.0, "stick": 0.0, "penetration": -np.inf}
    for n in range(2, run.n_steps + 1):
        run.advance(n)
        st = run.st
        active = 0
        for j, t in tangents:
            mj, mt, s = st.mu[j], st.mu[t], st.dy[t]
            worst["penetration"] = max(worst["penetration"], st.y_cur[j] - st.hi[j],
                                       st.lo[j] - st.y_cur[j])
            if mj == 0.0:
                assert mt == 0.0
                continue
            active += 1
            worst["cone"] = max(worst["cone"], abs(mt) - mu * abs(mj) * (1 + 1e-15))
            if abs(s) > 1e-12 * R:
                slip += 1
                edge = mu * abs(mj) * abs(s)           # λ_t s = −μλ_n|s| (μ_t s the same)
                worst["dissipation"] = max(worst["dissipation"], abs(mt * s + edge) / edge)
            else:
                stick += 1
                worst["stick"] = max(worst["stick"], abs(s) / R)
        corners += active > 1
    assert stick > 100 and slip > 500 and corners > 10, (stick, slip, corners)
    assert worst["cone"] <= 0.0
    assert worst["dissipation"] <= 1e-14
    assert worst["stick"] <= 1e-14
    assert worst["penetration"] <= 1e-12 * R
    result = run.result()
    assert result.max_nodal_violation <= 1e-12 * R
    w = result.work["friction"]
    assert w[-1] < 0 and np.diff(w).max() <= 1e-15 * abs(w[-1])


def test_mu_zero_on_faces_is_the_frictionless_run_bit_for_bit():
    system = beam_system(whirl(0.0, 6))
    assert system.tangents.size == 0 and system.friction is None
    zero = solve(system, 1e-4, 0.1, method=FRICTION_LAW, frames=50)
    plain = solve(system, 1e-4, 0.1, method=methods.PositionLevel("round-hole"), frames=50)
    assert zero.solver == "round-hole-friction" and zero.impacts > 5
    assert "friction" not in zero.work
    for name in ("energy", "contact_force", "frames_u", "frames_v", "frames_force"):
        assert np.array_equal(getattr(zero, name), getattr(plain, name))
    assert np.array_equal(zero.work["contact"], plain.work["contact"])
    auto = solve(system, 1e-4, 0.1, method=methods.PositionLevel(), frames=50)
    assert auto.solver == "active-set"        # auto on frictionless faces: as before
    rough = solve(beam_system(whirl(0.3, 6)), 1e-4, 0.1, method=methods.PositionLevel())
    assert rough.solver == "round-hole-friction"   # auto with μ > 0 on faces


@pytest.mark.parametrize("shapes", ["hexagons", "round and bars"])
def test_the_friction_scene_with_faces_closes_its_energy_identity(shapes):
    """The shipped friction scene (random loads, two baffles, J = 30) with its round holes
    made hexagons (inscribed radius 0.4 mm), or its second one flat bars w = ±R beside the
    first's round hole, all rough (μ = 0.3): auto runs the position-level law, no node
    beyond a wall, the energy identity with the friction's work to round-off (measured:
    6.4e-13 relative, hexagons over 0.2 s; 1.3e-12, round and bars over 0.3 s), friction
    that dissipates at every step."""
    scene = load(example("tube_round_holes_friction"))
    first, second = scene.problem.holes
    bars = Hole.faces([[0.0, 1.0, R], [0.0, -1.0, R]])
    holes = tuple(replace(h, hole=Hole.regular(6, R)) for h in (first, second)) \
        if shapes == "hexagons" else (first, replace(second, hole=bars))
    problem = replace(scene.problem, holes=holes)
    r = solve(beam_system(problem), scene.stepping.dt, 0.2, method=methods.PositionLevel())
    assert_exact_with_friction(r, R)


def test_the_tube_sticks_on_a_face_until_the_pull_reaches_mu_times_the_normal_force():
    """test_friction_beta's static threshold on the face of a square hole: P = 60 N
    presses the node at x = 0.75 on the face v = R, a pull along w grows from
    (1 − 1e-4) T* (T* = μ(P − ρS·R/f), f = e·K⁻¹e the node's flexibility) at 0.01 N/s;
    the node sticks until the pull reaches T* (measured: it slips at T*(1 + 3.3e-8);
    α = 1000/s settles the normal force's ringing)."""
    mu, P, t0, a, dt, start = 0.3, 60.0, 1.0, 0.01, 1e-4, 1 - 1e-4

    class Pull:
        def __call__(self, t):
            t = np.asarray(t, dtype=float)
            return np.where(t < t0, 0.0, start * T_star + a * (t - t0))

    system = beam_system(BeamProblem(TUBE, J=10, ends=("pinned", "pinned"), planes=2,
                                     damping=Damping(alpha=1000.0),
                                     holes=(HoleAt(Hole.regular(4, R), 0.75, friction=mu),),
                                     load=Load.point(0.75, P),
                                     second=Plane(load=Load(points=((0.75, Pull()),)))))
    n = system.meta["n_plane"]
    e = system.C[0, :n].toarray().ravel()
    T_star = mu * (P - TUBE.rho_S * R / (e @ np.linalg.solve(system.K[:n, :n].toarray(), e)))
    run = Run(BetaScheme(system, Stepping(dt, t0 + 2 * (1 - start) * T_star / a),
                         RoundHoleFriction()))
    run.advance(int(t0 / dt) - 1)
    j, t = system.tangents[0]
    assert run.st.mu[j] < 0 and run.st.mu[t] == 0.0     # pressed on v = R, no pull yet
    for step in range(int(t0 / dt), run.n_steps + 1):
        run.advance(step)
        if abs(run.st.mu[t]) >= mu * abs(run.st.mu[j]) * (1 - 1e-12):     # the first slip
            T = float(Pull()(step * dt))
            break
    else:
        pytest.fail("the tube never slipped")
    assert abs(T / T_star - 1) <= 1e-6


def test_a_restored_face_friction_run_goes_on_bit_for_bit():
    system = beam_system(whirl(0.3, 6))
    a, c = resumed(lambda: Run(BetaScheme(system, Stepping(1e-4, 0.1),
                                          RoundHoleFriction())), 444)
    assert np.array_equal(a.result().work["friction"][445:], c.result().work["friction"][445:])


def test_friction_on_faces_with_moreau_jean_is_refused_in_one_line(tmp_path, capsys):
    with pytest.raises(InputError, match="round-hole-friction"):
        MoreauJeanScheme(beam_system(whirl(0.3, 4)), Stepping(1e-4, 0.01))
    text = example("tube_round_holes_friction").read_text().replace(
        "hole = { radius = 0.0004 }", "hole = { sides = 6, radius = 0.0004 }")
    scene = tmp_path / "hex.toml"
    scene.write_text(text.replace("[contact]\n", "[contact]\nlaw = \"moreau-jean\"\n"))
    bad = tmp_path / "bad"
    bad.mkdir()
    assert_refused(run_main, [str(scene), "--out", str(bad / "run")],
                   "round-hole-friction", capsys, bad)
    scene.write_text(text)          # without a law: the position-level law, not Moreau–Jean
    assert load(scene).law == "auto"
