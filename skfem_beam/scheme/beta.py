"""The contact-implicit β-scheme as a one-step integrator: its operators, its state (by
field name), the start step, the loads of a chunk and the compiled loop over a chunk.
:class:`~skfem_beam.scheme.run.Run` drives it (chunks, saved rows, events, checkpoints)."""
from __future__ import annotations

import gc
import math
import sys
from contextlib import contextmanager
from dataclasses import replace
from types import FunctionType

import numpy as np
import scipy.sparse
from numba import typeof, types
from numba.core import event
from numba.core.dispatcher import LiftedCode

from .. import _startup
from ..checks import check_beta
from ..contact import ContactLaw, StepData, resolve
from ..contact.base import NoContact, no_explicit
from ..contact.registry import Auto
from ..contact.round_hole import disk_kinds
from ..errors import InputError, SolverError
from ..linalg import band_solve, row_layout_of, rows_matvec
from .kernels import (CONTACT_STEPS, FRICTION_COLUMN, IMPACT_FIELDS, NC_COLUMNS, SECTORS,
                      TANGENT_COLUMN, Inputs, Ops, PythonLaw, Series, State, csr_product,
                      energy_beta, friction_of_ops, lands_of, move_bounds, record, run_steps,
                      run_steps_python, saved_series, track_impacts)
from .operators import csr_arrays, load_norms, step_operators
from .stepping import Stepping

_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(4)
BAND_SOLVE = (types.float64[:, ::1], types.float64[::1])   # (Banded.chol, a vector)


class _CompileNotice(event.Listener):
    """One line on stderr, once per process, when numba starts compiling: the first run
    of a fresh install compiles the kernels (tens of seconds); later runs load them from
    numba's cache and compile nothing, so they say nothing.  The object-mode block through
    which the loop calls a law solved in Python (kernels.run_steps_python) cannot be cached
    and compiles in every run that reaches a contact (25 ms): it says nothing either."""
    said = False

    def on_start(self, ev):
        if isinstance((ev.data or {}).get("dispatcher"), LiftedCode):
            return
        if not _CompileNotice.said:
            _CompileNotice.said = True
            print("compiling numerical kernels (once per method and scene type; later runs "
                  "load them) …", file=sys.stderr, flush=True)

    def on_end(self, ev):
        pass


event.register("numba:compile", _CompileNotice())


class _LawAside(event.Listener):
    """At the first compile it sees, children compile the ``laws`` (contact.base.Compiled
    kernels)."""
    def __init__(self, laws):
        self.started, self.laws = False, laws

    def on_start(self, ev):
        if not self.started:
            self.started = True
            for kernel in self.laws:
                kernel.compile_aside()

    def on_end(self, ev):
        pass


@contextmanager
def _law_aside(laws):
    """While the step operators are built, or `band_solve` compiled: a first compile (a
    fresh install) sends ``laws`` (the law's kernels) aside.  A plate builds W without
    `band_solve` (operators.multi_rhs_W): BetaScheme compiles it once its law is set up,
    in this context, so that its law goes aside before the loop's compile (else nothing
    compiled before `start` and the law was not sent aside: 21 s on one core → 13 s).
    The loop's out-of-line callees (rows_matvec, energy_beta, ...) compile with the loop:
    a third process for them, on two cores, made every shipped scene's first run slower
    or no faster (docs/design.md, "The whole command")."""
    listener = _LawAside(tuple(laws))
    event.register("numba:compile", listener)
    try:
        yield
    finally:
        event.unregister("numba:compile", listener)


def uncompiled(kernel):
    """``kernel``'s Python function, its inlined helpers (``inline="always"``) called as
    Python functions too, recursively: the start step runs the loop's helpers uncompiled
    (BetaScheme.start), and a helper it called compiled on its own, apart from the loop
    that inlines it (`violation`, in a scene with holes: 0.4 CPU s of a first run).  What
    is compiled out of line (energy_beta, csr_product, ...) stays compiled: the loop's."""
    func = kernel.py_func
    names = func.__code__.co_names
    inlined = {n: uncompiled(v) for n, v in func.__globals__.items()
               if n in names and getattr(v, "targetoptions", {}).get("inline") == "always"}
    if not inlined:
        return func
    return FunctionType(func.__code__, {**func.__globals__, **inlined}, func.__name__,
                        func.__defaults__, func.__closure__)


