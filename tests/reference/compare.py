"""Comparing a run's arrays with the same run's arrays recorded on another machine.

Bits differ across machines (tests/reference/machine.py), and each impact amplifies the
difference: vibro-impact is chaotic.  So trajectories are compared row by row only before
the second impact, and by their statistics (mean, RMS, max and min of each column) after
it, each to a tolerance relative to the array's largest value.  Each run's tolerances
are its measured cross-machine spread with a margin (tolerances.json, written by
tests/reference/spread.py; docs/tests.md).
"""
from __future__ import annotations

import json
from functools import cache
from pathlib import Path

import numpy as np

TOLERANCES = Path(__file__).with_name("tolerances.json")
# a margin on round-off grown by the impacts: another machine's last bits are another
# sample of the same growth, within a decade or two of the measured ones
MARGIN = 100.0
FLOOR = {"before": 1e-12, "after": 1e-10}
# beyond this the trajectories have decorrelated (penalty runs, a few ms after their
# second contact): their short runs' statistics are another sample of the same dynamics,
# checked to 10 times the measured spread, at most the array's scale: gross errors only
DECORRELATED = 1e-4


def tolerance(measured: float, window: str) -> float:
    if measured > DECORRELATED:
        return min(10.0 * measured, 1.0)
    return max(MARGIN * measured, FLOOR[window])


def onsets(t, force) -> np.ndarray:
    """The instants a contact force switches on (any column nonzero after a zero row)."""
    on = np.abs(np.asarray(force, float)).reshape(len(t), -1).max(axis=1) > 0
    return np.asarray(t)[on & ~np.r_[False, on[:-1]]]


def second_impact(t, force) -> float:
    o = onsets(t, force)
    return float(o[1]) if len(o) > 1 else np.inf


def _times(ref: np.ndarray, t: np.ndarray):
    """The time of each row of ``ref``: ``t`` itself, or frames spread evenly over it;
    None for a vector of numbers (a summary)."""
    if ref.ndim == 0 or (ref.ndim == 1 and len(ref) != len(t) and len(ref) < 10):
        return None
    return t if len(ref) == len(t) else np.linspace(t[0], t[-1], len(ref))


def _statistics(a: np.ndarray) -> np.ndarray:
    return np.stack([a.mean(0), np.sqrt((a**2).mean(0)), a.max(0), a.min(0)])


def spread(got, ref, t, t2) -> dict:
    """{"before": the largest difference of a row before ``t2``, "after": of a statistic
    after it}, each relative to the largest |ref|."""
    got, ref, t = np.asarray(got, float), np.asarray(ref, float), np.asarray(t, float)
    assert got.shape == ref.shape, (got.shape, ref.shape)
    assert (np.isfinite(got) == np.isfinite(ref)).all(), "non-finite values differ"
    got, ref = np.nan_to_num(got), np.nan_to_num(ref)
    scale = np.abs(ref).max(initial=0.0) or 1.0
    tt = _times(ref, t)
    if tt is None:
        return {"before": 0.0, "after": float(np.abs(got - ref).max(initial=0.0) / scale)}
    g, r = got.reshape(len(tt), -1), ref.reshape(len(tt), -1)
    pre = tt < t2
    before = np.abs(g[pre] - r[pre]).max(initial=0.0) / scale
    after = 0.0 if pre.all() else \
        np.abs(_statistics(g[~pre]) - _statistics(r[~pre])).max() / scale
    return {"before": float(before), "after": float(after)}


def runs_of(path: Path) -> dict:
    """run name -> {key: array}, from one of the stored .npz files."""
    out = {}
    with np.load(path) as data:
        for k in data.files:
            name, key = k.split("/", 1)
            out.setdefault(name, {})[key] = data[k]
    return out


def time_and_second_impact(arrays: dict):
    """A run's time column and the start of its second impact (from its impacts table,
    or where its contact force switches on for the second time)."""
    t = arrays["t"]
    if "impacts_t_start" in arrays:
        s = arrays["impacts_t_start"]
        return t, float(s[1]) if len(s) > 1 else np.inf
    return t, second_impact(t, arrays.get("contact_force", arrays.get("force")))


ROUND_OFF = ("friction_residual",)   # a solver's residual is round-off itself: its bound
#                                    is asserted where it is computed (tests/test_friction.py)


def compared(arrays: dict) -> list:
    """The keys of a run compared across machines: all but time, impact times and
    round-off measures."""
    return [k for k in arrays if k != "t" and not k.startswith("impacts_")
            and k not in ROUND_OFF]


def run_spread(got: dict, ref: dict) -> dict:
    t, t2 = time_and_second_impact(ref)
    worst = {"before": 0.0, "after": 0.0}
    for key in compared(ref):
        s = spread(got[key], ref[key], t, t2)
        worst = {w: max(worst[w], s[w]) for w in worst}
    return worst


@cache
def _table() -> dict:
    return json.loads(TOLERANCES.read_text())


def decorrelated(run: str) -> bool:
    """Whether ``run``'s trajectories part across machines after its second impact: its
    count of impacts may differ then too."""
    return _table()["measured"][run]["after"] > DECORRELATED


def assert_close(run, key, got, ref, t, t2) -> None:
    """``got`` is ``ref`` to the tolerances of ``run`` ("group/name": tolerances.json)."""
    s, tol = spread(got, ref, t, t2), _table()["tolerance"][run]
    assert s["before"] <= tol["before"] and s["after"] <= tol["after"], \
        f"{run}/{key}: differs by {s['before']:.3g} before the second impact (t = {t2:.6g}) " \
        f"and {s['after']:.3g} in its statistics after it (bounds {tol['before']:.3g}, " \
        f"{tol['after']:.3g}: tests/reference/tolerances.json)"


def assert_run_close(run, got: dict, ref: dict) -> None:
    """Every compared array of a run (``got``) is its stored one (``ref``) to the run's
    tolerances, on the same time grid."""
    t, t2 = time_and_second_impact(ref)
    np.testing.assert_array_equal(got["t"], t)
    for key in compared(ref):
        assert_close(run, key, got[key], ref[key], t, t2)
