"""Moreau–Jean: contact enforced at velocity level with a Newton impact law (the θ-scheme
Siconos users run), as its own compiled integrator returning the same :class:`Result`.

    M(v^{n+1} − vⁿ) + Δt K(θu^{n+1} + (1−θ)uⁿ) + Δt B v^θ = Δt f^{n+θ} + Cᵀp^{n+1}
    u^{n+1} = uⁿ + Δt v^θ,      v^θ = θv^{n+1} + (1−θ)vⁿ

Index set: the constrained values whose predicted gap g(uⁿ + Δt/2 vⁿ) ≤ 0; on it the
Newton impact law 0 ≤ C v^{n+1} + e C vⁿ ⊥ p ≥ 0 (at a lower bound; at an upper bound
the signs flip), p = 0 elsewhere.  Substituted, each step is

    Â Δv = Δt (f − K uⁿ − Δtθ K vⁿ − B vⁿ) + Cᵀp,    Â = M + Δt²θ² K + Δtθ B,

a box QP in p with the Delassus matrix D = C Â⁻¹ Cᵀ, solved by the compiled exact
active set (:func:`skfem_beam.contact.active_set.box_qp`).

Why a module of its own and not a contact law of the β-scheme's loop: the β-scheme is
a two-step recursion in u alone (no velocity unknown), its law constrains u^{n+1}, and
the loop's step matrix is M + Δt²βK.  Moreau–Jean is a one-step scheme in (u, v) whose
law constrains v^{n+1} on an index set chosen from a predicted position, and whose
energy is ½vᵀMv + ½uᵀKu.  With θ = 1/2 the two coincide between impacts (Newmark
β = 1/4), but the state, the impulse and the energy differ, so hosting it in the loop
would not be exact.  It reuses the loop's bookkeeping instead: :class:`Run`'s chunks,
impact events and :class:`Result`.

What it records, in the units of the other methods: ``energy`` ½vᵀMv + ½uᵀKu;
velocity observers and frames use v itself; contact forces are p/Δt; penetration is
measured on the positions as for every method (it penetrates O(Δt): the index set only
switches the law on once the predicted gap closes); ``work``: with v^θ = (u^{n+1}−uⁿ)/Δt,
input Δt f·v^θ, contact pᵀC(vⁿ + v^{n+1})/2 (the impulse's work on the mean velocity: 0 for
e = 1, ≤ 0 below; pᵀCv^θ had put the scheme's dissipation there, +2.49 for θ = 1, e = 1
on point_stops), and "damping" Δt v^θᵀBv^θ plus the θ-scheme's numerical dissipation
(θ − ½)(ΔvᵀMΔv + Δt² v^θᵀKv^θ − pᵀCΔv), so energy − energy[0] + damping = input +
contact holds to round-off.  θ = ½, e = 1 conserves the energy at impacts; e = 0 loses
the constrained node's normal kinetic energy at each impact (O(h) on a mesh).
Obstacles that move with a support are refused; runs checkpoint and resume bit for bit
like the β-scheme's (:class:`Run` drives both).
"""
from __future__ import annotations

from collections import namedtuple
from dataclasses import replace

import numpy as np
from numba import njit

from ..checks import check_finite
from ..contact.active_set import box_qp
from ..contact.base import ContactLaw
from ..contact.restitution import Restitution
from ..errors import InputError
from ..linalg import add_columns, band_solve, row_layout, row_layout_of, rows_dot, rows_matvec
from .beta import (disk_rows, friction_of, hole_arrays, observers, penetration_samples,
                   refuse_lands, start_positions, tangent_rows, two_plane_state)
from ..contact.friction import MAX_SWEEPS, nsgs
from .kernels import (FAILED, FRICTION, IMPACT_FIELDS, ITERATIONS, ROW0, STOPPED_AT,
                      Inputs, Series, csr_product, saved_series, stop_code, track_holes,
                      track_impacts, violation)
from .operators import csr_arrays, load_norms, step_operators
from .stepping import Stepping