def observers(system) -> scipy.sparse.csr_matrix:
    """The observed values' rows (tip displacement, probes, ...), one per row."""
    if system.observe:
        return scipy.sparse.csr_matrix(np.vstack(list(system.observe.values())))
    return scipy.sparse.csr_matrix((0, system.n))


def friction_of(system) -> np.ndarray:
    """Coulomb's μ per constrained row (a round hole's first row; 0 elsewhere)."""
    mu = getattr(system, "friction", None)
    return np.zeros(system.C.shape[0]) if mu is None else \
        np.ascontiguousarray(mu, dtype=float)


def friction(system) -> bool:
    """Whether some contact of the system has Coulomb friction (μ > 0)."""
    return bool(np.any(friction_of(system) > 0))


def refuse_moving_friction(system) -> None:
    """Coulomb friction at a hole that moves in the run's frame (carried by a moving
    support, or fixed while the support moves: the lifted frame moves it) is refused: the
    friction law takes its slip from the lifted u, not relative to the hole (a user's
    carried hole: its friction work 3,700× apart between two liftings)."""
    centres = getattr(system, "row_centres", None)      # per row [cy, cz, sy, sz]
    if system.bound_motion is None or centres is None or not len(centres):
        return
    moving = (friction_of(system) > 0) & np.any(np.asarray(centres)[:, 2:4] != 0.0, axis=1)
    if moving.any():
        x = float(system.x_contact[int(np.argmax(moving))])
        raise InputError(f"Coulomb friction at the hole at x={x:g}, which moves with the "
                         "support's motion (carried, or fixed while the support moves), is "
                         "not modelled: the friction law's slip is not taken relative to "
                         "the moving hole; drop its friction, or the [motion]")


def obstacle_rows(system) -> np.ndarray:
    """Per constrained row the obstacle giving its lo and its hi (SemiDiscrete.row_obstacle;
    unknown: (0, 2))."""
    rows = getattr(system, "row_obstacle", None)
    return np.zeros((0, 2), np.int64) if rows is None else \
        np.ascontiguousarray(rows, dtype=np.int64).reshape(-1, 2)


def disk_rows(system) -> np.ndarray:
    """The (q, 2) row pairs of the system's round holes (none: (0, 2))."""
    disks = getattr(system, "disks", None)
    return np.zeros((0, 2), np.int64) if disks is None else \
        np.ascontiguousarray(disks, dtype=np.int64).reshape(-1, 2)


def tangent_rows(system) -> np.ndarray:
    """The (k, 2) rows (face, its tangent row) of the faces with friction (none: (0, 2))."""
    tangents = getattr(system, "tangents", None)
    return np.zeros((0, 2), np.int64) if tangents is None else \
        np.ascontiguousarray(tangents, dtype=np.int64).reshape(-1, 2)


def land_rows(system) -> np.ndarray:
    """The (q, 3) lands of the system's disks (contact.lands; all round: (0, 3))."""
    lands = getattr(system, "lands", None)
    return np.zeros((0, 3)) if lands is None else \
        np.ascontiguousarray(lands, dtype=float).reshape(-1, 3)


def refuse_lands(system, law: str) -> None:
    """One line when ``law`` meets a broached hole (the round-hole laws' alone)."""
    if np.any(land_rows(system)[:, 0] > 0):
        raise InputError(f"broached holes (lands) need the exact round-hole law (solver "
                         f"auto, round-hole or round-hole-friction), not {law}")


