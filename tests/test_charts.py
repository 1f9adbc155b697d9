"""Charts from data in memory: long series reduced without losing an extreme, the beam
drawn as ParaView shows it (ũ, with the obstacles), forces in newtons, legends."""
import tracemalloc
from contextlib import contextmanager
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest
from PIL import Image

from conftest import exit_code
from skfem_beam import beam_system, scenes, solve
from skfem_beam.cases import point_stops
from skfem_beam.output import charts
from skfem_beam.output.charts import (envelope, plot_reduced, shape_chart, shapes,
                                      trajectory_chart)
from skfem_beam.scenefile import run_main

N = 2_000_000


@pytest.fixture(scope="module")
def tip():
    """2,000,000 rows like a tip between stops at ±0.1 m: long stays on a stop, single-row
    spikes, and rows where it touches the stop once."""
    t = np.arange(N) * 1e-6
    y = np.clip(0.13 * np.sin(2 * np.pi * 3.1 * t) + 0.004 * np.sin(2 * np.pi * 410 * t),
                -0.1, 0.1)
    y[[777_777, 1_234_567]] = [0.0999999, -0.0999999]     # lone near-touches
    y[1_500_001] = 0.1                                    # a lone touch inside a free flight
    return t, y


@contextmanager
def kept_figure(store):
    """charts.figure, but the figure is kept open for inspection instead of saved."""
    fig, ax = plt.subplots(figsize=(9, 4), dpi=110)
    store.update(fig=fig, ax=ax)
    yield fig, ax


