"""One integration of a system: the start step, chunks of steps, checkpoints."""
from __future__ import annotations

import math
import sys
import time

import numpy as np
import scipy.sparse
from numba import typeof, types
from numba.core import event

from ..contact import ContactLaw, StepData, resolve
from ..contact.base import NoContact, no_explicit
from ..contact.registry import Auto
from ..errors import InputError, SolverError
from ..linalg import band_solve, rows_matvec
from ..stability import kappa_h, linear_limit
from .kernels import (EVENTS_FULL, FAILED, UNSTABLE, WORK_TERMS, Inputs, Ops, PythonLaw,
                      Series, State, csr_product, energy_beta, move_bounds, record, run_steps,
                      run_steps_python)
from .operators import csr_arrays, load_norms, step_operators
from .stepping import Result, Stepping

_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(4)
FIRST_ROWS = 1 << 15      # saved rows allocated at first; more as a chunk needs them
SAVED = ("obs", "obsv", "energy", "work", "lam")   # the saved series (rows × columns)


class _CompileNotice(event.Listener):
    """One line on stderr, once per process, when numba starts compiling: the first run
    of a fresh install compiles the kernels (tens of seconds); later runs load them from
    numba's cache and compile nothing, so they say nothing."""
    said = False

    def on_start(self, ev):
        if not _CompileNotice.said:
            _CompileNotice.said = True
            print("compiling numerical kernels (first run only) …", file=sys.stderr, flush=True)

    def on_end(self, ev):
        pass


