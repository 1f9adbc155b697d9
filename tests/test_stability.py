"""Where methods fail: the β-family's stability limits and the penalty method."""
import json

import numpy as np
import pytest

from conftest import assert_refused, exit_code
from skfem_beam import beam_system, scenes, solve
from skfem_beam.cases import stability_map
from skfem_beam.methods import Penalty
from skfem_beam.semidiscrete import beam_system as system_of
from skfem_beam.stability import (PAPER_KAPPA_BOUNDS, kappa_h, linear_limit, prop31_limit,
                                  stability_table)


@pytest.fixture(scope="module")
def pipe_system():
    return beam_system(scenes.point_stops())


def test_papers_bounds_hold_and_how_pessimistic(pipe_system):
    kappa = kappa_h(pipe_system)
    L, J, k2 = 1.501, 19, 282.84
    rows = stability_table(kappa, "hermite", k2, L / J, 0.25)
    ratios = {r["kappa_from"]: r["ratio_to_exact"] for r in rows}
    assert all(r >= 1 for r in ratios.values())              # they are upper bounds
    assert 27 < ratios["first paper (5.2), 24·420·19²/37"] < 28
    # the first paper's Δt for J=19, β=1/4: 2√(2/κ̄) = 3.3469e-6 s
    assert prop31_limit(rows[1]["kappa"], 0.25) == pytest.approx(3.3469e-6, rel=1e-4)
    bs = system_of(scenes.point_stops(element="bspline"))
    kb = kappa_h(bs)
    assert kb <= PAPER_KAPPA_BOUNDS["bspline"]["second paper, 5040"] * k2 / (L / J) ** 4


@pytest.mark.parametrize("beta", [0.0, 0.1])
def test_contact_scheme_fails_where_linear_newmark_does(pipe_system, beta):
    limit = linear_limit(kappa_h(pipe_system), beta)
    ok = solve(pipe_system, 0.9 * limit, 0.5, beta, save_every=10, frames=2)
    assert ok.status == "success" and ok.impacts > 0
    assert np.abs(ok.observed["tip_displacement"]).max() <= 0.1 * (1 + 1e-15)
    bad = solve(pipe_system, 1.2 * limit, 0.5, beta, save_every=10, frames=2)
    assert bad.status == "unstable" and bad.t[-1] < 0.1
    assert "linear stability limit" in bad.message and "step" in bad.message
    assert np.isfinite(bad.energy).all()


@pytest.mark.parametrize("beta", [0.25, 0.5])
def test_unconditional_for_beta_at_least_a_quarter(pipe_system, beta):
    paper_kappa = PAPER_KAPPA_BOUNDS["hermite"]["first paper (5.2), 24·420·19²/37"] * 282.84 \
        / (1.501 / 19) ** 4
    dt = 100 * prop31_limit(paper_kappa, 0.25)
    r = solve(pipe_system, dt, 0.5, beta)
    assert r.status == "success" and r.impacts > 0
    assert r.energy.max() < 10 * r.energy[0]


def test_penalty_penetrates_less_as_stiffness_grows(pipe_system):
    """Normal compliance penetrates (the contact scheme does not), less for stiffer springs."""
    pen = []
    for stiffness in (1e6, 1e7, 1e8):
        r = solve(pipe_system, 5e-6, 0.25, 0.25, Penalty(stiffness / scenes.PIPE_RHO_S, equation_units=True),
                  save_every=5, frames=2)
        assert r.status == "success"
        pen.append(np.abs(r.observed["tip_displacement"]).max() - 0.1)
    assert pen[0] > 3 * pen[1] > 9 * pen[2] > 0
    exact = solve(pipe_system, 5e-6, 0.25, 0.25, save_every=5, frames=2)
    assert np.abs(exact.observed["tip_displacement"]).max() - 0.1 <= 1e-16


def test_stability_map_small_grid(tmp_path):
    out = tmp_path / "map"
    assert exit_code(stability_map.main, ["--betas", "0,0.5", "--ratios", "0.9,1.2",
                                          "--T", "0.05", "--out", str(out)]) == 0
    rows = (out / "stability_map.csv").read_text().splitlines()
    assert len(rows) == 1 + 2 * 2 * 2
    s = json.loads((out / "summary.json").read_text())
    assert s["unstable"] >= 2 and (out / "stability_map.png").stat().st_size > 10_000


def test_stability_map_refuses_a_grid_over_budget(tmp_path, capsys):
    assert_refused(stability_map.main, ["--ratios", "0.01", "--T", "2", "--max-seconds", "1",
                                        "--out", str(tmp_path / "m")], "--max-seconds=1", capsys,
                   tmp_path)
