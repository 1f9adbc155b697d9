"""The compiled time loop: one step of the scheme on one state.

Three named tuples travel through the loop (numba compiles them as plain structs):

- ``Ops``: what is fixed for the run (operators in banded row layout, the constraint,
  observer and penetration-sample rows as CSR triples, the law's constants);
- ``State``: uⁿ⁻¹, uⁿ and what the next step needs (the law's warm start, y = Cu of
  both states, contact flags, counters and running diagnostics), plus scratch;
- ``Series``: the saved series and field frames.

A step (the module docstring of :mod:`skfem_beam.scheme` has the equations):

    r  ← explicit(Cuⁿ, Cuⁿ⁻¹, …)             the law's explicit force (0 for most laws)
    x  ← x_free = 2uⁿ − uⁿ⁻¹ + A⁻¹(Δt²(Gⁿ + Cᵀr − K uⁿ) − Δt B(uⁿ − uⁿ⁻¹))     free_step
    μ  ← law(D, C x_free, Cuⁿ, Cuⁿ⁻¹, lo, hi, …)                         the contact law
    uⁿ⁺¹ = x_free + W μ                                                   finish_step
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba import njit, objmode

from ..linalg import band_solve, rows_dot, rows_matvec

FAILED, UNSTABLE = 1, 2

Ops = namedtuple("Ops", [
    "dt", "beta", "save_every", "frame_every",
    "Kb", "Bb", "Achol", "Eb",        # K, damping B (0 rows: none), A's factor, M/Δt² + βK
    "loads",                          # (n, k) load vectors b_k
    "Cp", "Ci", "Cx", "lo", "hi",     # constrained values y = C u and their bounds
    "W", "D",                         # A⁻¹Cᵀ and the Delassus matrix C A⁻¹ Cᵀ
    "Op", "Oi", "Ox",                 # observed values (e.g. the tip)
    "Sp", "Si", "Sx", "slo", "shi",   # penetration samples between the nodes and their bounds
    "params",                         # the contact law's constants
])
State = namedtuple("State", [
    "u_prev", "u_cur",                # uⁿ⁻¹, uⁿ
    "y_prev", "y_cur",                # C uⁿ⁻¹, C uⁿ
    "law_state", "active", "active_prev",
    "stats",      # [max nodal violation, max (g1−u)⁺ sampled, max (u−g2)⁺ sampled, -]
    "counters",   # [impacts, steps in contact, law iterations, step where it stopped]
    "r_e",                            # the law's explicit force (see contact.base)
    "x", "yf", "mu", "Ku", "d",       # the step's free solution (then uⁿ⁺¹), C x, μ, K uⁿ, scratch
])
Series = namedtuple("Series", ["obs", "obsv", "energy", "lam", "frames_u", "frames_v",
                               "frames_f"])


@njit(cache=True)
def csr_product(Rp, Ri, Rx, u, y):
    """y ← R u for R given as CSR arrays."""
    for r in range(y.size):
        s = 0.0
        for p in range(Rp[r], Rp[r + 1]):
            s += Rx[p] * u[Ri[p]]
        y[r] = s


@njit(cache=True, inline="always")
def free_step(ops, st, Gn):
    """st.x ← the step without contact, st.yf ← C x, st.Ku ← K uⁿ (reused by the energy);
    ``Gn``: the load coefficients Gⁿ of this step; st.r_e: the law's explicit force."""
    dt2 = ops.dt * ops.dt
    x, u_cur, u_prev = st.x, st.u_cur, st.u_prev
    rows_matvec(ops.Kb, u_cur, st.Ku)
    for i in range(x.size):
        s = -st.Ku[i]
        for k in range(Gn.size):
            s += Gn[k] * ops.loads[i, k]
        x[i] = dt2 * s
    for r in range(st.r_e.size):
        if st.r_e[r] != 0.0:
            for p in range(ops.Cp[r], ops.Cp[r + 1]):
                x[ops.Ci[p]] += dt2 * ops.Cx[p] * st.r_e[r]
    if ops.Bb.shape[0]:
        for i in range(st.d.size):
            st.d[i] = u_cur[i] - u_prev[i]
        rows_matvec(ops.Bb, st.d, x, -ops.dt, True)
    band_solve(ops.Achol, x)
    for i in range(x.size):
        x[i] += 2.0 * u_cur[i] - u_prev[i]
    csr_product(ops.Cp, ops.Ci, ops.Cx, x, st.yf)