event.register("numba:compile", _CompileNotice())


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
    """The scheme's state and saved series for ``system`` on the grid ``stepping``,
    with the contact law ``law`` (a name of ``contact.LAWS``, "auto", or a law object).

    ``advance(n1)`` steps up to state n1; ``checkpoint()``/``restore()`` give the full
    state (uⁿ⁻¹, uⁿ, step, warm starts, running diagnostics), so that a restored run
    continues bit for bit.  :func:`~skfem_beam.scheme.solve` drives it; the output
    pipeline drives it too when it streams files and writes checkpoints.
    """

    _next = ((-1, -1), None)   # the next chunk's (n0, n1) and inputs, computed ahead (advance)

    def __init__(self, system, stepping: Stepping, law: str | ContactLaw = "auto"):
        self._build(system, stepping, law)

    def _build(self, system, stepping, law) -> None:
        """Operators, the law, the state and buffers, the start step (a subclass with
        another integrator, e.g. Moreau–Jean, builds its own)."""
        s, m = stepping, system.C.shape[0]
        n_steps = s.steps
        self.system, self.stepping = system, s
        self.dt, self.beta, self.n_steps = s.dt, s.beta, n_steps
        self.save_every, self.frame_every = s.save_every, s.frame_every
        self.shift = 0.5 * s.dt if s.load_window == "centered" else 0.0
        self.op = op = step_operators(system, s.dt, s.beta, s.massless)
        step = StepData(op.A, op.C, op.D, np.ascontiguousarray(system.lo, dtype=float),
                        np.ascontiguousarray(system.hi, dtype=float), s.dt, s.beta)
        law = resolve(law) if not isinstance(law, ContactLaw) else law
        if m == 0:
            law = NoContact()
        elif isinstance(law, Auto):
            law = law.choose(step)
        self.law, self.solver = law, law.name
        params = law.setup(step)
        self.pysolver = law.solver(step) if law.kernel is None else None
        if op.Z.size and (law.kernel is None or law.explicit is not None):
            raise InputError(f"massless='quasi-static' needs an exact compiled contact law "
                             f"(projection, active-set, restitution), not {law.name!r}")

        self.loads = np.ascontiguousarray(system.loads, dtype=float)
        self.load_norm = load_norms(system, s.dt, s.beta)
        Orows = scipy.sparse.csr_matrix(np.vstack(list(system.observe.values()))) \
            if system.observe else scipy.sparse.csr_matrix((0, system.n))
        if system.sample_E is not None and system.sample_E.shape[0]:
            samples = csr_arrays(system.sample_E)
            slo = np.ascontiguousarray(system.sample_lo, dtype=float)
            shi = np.ascontiguousarray(system.sample_hi, dtype=float)
        else:
            samples = (np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros(0))
            slo = shi = np.zeros(0)
        moving = system.bound_motion is not None
        if moving and self.pysolver is not None:
            raise InputError(f"solver={law.name!r} is set up for bounds at rest; with obstacles "
                             f"that move with a support use active-set or projection")
        shift = np.ascontiguousarray(system.bound_shift, dtype=float) if moving else np.zeros(0)
        sshift = np.ascontiguousarray(system.sample_shift, dtype=float) \
            if moving and slo.size else np.zeros(0)
        self.ops = Ops(s.dt, s.beta, s.save_every, s.frame_every, op.Kb.rows, op.Bb,
                       op.Ab.chol, op.Eb.rows, self.loads, *csr_arrays(op.C), step.lo, step.hi,
                       shift, sshift, op.W, op.D, *csr_arrays(Orows), *samples, slo, shi, params,
                       op.Z, *csr_arrays(system.K.tocsr()[op.Z]))
        n = system.n
        self.st = State(np.empty(n), np.empty(n), np.empty(m), np.empty(m),
                        step.lo.copy(), step.hi.copy(), slo.copy(), shi.copy(),
                        np.zeros(m, np.int8), np.zeros(m, np.bool_), np.zeros(m, np.bool_),
                        np.zeros(4), np.zeros(6, np.int64), np.zeros(3),
                        np.full((m, 6), -1.0), np.zeros(m),
                        np.empty(n), np.empty(m), np.zeros(m), np.empty(n), np.empty(n),
                        np.zeros(m), np.zeros(op.Z.size))
        nframes, nobs = n_steps // s.frame_every + 1, Orows.shape[0]
        rows = min(n_steps // s.save_every + 1, FIRST_ROWS)   # grown as the run needs them
        self.out = Series(np.full((rows, nobs), np.nan), np.full((rows, nobs), np.nan),
                          np.full(rows, np.nan), np.zeros((rows, 3)), np.zeros((rows, m)),
                          np.full((nframes, n), np.nan), np.full((nframes, n), np.nan),
                          np.zeros((nframes, m)), np.zeros((max(4096, 4 * m), 7)))
        self.events = []       # impact event rows taken from the compiled loop's buffer
        self._compile_side_by_side()
        self._start(Orows, law.setup(step, first=True))
        self.load_bound = 0.0  # Σ‖Gⁿ‖_{N⁻¹}Δt so far: the a-priori energy bound grows with it
        self.n = 1             # the last computed state
        self.wall = 0.0
        self.status, self.message = "running", ""
        self._steps(1, 1, 0.0)   # load the compiled loop now, outside the timed loop

    @property
    def _kernels(self):
        """The compiled law and its explicit part (no-ops for a law solved in Python)."""
        return ((self.law.kernel or NoContact.kernel).cfunc,
                (self.law.explicit or no_explicit).cfunc)

    def _compile_side_by_side(self) -> None:
        """A fresh install (this process has compiled a kernel already, so numba's cache is
        cold) compiles the law in a child process while this one compiles the loop for
        these arrays' types; then it waits for the law (see contact.base.Compiled)."""
        if self.law.kernel is None or not _CompileNotice.said:
            return
        kernel, explicit = self.law.kernel, self.law.explicit or no_explicit
        # the types of the arguments exactly as _steps passes them: the same compiled loop
        loop = (types.FunctionType(kernel.signature), types.FunctionType(explicit.signature))
        args = (self.ops, self.st, self.out, 1, 1,
                Inputs(np.zeros((0, self.loads.shape[1])), np.zeros(0)), 0.0)
        loop += tuple(typeof(a) for a in args)
        if loop in run_steps.overloads:
            return
        for k in (self.law.kernel, self.law.explicit):
            if k is not None:
                k.compile_aside()
        run_steps.compile(loop)
        _ = self._kernels     # wait for the law: the start step calls what it compiled

    def _start(self, Orows, first_params) -> None:
        """u¹: one step of the scheme itself, from u⁰ and the fictitious u⁻¹ = u¹ − 2Δt v⁰
        (central difference at t = 0).  Substituted, it reads

            A u¹ = M(u⁰ + Δt v⁰) − Δt²/2 (1−2β) K u⁰ + βΔt³ K v⁰ − Δt²/2 B v⁰ + Δt²/2 f(0),

        second order and implicit in K: rough data (u0'' ≠ 0 at a free end) pump no
        energy into the top modes (an explicit Taylor start gave ½E_β¹ = 855 instead of
        166.8 for the energy-decay scene at J = 80, Δt = 1e-3).  Its contact is the
        chosen law's (a spring's force at u⁰ weighted ½(1−2β), see contact.penalty).

        It runs the loop's helpers and the law as the Python functions they are compiled
        from (``py_func``, the law's ``func``), on the same arrays: one step, the same
        floating-point operations in the same order, so the same numbers; compiling them
        apart from the loop, which inlines them, cost 3–4 s on a fresh install.  What they
        call that is compiled (energy_beta, box_qp, ...) is shared with the loop.
        """
        system, op, st, out = self.system, self.op, self.st, self.out
        dt, beta, M, K, B = self.dt, self.beta, system.M, system.K, system.B
        u0, v0 = system.u0.astype(float), system.v0.astype(float)
        st.u_prev[:] = u0
        f0 = self.loads @ np.array([float(a(np.array([0.0]))[0]) for a in system.load_time]) \
            if self.loads.shape[1] else np.zeros(system.n)
        F0 = M @ (u0 + dt * v0) - 0.5 * dt**2 * (1 - 2 * beta) * (K @ u0) \
            + beta * dt**3 * (K @ v0) + 0.5 * dt**2 * f0
        if B is not None:
            F0 -= 0.5 * dt**2 * (B @ v0)
        if op.Z.size:   # quasi-static massless rows: K u¹ = f¹ + Cᵀλ¹ there, times β
            F0[op.Z] = beta * dt**2 * (self.loads[op.Z] @ self.load_averages(1, 1)[1])
        csr_product(self.ops.Cp, self.ops.Ci, self.ops.Cx, u0, st.y_prev)
        move_bounds.py_func(self.ops, st, self.motion(np.array([dt]))[0])   # bounds at t₁
        if self.law.explicit is not None:   # its force at u⁰ as load, implicit at u¹ (as K)
            self.law.explicit.func(st.y_prev, st.y_prev, st.lo, st.hi, first_params, st.r_e)
            F0 += dt**2 * (op.C.T @ st.r_e)
            st.r_e[:] = 0.0
        u1 = F0.copy()
        band_solve(op.Ab.chol, u1)
        if st.mu.size:
            st.x[:] = u1
            csr_product(self.ops.Cp, self.ops.Ci, self.ops.Cx, u1, st.yf)
            if self.pysolver is not None:
                mu, _ = self.pysolver.solve(u1, st.yf.copy())
                st.mu[:] = mu
            else:
                st.y_cur[:] = st.y_prev
                if self.law.kernel.func(self.ops.D, st.yf, st.y_cur, st.y_prev, st.lo, st.hi,
                                        first_params, st.law_state, st.mu, st.active) < 0:
                    raise SolverError("the first step's contact problem could not be solved")
                st.law_state[:] = 0
                st.active[:] = False
            u1 = u1 + op.W @ st.mu
        st.u_cur[:] = u1
        csr_product(self.ops.Cp, self.ops.Ci, self.ops.Cx, u1, st.y_cur)
        st.mu[:] = 0.0     # state 1 records no contact force

        # states 0 and 1 (E_β needs two states: the energy saved at t = 0 is E_β¹)
        out.obs[0] = Orows @ st.u_prev
        out.obsv[0] = Orows @ system.v0
        rows_matvec(op.Kb.rows, st.u_prev, st.Ku, 1.0, False)   # K uⁿ⁻¹ for the energy
        record.py_func(1, self.ops, st, out)
        out.frames_u[0], out.frames_v[0] = st.u_prev, system.v0
        self.E1 = 0.5 * energy_beta(op.Eb.rows, st.u_prev, st.u_cur, st.Ku, st.d)
        if not (np.isfinite(st.u_cur).all() and math.isfinite(self.E1)):
            raise InputError("the initial state and load are too large for floating point: "
                             f"the first step's energy is {self.E1:g}")
        out.energy[0] = self.E1

    def motion(self, t):
        """φ(t) that moves the bounds (zero when they do not move)."""
        phi = self.system.bound_motion
        return np.asarray(phi(t), dtype=float) if phi is not None else np.zeros(np.shape(t))

    def _inputs(self, n0, n1):
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

    @property
    def row0(self) -> int:
        """The first saved row still held (rows before it were released)."""
        return int(self.st.counters[5])

    def release(self, k: int) -> None:
        """Drop the saved rows before row k (their values were written elsewhere): memory
        then stays flat however long the run; ``obs[k0:k1]`` etc. keep their indices."""
        shift = min(int(k), self.n // self.save_every + 1) - self.row0
        if shift > 0:
            for name in SAVED:
                a = getattr(self.out, name)
                a[:len(a) - shift] = a[shift:]
            self.st.counters[5] += shift

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
                            else 0.0)
                b[:have] = a
                grown[name] = b
            self.out = self.out._replace(**grown)

    def _steps(self, n0, n1, Ebound, inputs=None):
        """The compiled loop over steps n0..n1−1 (see kernels.run_steps)."""
        self._hold_rows(n1 // self.save_every)
        if inputs is None:
            inputs = Inputs(np.zeros((0, self.loads.shape[1])), np.zeros(0),
                            np.zeros((0, self.op.Z.size)))
        if self.pysolver is None:
            try:
                return run_steps(*self._kernels, self.ops, self.st, self.out, n0, n1, inputs,
                                 Ebound)
            except TypeError as e:
                # numba 0.68: a Ctrl-C landing while the dispatcher unboxes the law's C
                # callback surfaces as this TypeError (seen once in CI): it is the interrupt
                if "_get_wrapper_address" in str(e):
                    raise KeyboardInterrupt from e
                raise
        PythonLaw.solver, PythonLaw.state, PythonLaw.error = self.pysolver, self.st, None
        try:
            return run_steps_python(self.ops, self.st, self.out, n0, n1, inputs, Ebound)
        finally:
            PythonLaw.solver = PythonLaw.state = None

    def _take_events(self) -> None:
        k = int(self.st.counters[4])
        if k:
            self.events.append(self.out.events[:k].copy())
            self.st.counters[4] = 0

    def _all_events(self) -> np.ndarray:
        return np.concatenate(self.events) if self.events else np.zeros((0, 7))

    def impact_events(self, last: int | None = None) -> dict:
        """One row per impact of a constrained value so far: ``value`` (its index), ``x``,
        ``t_start``, ``t_end`` (the first state off the obstacle), ``velocity`` (approach
        velocity (yⁿ − yⁿ⁻¹)/Δt before contact), ``peak_force`` (max |λ|), ``impulse``
        (Σ λΔt), ``max_violation`` (m), in the system's units, and ``open``: 1 for an
        event the loop still holds at the last state (``last``, default ``n``): in contact
        (t_end is then that state) or within the two states after t_end that a spring's
        trailing force reaches; its peak and impulse are those so far."""
        last = self.n if last is None else int(last)
        done = self._all_events()
        rows = [np.column_stack([done, np.zeros(len(done))])]
        open_ = self.st.impact[:, 0] >= 0
        if open_.any():
            j = np.flatnonzero(open_)
            e = self.st.impact[j]
            end = np.where(e[:, 5] >= 0, e[:, 5], last)
            rows.append(np.column_stack([j, e[:, 0], end, e[:, 1:5], np.ones(j.size)]))
        table = np.concatenate(rows)
        table = table[np.lexsort((table[:, 0], table[:, 1]))]
        x = np.asarray(self.system.x_contact, dtype=float)
        value = table[:, 0].astype(int)
        return {"value": value, "x": x[value], "t_start": table[:, 1] * self.dt,
                "t_end": table[:, 2] * self.dt, "velocity": table[:, 3],
                "peak_force": table[:, 4], "impulse": table[:, 5], "max_violation": table[:, 6],
                "open": table[:, 7].astype(int)}

    @property
    def done(self) -> bool:
        return self.status != "running"

    def advance(self, n1: int) -> None:
        """Compute states self.n+1 .. n1; sets ``status`` to "success" at N or "unstable"."""
        n0, n1 = self.n, min(int(n1), self.n_steps)
        if self.done or n1 <= n0:
            return
        t0 = time.perf_counter()
        inputs = (self._next if self._next[0] == (n0, n1) else self._inputs(n0, n1))[1]
        G = inputs.G
        self.load_bound += float((np.abs(G) @ self.load_norm).sum()) * self.dt \
            if G.shape[1] else 0.0
        # the bound grows with n: its chunk-end value is the loosest for the chunk
        Ebound = self.stepping.growth_limit * (math.sqrt(abs(self.E1)) + self.load_bound) ** 2 \
            + 1e-300
        if not math.isfinite(Ebound):
            raise InputError(f"the load is too large for floating point: its work by step {n1} "
                             f"is {self.load_bound:g}")
        code, at = self._steps(n0, n1, Ebound, inputs), n0
        while code == EVENTS_FULL:       # take the impact events, go on from where it stopped
            self._take_events()
            at, k = int(self.st.counters[3]), int(self.st.counters[3]) - n0
            code = self._steps(at, n1, Ebound, Inputs(G[k:], inputs.phi[k:],
                                                      inputs.H[k:] if inputs.H.shape[0]
                                                      else inputs.H))
        self._take_events()
        if code == 0 and n1 < self.n_steps:
            # the next chunk's inputs now, while the writer thread may still be formatting
            # the last chunk's rows but has not got this one's: computed while it formats
            # them, they wait for the GIL it holds (measured: 2.5 s instead of 0.3 s over
            # 2,000,000 steps saved at every step)
            self._next = self._inputs(n1, min(2 * n1 - n0, self.n_steps))
        self.wall += time.perf_counter() - t0
        k = int(self.st.counters[3])
        if code == FAILED:
            why = f": {PythonLaw.error}" if PythonLaw.error is not None else ""
            if PythonLaw.error is not None and not isinstance(PythonLaw.error, SolverError):
                raise PythonLaw.error     # a bug in a user's law: its own traceback
            raise SolverError(f"the {self.solver} contact solver failed at step {k} "
                              f"(t={k * self.dt:.6g} s){why}")
        if code == UNSTABLE:
            limit = linear_limit(kappa_h(self.system), self.beta)
            self.status = "unstable"
            self.message = (f"unstable at step {k} (t={k * self.dt:.6g} s): energy "
                            f"{self.energy[k // self.save_every]:.3g} exceeds {Ebound:.3g}; "
                            f"dt={self.dt:g} s, beta={self.beta:g}, linear stability limit "
                            f"2/√(κ_h(1−4β)) = {limit:.4g} s")
            self.n = (k // self.save_every - 1) * self.save_every   # last good saved state
            return
        self.n = n1
        if n1 == self.n_steps:
            self.status, self.message = "success", "the run reached T"

    # the saved series by saved-row number (see SavedRows), as the output pipeline reads them
    obs = property(lambda self: SavedRows(self, "obs"))
    obsv = property(lambda self: SavedRows(self, "obsv"))
    energy = property(lambda self: SavedRows(self, "energy"))
    work = property(lambda self: SavedRows(self, "work"))
    lam = property(lambda self: SavedRows(self, "lam"))
    fr = property(lambda self: self.out.frames_u)
    frv = property(lambda self: self.out.frames_v)
    frf = property(lambda self: self.out.frames_f)
    u_prev = property(lambda self: self.st.u_prev)
    u_cur = property(lambda self: self.st.u_cur)

    _STATE = {"u_prev": "u_prev", "u_cur": "u_cur", "state": "law_state",
              "active_prev": "active_prev", "stats": "stats", "counters": "counters",
              "lo": "lo", "hi": "hi", "slo": "slo", "shi": "shi", "work_sums": "work",
              "impact": "impact"}
    _FRAMES = {"fr": "frames_u", "frv": "frames_v", "frf": "frames_f"}

    def checkpoint(self) -> dict:
        """Everything needed to continue bit for bit (saved series are the caller's; the
        field frames, a few hundred at most, come along so they can be written anew)."""
        if self.pysolver is not None:
            raise InputError(f"checkpoints need a compiled contact law (projection, "
                             f"active-set, penalty), not {self.solver!r}")
        return {**{k: getattr(self.st, v).copy() for k, v in self._STATE.items()},
                **{k: getattr(self.out, v).copy() for k, v in self._FRAMES.items()},
                "events": self._all_events(), "n": self.n, "load_bound": self.load_bound,
                "wall": self.wall, "E1": self.E1, "frame_every": self.frame_every}

    def restore(self, ck: dict) -> None:
        """Continue from ``checkpoint()``: of this run, or of the same run with a shorter
        T (extending it).  The checkpoint's frame spacing is kept, so its frames stay
        valid (a run extended to 2T keeps every frame_every-th step: twice the frames)."""
        every = int(ck.get("frame_every", self.frame_every))
        if every != self.frame_every:
            nframes, out = self.n_steps // every + 1, self.out
            self.frame_every, self.ops = every, self.ops._replace(frame_every=every)
            self.out = out._replace(**{v: np.full((nframes, getattr(out, v).shape[1]),
                                                  0.0 if v == "frames_f" else np.nan)
                                       for v in self._FRAMES.values()})
        for k, v in self._STATE.items():
            getattr(self.st, v)[...] = ck[k]
        for k, v in self._FRAMES.items():
            getattr(self.out, v)[:len(ck[k])] = ck[k]
        ops = self.ops
        csr_product(ops.Cp, ops.Ci, ops.Cx, self.st.u_prev, self.st.y_prev)
        csr_product(ops.Cp, ops.Ci, ops.Cx, self.st.u_cur, self.st.y_cur)
        self.events = [np.asarray(ck["events"], dtype=float).reshape(-1, 7)]
        self.n, self.load_bound, self.wall, self.E1 = int(ck["n"]), float(ck["load_bound"]), \
            float(ck["wall"]), float(ck["E1"])

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
            observed={k: obs[:, i] for i, k in enumerate(names)},
            velocity={k: obsv[:, i] for i, k in enumerate(names)}, energy=out.energy[:keep],
            contact_force=out.lam[:keep], frames_t=np.arange(nf) * self.frame_every * self.dt,
            frames_u=out.frames_u[:nf], frames_v=out.frames_v[:nf],
            frames_force=out.frames_f[:nf],
            status=self.status, message=self.message, steps=self.n, dt=self.dt,
            T=self.n_steps * self.dt, beta=self.beta, solver=self.solver, wall_time_s=self.wall,
            max_nodal_violation=float(max(st[0], 0.0)),
            max_penetration=float(max(st[1], st[2], st[0], 0.0)),
            max_penetration_below=float(st[1]), max_penetration_above=float(st[2]),
            impacts=int(c[0]), contact_fraction=float(c[1]) / max(1, self.n - 1),
            qp_iterations=int(c[2]),
            work={k: out.work[:keep, i] for i, k in enumerate(WORK_TERMS)},
            impact_events=self.impact_events(), system=self.system)
