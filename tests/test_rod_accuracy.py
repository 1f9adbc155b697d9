"""Issue 40 on the periodic rod (N = 80, T = 12): the named settings of
bench.rod_study.ACCURACY against the issue's targets, with the study's one error measure
(rod_study.relative_error).  docs/methods.md, "The rod's accuracy study", has the table."""
import numpy as np
import pytest

from skfem_beam.bench import rod_study as rs


def test_relative_error_is_the_formula():
    u = np.array([0.5, 0.25, 0.0, 0.25])
    u_h = u + np.array([0.0, 0.01, 0.0, -0.02])
    assert rs.relative_error(u_h, u) == pytest.approx(np.sqrt(5e-4 / 0.375), rel=1e-14)


@pytest.fixture(scope="module")
def rows():
    names = {rs.BEST[0.4], rs.BEST[0.04], rs.ENERGY, "average, β=1/4"}
    return {(n, c): rs.accuracy_row(n, c) for n in names for c in rs.ACCURACY_COURANTS}


def test_best_at_courant_004_meets_the_target(rows):
    r = rows[rs.BEST[0.04], 0.04]
    assert r["penetration"] <= 1e-12
    assert r["error"] <= 0.016


def test_best_at_courant_04_meets_the_target(rows):
    """P2 elements, the average mass, β = 0.09: 0.00618 (issue 40: ≤ 0.0062, zero
    penetration), and ≤ 0.016 at Δt/h = 0.04 (0.0067)."""
    r = rows[rs.BEST[0.4], 0.4]
    assert r["penetration"] <= 1e-12
    assert r["error"] <= 0.0062
    assert rows[rs.BEST[0.4], 0.04]["error"] <= 0.016
    assert rows[rs.BEST[0.4], 0.04]["penetration"] <= 1e-12


def test_best_at_courant_04_beats_getfem(rows):
    """Half GetFEM's best (Signorini–Newmark β = 1/2, 0.0124) without penetration."""
    r = rows[rs.BEST[0.4], 0.4]
    assert r["penetration"] <= 1e-12
    assert r["error"] <= 0.5 * rs.GETFEM["error"]["0.4"]


def test_best_at_courant_04_beats_the_default_without_penetration(rows):
    r, default = rows[rs.BEST[0.4], 0.4], rows["average, β=1/4", 0.4]
    assert r["penetration"] <= 1e-12
    assert r["error"] < default["error"]


@pytest.mark.parametrize("courant", rs.ACCURACY_COURANTS)
def test_energy_setting_keeps_its_energy(rows, courant):
    r, default = rows[rs.ENERGY, courant], rows["average, β=1/4", courant]
    assert r["penetration"] <= 1e-12
    assert abs(r["drift"]) <= 0.005
    # through an impact it keeps what the default loses (O(h) per impact)
    assert abs(r["impact_change"]) < 0.25 * abs(default["impact_change"])


def test_winners_are_named_settings_of_scene_keys():
    for name in (*rs.BEST.values(), rs.ENERGY):
        keys = rs.ACCURACY[name]
        assert set(keys) <= {"mesh.mass", "mesh.massless", "mesh.element", "time.beta",
                             "contact.theta",
                             "contact.law", "contact.restitution"}
