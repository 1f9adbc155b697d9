"""The bar run's analysis: its errors against an exact solution, its contact periods
and its energy across the first contact."""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .run import BarRun


def l2_time(e: np.ndarray, dt: float) -> float:
    """Discrete L²(0, T) norm √(Δt Σₙ eₙ²) (samples that are NaN, e.g. force[0], skipped)."""
    e = np.asarray(e, dtype=float)
    return float(np.sqrt(dt * np.sum(e[np.isfinite(e)] ** 2)))


def errors(run: BarRun, exact) -> dict:
    """L²-in-time errors of u(0,·), u(L,·) and the reaction R against ``exact``
    (a :class:`skfem_beam.reference.BarExact`), and the largest pointwise ones."""
    t, dt = run.t, run.result.dt * run.every
    e = {"u0": run.u0 - exact.u(0.0, t), "uL": run.uL - exact.u(run.bar.L, t),
         "force": run.force - exact.contact_force(t)}
    out = {f"l2_{k}": l2_time(v, dt) for k, v in e.items()}
    # an all-NaN series (a run unstable at its first step): None, not numpy's warning
    out.update({f"max_{k}": float(np.nanmax(np.abs(v))) if np.isfinite(v).any() else None
                for k, v in e.items()})
    return out


def contact_periods(t: np.ndarray, force: np.ndarray, merge: float = 0.0
                    ) -> list[tuple[float, float]]:
    """Maximal runs of steps with a positive reaction, as (first, last) times; runs
    separated by less than ``merge`` seconds count as one (the chatter of a grazing
    separation)."""
    on = np.nan_to_num(force, nan=0.0) > 0
    on[0] = on[0] or (on.size > 1 and on[1])      # the start step of an impact at t = 0
    edges = np.flatnonzero(np.diff(np.concatenate([[0], on.astype(int), [0]])))
    periods: list[tuple[float, float]] = []
    for a, b in zip(edges[::2], edges[1::2]):
        if periods and t[a] - periods[-1][1] < merge:
            periods[-1] = (periods[-1][0], float(t[b - 1]))
        else:
            periods.append((float(t[a]), float(t[b - 1])))
    return periods


def energy_report(run: BarRun) -> dict:
    """Energy before the first contact and just after it ends (E + load potential).

    The exact elastic bar (b = 0) conserves it, so ``loss`` is the scheme's own.  Runs
    of contact less than a tenth of a wave transit L/c apart count as one period.
    """
    E = run.energy + run.load_potential
    bar = run.bar
    periods = contact_periods(run.t, run.force, merge=0.1 * bar.L / bar.c)
    out = {"energy_initial": float(E[0]), "energy_final": float(E[-1]),
           "contact_periods": periods}
    if periods:
        i0 = int(np.searchsorted(run.t, periods[0][0]))
        i1 = int(np.searchsorted(run.t, periods[0][1])) + 1
        before = float(E[max(i0 - 1, 0)])
        out["energy_before_contact"] = before
        if i1 < E.size:
            after = float(E[i1])
            out.update(energy_after_contact=after, energy_loss=before - after,
                       energy_loss_relative=(before - after) / abs(before) if before else None)
    return out
