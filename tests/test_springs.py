"""Spring supports of their own stiffness each ([[obstacles]] stiffness, damping per
obstacle; the penalty law's κ and c per row and side, contact.penalty)."""
import json
import math

import numpy as np
import pytest

from conftest import assert_refused, exit_code
from skfem_beam import InputError
from skfem_beam.methods import Penalty
from skfem_beam.scenefile import load, run_main
from skfem_beam.scheme import solve
from skfem_beam.semidiscrete import beam_system

# A steel rod cantilever (d = 10 mm, L = 0.5 m: tip stiffness 3EI/L³ = 2356 N/m, first
# mode 28 Hz) pushed at its tip by 20 sin 2t N, quasi-static, between a stop 1 mm below
# the tip (obstacle 0, k1) and one 1 mm above it (obstacle 1, k2).
SCENE = """kind = "beam"
[material]
E = 2e11
rho = 7850.0
[section]
rod = { diameter = 0.01 }
[geometry]
L = 0.5
[ends]
left = "clamped"
right = "free"
[[obstacles]]
x = 0.5
g1 = -0.001
stiffness = 2e4
[[obstacles]]
x = 0.5
g2 = 0.001
stiffness = 1e5
[[loads]]
x = 0.5
amplitude = 20.0
omega = 2.0
[damping]
zeta = 0.05
f1 = 20.0
f2 = 200.0
[mesh]
J = 10
[time]
dt = 1e-3
T = 3.2
"""
K1, K2, F0, GAP = 2e4, 1e5, 20.0, 1e-3
EI = 2e11 * math.pi * 0.01 ** 4 / 64
K_BEAM = 3 * EI / 0.5 ** 3


def write(folder, text=SCENE, name="two.toml"):
    path = folder / name
    path.write_text(text)
    return path


def test_each_obstacle_reports_the_deflection_of_its_own_spring(tmp_path, capsys):
    """Obstacles of 2e4 and 1e5 N/m under the same quasi-static push, up then down: each
    reports its own largest deflection, the static (F0 − k_b·gap)/(k_b + k) of a cantilever
    of tip stiffness k_b = 3EI/L³ on that spring to 0.1 %, and force/deflection = its k."""
    out = tmp_path / "run"
    assert exit_code(run_main, [str(write(tmp_path)), "--format", "none", "--out",
                                str(out)]) == 0
    printed = capsys.readouterr().out
    assert "spring supports" in printed and "0.7893" in printed and "0.1724" in printed
    s = json.loads((out / "summary.json").read_text())
    assert s["penalty_stiffness_N_per_m"] == [K1, K2]
    low, high = s["spring_supports"]
    for entry, k in ((low, K1), (high, K2)):
        static = (F0 - K_BEAM * GAP) / (K_BEAM + k)
        assert entry["stiffness"] == k and entry["impacts"] >= 1
        assert abs(entry["max_deflection"] / static - 1) < 1e-3, (entry, static)
        assert abs(entry["max_force"] / entry["max_deflection"] / k - 1) < 1e-3, entry
    assert abs(low["max_deflection"] / high["max_deflection"] - (K_BEAM + K2) / (K_BEAM + K1)) \
        < 2e-3
    assert s["max_support_deflection"] == low["max_deflection"]


def test_a_spring_behaves_as_in_the_run_where_all_have_its_stiffness(tmp_path):
    """The obstacle above (1e5 N/m) is touched first: until the one below (2e4) is, the run
    is the all-1e5 run bit for bit; afterwards it is not.  And one stiffness given per
    obstacle, all equal, is the one-number run bit for bit (springs and dashpots)."""
    system = beam_system(load(write(tmp_path)).problem)
    mixed = solve(system, 1e-3, 3.2, 0.25, Penalty((K1, K2)))
    stiff = solve(system, 1e-3, 3.2, 0.25, Penalty(K2))
    tip = "tip_displacement"
    first_low = int(np.argmax(mixed.observed[tip] < -GAP))
    assert 1000 < first_low < 3200
    assert np.array_equal(mixed.observed[tip][:first_low], stiff.observed[tip][:first_low])
    assert not np.array_equal(mixed.observed[tip], stiff.observed[tip])
    for k, c in ((K2, 0.0), (K1, 30.0)):
        one = solve(system, 1e-3, 3.2, 0.25, Penalty(k, damping=c))
        each = solve(system, 1e-3, 3.2, 0.25, Penalty((k, k), damping=(c, c)))
        assert one.impacts > 0
        for a, b in ((one.observed[tip], each.observed[tip]), (one.energy, each.energy),
                     (one.contact_force, each.contact_force)):
            assert np.array_equal(a, b)