MJOps = namedtuple("MJOps", [
    "dt", "theta", "e", "save_every", "frame_every",
    "Kb", "Kj", "Mb", "Mj", "Bb", "Bj",   # K, M, B in the row layout (linalg.Banded)
    "Achol", "loads",                      # Â's factor; load vectors
    "Cp", "Ci", "Cx", "Wt", "D",           # constraint rows, (Â⁻¹Cᵀ)ᵀ, C Â⁻¹ Cᵀ
    "Op", "Oi", "Ox", "Sp", "Si", "Sx",    # observers, penetration samples
    "pair", "disks", "Np", "Ni", "Nx", "Nc",   # two planes: rows, nodes, holes (kernels.Ops)
    "fric", "tol",                         # round holes: μ per first row; the NSGS tolerance
])
MJState = namedtuple("MJState", [
    "u_prev", "u_cur", "v",
    "y_prev", "y_cur", "dy", "yv", "yp",   # C uⁿ⁻¹, C uⁿ, C(uⁿ⁺¹ − uⁿ⁻¹), C vⁿ, predicted C u
    "lo", "hi", "slo", "shi", "lo_e", "hi_e",
    "law_state", "active", "active_prev", "stats", "counters", "work", "impact",
    "pos", "rowwork", "sectors", "hk", "fc",   # two planes (kernels.State)
    "fres",                                # round holes: [the step's NSGS residual, max]
    "slid",                                # two planes: a row's |F_n||v_t|Δt (mj_steps)
    "mu",                                  # Δt·p (so that mu/Δt² is the force p/Δt)
    "p", "wf", "x", "dv", "Ku", "Kv",   # scratch
])


NAME = "moreau-jean"     # the method's name everywhere (flags, scene files, results)


class MoreauJeanLaw(ContactLaw):
    """The name a Moreau–Jean result reports as its solver."""
    name = NAME


@njit(cache=True)
def mj_record(n, ops, st, out):
    """Penetration (every step) and the saved series of state n (v is the scheme's own)."""
    stats = st.stats
    for r in range(st.y_cur.size):
        stats[0] = max(stats[0], st.lo[r] - st.y_cur[r], st.y_cur[r] - st.hi[r])
    for r in ops.disks:     # round holes: beyond the circle (the box is the disk's square)
        stats[0] = max(stats[0], violation(ops.pair, None, st.lo, st.hi, st.y_cur, r))
    for r in range(st.slo.size):
        s = 0.0
        for q in range(ops.Sp[r], ops.Sp[r + 1]):
            s += ops.Sx[q] * st.u_cur[ops.Si[q]]
        stats[1] = max(stats[1], st.slo[r] - s)
        stats[2] = max(stats[2], s - st.shi[r])
    dt2 = ops.dt * ops.dt
    if n % ops.save_every == 0:
        k = n // ops.save_every - st.counters[ROW0]   # rows from there on (see Run)
        for r in range(ops.Op.size - 1):     # observed values and the velocity v itself
            out.obs[k, r] = 0.0
            out.obsv[k, r] = 0.0
            for q in range(ops.Op[r], ops.Op[r + 1]):
                out.obs[k, r] += ops.Ox[q] * st.u_cur[ops.Oi[q]]
                out.obsv[k, r] += ops.Ox[q] * st.v[ops.Oi[q]]
        out.energy[k] = 0.5 * (rows_dot(ops.Mb, ops.Mj, st.v, st.v)
                               + rows_dot(ops.Kb, ops.Kj, st.u_cur, st.u_cur))
        out.work[k, :] = st.work
        out.lam[k, :] = st.mu / dt2
        out.resid[k] = st.fres[0]
    if n % ops.frame_every == 0:
        k = n // ops.frame_every
        for i in range(st.u_cur.size):
            out.frames_u[k, i] = st.u_cur[i]
            out.frames_v[k, i] = st.v[i]
        for j in range(st.mu.size):
            out.frames_f[k, j] = st.mu[j] / dt2


@njit(cache=True, inline="always")
def mj_impulse(ops, st):
    """p from the impact law on the index set (box QP in the velocity values); returns
    the active set's iterations (< 0: failed).  st.x holds v_free on entry."""
    dt, inf = ops.dt, np.inf
    for i in range(st.x.size):
        st.dv[i] = st.u_cur[i] + 0.5 * dt * st.v[i]
    csr_product(ops.Cp, ops.Ci, ops.Cx, st.dv, st.yp)
    csr_product(ops.Cp, ops.Ci, ops.Cx, st.x, st.wf)
    for j in range(st.wf.size):
        st.wf[j] += ops.e * st.yv[j]
        st.lo_e[j] = 0.0 if st.yp[j] <= st.lo[j] else -inf
        st.hi_e[j] = 0.0 if st.yp[j] >= st.hi[j] else inf
        if (st.law_state[j] < 0 and st.lo_e[j] == -inf) or \
                (st.law_state[j] > 0 and st.hi_e[j] == inf):
            st.law_state[j] = 0          # warm start only from members of the index set
    if st.wf.size == 0:
        return 0
    return box_qp(ops.D, st.wf, st.lo_e, st.hi_e, st.law_state, st.p)


