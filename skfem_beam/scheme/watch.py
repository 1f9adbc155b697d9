"""What the compiled loop's energy test (kernels.stop_code: |½E_β| ≤ the a-priori bound at
every saved state) does not see, checked after each chunk, in Python, on the chunk's saved
energies and its last state.

- **A negative energy.**  ½E_β = ½δᵀ(M/Δt² + (β − ¼)K)δ + ½aᵀKa (δ = uⁿ − uⁿ⁻¹, a their
  mean) is positive for every state exactly when Δt is below the linear stability limit
  (β < ¼) or always (β ≥ ¼), so a saved ½E_β below round-off's −1e-9 × the bound (plus
  the start's terms, :meth:`Watch._terms`) means the
  unstable modes have taken over: just above the limit the tip jumped from stop to stop at
  every step while ½E_β went from 1.4 to −5,400, inside the loose a-priori bound.
- **A growing kinetic energy under a constant ½E_β.**  Without contact the scheme conserves
  ½E_β exactly, unstable or not (β = 0 beyond the limit: ½E_β stays 1.32 while the beam
  reaches 1e4 m/s); the kinetic energy ½δᵀMδ/Δt² ≤ ½E_β/(1 − r²) while stable, r² =
  Δt²κ_h(¼ − β) < 1 (r = 0 for β ≥ ¼), so past the bound / (1 − min(r², 0.99)) it is not.
- **The last state of a chunk**, saved or not (``save_every`` may not divide the chunk, or
  be larger than the run): finite, and the two tests above.

An unstable run keeps its saved rows up to the last state that passed these tests, stepped
again from its chunk's start so that its running diagnostics (penetration, impacts) are
theirs, where the energy is a norm of the state (:meth:`Watch.norm`); where it is not (Δt
at or beyond the linear limit, massless rows) ½E_β can hide the growth until the chunk's
end, and the run keeps no row after the start of the chunk it was found in.

A redistributed mass (massless rows: M singular) leaves ½E_β indefinite on those rows
whatever Δt: there only finiteness and the loop's bound are checked."""
from __future__ import annotations

import math

import numpy as np

ROUND_OFF = 1e-9       # a saved energy below −ROUND_OFF × (bound + Watch.scale) is negative
R2_CAP = 0.99          # r² used at or beyond the linear limit (no bound there)


class Watch:
    """The checks above for one run (``run``: scheme.Run); ``bad(n0, n1, Ebound)`` after
    the chunk n0 → n1 (Ebound: the bound at n1): None, or (the state where it failed,
    why, the last saved state that passed them all)."""

    def __init__(self, run):
        self.run, self._kappa = run, None
        from ..spaces.redistribution import massless_rows
        self.definite = massless_rows(run.system.M).size == 0
        self.scale = self._terms(run.u_cur, run.u_prev)

    def _terms(self, u, u_prev) -> float:
        """½E_β's sums taken term by term in absolute value at (u, u_prev): what its
        round-off is relative to.  A state of zero energy that is not zero (a free plate at
        rest in a rigid mode, no load: the bound is 0) computes ½E_β = ±1e-17, not 0."""
        s, dt = self.run.system, self.run.dt
        d, a = np.abs(u - u_prev), 0.5 * np.abs(u + u_prev)
        M, K = abs(s.M), abs(s.K)
        beta = 0.25 if self.run.beta is None else self.run.beta
        return 0.5 * float(d @ (M @ d) / dt ** 2 + abs(beta - 0.25) * (d @ (K @ d))
                           + a @ (K @ a))

    def bad(self, n0: int, n1: int, Ebound: float):
        floor = -ROUND_OFF * (Ebound + self.scale)
        negative = self.negative(n0, n1)
        if negative is not None:
            return negative
        why = self._last_state(Ebound, floor)
        # the chunk's saved rows before n1 were not seen with this state's tests
        return None if why is None else (n1, why, n0 // self.run.save_every
                                         * self.run.save_every)

    def negative(self, n0: int, n1: int):
        """The first saved state of n0 < n ≤ n1 whose energy is negative, as ``bad``."""
        run, every = self.run, self.run.save_every
        if not self.definite:
            return None
        rows = np.arange(n0 // every + 1, n1 // every + 1)
        energy = np.asarray(run.energy[rows], dtype=float) if rows.size else rows
        bound = np.asarray(run.bound[rows], dtype=float) if rows.size else rows
        below = np.flatnonzero(energy < -ROUND_OFF * (bound + self.scale))  # each row's own
        if not below.size:
            return None
        k = int(rows[below[0]]) * every
        return k, f"energy {energy[below[0]]:.3g} < 0 (½E_β is positive while stable)", \
            k - every

    def _last_state(self, Ebound: float, floor: float) -> str | None:
        run = self.run
        u, u_prev = run.u_cur, run.u_prev
        if not (np.isfinite(u).all() and np.isfinite(u_prev).all()):
            return "the state is not finite"
        if run.beta is None or not self.definite:   # Moreau–Jean: ½vᵀMv + ½uᵀKu, the loop's
            return None
        s, dt = run.system, run.dt
        d, a = u - u_prev, 0.5 * (u + u_prev)
        kinetic = 0.5 * float(d @ (s.M @ d)) / dt ** 2
        # the structure's ½E_β (a penalty run saves its springs' energy besides)
        energy = kinetic + 0.5 * float((run.beta - 0.25) * (d @ (s.K @ d)) + a @ (s.K @ a))
        if not (math.isfinite(energy) and floor <= energy <= Ebound):
            return f"energy {energy:.3g} outside [0, {Ebound:.3g}]"
        if kinetic > Ebound and kinetic > Ebound / (1 - min(self._r2(), R2_CAP)):
            return f"kinetic energy {kinetic:.3g} above {Ebound:.3g}/(1 − r²)"
        return None

    def norm(self) -> bool:
        """Whether the saved energy is a norm of the state (Moreau–Jean's always; ½E_β
        with no massless rows and β ≥ ¼, or Δt below the linear limit, r² < 1, without
        penalty springs, whose stiffness that limit does not see): then every
        saved state that passed the loop's bound is a state of bounded energy, and an
        unstable run keeps its rows up to the last one (scheme.Run._unstable); else the
        growth can hide in it (module docstring) and they end at the chunk's start."""
        if self.run.beta is None:
            return True
        # penalty springs stiffen the structure beyond κ_h: below β = ¼ their limit is lower
        return self.definite and (self.run.beta >= 0.25 or not self.run.springs) \
            and self._r2() < 1.0

    def _r2(self) -> float:
        if self._kappa is None:
            from ..stability import kappa_h
            self._kappa = kappa_h(self.run.system)
        return self.run.dt ** 2 * self._kappa * max(0.25 - self.run.beta, 0.0)