@njit(cache=True, inline="always")
def finish_step(ops, st):
    """uⁿ⁺¹ = x_free + W μ; shift (uⁿ⁻¹, uⁿ) ← (uⁿ, uⁿ⁺¹) and their constrained values."""
    x, mu = st.x, st.mu
    for j in range(mu.size):
        if mu[j] != 0.0:
            for i in range(x.size):
                x[i] += ops.W[i, j] * mu[j]
    for i in range(x.size):
        st.u_prev[i] = st.u_cur[i]
        st.u_cur[i] = x[i]
    for j in range(mu.size):
        st.y_prev[j] = st.y_cur[j]
    csr_product(ops.Cp, ops.Ci, ops.Cx, st.u_cur, st.y_cur)


@njit(cache=True)
def energy_beta(Eb, u_prev, u_cur, Ku, d):
    """E_β = δᵀ(M/Δt² + βK)δ + uⁿᵀ K uⁿ⁻¹,  δ = uⁿ − uⁿ⁻¹ (exactly conserved without contact).

    ``Eb`` is M/Δt² + βK in row layout; ``Ku`` is K uⁿ⁻¹, left by the step.
    """
    for i in range(d.size):
        d[i] = u_cur[i] - u_prev[i]
    s = rows_dot(Eb, d, d)
    for i in range(d.size):
        s += u_cur[i] * Ku[i]
    return s


@njit(cache=True, inline="always")
def record(n, ops, st, out):
    """Diagnostics after state n: penetration (every step), saved series, frames."""
    stats, u_cur, u_prev, dt = st.stats, st.u_cur, st.u_prev, ops.dt
    for r in range(st.y_cur.size):
        v = max(ops.lo[r] - st.y_cur[r], st.y_cur[r] - ops.hi[r])
        if v > stats[0]:
            stats[0] = v
    for r in range(ops.slo.size):
        s = 0.0
        for p in range(ops.Sp[r], ops.Sp[r + 1]):
            s += ops.Sx[p] * u_cur[ops.Si[p]]
        if ops.slo[r] - s > stats[1]:
            stats[1] = ops.slo[r] - s
        if s - ops.shi[r] > stats[2]:
            stats[2] = s - ops.shi[r]
    dt2 = dt * dt
    if n % ops.save_every == 0:
        k = n // ops.save_every
        for r in range(ops.Op.size - 1):
            s = 0.0
            sv = 0.0
            for p in range(ops.Op[r], ops.Op[r + 1]):
                s += ops.Ox[p] * u_cur[ops.Oi[p]]
                sv += ops.Ox[p] * (u_cur[ops.Oi[p]] - u_prev[ops.Oi[p]])
            out.obs[k, r] = s
            out.obsv[k, r] = sv / dt
        out.energy[k] = 0.5 * energy_beta(ops.Eb, u_prev, u_cur, st.Ku, st.d)
        for j in range(st.mu.size):
            out.lam[k, j] = st.mu[j] / dt2
    if n % ops.frame_every == 0:
        k = n // ops.frame_every
        for i in range(u_cur.size):
            out.frames_u[k, i] = u_cur[i]
            out.frames_v[k, i] = (u_cur[i] - u_prev[i]) / dt
        for j in range(st.mu.size):
            out.frames_f[k, j] = st.mu[j] / dt2