def hole_arrays(system):
    """Ops' (pair, disks, Np, Ni, Nx, Nc) of ``system`` (kernels.Ops): the round holes'
    row pairs and first rows and, in two planes, each row's node and hole (one plane:
    empty; Nc's columns 6:9: a disk's first row's lands, kernels.violation).  A face's
    tangent row (friction) has pair −1, as a disk's second row, its direction t in Nc's
    columns 4:6 and its face's row the tangent row in TANGENT_COLUMN."""
    m = system.C.shape[0]
    disks = disk_rows(system)
    pair = disk_kinds(m, disks)
    first = np.ascontiguousarray(disks[:, 0])
    if getattr(system, "row_nodes", None) is None or not m:
        return (pair, first, np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros(0),
                np.zeros((0, NC_COLUMNS)))
    Nc = np.zeros((m, NC_COLUMNS))
    Nc[:, :4] = system.row_centres
    lands = land_rows(system)
    if lands.shape[0]:               # both rows of a pair: record skips its box
        Nc[first, 6:9] = lands
        Nc[pair[first], 6:9] = lands
    C = system.C.tocsr()
    for j in range(m):
        if pair[j] == 0:        # a face: its normal is its row on the node's (v, w)
            nv, nw = (system.row_nodes[2 * j + c].multiply(C[j]).sum() /
                      system.row_nodes[2 * j + c].multiply(system.row_nodes[2 * j + c]).sum()
                      for c in range(2))
            Nc[j, 4:6] = nv, nw
    for j, t in tangent_rows(system):
        pair[t] = -1
        Nc[j, TANGENT_COLUMN] = t
    return (pair, first, *csr_arrays(system.row_nodes), np.ascontiguousarray(Nc))


def row_planes(pair, Nc) -> np.ndarray:
    """(m, 2): each constrained row's force direction in (v, w) (its face's normal, or a
    round hole's rows (1, 0) and (0, 1)), so that the net contact force in each plane is
    λ @ row_planes; ``pair``, ``Nc``: the run's (kernels.Ops, :func:`hole_arrays`)."""
    m = pair.size
    out = np.array(Nc[:, 4:6]) if Nc.shape[0] else np.zeros((m, 2))
    for j in range(m):
        if pair[j] > 0:
            out[j], out[pair[j]] = (1.0, 0.0), (0.0, 1.0)
    return out


def two_plane_state(ops, nsgs: bool = False) -> dict:
    """State's pos, rowwork, sectors (rows × 4, 3, SECTORS in two planes; none in one),
    hk, and fc (rows × 6 for Moreau–Jean's round holes, ``nsgs``: contact.friction.nsgs
    keeps each contact's impulses, velocities and normal there; else none)."""
    m = ops.Nc.shape[0]
    return {"pos": np.zeros((m, 4)), "rowwork": np.zeros((m, 3)),
            "sectors": np.zeros((m, SECTORS)), "hk": np.zeros(4),
            "fc": np.zeros((ops.pair.size if nsgs else 0, 6))}


def start_positions(ops, st, u0, u1, phi=(0.0, 0.0)) -> None:
    """State.pos of states 0 and 1 (two planes): each row's node (v, w) in u⁰ and u¹ less
    its hole's centre at φ(t₀), φ(t₁) (``phi``: the bounds' motion; kernels.node_position)."""
    m = ops.Nc.shape[0]
    if m:
        nodes = scipy.sparse.csr_matrix((ops.Nx, ops.Ni, ops.Np), shape=(2 * m, u0.size))
        Nc = ops.Nc
        st.pos[:, :2] = (nodes @ u0).reshape(m, 2) - (Nc[:, 0:2] + Nc[:, 2:4] * phi[0])
        st.pos[:, 2:] = (nodes @ u1).reshape(m, 2) - (Nc[:, 0:2] + Nc[:, 2:4] * phi[1])


def penetration_samples(system):
    """CSR arrays of the penetration samples and their bounds (none: empty arrays)."""
    if system.sample_E is not None and system.sample_E.shape[0]:
        return (csr_arrays(system.sample_E), np.ascontiguousarray(system.sample_lo, dtype=float),
                np.ascontiguousarray(system.sample_hi, dtype=float))
    return (np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros(0)), np.zeros(0), np.zeros(0)


