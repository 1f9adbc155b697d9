"""The driver of a run: a one-step integrator (:mod:`.beta`, :mod:`.moreau_jean`) taken
over the time grid in chunks, its saved rows (released once written), impact events,
checkpoints and restores, the same for every method."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..errors import Deferred, InputError, SolverError
from ..stability import kappa_h, linear_limit
from .kernels import (CONTACT_STEPS, EVENT_COLUMNS, EVENTS_FULL, EVENTS_WRITTEN, FAILED, ROW0,
                      STOPPED_AT, UNSTABLE, WORK_TERMS, Inputs, PythonLaw)
from .stepping import Named, Result
from .watch import ROUND_OFF, Watch

FIRST_ROWS = 1 << 15      # saved rows allocated at first; more as a chunk needs them
SAVED = ("obs", "obsv", "energy", "work", "lam", "resid", "bound")   # the saved series, by row


@dataclass(frozen=True)
class Record:
    """A run's tallies so far, as output reads them (``Run.record``): a snapshot, its
    arrays read-only copies that stay as they were while the run goes on.  Nothing outside
    ``scheme/`` reads the compiled loop's state; a tally output needs is added here.

    Per-row arrays have a row per constrained value (the system's C rows; m = 0 in one
    plane, where the loop keeps no per-row tallies).

    contact_steps      states so far with some constrained value in contact
    row_work           (m, 3) per row, in the units of energy: Σ its share of the contact
                       work ½μ(y^{n+1} − y^{n−1})/Δt² (impact work), Σ |F_n||v_t|Δt (normal
                       work, Archard's wear), Σ friction work
    sector_work        (m, SECTORS) per row: the normal work per 30° sector of the node's
                       angle in its hole, from −π (wear per sector)
    row_planes         (m, 2) each row's force direction in (v, w) (a face's normal, a round
                       hole's rows (1, 0) and (0, 1)): the net force per plane is λ @ it
    friction_tallied   whether row_work's friction column is this run's: the system has
                       friction, or its law solves round holes by Gauss–Seidel (Moreau–Jean),
                       which tallies it even at μ = 0
    friction_residual  the largest residual of the friction's Gauss–Seidel (NSGS) so far;
                       None for a law without one (position level: each block exact)
    work               the run's work sums so far, in the order of ``Run.work_terms``
                       (damping, input, contact, …), in the units of the saved energy
    """
    contact_steps: int
    row_work: np.ndarray
    sector_work: np.ndarray
    row_planes: np.ndarray
    friction_tallied: bool
    friction_residual: float | None
    work: np.ndarray


def _frozen(a) -> np.ndarray:
    """A read-only copy of ``a``."""
    a = np.array(a, dtype=float)
    a.flags.writeable = False
    return a


class SavedRows:
    """A saved series indexed by saved-row number k (state k·save_every), whatever rows
    the run has released: ``run.obs[k0:k1, 0]``, ``run.lam[rows + 1, 0]``."""

    def __init__(self, run, name: str):
        self.run, self.name = run, name

    def _rows(self, index):
        rows, rest = (index[0], index[1:]) if isinstance(index, tuple) else (index, ())
        row0 = self.run.row0
        if isinstance(rows, slice):
            start = row0 if rows.start is None else rows.start
            stop = self.run.n // self.run.save_every + 1 if rows.stop is None else rows.stop
            if stop <= start:
                return (slice(0, 0), *rest)
            if start < row0:
                raise IndexError(f"saved rows before {row0} were released")
            return (slice(start - row0, stop - row0, rows.step), *rest)
        rows = np.asarray(rows) - row0
        if np.any(rows < 0):
            raise IndexError(f"saved rows before {row0} were released")
        return (rows, *rest)

    def __getitem__(self, index):
        return getattr(self.run.out, self.name)[self._rows(index)]

    def __setitem__(self, index, value):
        rows = self._rows(index)[0]
        last = rows.stop - 1 if isinstance(rows, slice) else int(np.max(rows))
        self.run._hold_rows(last + self.run.row0)
        getattr(self.run.out, self.name)[self._rows(index)] = value


class Run:
    """A run of a one-step integrator ``scheme`` (:class:`.beta.BetaScheme`,
    :class:`.moreau_jean.MoreauJeanScheme`: each holds its system, its time grid and its
    law) over the grid, the same for every method; ``method.build(system, stepping)``
    (:mod:`.methods`) makes one.

    ``advance(n1)`` steps up to state n1; ``checkpoint()``/``restore()`` give the full
    state (the integrator's fields, warm starts, running diagnostics), so that a restored
    run continues bit for bit.  :func:`~skfem_beam.scheme.solve` drives it; the output
    pipeline drives it too when it streams files and writes checkpoints.
    """

    _next = ((-1, -1), None)   # the next chunk's (n0, n1) and inputs, computed ahead (advance)

    def __init__(self, scheme):
        with Deferred():           # signals wait while the kernels compile or load
            self._drive(scheme)

    def _drive(self, scheme) -> None:
        """Take ``scheme`` from its first state: buffers, the start, the compiled loop
        loaded outside the timed loop."""
        self.scheme, self.system, self.stepping = scheme, scheme.system, scheme.stepping
        self.dt, self.beta, self.theta = scheme.dt, scheme.beta, scheme.theta
        self.n_steps, self.save_every = scheme.n_steps, scheme.save_every
        self.frame_every = scheme.frame_every
        rows = min(self.n_steps // self.save_every + 1, FIRST_ROWS)   # grown as needed
        self.out = scheme.series(rows, self.n_steps // self.frame_every + 1)
        self.events = []       # impact event rows taken from the compiled loop's buffer
        self.load_bound = 0.0  # Σ‖Gⁿ‖_{N⁻¹}Δt so far: the a-priori energy bound grows with it
        self.wall = 0.0
        self.status, self.message = "running", ""
        self.n = scheme.start(self.out)     # the last computed state
        # the a-priori bound's start: the first state's energy, and a spring's compression
        self.E1 = float(self.out.energy[0]) + getattr(scheme, "stored_energy", float)()
        self.watch = Watch(self)
        self.over_budget = -1       # the first saved state above the a-priori bound itself
        self._steps(self.n, self.n)         # the compiled loop loaded (or compiled) here
        if self.n == 0:                     # a scheme that starts from the data itself
            self.advance(1)

    # the integrator's parts, for the scheme's own modules and the tests (output reads
    # ``record``, the saved series and ``impact_events``; tests/test_code_shape.py checks)
    st = property(lambda self: self.scheme.st)
    ops = property(lambda self: self.scheme.ops)
    op = property(lambda self: self.scheme.op)
    law = property(lambda self: self.scheme.law)
    solver = property(lambda self: self.scheme.solver)
    springs = property(lambda self: self.scheme.springs)
    pysolver = property(lambda self: self.scheme.pysolver)
    loads = property(lambda self: self.scheme.loads)
    load_norm = property(lambda self: self.scheme.load_norm)

    @property
    def record(self) -> Record:
        """The run's tallies so far (:class:`Record`): what output reads of the compiled
        loop, as a read-only snapshot."""
        st = self.st
        if getattr(self, "_row_planes", None) is None:    # fixed for the run: once
            from .beta import row_planes
            self._row_planes = _frozen(row_planes(self.ops.pair, self.ops.Nc))
        fres = getattr(st, "fres", None)
        return Record(contact_steps=int(st.counters[CONTACT_STEPS]),
                      row_work=_frozen(st.rowwork), sector_work=_frozen(st.sectors),
                      row_planes=self._row_planes,
                      friction_tallied=bool(st.fc.shape[0]) or "friction" in self.work_terms,
                      friction_residual=None if fres is None else float(fres[1]),
                      work=_frozen(st.work))

    @property
    def label(self) -> str:
        """"beta=…" for the β-scheme, "theta=…" for Moreau–Jean (for titles and messages)."""
        return f"theta={self.theta:g}" if self.theta is not None else f"beta={self.beta:g}"

    @property
    def work_terms(self) -> tuple[str, ...]:
        """The work terms of the run: WORK_TERMS, and "friction" when it has friction."""
        from .beta import friction
        return WORK_TERMS + (("friction",) if friction(self.system) else ())

    @property
    def stopped_at(self) -> int:
        """The step where the compiled loop last stopped (a failed step: the one after)."""
        return int(self.st.counters[STOPPED_AT])

    @property
    def row0(self) -> int:
        """The first saved row still held (rows before it were released)."""
        return int(self.st.counters[ROW0])

    def release(self, k: int) -> None:
        """Drop the saved rows before row k (their values were written elsewhere): memory
        then stays flat however long the run; ``obs[k0:k1]`` etc. keep their indices."""
        shift = min(int(k), self.n // self.save_every + 1) - self.row0
        if shift > 0:
            for name in SAVED:
                a = getattr(self.out, name)
                a[:len(a) - shift] = a[shift:]
            self.st.counters[ROW0] += shift

    def _hold_rows(self, last: int) -> None:
        """Room in the saved-series buffers for rows up to ``last`` (doubling)."""
        need = last - self.row0 + 1
        have = self.out.energy.shape[0]
        if need > have:
            size = max(need, 2 * have)
            grown = {}
            for name in SAVED:
                a = getattr(self.out, name)
                b = np.full((size,) + a.shape[1:], np.nan if name in ("obs", "obsv", "energy")
                            else np.inf if name == "bound" else 0.0)
                b[:have] = a
                grown[name] = b
            self.out = self.out._replace(**grown)

    def _steps(self, n0, n1, inputs=None):
        """The integrator's loop over steps n0..n1−1, with room for their saved rows."""
        self._hold_rows(n1 // self.save_every)
        return self.scheme.steps(self.out, n0, n1, inputs)

    def _chunk(self, n0, n1, inputs) -> int:
        """Steps n0..n1−1 (``inputs`` from n0), the impact events taken as they fill their
        buffer; the loop's stop code."""
        code = self._steps(n0, n1, inputs)
        while code == EVENTS_FULL:       # take the impact events, go on from where it stopped
            self._take_events()
            k = self.stopped_at - n0
            code = self._steps(self.stopped_at, n1,
                               Inputs(inputs.G[k:], inputs.phi[k:],
                                      inputs.H[k:] if inputs.H.shape[0] else inputs.H))
        self._take_events()
        return code

    def _snapshot(self) -> dict:
        """The integrator's state now (its CHECKPOINT fields, a Python law's warm start),
        the events so far; ``again``: False for a Python law that cannot save its state
        (stepping again would not give the same states)."""
        sc = self.scheme
        again = sc.pysolver is None or hasattr(sc.pysolver, "checkpoint")
        return {"st": {v: getattr(sc.st, v).copy() for v in sc.CHECKPOINT.values()},
                "solver": sc.pysolver.checkpoint() if sc.pysolver is not None and again
                else None, "events": len(self.events), "again": again}

    def _back_to(self, snap: dict) -> None:
        sc = self.scheme
        for v, a in snap["st"].items():
            getattr(sc.st, v)[...] = a
        sc.restored()
        if snap["solver"] is not None:
            sc.pysolver.restore(snap["solver"])
        del self.events[snap["events"]:]

    def _take_events(self) -> None:
        k = int(self.st.counters[EVENTS_WRITTEN])
        if k:
            self.events.append(self.out.events[:k].copy())
            self.st.counters[EVENTS_WRITTEN] = 0

    def _all_events(self) -> np.ndarray:
        return np.concatenate(self.events) if self.events else \
            np.zeros((0, len(EVENT_COLUMNS)))

    def impact_events(self, last: int | None = None) -> dict:
        """One row per impact of a constrained value so far: ``value`` (its index), ``x``,
        ``t_start``, ``t_end`` (the first state off the obstacle), ``velocity`` (approach
        velocity (yⁿ − yⁿ⁻¹)/Δt before contact), ``peak_force`` (max |λ|), ``impulse``
        (Σ λΔt; a round hole's: Σ|λ|Δt of its pair), ``max_violation`` (m), in the
        system's units, and ``open``: 1 for an event the loop still holds at the last state
        (``last``, default ``n``): in contact (t_end is then that state) or within the two
        states after t_end that a spring's trailing force reaches; its peak and impulse are
        those so far.  Two planes add ``angle`` (rad, of the node's offset from its hole's
        centre at the first state in contact), ``normal_velocity`` and
        ``tangential_velocity`` (m/s, the node's velocity before it, along the wall's
        outward normal and counter-clockwise along the wall), NaN in one plane; with
        friction ``slip`` (Σ|u_t|Δt, m) and ``friction_impulse`` (Σ|p_t|), else 0."""
        last = self.n if last is None else int(last)
        done = self._all_events()
        rows = [np.column_stack([done, np.zeros(len(done))])]
        open_ = self.st.impact[:, 0] >= 0
        if open_.any():
            j = np.flatnonzero(open_)
            e = self.st.impact[j]
            end = np.where(e[:, 5] >= 0, e[:, 5], last)
            rows.append(np.column_stack([j, e[:, 0], end, e[:, 1:5], e[:, 6:],
                                         np.ones(j.size)]))
        table = np.concatenate(rows)
        table = table[np.lexsort((table[:, 0], table[:, 1]))]
        x = np.asarray(self.system.x_contact, dtype=float)
        value = table[:, 0].astype(int)
        return {"value": value, "x": x[value], "t_start": table[:, 1] * self.dt,
                "t_end": table[:, 2] * self.dt,
                "velocity": self._relative(table[:, 3], value, table[:, 1]),
                "peak_force": table[:, 4], "impulse": table[:, 5], "max_violation": table[:, 6],
                "angle": table[:, 7], "normal_velocity": table[:, 8],
                "tangential_velocity": table[:, 9], "slip": table[:, 10],
                "friction_impulse": table[:, 11], "open": table[:, 12].astype(int)}

    def _relative(self, velocity, value, first):
        """The approach velocities (yⁿ − yⁿ⁻¹)/Δt of the values at their first state in
        contact ``first`` − 1, taken relative to their obstacle where it moves in the lifted
        variable (bounds + shift·φ(t)): the loop's are the lifted variable's, which a
        fixed stop under the static lifting saw 25 % slow and a carried one under the
        paper's 5× slow.  One plane (a hole's approach is normal_velocity)."""
        s, phi = self.system.bound_shift, self.system.bound_motion
        if phi is None or s is None or self.system.planes != 1 or not np.any(s[value]):
            return velocity
        moving = s[value] != 0
        t = (first[moving] - 1) * self.dt
        out = np.array(velocity, dtype=float)
        out[moving] -= s[value][moving] * (np.asarray(phi(t)) - np.asarray(phi(t - self.dt))) \
            / self.dt
        return out

    @property
    def done(self) -> bool:
        return self.status != "running"

    def advance(self, n1: int) -> None:
        """Compute states self.n+1 .. n1; sets ``status`` to "success" at N or "unstable"."""
        n0, n1 = self.n, min(int(n1), self.n_steps)
        if self.done or n1 <= n0:
            return
        t0 = time.perf_counter()
        with np.errstate(over="ignore", invalid="ignore"):     # a load's inf: refused below
            inputs = (self._next if self._next[0] == (n0, n1)
                      else self.scheme.inputs(n0, n1))[1]
        G = inputs.G
        Ebound = self._energy_bounds(G, n0, n1)
        # the state before the chunk: an unstable chunk is stepped again from it, up to its
        # last good state (_unstable)
        self._before = self._snapshot(), n0, inputs
        code = self._chunk(n0, n1, inputs)
        self._note_over_budget(n0, self.stopped_at if code == UNSTABLE else n1)
        if code == 0 and n1 < self.n_steps:
            # the next chunk's inputs now, while the writer thread may still be formatting
            # the last chunk's rows but has not got this one's: computed while it formats
            # them, they wait for the GIL it holds (measured: 2.5 s instead of 0.3 s over
            # 2,000,000 steps saved at every step)
            with np.errstate(over="ignore", invalid="ignore"):
                self._next = self.scheme.inputs(n1, min(2 * n1 - n0, self.n_steps))
        self.wall += time.perf_counter() - t0
        k = self.stopped_at
        if code == FAILED:
            error = PythonLaw.error if self.pysolver is not None else None   # this run's
            why = f": {error}" if error is not None else getattr(self.scheme, "failure", str)()
            if error is not None and not isinstance(error, SolverError):
                raise error               # a bug in a user's law: its own traceback
            # the last good state, whose diagnostics the run's are (its rows end at the last
            # saved state at or before it): written before the error is said
            self.n = max(self.n, k - 1)
            raise SolverError(f"the {self.solver} contact solver failed at step {k} "
                              f"(t={k * self.dt:.6g} s){why}")
        if code == UNSTABLE:
            early = self.watch.negative(n0, k)   # a negative energy, there or before
            if early is not None:
                return self._unstable(*early)
            row = k // self.save_every
            return self._unstable(k, f"|energy| {abs(self.energy[row]):.3g} exceeds "
                                  f"{self.out.bound[row - self.row0]:.3g}", (row - 1)
                                  * self.save_every)
        bad = self.watch.bad(n0, n1, Ebound)
        if bad is not None:
            return self._unstable(*bad)
        self.n = n1
        if n1 == self.n_steps:
            self.status, self.message = "success", "the run reached T"

    def check_loads(self, chunk: int) -> None:
        """The next chunk's loads, computed now (``advance`` takes them) and refused when
        too large for floats: a command calls it before its folder is made or emptied
        (found in the run, the refusal had removed an --overwrite's earlier run)."""
        n0, n1 = self.n, min(self.n + int(chunk), self.n_steps)
        if self.done or n1 <= n0:
            return
        with np.errstate(over="ignore", invalid="ignore"):
            self._next = self.scheme.inputs(n0, n1)
        self._load_work(self._next[1].G)

    def _load_work(self, G) -> np.ndarray:
        """The load's work bound after each step of a chunk whose loads are ``G`` (its work
        so far added, docs/design.md); a load too large for floats refused."""
        with np.errstate(over="ignore", invalid="ignore"):
            steps = (np.abs(G) @ self.load_norm) * self.dt if G.shape[1] \
                else np.zeros(G.shape[0])
            work = self.load_bound + np.cumsum(steps)
            last = float(work[-1]) if work.size else self.load_bound
            if not math.isfinite(self._bound(last)):
                raise InputError("the load is too large for floating point: its work by step "
                                 f"{self.n + G.shape[0]} is {last:g}" if math.isfinite(last)
                                 else "the load is too large for floating point: its work "
                                 "overflows")
        return work

    def _bound(self, work):
        """The a-priori energy bound after the load's work bound ``work`` (a number or an
        array): growth_limit (√(|E¹| + its round-off) + work)², + 1e-300; a product, not
        ``**``, so that a float too large gives inf, not an OverflowError."""
        root = math.sqrt(abs(self.E1) + ROUND_OFF * self.watch.scale) + work
        return self.stepping.growth_limit * root * root + 1e-300

    def _energy_bounds(self, G, n0: int, n1: int) -> float:
        """The a-priori energy bound of each saved state n0 < k ≤ n1 (n0 < n1), written
        beside its energy (Series.bound, which the loop tests), from the load's work up to
        k: a run is found unstable at the same state however it is cut into chunks
        (--flush-every moved it by up to 71 steps when the chunk's end value served every
        state in it).  Returns the bound at n1 (the last state's tests, Watch)."""
        work = self._load_work(G)
        self.load_bound = float(work[-1])
        with np.errstate(over="ignore"):
            bound = self._bound(work)
        if self.system.bound_motion is not None:
            # moving obstacles (a shaken support's, a carried hole) work on the structure
            # beyond the loads' bound: each state of the chunk keeps its end value, the
            # loosest (a chunk of 10 steps found a stable carried-hole run unstable)
            bound[:] = bound[-1]
        every = self.save_every
        k = np.arange((n0 // every + 1) * every, n1 + 1, every)
        self._hold_rows(n1 // every)
        self.out.bound[k // every - self.row0] = bound[k - n0 - 1]
        return float(bound[-1])

    def _note_over_budget(self, n0: int, n1: int) -> None:
        """The first saved state in (n0, n1] whose energy passes the a-priori bound itself
        (Series.bound / growth_limit: the energy the loads can have given), if none did
        before: an unstable run's rows from there on show the growth, which its line
        names (an unstable penalty run kept 500 rows of it, unmarked)."""
        if self.over_budget >= 0 or self.out.bound.size == 0:
            return
        every, limit = self.save_every, self.stepping.growth_limit
        rows = np.arange(n0 // every + 1, n1 // every + 1) - self.row0
        over = np.flatnonzero(~(np.abs(self.out.energy[rows]) * limit <= self.out.bound[rows]))
        if over.size:
            self.over_budget = int(rows[over[0]] + self.row0) * every

    def _unstable(self, k: int, why: str, good: int) -> None:
        """Stop as unstable at state ``k`` (``why``), keeping the saved states up to
        ``good`` (the last one that passed every test): the chunk is stepped again from
        its start to ``good`` (the same bits), so that the running diagnostics
        (penetration, impacts, contact steps) are those of the states kept."""
        snap, n0, inputs = self._before
        self._back_to(snap)
        if not (snap["again"] and self.watch.norm()) or good <= n0 \
                or self._chunk(n0, good, inputs) != 0:
            # the chunk's start: the energy is no norm (Watch.norm), a Python law without a
            # checkpoint, or a code ≠ 0 stepping again to good (not seen: the same states)
            # the run ends at the chunk's start, whose diagnostics those are (its rows at
            # the last saved state before it, as any run that save_every does not divide)
            self._back_to(snap)
            good, cut = n0, n0 < good
        else:
            cut = False
        self.status = "unstable"
        self.message = f"unstable at step {k} (t={k * self.dt:.6g} s): {why}; " \
            f"dt={self.dt:g} s, {self.label}"
        if cut:
            self.message += (f"; rows kept up to the chunk's start, step {good}: this "
                             "run's energy is no norm of its state (massless rows, Δt beyond "
                             "the linear limit, or penalty springs below β = 1/4) and can hide "
                             "the growth before")
        if 0 <= self.over_budget < k:
            self.message += (f"; its energy passed the loads' a-priori bound (√E¹ + their "
                             f"work)² at t={self.over_budget * self.dt:.6g} s: the rows from "
                             "there on show the instability's growth")
        if self.beta is not None:
            limit = linear_limit(kappa_h(self.system), self.beta)
            if math.isfinite(limit):        # β ≥ 1/4 has none
                self.message += f", linear stability limit 2/√(κ_h(1−4β)) = {limit:.4g} s"
                if self.springs:            # the limit a Δt below it went unstable under
                    self.message += " of the structure alone: the penalty springs lower it"
        self.n = good

    # the saved series by saved-row number (see SavedRows), as the output pipeline reads them
    obs = property(lambda self: SavedRows(self, "obs"))
    obsv = property(lambda self: SavedRows(self, "obsv"))
    energy = property(lambda self: SavedRows(self, "energy"))
    bound = property(lambda self: SavedRows(self, "bound"))     # each row's energy bound
    work = property(lambda self: SavedRows(self, "work"))
    lam = property(lambda self: SavedRows(self, "lam"))
    resid = property(lambda self: SavedRows(self, "resid"))
    fr = property(lambda self: self.out.frames_u)
    frv = property(lambda self: self.out.frames_v)
    frf = property(lambda self: self.out.frames_f)
    u_prev = property(lambda self: self.st.u_prev)
    u_cur = property(lambda self: self.st.u_cur)

    _FRAMES = {"fr": "frames_u", "frv": "frames_v", "frf": "frames_f"}

    def checkpoint(self) -> dict:
        """Everything needed to continue bit for bit: the integrator's state (its
        CHECKPOINT fields, and a Python-solved law's warm start), the events, the counters
        of the driver (saved series are the caller's; the field frames, a few hundred at
        most, come along so they can be written anew)."""
        sc = self.scheme
        solver = sc.pysolver
        if solver is not None and not hasattr(solver, "checkpoint"):
            raise InputError(f"checkpoints need a law that can save its state, not "
                             f"{self.solver!r}")
        saved = {k: getattr(sc.st, v).copy() for k, v in sc.CHECKPOINT.items()}
        if solver is not None:
            saved.update({f"solver_{k}": np.array(v) for k, v in solver.checkpoint().items()})
        return {**saved, **{k: getattr(self.out, v).copy() for k, v in self._FRAMES.items()},
                "events": self._all_events(), "n": self.n, "load_bound": self.load_bound,
                "wall": self.wall, "E1": self.E1, "frame_every": self.frame_every,
                "over_budget": self.over_budget}

    def restore(self, ck: dict) -> None:
        """Continue from ``checkpoint()``: of this run, or of the same run with a shorter
        T (extending it).  The checkpoint's frame spacing is kept, so its frames stay
        valid (a run extended to 2T keeps every frame_every-th step: twice the frames)."""
        every = int(ck.get("frame_every", self.frame_every))
        if every != self.frame_every:
            nframes, out = self.n_steps // every + 1, self.out
            self.frame_every = self.scheme.frame_every = every
            self.scheme.ops = self.ops._replace(frame_every=every)
            self.out = out._replace(**{v: np.full((nframes, getattr(out, v).shape[1]),
                                                  0.0 if v == "frames_f" else np.nan)
                                       for v in self._FRAMES.values()})
        sc = self.scheme
        for k, v in sc.CHECKPOINT.items():
            getattr(sc.st, v)[...] = ck[k]
        for k, v in self._FRAMES.items():
            getattr(self.out, v)[:len(ck[k])] = ck[k]
        sc.restored()
        if sc.pysolver is not None:
            sc.pysolver.restore({k[7:]: ck[k] for k in ck if k.startswith("solver_")})
        self.events = [np.asarray(ck["events"], dtype=float).reshape(-1, len(EVENT_COLUMNS))]
        self.n, self.load_bound, self.wall, self.E1 = int(ck["n"]), float(ck["load_bound"]), \
            float(ck["wall"]), float(ck["E1"])
        self.over_budget = int(ck.get("over_budget", -1))
        if self.n >= self.n_steps:       # a checkpoint at the last step: nothing to compute
            self.status, self.message = "success", "the run reached T"

    def result(self) -> Result:
        """The run so far (its saved series from ``row0``: all of them unless an output
        pipeline released the rows it wrote)."""
        first, keep = self.row0, self.n // self.save_every + 1 - self.row0
        nf = self.n // self.frame_every + 1
        names = list(self.system.observe)
        out, st, c = self.out, self.st.stats, self.st.counters
        obs, obsv = out.obs[:keep], out.obsv[:keep]
        return Result(
            t=np.arange(first, first + keep) * self.save_every * self.dt,
            observed=Named({k: obs[:, i] for i, k in enumerate(names)}),
            velocity=Named({k: obsv[:, i] for i, k in enumerate(names)}),
            energy=out.energy[:keep],
            contact_force=out.lam[:keep], frames_t=np.arange(nf) * self.frame_every * self.dt,
            frames_u=out.frames_u[:nf], frames_v=out.frames_v[:nf],
            frames_force=out.frames_f[:nf],
            status=self.status, message=self.message, steps=self.n, dt=self.dt,
            T=self.n_steps * self.dt, beta=self.beta, theta=self.theta, solver=self.solver, wall_time_s=self.wall,
            max_nodal_violation=float(max(st[0], 0.0)),
            max_penetration=float(max(st[1], st[2], st[0], 0.0)),
            max_penetration_below=float(st[1]), max_penetration_above=float(st[2]),
            impacts=int(c[0]), contact_fraction=float(c[1]) / max(1, self.n - 1 + getattr(
                self.scheme, "counts_state_one", 0)),
            qp_iterations=int(c[2]),
            work=Named({k: out.work[:keep, i] for i, k in enumerate(self.work_terms)}),
            impact_events=self.impact_events(), system=self.system,
            springs=self.springs)