@njit(cache=True, inline="always")
def mj_holes(ops, st):
    """Round holes: the impulses of contact.friction.nsgs (Coulomb friction, and the box
    rows beside them) from y_θ = uⁿ + (1−θ)Δt vⁿ; st.fres ← its residual.  st.x holds
    v_free on entry."""
    dt, th = ops.dt, ops.theta
    for i in range(st.x.size):
        st.dv[i] = st.u_cur[i] + (1.0 - th) * dt * st.v[i]
    csr_product(ops.Cp, ops.Ci, ops.Cx, st.dv, st.yp)
    csr_product(ops.Cp, ops.Ci, ops.Cx, st.x, st.wf)
    its, res = nsgs(ops.D, (ops.pair, ops.fric, st.lo, st.hi),
                    (st.wf, st.yv, st.yp, st.y_cur, ops.e, ops.tol, th * dt),
                    (st.p, st.fc, st.lo_e, st.hi_e))
    st.fres[0] = res
    st.fres[1] = max(st.fres[1], res)
    return its


@njit(cache=True)
def mj_steps(ops, st, out, n0, n1, inputs):
    """Steps n = n0..n1−1 of Moreau–Jean (module docstring); the codes of
    :func:`skfem_beam.scheme.kernels.run_steps`."""
    dt, th = ops.dt, ops.theta
    n, m = st.x.size, st.mu.size
    for step in range(n0, n1):
        Gn = inputs.G[step - n0]
        rows_matvec(ops.Kb, ops.Kj, st.u_cur, st.Ku, 1.0, np.bool_(False))
        rows_matvec(ops.Kb, ops.Kj, st.v, st.Kv, 1.0, np.bool_(False))
        x = st.x
        for i in range(n):
            s = -st.Ku[i] - dt * th * st.Kv[i]
            for k in range(Gn.size):
                s += Gn[k] * ops.loads[i, k]
            x[i] = dt * s
        if ops.Bb.shape[0]:
            rows_matvec(ops.Bb, ops.Bj, st.v, x, -dt, np.bool_(True))
        band_solve(ops.Achol, x)
        for i in range(n):
            x[i] += st.v[i]                      # v_free
        its = mj_holes(ops, st) if ops.disks.size else mj_impulse(ops, st)
        if its < 0:
            st.counters[STOPPED_AT] = step + 1
            return FAILED
        st.counters[ITERATIONS] += its
        add_columns(ops.Wt, st.p, x)
        # x = v^{n+1}; dv = Δv; Kv ← v^θ
        for i in range(n):
            st.dv[i] = x[i] - st.v[i]
            st.Kv[i] = st.v[i] + th * st.dv[i]
        for k in range(Gn.size):
            s = 0.0
            for i in range(n):
                s += ops.loads[i, k] * st.Kv[i]
            st.work[1] += dt * Gn[k] * s
        if ops.Bb.shape[0]:
            st.work[0] += dt * rows_dot(ops.Bb, ops.Bj, st.Kv, st.Kv)
        if th != 0.5:
            st.work[0] += (th - 0.5) * (rows_dot(ops.Mb, ops.Mj, st.dv, st.dv)
                                        + dt * dt * rows_dot(ops.Kb, ops.Kj, st.Kv, st.Kv))
        for i in range(n):
            st.u_prev[i] = st.u_cur[i]
            st.u_cur[i] += dt * st.Kv[i]
            st.v[i] = x[i]
        for j in range(m):
            st.dy[j] = -st.y_prev[j]
            st.y_prev[j] = st.y_cur[j]
        csr_product(ops.Cp, ops.Ci, ops.Cx, st.u_cur, st.y_cur)
        csr_product(ops.Cp, ops.Ci, ops.Cx, st.v, st.yv)
        if th != 0.5:   # μ holds CΔv here: the impulse's θ share is numerical dissipation
            csr_product(ops.Cp, ops.Ci, ops.Cx, st.dv, st.mu)
            for j in range(m):
                d = (th - 0.5) * st.p[j] * st.mu[j]
                st.work[2] -= d
                st.work[0] -= d
                if st.rowwork.shape[0]:
                    st.rowwork[j, 0] -= d
        for j in range(m):
            st.dy[j] += st.y_cur[j]
            st.work[2] += st.p[j] * (st.y_cur[j] - st.y_prev[j]) / dt
            st.mu[j] = st.p[j] * dt
            st.active[j] = st.p[j] != 0.0
        if st.rowwork.shape[0]:          # two planes: each row's share
            for j in range(m):
                st.rowwork[j, 0] += st.p[j] * (st.y_cur[j] - st.y_prev[j]) / dt
        st.slid[:] = np.nan
        for a in ops.disks:              # a round hole's friction part of its work
            b = ops.pair[a]
            st.active[b] = False
            st.active[a] = st.p[a] != 0.0 or st.p[b] != 0.0
            if st.fc.shape[0] and ops.fric[a] > 0.0:
                # Archard's |F_n||v_t|Δt: the friction work over μ, the share of the
                # impulse that slid (the central difference counted, at an impact that
                # sticks, the velocity before it: a rate that did not fall with μ)
                st.slid[a] = 0.0
            if st.fc.shape[0] and st.fc[a, 1] != 0.0:
                f = st.fc[a, 1] * (-st.fc[a, 5] * (st.y_cur[a] - st.y_prev[a])
                                   + st.fc[a, 4] * (st.y_cur[b] - st.y_prev[b])) / dt
                st.work[2] -= f
                st.work[FRICTION] += f
                st.slid[a] = abs(f) / ops.fric[a]
                if st.rowwork.shape[0]:
                    st.rowwork[a, 0] -= f
                    st.rowwork[a, 2] += f
        full = track_impacts(ops, st, out, step, None)      # no broached hole (refused)
        if ops.Nc.shape[0]:
            track_holes(ops, st, step, st.hk, None, None, st.slid)   # (Nc: no μ; above)
        mj_record(step + 1, ops, st, out)
        code = stop_code(ops, st, out, step, full)     # the β-scheme's test, on its rows
        if code:
            return code
    return 0


