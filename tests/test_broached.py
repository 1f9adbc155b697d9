"""Broached holes (``lands``): the block's projection onto K, full lands as the round hole
and lands of (almost) no width as the n-gon before the second impact, no node out of K in
the shipped trefoil scene, the outline on ∂K, and the one-line refusals."""
import math
from dataclasses import replace

import numpy as np
import pytest

from conftest import assert_refused, compiled, exit_code, random_broached
from skfem_beam.contact.round_hole import land_cone_solve, land_project
from skfem_beam.errors import InputError
from skfem_beam.holes import Hole, hole_from_table, land_excess
from skfem_beam.scenefile import example, load, run_main
from skfem_beam.scheme import solve
from skfem_beam.semidiscrete import beam_system

R = 4e-4          # the shipped tube scenes' radial clearance (m)


def excess(hole, p):
    """How far p lies beyond the hole's K (≤ 0: inside), per point."""
    return np.array([land_excess(a, b, hole.radius, *hole.land_row()) for a, b in p])


def scene_with(name, hole):
    """The problem of the shipped scene ``name`` with ``hole`` at each of its baffles."""
    problem = load(example(name)).problem
    return replace(problem, holes=tuple(replace(h, hole=hole) for h in problem.holes))


def observed(result):
    return np.column_stack([result.observed[k] for k in sorted(result.observed)])


def before_second_impact(result):
    """Saved states before the second impact's time (both baffles are hit at once)."""
    times = np.unique(result.impact_events["t_start"])
    return int(np.searchsorted(result.t, times[1]))


def boundary_samples(hole, per=60):
    """Points along the outline and the straight pieces between them (in K: on ∂K in the
    lobes, chords of the arcs over the lands)."""
    o = hole.outline(4001)[:-1]
    return np.concatenate([o + t * (np.roll(o, -1, 0) - o) for t in np.linspace(0, 1, per)])


# ---------------------------------------------------------------- one block
def test_one_block_is_the_projection_onto_k_in_the_d_metric():
    """land_project against a dense sampling of ∂K: its point lies in K and no sample is
    closer in the metric D⁻¹ (random SPD D, lands, widths, angles)."""
    rng = np.random.default_rng(0)
    root, mu = np.empty(3), np.empty(2)
    pieces = set()
    for _ in range(120):
        hole, D = random_broached(rng, (0.01, 1.0), 0.1)
        z = rng.normal(size=2) * 2.5
        code = compiled(land_project)(D[0, 0], D[0, 1], D[1, 1], z[0], z[1], 1.0,
                                      *hole.land_row(), root, mu)
        if excess(hole, [z])[0] <= 0:
            assert code == 0 and not mu.any()
            continue
        p = z + D @ mu
        pieces.add(1 if code == 1 else 2 + (code - 2) % 3)
        assert abs(excess(hole, [p])[0]) <= 1e-13           # on ∂K
        q = boundary_samples(hole) - z
        cost = np.einsum("ij,jk,ik->i", q, np.linalg.inv(D), q)
        assert (p - z) @ np.linalg.solve(D, p - z) <= cost.min() * (1 + 1e-9)
    assert pieces == {1, 2, 3, 4}        # arcs, both kinds of line, corners: all taken


def test_several_blocks_satisfy_the_kkt_conditions_after_the_polish():
    """Two broached blocks coupled by D: y = y_f + Dμ on ∂K where μ ≠ 0, μ in the
    inward normal cone (μ = D⁻¹(p − z) of each block's projection: a fixed point)."""
    rng = np.random.default_rng(1)
    hole = Hole.broached(3, math.radians(40), 1.0)
    kind = np.array([1, -1, 3, -1])
    lands = np.zeros((4, 3))
    lands[[0, 2]] = hole.land_row()
    lo, hi = -np.ones(4), np.ones(4)
    root, out = np.empty(3), np.empty(2)
    for _ in range(50):
        A = rng.normal(size=(4, 4))
        D = A @ A.T + 0.5 * np.eye(4)
        yf = rng.normal(size=4) * 2.0
        mu, active = np.zeros(4), np.zeros(4, np.bool_)
        assert land_cone_solve(D, yf, lo, hi, kind, lands, mu, active) > 0
        y = yf + D @ mu
        for a in (0, 2):
            b = a + 1
            z = y[[a, b]] - D[[a, b]][:, [a, b]] @ mu[[a, b]]   # without its own μ
            compiled(land_project)(D[a, a], D[a, b], D[b, b], z[0], z[1], 1.0,
                                   *hole.land_row(), root, out)
            assert np.abs(out - mu[[a, b]]).max() <= 1e-12 * max(1.0, np.abs(mu).max())
            assert excess(hole, [y[[a, b]]])[0] <= 1e-13


# ---------------------------------------------------------------- its limits
def test_lands_of_full_width_are_the_round_hole_before_the_second_impact():
    round_ = solve(beam_system(scene_with("tube_round_holes", Hole.round(R))), 1e-4, 0.1)
    full = solve(beam_system(scene_with("tube_round_holes",
                                        Hole.broached(3, 2 * math.pi / 3, R))), 1e-4, 0.1)
    assert full.solver == round_.solver == "round-hole"
    k = before_second_impact(round_)
    assert k > 10 and before_second_impact(full) == k
    assert np.abs(observed(full)[:k] - observed(round_)[:k]).max() <= 1e-12 * R