@njit(cache=True, inline="always")
def call_law(law, ops, st):
    """One call of a compiled law on the state's free step (the start step uses it)."""
    return law(ops.D, st.yf, st.y_cur, st.y_prev, ops.lo, ops.hi, ops.params, st.law_state,
               st.mu, st.active)


@njit(cache=True)
def call_explicit(explicit, ops, y_cur, y_prev, r):
    return explicit(y_cur, y_prev, ops.lo, ops.hi, ops.params, r)


@njit(cache=True, inline="always")
def end_step(ops, st, out, step, Ebound):
    """After the law: uⁿ⁺¹, the contact bookkeeping and the diagnostics of state step+1.
    Returns UNSTABLE when its saved energy is non-finite or above Ebound, else 0."""
    counters = st.counters
    finish_step(ops, st)
    for j in range(st.r_e.size):   # the contact force: explicit and implicit parts
        if st.r_e[j] != 0.0:
            st.mu[j] += ops.dt * ops.dt * st.r_e[j]
    any_active = False
    for j in range(st.active.size):
        a = st.active[j]
        if a and not st.active_prev[j]:
            counters[0] += 1
        st.active_prev[j] = a
        any_active = any_active or a
    if any_active:
        counters[1] += 1
    record(step + 1, ops, st, out)
    if (step + 1) % ops.save_every == 0 \
            and not abs(out.energy[(step + 1) // ops.save_every]) <= Ebound:
        counters[3] = step + 1
        return UNSTABLE
    return 0


# Compiled without numba's reference counting: the loop allocates nothing, and the
# refcount operations on the named tuples' arrays cost 0.6 µs of a 1.3 µs step (measured).
@njit(cache=True, _nrt=False)
def run_steps(law, explicit, ops, st, out, n0, n1, G, Ebound):
    """Steps n = n0..n1−1 (computing uⁿ⁺¹) with a compiled law: its explicit force, the
    free step, the law, then `end_step`.  ``G[n − n0]``: the load coefficients Gⁿ.

    Returns 0, FAILED (the law failed at step counters[3]) or UNSTABLE (the energy saved
    at state counters[3] is non-finite or above Ebound).
    """
    for step in range(n0, n1):
        explicit(st.y_cur, st.y_prev, ops.lo, ops.hi, ops.params, st.r_e)
        free_step(ops, st, G[step - n0])
        its = call_law(law, ops, st)
        if its < 0:
            st.counters[3] = step + 1
            return FAILED
        st.counters[2] += its
        code = end_step(ops, st, out, step, Ebound)
        if code:
            return code
    return 0


class PythonLaw:
    """The law solved in Python that `run_steps_python` calls (one run at a time per
    process), and the error it raised, if any."""
    solver = None
    error = None


def _solve_in_python(x, yf, mu) -> int:
    try:
        m, its = PythonLaw.solver.solve(x, yf)
    except Exception as e:        # handed back to the run, which raises it with the step
        PythonLaw.error = e
        return -1
    mu[:] = m
    return its


@njit(cache=True)
def run_steps_python(ops, st, out, n0, n1, G, Ebound):
    """The same steps as `run_steps` with the law solved in Python (`PythonLaw.solver`,
    e.g. OSQP or daqp): the compiled loop calls it for μ at each step."""
    for step in range(n0, n1):
        free_step(ops, st, G[step - n0])
        x, yf, mu = st.x, st.yf, st.mu
        with objmode(its="int64"):
            its = _solve_in_python(x, yf, mu)
        if its < 0:
            st.counters[3] = step + 1
            return FAILED
        for j in range(mu.size):
            st.active[j] = mu[j] != 0.0
        st.counters[2] += its
        code = end_step(ops, st, out, step, Ebound)
        if code:
            return code
    return 0


def empty_csr(n_rows: int = 0):
    return (np.zeros(n_rows + 1, np.int64), np.zeros(0, np.int64), np.zeros(0))