@pytest.mark.parametrize("stiffness, damping, word", [
    ((K1, K2, K1), 0.0, "Penalty stiffness: 3 values for 2 obstacle(s)"),
    ((K1,), (1.0, 2.0, 3.0), "Penalty damping: 3 values for 2 obstacle(s)"),
])
def test_a_value_per_obstacle_needs_one_for_each(tmp_path, stiffness, damping, word):
    """Too many values was run with the extra ones left out, silently."""
    system = beam_system(load(write(tmp_path)).problem)
    with pytest.raises(InputError) as e:
        solve(system, 1e-3, 0.01, 0.25, Penalty(stiffness, damping=damping))
    assert str(e.value).startswith(word)


@pytest.mark.parametrize("change, word", [
    (("--set", "obstacles.1.stiffness=0"), "[obstacles.1] stiffness=0 must be > 0"),
    (("--set", "obstacles.0.stiffness=-5e3"), "[obstacles.0] stiffness=-5000 must be > 0"),
    (("--set", "obstacles.1.damping=-1"), "[obstacles.1] damping=-1 must be ≥ 0"),
    ("damping without stiffness", "[obstacles.1] damping is a dashpot beside"),
    ("one rigid", "[obstacles.1] has no stiffness while [obstacles.0] has one"),
    ("two planes", "may differ per obstacle in one plane only"),
])
def test_bad_stiffness_or_damping_is_refused_in_one_line(tmp_path, capsys, change, word):
    text = SCENE
    if change == "damping without stiffness":
        text = SCENE.replace("stiffness = 1e5", "damping = 10.0")
    elif change == "one rigid":
        text = SCENE.replace("stiffness = 1e5\n", "")
    elif change == "two planes":
        text = "planes = 2\n" + SCENE
    src = write(tmp_path, text)
    folder = tmp_path / "runs"
    folder.mkdir()
    argv = [str(src), *(change if isinstance(change, tuple) else ()), "--format", "none",
            "--out", str(folder / "run")]
    assert_refused(run_main, argv, word, capsys, folder)


def test_two_plane_supports_report_their_springs(tmp_path, capsys):
    """The shipped tube in two round holes on springs (one stiffness for all, as two planes
    take it): summary.json's spring_supports has one entry per hole, its largest deflection
    is the run's max_support_deflection, and force/deflection is the stiffness (the force is
    the β-weighted spring's: within 3 %); the terminal prints the table.  (Two-plane runs
    had no spring_supports at all.)"""
    from skfem_beam.scenefile import example
    out = tmp_path / "run"
    assert exit_code(run_main, [str(example("tube_round_holes.toml")), "--set",
                                "obstacles.0.stiffness=1e6", "--set", "obstacles.1.stiffness=1e6",
                                "--T", "0.3", "--format", "none", "--out", str(out)]) == 0
    assert "spring supports" in capsys.readouterr().out
    s = json.loads((out / "summary.json").read_text())
    springs = s["spring_supports"]
    assert [e["where"] for e in springs] == ["support at x=0.5", "support at x=1"]
    assert max(e["max_deflection"] for e in springs) == s["max_support_deflection"] > 0
    for e in springs:
        assert e["stiffness"] == 1e6 and e["impacts"] >= 10
        assert abs(e["max_force"] / e["max_deflection"] / 1e6 - 1) < 0.03, e


def test_a_span_of_springs_deflects_as_much_as_its_springs(tmp_path):
    """max_support_deflection is the springs' largest compression, at the nodes where they
    act: on flat obstacles along a span it was max_penetration, the beam's between the
    nodes too (1.4e-4 m against the springs' 7.4e-5)."""
    from skfem_beam.cases import flat_obstacles
    out = tmp_path / "run"
    assert exit_code(flat_obstacles.main, ["--law", "penalty", "--stiffness", "1e6", "--dt",
                                           "1e-4", "--format", "none", "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    springs = max(e["max_deflection"] for e in s["spring_supports"])
    assert s["max_support_deflection"] == springs == s["max_nodal_violation"] > 0
    assert s["max_penetration"] > 1.5 * springs         # the beam between the nodes