class BetaScheme:
    """The β-scheme of ``system`` on ``stepping`` with the contact law ``law`` (a name of
    ``contact.STEP_SOLVERS``, "auto", or a law object) and Newmark's ``beta`` (the β of
    the method that builds it: :class:`.methods.PositionLevel`, :class:`.methods.Penalty`)."""

    # checkpoint key → state field: what a restored run needs to go on bit for bit
    CHECKPOINT = {"u_prev": "u_prev", "u_cur": "u_cur", "state": "law_state",
                  "active_prev": "active_prev", "stats": "stats", "counters": "counters",
                  "lo": "lo", "hi": "hi", "slo": "slo", "shi": "shi", "work_sums": "work",
                  "impact": "impact", "pos": "pos", "rowwork": "rowwork", "sectors": "sectors"}

    def __init__(self, system, stepping: Stepping, law: str | ContactLaw = "auto",
                 beta: float = 0.5):
        s, m, beta = stepping, system.C.shape[0], check_beta(beta)
        self.system, self.stepping = system, s
        self.dt, self.beta, self.theta, self.n_steps = s.dt, beta, None, s.steps
        self.save_every, self.frame_every = s.save_every, s.frame_every
        self.shift = 0.5 * s.dt if s.load_window == "centered" else 0.0
        law = resolve(law) if not isinstance(law, ContactLaw) else law
        if isinstance(law, Auto) and m > 0:
            law = law.before_operators(system.n, system.C) or law
        x_space = law.x_space and m > 0   # no W, no D
        rows = StepData(None, system.C, None, np.ascontiguousarray(system.lo, dtype=float),
                        np.ascontiguousarray(system.hi, dtype=float), s.dt, beta,
                        disk_rows(system), land_rows(system), friction_of(system),
                        obstacle_rows(system), tangent_rows(system))
        # a law whose kernel its rows decide goes aside at the operators' first compile
        # (a fresh install's `band_solve`), not after them: 0.4 s sooner
        with _law_aside(law.kernels_for(rows) if m > 0 else ()):
            self.op = op = step_operators(system, s.dt, beta, s.massless, delassus=not x_space)
        self.step = replace(rows, A=op.A, C=op.C, D=op.D)
        self.law = law = self._law(law, m)
        if friction(system) and not law.friction:
            raise InputError(f"Coulomb friction needs law = round-hole-friction (or auto: "
                             f"exact contact at position level) or moreau-jean (a "
                             f"velocity-level law), not {law.name}")
        refuse_moving_friction(system)
        if law.name not in ("round-hole", "round-hole-friction"):
            refuse_lands(system, f"the {law.name} law")
        if self.step.disks.size and not law.round_holes:
            raise InputError(f"the {law.name} law takes flat faces only; round holes need "
                             "the exact round-hole law (solver auto or round-hole) or the "
                             "penalty law")
        self.solver, self.springs = law.name, law.springs
        params = law.setup(self.step)       # (it may choose the law's kernel)
        self.pysolver = law.solver(self.step) if law.kernel is None else None
        if op.Z.size and (law.kernel is None or law.explicit is not None):
            raise InputError(f"massless='quasi-static' needs an exact compiled contact law "
                             f"(projection, active-set, restitution), not {law.name!r}")
        with _law_aside(k for k in (law.kernel, law.explicit) if k is not None):
            # the start step's and the loop's `band_solve`, should step_operators not have
            # compiled it (a plate's W is one LAPACK solve; an x-space law has no W): a
            # fresh install then sends the law aside (a warm one loads it)
            band_solve.compile(BAND_SOLVE)
        self.loads = np.ascontiguousarray(system.loads, dtype=float)
        self.load_norm = load_norms(system, s.dt, beta)
        self.Orows = observers(system)
        self.ops = self._ops(params)
        self.st = self._state()
        # the loop's code for holes and massless rows: compiled for a run that has them
        # (with friction's work split only where some row has Coulomb's μ)
        self.holes = (self.st.hk, friction_of_ops(self.ops)) if self.ops.Nc.shape[0] else None
        self.massless = self.st.ez if self.ops.Zr.size else None
        self.lands = lands_of(self.ops)       # ... and for broached holes

    def _law(self, law: ContactLaw, m: int) -> ContactLaw:
        """The law to run: none without constraints; "auto" decided for this step."""
        if m == 0:
            return NoContact()
        return law.choose(self.step) if isinstance(law, Auto) else law

    def _ops(self, params) -> Ops:
        """The loop's constants (kernels.Ops)."""
        system, s, op, step = self.system, self.stepping, self.op, self.step
        samples, slo, shi = penetration_samples(system)
        moving = system.bound_motion is not None
        shift = np.ascontiguousarray(system.bound_shift, dtype=float) if moving else np.zeros(0)
        sshift = np.ascontiguousarray(system.sample_shift, dtype=float) \
            if moving and slo.size else np.zeros(0)
        return Ops(s.dt, self.beta, s.save_every, s.frame_every, *row_layout_of(op.Kb),
                   *row_layout_of(op.Bb), op.Ab.chol, *row_layout_of(op.Eb), self.loads,
                   *csr_arrays(op.C), step.lo, step.hi, shift, sshift,
                   op.W.T, op.D, *csr_arrays(self.Orows), *samples, slo, shi, params, op.Z,
                   *csr_arrays(system.K.tocsr()[op.Z]), *self._holes())

    def _holes(self):
        """hole_arrays, and Nc's column FRICTION_COLUMN ← each round hole's and each face's
        μ when the law takes friction (kernels.friction_split, face_friction_split: its
        work is then split off the contact's)."""
        arrays = hole_arrays(self.system)
        if self.law.friction and arrays[-1].shape[0]:
            first = np.concatenate([arrays[1], tangent_rows(self.system)[:, 0]])
            arrays[-1][first, FRICTION_COLUMN] = friction_of(self.system)[first]
        return arrays

    def _state(self) -> State:
        """The loop's state (kernels.State), by field name."""
        n, m, z = self.system.n, self.system.C.shape[0], np.zeros
        ops = self.ops
        return State(u_prev=np.empty(n), u_cur=np.empty(n), y_prev=np.empty(m),
                     y_cur=np.empty(m), lo=ops.lo.copy(), hi=ops.hi.copy(),
                     slo=ops.slo.copy(), shi=ops.shi.copy(), law_state=z(m, np.int8),
                     active=z(m, np.bool_), active_prev=z(m, np.bool_), stats=z(4),
                     counters=z(6, np.int64), work=z(4),
                     impact=np.full((m, IMPACT_FIELDS), -1.0), **two_plane_state(ops),
                     r_e=z(m), x=np.empty(n), yf=np.empty(m), mu=z(m), Ku=np.empty(n),
                     d=np.empty(n), dy=z(m), ez=z(self.op.Z.size))

    def series(self, rows: int, nframes: int) -> Series:
        """Saved-series buffers of ``rows`` rows and ``nframes`` field frames."""
        return saved_series(self.system, self.Orows, rows, nframes)

    @property
    def _kernels(self):
        """The compiled law and its explicit part (no-ops for a law solved in Python)."""
        return ((self.law.kernel or NoContact.kernel).cfunc,
                (self.law.explicit or no_explicit).cfunc)

    def _compile_side_by_side(self, out) -> None:
        """A fresh install (this process has compiled a kernel already, so numba's cache is
        cold) compiles the law in a child process while this one compiles the loop for
        these arrays' types; then it waits for the law (see contact.base.Compiled)."""
        if self.law.kernel is None or not _CompileNotice.said:
            return
        kernel, explicit = self.law.kernel, self.law.explicit or no_explicit
        # the types of the arguments exactly as _steps passes them: the same compiled loop
        loop = (types.FunctionType(kernel.signature), types.FunctionType(explicit.signature))
        args = (self.ops, self.st, out, 1, 1,
                Inputs(np.zeros((0, self.loads.shape[1])), np.zeros(0)), self.holes,
                self.massless, self.lands)
        loop += tuple(typeof(a) for a in args)
        if loop in run_steps.overloads:
            return
        for k in (self.law.kernel, self.law.explicit):
            if k is not None:
                k.compile_aside()
        run_steps.compile(loop)
        _ = self._kernels     # wait for the law: the start step calls what it compiled
        if _startup.COMMAND:
            # the millions of objects the compile left out of the collector's sight: its next
            # full collection walked them all (0.25 s of a broached tube's first run, in
            # writing its frames); a command ends with the run
            gc.freeze()

    def start(self, out) -> int:
        """u¹: one step of the scheme itself, from u⁰ and the fictitious u⁻¹ = u¹ − 2Δt v⁰
        (central difference at t = 0).  Substituted, it reads

            A u¹ = M(u⁰ + Δt v⁰) − Δt²/2 (1−2β) K u⁰ + βΔt³ K v⁰ − Δt²/2 B v⁰ + Δt²/2 f(0),

        second order and implicit in K: a rough u⁰ (u0'' ≠ 0 at a free end) pumps no
        energy into the top modes (an explicit Taylor start gave ½E_β¹ = 855 instead of
        166.8 for the energy-decay scene at J = 80, Δt = 1e-3); a rough v⁰ does: a mode
        with ωΔt ≫ 1 gets Δt·v⁰, not v⁰/ω, (ωΔt)² times its energy (the commands warn:
        cases._beam.warn_rough_start).  Its contact is the
        chosen law's (a spring's force at u⁰ weighted ½(1−2β), see contact.penalty).

        It runs the loop's helpers and the law as the Python functions they are compiled
        from (``py_func``, the law's ``func``), on the same arrays: one step, the same
        floating-point operations in the same order, so the same numbers; compiling them
        apart from the loop, which inlines them, cost 3–4 s on a fresh install.  What they
        call that is compiled (energy_beta, box_qp, ...) is shared with the loop.
        """
        self._compile_side_by_side(out)
        first_params = self.law.setup(self.step, first=True)
        u0 = self.system.u0.astype(float)
        self.st.u_prev[:] = u0
        u1 = self._first_free_step(u0, first_params)
        self._first_contact(u1, first_params)
        self._record_first_states(out)
        self._open_first_events(out)
        return 1

    def _open_first_events(self, out) -> None:
        """A value the start step's law held on its obstacle opens its event at state 1,
        with the velocity it had, C v⁰ (it opened at state 2 with velocity 0): the loop's
        track_impacts at step 0, without a force (state 1 records none)."""
        st = self.st
        if not self.first_active.any():
            return
        saved = st.active.copy(), st.dy.copy(), st.mu.copy(), st.counters[CONTACT_STEPS]
        v0 = np.zeros(st.mu.size)
        csr_product(self.ops.Cp, self.ops.Ci, self.ops.Cx, self.system.v0.astype(float), v0)
        st.active[:] = self.first_active
        st.dy[:] = st.y_cur - st.y_prev + self.dt * v0   # (yⁿ − yⁿ⁻¹)/Δt reads v0 at n = 0
        st.mu[:] = 0.0
        uncompiled(track_impacts)(self.ops, st, out, 0, self.lands)
        # the contact steps count states 2..n, over the n − 1 steps of t₁..tₙ (state 1
        # counted too, a run in contact from its start read contact_fraction n/(n − 1))
        (st.active[:], st.dy[:], st.mu[:], st.counters[CONTACT_STEPS]) = saved

    def _first_free_step(self, u0, first_params) -> np.ndarray:
        """The start step's solution without the law's multipliers (docstring of start)."""
        system, op, st = self.system, self.op, self.st
        dt, beta, M, K, B = self.dt, self.beta, system.M, system.K, system.B
        v0 = system.v0.astype(float)
        f0 = self.loads @ np.array([float(a(np.array([0.0]))[0]) for a in system.load_time]) \
            if self.loads.shape[1] else np.zeros(system.n)
        F0 = M @ (u0 + dt * v0) - 0.5 * dt**2 * (1 - 2 * beta) * (K @ u0) \
            + beta * dt**3 * (K @ v0) + 0.5 * dt**2 * f0
        if B is not None:
            F0 -= 0.5 * dt**2 * (B @ v0)
            # the step's factor carries Δt/2·B u¹, which the start's equation has not (its
            # u⁻¹ = u¹ − 2Δt v⁰ makes the damping B v⁰): its part Δt/2·B(u⁰ + Δt v⁰), to
            # O(Δt³).  Without it a damped start from a non-uniform u⁰ got the velocity
            # −½M⁻¹B u⁰ at no cost of Δt: 3 % of a viscous bar's mode, whatever N and Δt
            d = B @ (u0 + dt * v0)
            if np.any(d):
                F0 += 0.5 * dt * d
        if op.Z.size:   # quasi-static massless rows: K u¹ = f¹ + Cᵀλ¹ there, times β
            F0[op.Z] = beta * dt**2 * (self.loads[op.Z] @ self.load_averages(1, 1)[1])
        csr_product(self.ops.Cp, self.ops.Ci, self.ops.Cx, u0, st.y_prev)
        uncompiled(move_bounds)(self.ops, st, self.motion(np.array([dt]))[0])   # bounds at t₁
        if self.law.explicit is not None:   # its force at u⁰ as load, implicit at u¹ (as K)
            self.law.explicit.func(st.y_prev, st.y_prev, st.lo, st.hi, first_params, st.r_e)
            F0 += dt**2 * (op.C.T @ st.r_e)
            st.r_e[:] = 0.0
        band_solve(op.Ab.chol, F0)
        return F0

    def _first_contact(self, u1, first_params) -> None:
        """u¹ = the free solution + W μ with the chosen law's μ (state 1 records no
        contact force)."""
        op, st = self.op, self.st
        self.first_active = np.zeros(st.mu.size, dtype=bool)
        if st.mu.size:
            st.x[:] = u1
            csr_product(self.ops.Cp, self.ops.Ci, self.ops.Cx, u1, st.yf)
            if self.pysolver is not None:
                mu, _ = self.pysolver.solve(u1, st.yf.copy(), st.lo, st.hi)
                st.mu[:] = mu
                self.first_active[:] = st.mu != 0.0
            else:
                st.y_cur[:] = st.y_prev
                if self.law.kernel.func(self.ops.D, st.yf, st.y_cur, st.y_prev, st.lo, st.hi,
                                        first_params, st.law_state, st.mu, st.active) < 0:
                    raise SolverError("the first step's contact problem could not be solved")
                st.law_state[:] = 0
                self.first_active[:] = st.active
                st.active[:] = False
            if op.W.shape[1] == st.mu.size:     # else an x-space law wrote u¹ into u1
                # W in C order: the BLAS call, and so the bits, of the pinned runs; with
                # no contact W·0 is +0.0 everywhere, added without a copy of W
                u1 = u1 + (np.ascontiguousarray(op.W) @ st.mu if st.mu.any() else 0.0)
        st.u_cur[:] = u1
        csr_product(self.ops.Cp, self.ops.Ci, self.ops.Cx, u1, st.y_cur)
        st.mu[:] = 0.0

    def _record_first_states(self, out) -> None:
        """States 0 and 1 (E_β needs two states: the energy saved at t = 0 is E_β¹)."""
        system, op, st, Orows = self.system, self.op, self.st, self.Orows
        start_positions(self.ops, st, st.u_prev, st.u_cur,
                        self.motion(np.array([0.0, self.dt])))
        out.obs[0] = Orows @ st.u_prev
        out.obsv[0] = Orows @ system.v0
        rows_matvec(op.Kb.rows, op.Kb.cols, st.u_prev, st.Ku, 1.0, False)   # K uⁿ⁻¹: energy
        uncompiled(record)(1, self.ops, st, out, self.lands)
        out.frames_u[0], out.frames_v[0] = st.u_prev, system.v0
        self.E1 = 0.5 * energy_beta(op.Eb.rows, op.Eb.cols, st.u_prev, st.u_cur, st.Ku, st.d)
        if not (np.isfinite(st.u_cur).all() and math.isfinite(self.E1)):
            raise InputError("the initial state and load are too large for floating point: "
                             f"the first step's energy is {self.E1:g}")
        out.energy[0] = self.E1

    def data_energy(self) -> float:
        """½v⁰ᵀMv⁰ + ½u⁰ᵀKu⁰: the initial data's energy, which the start's ½E_β¹ should not
        pass (cases._beam.warn_rough_start)."""
        u0, v0 = self.system.u0.astype(float), self.system.v0.astype(float)
        return 0.5 * float(v0 @ (self.system.M @ v0) + u0 @ (self.system.K @ u0))

    def stored_energy(self) -> float:
        """The penalty springs' energy at the start (0 for other laws): the a-priori energy
        bound (Run._bound) adds it, else a bar released from a compressed spring was found
        unstable at step 3 (its structure's energy grew from 3e-5 to the spring's 0.025)."""
        stored = getattr(self.law, "stored", None)
        if stored is None or not self.step.lo.size:
            return 0.0
        shift = self.system.bound_shift if self.system.bound_shift is not None else 0.0
        move = shift * float(self.motion(np.array([0.0]))[0])
        return stored(self.step, self.system.C @ self.system.u0.astype(float),
                      self.step.lo + move, self.step.hi + move)

    def motion(self, t):
        """φ(t) that moves the bounds (zero when they do not move)."""
        phi = self.system.bound_motion
        return np.asarray(phi(t), dtype=float) if phi is not None else np.zeros(np.shape(t))

    def inputs(self, n0, n1):
        """((n0, n1), Inputs of steps n0..n1−1): loads, bound motion, massless-row load."""
        G = self.load_coefficients(n0, n1)
        return (n0, n1), Inputs(G, self.motion(np.arange(n0 + 1, n1 + 1) * self.dt),
                                self.massless_load(n0, n1))

    def load_coefficients(self, n0, n1):
        """Gⁿ = βf^{n+1} + (1−2β)fⁿ + βf^{n−1} for n = n0..n1−1 (per chunk: flat memory)."""
        if not self.loads.shape[1]:
            return np.zeros((n1 - n0, 0))
        f, beta = self.load_averages(n0, n1), self.beta
        return np.ascontiguousarray(beta * f[2:] + (1 - 2 * beta) * f[1:-1] + beta * f[:-2])

    def massless_load(self, n0, n1):
        """The load at the quasi-static massless rows, (1−2β)fⁿ + βf^{n−1} there, for
        n = n0..n1−1 (kernels.massless_force); none without such rows or loads."""
        Z = self.op.Z
        if not (Z.size and self.loads.shape[1]):
            return np.zeros((0, Z.size))
        f, beta = self.load_averages(n0, n1), self.beta
        return np.ascontiguousarray(((1 - 2 * beta) * f[1:-1] + beta * f[:-2]) @ self.loads[Z].T)

    def load_averages(self, n0, n1):
        """fᵐ_k, m = n0−1..n1: the load functions averaged over each step's window."""
        nk = self.loads.shape[1]
        dt = self.dt
        t = np.arange(n0 - 1, n1 + 1) * dt - self.shift
        f = np.empty((t.size, nk))
        for b in range(0, t.size, 4096):   # blocks that stay in cache: 1.7× faster (measured)
            s = t[b:b + 4096] + 0.5 * dt * (1.0 + _GAUSS_X[:, None])   # 4 Gauss points/step
            for k, a in enumerate(self.system.load_time):
                # fⁿ = (1/Δt)∫ f dt, exact to O((ωΔt)⁸); summed elementwise, so that a value
                # does not depend on where the chunk starts (a resumed run goes on bit for bit)
                v = np.asarray(a(s), dtype=float)
                f[b:b + 4096, k] = (_GAUSS_W[0] * v[0] + _GAUSS_W[1] * v[1]
                                    + _GAUSS_W[2] * v[2] + _GAUSS_W[3] * v[3]) / 2.0
        return f

    def failure(self) -> str:
        """Why a step failed, where its law says (its ``failure``), for the run's line."""
        why = getattr(self.law, "failure", "")
        return f": {why}" if isinstance(why, str) and why else ""

    def steps(self, out, n0, n1, inputs=None):
        """The compiled loop over steps n0..n1−1 (see kernels.run_steps)."""
        if inputs is None:
            inputs = Inputs(np.zeros((0, self.loads.shape[1])), np.zeros(0),
                            np.zeros((0, self.op.Z.size)))
        if self.pysolver is None:
            try:
                return run_steps(*self._kernels, self.ops, self.st, out, n0, n1, inputs,
                                 self.holes, self.massless, self.lands)
            except TypeError as e:
                # numba 0.68: a Ctrl-C landing while the dispatcher unboxes the law's C
                # callback surfaces as this TypeError (seen once in CI): it is the interrupt
                if "_get_wrapper_address" in str(e):
                    raise KeyboardInterrupt from e
                raise
        PythonLaw.solver, PythonLaw.state, PythonLaw.error = self.pysolver, self.st, None
        try:
            return run_steps_python(self.ops, self.st, out, n0, n1, inputs,
                                    bool(getattr(self.law, "free_inside", True)), self.holes,
                                    self.massless, self.lands)
        finally:
            PythonLaw.solver = PythonLaw.state = None

    def restored(self) -> None:
        """After the checkpoint's fields were put back: C uⁿ⁻¹, C uⁿ from them."""
        ops, st = self.ops, self.st
        csr_product(ops.Cp, ops.Ci, ops.Cx, st.u_prev, st.y_prev)
        csr_product(ops.Cp, ops.Ci, ops.Cx, st.u_cur, st.y_cur)