@pytest.mark.parametrize("n", [3, 4])
def test_lands_of_almost_no_width_are_the_ngon_before_the_second_impact(n):
    """Lands 1e-14° wide against the n-gon's faces (the active set's run): the lines turn
    by 1e-16 rad from the faces (1e-10° gave 1.1e-11 R: the width's own effect)."""
    ngon = solve(beam_system(scene_with("tube_round_holes", Hole.regular(n, R))), 1e-4, 0.1)
    thin = solve(beam_system(scene_with("tube_round_holes",
                                        Hole.broached(n, math.radians(1e-14), R))), 1e-4, 0.1)
    assert ngon.solver == "active-set" and thin.solver == "round-hole"
    k = before_second_impact(ngon)
    assert k > 10 and before_second_impact(thin) == k
    assert np.abs(observed(thin)[:k] - observed(ngon)[:k]).max() <= 1e-12 * R


# ---------------------------------------------------------------- the shipped scenes
@pytest.mark.parametrize("name, lands", [("tube_trefoil_holes", 3),
                                         ("tube_quatrefoil_holes", 4)])
def test_no_node_leaves_k_in_the_shipped_scenes(name, lands):
    problem = load(example(name)).problem
    hole = problem.holes[0].hole
    assert hole.lands == lands and hole.land_width == pytest.approx(math.radians(40))
    result = solve(beam_system(problem), 1e-4, 0.3)
    assert result.solver == "round-hole" and result.impacts > 10
    for x in (0.5, 1.0):
        p = np.column_stack([result.observed[f"hole_{x:g}_displacement_v"],
                             result.observed[f"hole_{x:g}_displacement_w"]])
        assert excess(hole, p).max() <= 1e-12 * R
        assert np.hypot(p[:, 0], p[:, 1]).max() > 1.01 * R    # into a lobe, on its line
    assert result.max_nodal_violation <= 1e-12 * R


@pytest.mark.usefixtures("charts")
def test_the_trefoil_scene_draws_its_outline(tmp_path):
    out = tmp_path / "run"
    assert exit_code(run_main, [str(example("tube_trefoil_holes")), "--set", "time.T=0.05",
                                "--out", str(out)]) == 0
    assert (out / "orbit_0.5.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("lands, width, angle", [(3, 40, 0), (4, 40, 10), (2, 30, -70),
                                                 (3, 120, 0), (5, 1e-6, 33), (4, 89.9, 0)])
def test_the_outline_lies_on_the_wall(lands, width, angle):
    hole = Hole.broached(lands, math.radians(width), R, math.radians(angle), (1e-5, -2e-5))
    o = hole.outline() - np.array(hole.centre)
    assert np.array_equal(o[0], o[-1])
    assert np.abs(excess(hole, o)).max() <= 1e-15 * 1e3 * R
    # drawn between its points it stays in K: chords of the arcs, the lobes' lines on ∂K
    drawn = boundary_samples(hole, 7) - hole.centre
    assert excess(hole, drawn).max() <= 1e-12 * R
    lobe = np.hypot(drawn[:, 0], drawn[:, 1]) > R * (1 + 1e-9)
    assert lobe.any() == (width < 360 / lands)
    assert np.abs(excess(hole, drawn[lobe])).max(initial=0.0) <= 1e-12 * R
    assert np.hypot(o[:, 0], o[:, 1]).min() == pytest.approx(R, rel=1e-12)


# ---------------------------------------------------------------- refusals
@pytest.mark.parametrize("table, word", [
    ({"lands": 1, "land_width": 40, "radius": R}, "lands=1"),
    ({"lands": 2.5, "land_width": 40, "radius": R}, "lands=2.5"),
    ({"lands": 3, "land_width": 0, "radius": R, "angle": 90},     # the n-gon, named
     "lands of no width are the regular polygon of 3 sides, { sides = 3, radius = r, "
     "angle = 1.5708 } in a scene file (its angle in rad"),
    ({"lands": 3, "land_width": -5, "radius": R}, "(0, 120]"),
    ({"lands": 4, "land_width": 91, "radius": R}, "(0, 90]"),
    ({"lands": 3, "land_width": 40, "radius": 0.0}, "radius=0"),
    ({"lands": 3, "land_width": 40, "radius": -R}, "radius="),
    ({"lands": 3, "radius": R}, "land_width"),
    ({"lands": 3, "land_width": 40, "radius": R, "sides": 3}, "broached"),
])
def test_bad_lands_are_refused_in_one_line(table, word):
    with pytest.raises(InputError) as e:
        hole_from_table(table, "obstacles[0].hole")
    assert word in str(e.value) and "\n" not in str(e.value)


@pytest.mark.parametrize("hole, setting, word", [
    ("{ lands = 1, land_width = 40.0, radius = 0.0004 }", None, "lands=1"),
    ("{ lands = 3, land_width = 130.0, radius = 0.0004 }", None, "land_width"),
    ("{ lands = 3, land_width = 40.0, radius = 0.0004 }", "contact.law=\"penalty\"",
     "broached"),
])
def test_bad_broached_scenes_are_refused_in_one_line(tmp_path, capsys, hole, setting, word):
    text = example("tube_trefoil_holes").read_text().replace(
        "{ lands = 3, land_width = 40.0, radius = 0.0004, angle = 0.0 }", hole)
    if setting:
        text += "\n[contact]\nlaw = \"penalty\"\nstiffness = 1e7\n"
    scene = tmp_path / "scene.toml"
    scene.write_text(text)
    folder = tmp_path / "out"
    folder.mkdir()
    assert_refused(run_main, [str(scene), "--out", str(folder / "run"), "--format", "none"],
                   word, capsys, folder)