def test_envelope_keeps_every_column_extreme(tip):
    t, y = tip
    columns = 990
    tr, yr = envelope(t, y, columns)
    assert tr.size <= 2 * columns + 4 and np.all(np.diff(tr) > 0)
    # every sample kept is a sample of the series (no interpolation, no smoothing)
    idx = np.searchsorted(t, tr)
    assert np.array_equal(t[idx], tr) and np.array_equal(y[idx], yr)
    chunk = -(-N // columns)
    for k0 in range(0, N, chunk):                      # each pixel column's min and max
        sel = (idx >= k0) & (idx < k0 + chunk)
        assert yr[sel].max() == y[k0:k0 + chunk].max()
        assert yr[sel].min() == y[k0:k0 + chunk].min()
    assert yr.max() == 0.1 and yr.min() == -0.1       # the stop values themselves
    assert 1_500_001 in idx and 777_777 in idx and 1_234_567 in idx
    assert idx[0] == 0 and idx[-1] == N - 1


def test_envelope_copies_nothing_and_keeps_nan_gaps(tip):
    t, y = tip
    tracemalloc.start()
    envelope(t, y, 1000)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 0.1 * y.nbytes, peak                 # no copy of the 16 MB series
    z = y.copy()
    z[:1] = np.nan                                     # the bar's R(0) is NaN
    tr, zr = envelope(t, z, 1000)
    assert np.isnan(zr[0]) and np.nanmax(zr) == 0.1 and np.nanmin(zr) == -0.1
    short = np.arange(50.0)
    assert envelope(short, short, 1000)[1] is short   # short series drawn as they are


def test_a_long_series_is_drawn_reduced_with_a_legend(tip, monkeypatch, tmp_path):
    t, y = tip
    store = {}
    monkeypatch.setattr(charts, "figure", lambda *a, **k: kept_figure(store))
    trajectory_chart(tmp_path / "tip.png", t, {"ũ(L, t)": y}, stops=(-0.1, 0.1))
    ax = store["ax"]
    line = ax.lines[0]
    assert line.get_xdata().size <= 2 * 990 + 4 and max(line.get_ydata()) == 0.1
    labels = ax.get_legend_handles_labels()[1]
    assert labels == ["ũ(L, t)", "obstacle g1 = -0.1 m", "obstacle g2 = 0.1 m"]
    plt.close(store["fig"])
    fig, ax = plt.subplots(figsize=(4, 3), dpi=100)
    assert plot_reduced(ax, t, y)[0].get_xdata().size <= 2 * 400 + 4
    plt.close(fig)


def test_beam_shapes_show_the_physical_displacement_and_the_stops(monkeypatch, tmp_path):
    """ũ = u + h(x)φ(t): at x = 0 every curve sits on the support φ(t) = 0.2 sin 10t (the
    relative u would start at 0), at x = L on u(L) (h(L) = 0); the stops are markers."""
    r = solve(beam_system(scenes.point_stops()), dt=5e-5, T=0.6, beta=0.5, frames=12)
    store = {}
    monkeypatch.setattr(charts, "figure", lambda *a, **k: kept_figure(store))
    shape_chart(tmp_path / "shapes.png", shapes(r, count=6))
    ax = store["ax"]
    curves = [ln for ln in ax.lines if ln.get_xdata().size > 2]
    assert len(curves) == 6
    L = 1.501
    times = np.unique(np.linspace(0, r.frames_t.size - 1, 6).astype(int))
    for ln, k in zip(curves, times):
        x, u = np.asarray(ln.get_xdata()), np.asarray(ln.get_ydata())
        assert x[0] == 0 and x[-1] == pytest.approx(L)
        # φ = 0.2 sin 10t and the tip, which stays between the stops at ±0.1
        assert u[0] == pytest.approx(0.2 * np.sin(10 * r.frames_t[k]), abs=5e-12 * 0.2)
        assert u[-1] == pytest.approx(r.observed["tip_displacement"][round(r.frames_t[k] / r.dt)],
                                      abs=1e-11 * 0.1)
    assert max(abs(ln.get_ydata()[0]) for ln in curves) > 0.15     # the support has moved
    stops = {ln.get_label(): (ln.get_xdata()[0], ln.get_ydata()[0]) for ln in ax.lines
             if ln.get_marker() in ("^", "v")}
    assert stops == {"obstacle g1 (lower) (point stop)": (pytest.approx(L), -0.1),
                     "obstacle g2 (upper) (point stop)": (pytest.approx(L), 0.1)}
    assert ax.get_legend() is not None and ax.get_ylabel() == "ũ (m)"
    plt.close(store["fig"])


def test_elastic_stops_are_drawn_hollow_and_named(monkeypatch, tmp_path):
    """The penalty law's stops are springs the beam presses into: the command's shapes
    say so (run.springs), hollow markers and "elastic" in the legend; rigid ones filled."""
    store = {}
    monkeypatch.setattr(charts, "figure", lambda *a, **k: kept_figure(store))
    from skfem_beam.cases import _beam
    drawn = []
    monkeypatch.setattr(_beam, "draw", lambda f, path, *a, **k: drawn.append(path.name)
                        or (f(path, *a, **k) if f is shape_chart else None))
    for law, elastic in (("penalty", True), ("projection", False)):
        args = ["--T", "0.05", "--out", str(tmp_path / law)]
        args += ["--law", "penalty", "--stiffness", "1e7"] if elastic else ["--solver", law]
        assert point_stops.main(args) == 0
        stops = [ln for ln in store["ax"].lines if ln.get_marker() in ("^", "v")]
        assert sorted(ln.get_label() for ln in stops) == [
            f"obstacle g1 (lower{', elastic' * elastic}) (point stop)",
            f"obstacle g2 (upper{', elastic' * elastic}) (point stop)"]
        assert all((ln.get_markerfacecolor() == "none") == elastic for ln in stops)
        plt.close(store["fig"])
    assert drawn.count("beam_shapes.png") == 2


def test_flat_obstacles_are_lines(monkeypatch, tmp_path):
    r = solve(beam_system(scenes.flat_obstacles(J=20)), dt=1e-3, T=0.05, beta=0.5, frames=5)
    store = {}
    monkeypatch.setattr(charts, "figure", lambda *a, **k: kept_figure(store))
    shape_chart(tmp_path / "shapes.png", shapes(r))
    g = {ln.get_label(): ln for ln in store["ax"].lines if ln.get_label().startswith("obstacle")}
    assert set(g) == {"obstacle g1 (lower)", "obstacle g2 (upper)"}
    x, g2 = np.asarray(g["obstacle g2 (upper)"].get_xdata()), \
        np.asarray(g["obstacle g2 (upper)"].get_ydata())
    L = x[-1]
    assert np.all(g2[x >= L / 2] == 0.01) and np.all(np.isnan(g2[x < L / 2 - 1e-9]))
    plt.close(store["fig"])


@pytest.mark.usefixtures("charts")
def test_case_charts_force_in_newtons(monkeypatch, tmp_path):
    """The pipe's ρS is known: its contact force chart is in N (the contact_force_N column)."""
    figures = {}

    @contextmanager
    def keep(path, *a, **k):
        with kept_figure(figures.setdefault(path.name, {})) as fa:
            yield fa

    monkeypatch.setattr(charts, "figure", keep)
    out = tmp_path / "run"
    assert exit_code(point_stops.main, ["--T", "0.3", "--out", str(out), "--format", "none"]) == 0
    assert set(figures) == {"tip_displacement.png", "energy.png", "contact_force.png",
                            "beam_shapes.png"}
    ax = figures["contact_force.png"]["ax"]
    assert ax.get_ylabel() == "force (N)"
    rows = np.loadtxt(out / "timeseries.csv", delimiter=",", skiprows=1)
    force_N = rows[:, 5]
    y = ax.lines[0].get_ydata()
    assert np.max(np.abs(y)) == np.max(np.abs(force_N)) > 10      # N, not m²/s² ÷ ρS
    # the energy in J (energy_J = ρS·energy) with the work terms of its balance
    names = rows_header(out)
    ax = figures["energy.png"]["ax"]
    assert ax.get_ylabel() == "energy (J)"
    lines = {ln.get_label(): ln.get_ydata() for ln in ax.lines}
    assert set(lines) == {"½E_β", "work of the loads (support motion included)",
                          "work of the contact forces"}
    width = charts._columns(figures["energy.png"]["fig"])
    for label, col in (("½E_β", "energy_J"), ("work of the contact forces", "work_contact_J")):
        np.testing.assert_array_equal(lines[label],
                                      envelope(rows[:, 0], rows[:, names.index(col)], width)[1])
    for name, fa in figures.items():
        assert fa["ax"].get_legend() is not None, name
        plt.close(fa["fig"])


def rows_header(folder):
    return (folder / "timeseries.csv").read_text().split("\n", 1)[0].split(",")


def test_carried_obstacles_move_with_the_support(monkeypatch, tmp_path):
    """A stop carried by the shaken frame is drawn at g + φ(t_k) for each drawn frame (in
    its colour); the stop fixed to the ground once, in black, at g."""
    import sys
    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    from test_units import SHAKE, _shaken
    from skfem_beam import Obstacles
    obs = Obstacles.combine(Obstacles.stops([0.5], -5e-4, 5e-4, carried=True),
                            Obstacles.point_stops(1.0, -0.004, 0.004))
    r = solve(beam_system(_shaken(obstacles=obs)), dt=1e-5, T=0.05, frames=10)
    store = {}
    monkeypatch.setattr(charts, "figure", lambda *a, **k: kept_figure(store))
    shape_chart(tmp_path / "shapes.png", shapes(r, count=6))
    marks = [ln for ln in store["ax"].lines if ln.get_marker() in ("^", "v")]
    moving = sorted((float(ln.get_ydata()[0]) for ln in marks if ln.get_xdata()[0] == 0.5))
    times = r.frames_t[np.unique(np.linspace(0, r.frames_t.size - 1, 6).astype(int))]
    want = sorted([g + float(SHAKE(t)) for t in times for g in (-5e-4, 5e-4)])
    np.testing.assert_allclose(moving, want, rtol=0, atol=4e-13 * np.abs(want).max())
    fixed = {float(ln.get_ydata()[0]) for ln in marks if ln.get_xdata()[0] == 1.0}
    assert fixed == {-0.004, 0.004}
    plt.close(store["fig"])


def test_long_series_kept_for_the_charts_keep_every_extreme_in_bounded_memory(tmp_path):
    """2,000,000 rows streamed in 100 chunks: the rows held for the charts stay bounded,
    spread over the whole run (no gap wider than two time bins), every column's overall
    extremes are among them, and in every 20 ms window the held rows span what the full
    series spans there, to within one bin's change of the signal."""
    from skfem_beam.output.series import BINS, KEEP_ROWS, SeriesFile
    sf = SeriesFile(tmp_path / "ts.csv", ["t", "y", "z", "quiet"])   # quiet: all ties
    rng = np.random.default_rng(1)
    windows = []
    zmax, zmin = -np.inf, np.inf
    for c in range(100):
        t = np.arange(c * 20000, (c + 1) * 20000) * 1e-6
        y, z = np.sin(2 * np.pi * 3 * t), rng.standard_normal(t.size)
        sf.append({"t": t, "y": y, "z": z, "quiet": np.zeros(t.size)})
        windows.append((t[0], t[-1], y.min(), y.max()))
        zmax, zmin = max(zmax, z.max()), min(zmin, z.min())
    sf.close()
    data = sf.data()
    assert not data.complete and data["t"].size < KEEP_ROWS + 10 * BINS   # not 2e6
    width = 2 * 2.0 / BINS
    assert np.diff(data["t"]).max() <= width
    assert data["z"].max() == zmax and data["z"].min() == zmin
    slope = 2 * np.pi * 3                 # |dy/dt| ≤ this
    for a, b, lo, hi in windows:
        held = data["y"][(data["t"] >= a) & (data["t"] <= b)]
        assert held.min() <= lo + slope * width and held.max() >= hi - slope * width


# the plates' shipped scenes draw theirs in tests/test_plate_scenes.py
SHIPPED = sorted((Path(charts.__file__).parents[1] / "scene_files").glob("*.toml"))


@pytest.mark.usefixtures("charts")
@pytest.mark.parametrize("scene", SHIPPED, ids=lambda p: p.stem)
def test_every_shipped_scene_draws_its_charts(scene, tmp_path):
    """The suite's commands draw no chart (tests/conftest.py): every shipped scene, run
    briefly, draws its own, each a picture of the chart's size."""
    out = tmp_path / "run"
    assert exit_code(run_main, [str(scene), "--set", "time.T=0.02", "--format", "none",
                                "--out", str(out)]) == 0
    pictures = sorted(out.glob("*.png"))
    assert pictures, sorted(p.name for p in out.iterdir())
    for path in pictures:
        with Image.open(path) as image:
            assert min(image.size) >= 300, (path.name, image.size)