NSGS_TOL = 1e-12     # friction's Gauss–Seidel: a sweep's largest change, relative


def check_theta(theta, name: str = "theta=") -> float:
    """θ ∈ [1/2, 1], where the θ-scheme is unconditionally stable; ``name``: the key or
    flag as the user wrote it ("theta=", "--theta ", "[contact] theta = ")."""
    theta = check_finite(name.rstrip("= "), theta)
    if 0.5 <= theta <= 1.0:
        return theta
    raise InputError(f"{name}{theta:g} must lie in [1/2, 1] (the θ-scheme is "
                     f"unconditionally stable there)")


# checkpointed: every field of MJState but the step's scratch (p, wf, x, dv, Ku, Kv, hk)
_MJ_SCRATCH = ("p", "wf", "x", "dv", "Ku", "Kv", "hk", "slid")


class MoreauJeanScheme:
    """Moreau–Jean of ``system`` on ``stepping`` (its β is not used) as a one-step
    integrator, with ``theta`` ∈ [1/2, 1] and Newton restitution ``restitution`` ∈ [0, 1];
    the interface of :class:`~.beta.BetaScheme`, so that :class:`Run` drives both."""

    CHECKPOINT = {f: f for f in MJState._fields if f not in _MJ_SCRATCH}
    pysolver = None

    def __init__(self, system, stepping: Stepping, theta: float = 0.5,
                 restitution: float = 0.0):
        self.theta, self.e = check_theta(theta), Restitution(restitution).e
        if system.bound_motion is not None:
            raise InputError(f"law={NAME!r} does not handle obstacles that move with a "
                             "support: use the position-level scheme")
        refuse_lands(system, NAME)
        if tangent_rows(system).size:
            raise InputError(f"friction on a hole's flat faces takes the position-level law "
                             f"round-hole-friction (or auto), not {NAME} (round holes only)")
        if disk_rows(system).size and self.e > 0:
            raise InputError(f"restitution={self.e:g} with round holes: {NAME} holds a node "
                             "on the wall at the step's end there (e = 0)")
        s, th = stepping, self.theta
        self.system, self.stepping, self.law = system, s, MoreauJeanLaw()
        self.solver, self.springs = self.law.name, self.law.springs
        self.dt, self.beta, self.n_steps = s.dt, None, s.steps
        self.save_every, self.frame_every, self.shift = s.save_every, s.frame_every, 0.0
        # Â = M + Δt²θ²K + ΔtθB is step_operators' A with β = θ² and B scaled by 2θ
        B = system.B
        self.op = step_operators(replace(system, B=None if B is None else 2 * th * B),
                                 s.dt, th * th)
        self.loads = np.ascontiguousarray(system.loads, dtype=float)
        self.load_norm = load_norms(system, s.dt, th * th)
        self.Orows = observers(system)
        self.ops = self._ops()
        self.st = self._state()

    def _ops(self) -> MJOps:
        system, s, op = self.system, self.stepping, self.op
        samples, _, _ = penetration_samples(system)
        B = system.B
        return MJOps(s.dt, self.theta, self.e, s.save_every, s.frame_every,
                     *row_layout_of(op.Kb), *row_layout(system.M),
                     *(row_layout(B) if B is not None else row_layout_of(None)), op.Ab.chol,
                     self.loads, *csr_arrays(op.C),
                     op.W.T, op.D, *csr_arrays(self.Orows), *samples, *hole_arrays(system),
                     friction_of(system), NSGS_TOL)

    def _state(self) -> MJState:
        system, op, z = self.system, self.op, np.zeros
        n, m = system.n, system.C.shape[0]
        _, slo, shi = penetration_samples(system)
        lo, hi = (np.ascontiguousarray(b, dtype=float) for b in (system.lo, system.hi))
        u0, v0 = system.u0.astype(float), system.v0.astype(float)
        return MJState(u_prev=u0.copy(), u_cur=u0, v=v0, y_prev=op.C @ system.u0,
                       y_cur=op.C @ system.u0, dy=z(m), yv=op.C @ system.v0, yp=z(m),
                       lo=lo, hi=hi, slo=np.array(slo, float), shi=np.array(shi, float),
                       lo_e=z(m), hi_e=z(m), law_state=z(m, np.int8), active=z(m, np.bool_),
                       active_prev=z(m, np.bool_), stats=z(4), counters=z(6, np.int64),
                       work=z(4), impact=np.full((m, IMPACT_FIELDS), -1.0),
                       **two_plane_state(self.ops, bool(disk_rows(system).size)),
                       fres=z(2), slid=z(m), mu=z(m), p=z(m), wf=z(m),
                       x=z(n), dv=z(n), Ku=z(n), Kv=z(n))

    def series(self, rows: int, nframes: int) -> Series:
        """Saved-series buffers (Moreau–Jean keeps its frames, whatever the run asked)."""
        return saved_series(self.system, self.Orows, rows, nframes)

    # its loop computes state 1 and counts its contact: contact_fraction over n states (the
    # β-scheme's start step counts none, over the n − 1 of states 2..n); n − 1 read 1.0033
    counts_state_one = 1

    def start(self, out) -> int:
        """State 0 is the data themselves: recorded; the driver steps on from there."""
        start_positions(self.ops, self.st, self.st.u_cur, self.st.u_cur)
        mj_record(0, self.ops, self.st, out)
        return 0

    def inputs(self, n0, n1):
        """((n0, n1), Inputs): f^{n+θ}, the load functions at tₙ + θΔt, n = n0..n1−1."""
        t = (np.arange(n0, n1) + self.theta) * self.dt
        if not self.loads.shape[1]:
            G = np.zeros((n1 - n0, 0))
        else:
            G = np.ascontiguousarray(np.column_stack(
                [np.broadcast_to(np.asarray(a(t), dtype=float), t.shape) for a in
                 self.system.load_time]))
        return (n0, n1), Inputs(G, np.zeros(n1 - n0))

    def steps(self, out, n0, n1, inputs=None):
        if inputs is None:
            inputs = Inputs(np.zeros((0, self.loads.shape[1])), np.zeros(0))
        return mj_steps(self.ops, self.st, out, n0, n1, inputs)

    def restored(self) -> None:
        """Every field it needs is in the checkpoint."""

    def failure(self) -> str:
        """Why a step failed, when friction's Gauss–Seidel missed its tolerance."""
        if not self.ops.disks.size:
            return ""
        return (f": friction's Gauss–Seidel did not reach {self.ops.tol:g} in "
                f"{MAX_SWEEPS} sweeps (residual {self.st.fres[0]:.3g})")

