"""The compiled time loop: one step of the scheme on one state.

Three named tuples travel through the loop (numba compiles them as plain structs):

- ``Ops``: what is fixed for the run (operators in banded row layout, the constraint,
  observer and penetration-sample rows as CSR triples, the law's constants);
- ``State``: uⁿ⁻¹, uⁿ and what the next step needs (the law's warm start, y = Cu of
  both states, contact flags, counters and running diagnostics), plus scratch;
- ``Series``: the saved series, field frames and impact events;
- ``Inputs``: what the chunk's steps take from outside: the load coefficients Gⁿ and
  φ(t_{n+1}), the motion that moves the bounds (zero when they do not move).

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

from ..contact.lands import land_excess, land_normal, land_split
from ..linalg import add_columns, band_solve, csr_product, rows_dot, rows_matvec

Ops = namedtuple("Ops", [
    "dt", "beta", "save_every", "frame_every",
    "Kb", "Kj", "Bb", "Bj",           # K, damping B (0 rows: none) in the row layout
    "Achol", "Eb", "Ej",              # A's factor, M/Δt² + βK (linalg.Banded)
    "loads",                          # (n, k) load vectors b_k
    "Cp", "Ci", "Cx", "lo", "hi",     # constrained values y = C u and their bounds at rest
    "shift", "sshift",                # bounds at t: lo + shift·φ(t) (and samples); () if fixed
    "Wt", "D",                        # Wᵀ = C A⁻¹ (m × n: W's columns contiguous, for
    #                                   W μ) and the Delassus matrix C A⁻¹ Cᵀ
    "Op", "Oi", "Ox",                 # observed values (e.g. the tip)
    "Sp", "Si", "Sx", "slo", "shi",   # penetration samples between the nodes and their bounds
    "params",                         # the contact law's constants
    "Zr", "Zp", "Zi", "Zx",           # quasi-static massless rows: their indices, K's rows
    "pair",                           # per row: a round hole's first row holds its second
    #                                   row's index, its second row −1, other rows 0
    "disks",                          # the round holes' first rows
    "Np", "Ni", "Nx", "Nc",           # two planes: each row's node (v, w) as CSR rows 2j,
    #                                   2j+1, and [cy, cz, sy, sz, ny, nz, n, h, a, f]: its
    #                                   hole's centre at rest, the centre's motion per unit
    #                                   φ, the row's normal ((0, 0): radial, a round hole), a
    #                                   broached hole's lands, half width, first land's angle
    #                                   (both rows of its pair; n = 0: not broached, see
    #                                   contact.lands), a round hole's Coulomb μ when the
    #                                   β-scheme's law takes friction (first row; else 0,
    #                                   see friction_split); none: 1 plane
])
State = namedtuple("State", [
    "u_prev", "u_cur",                # uⁿ⁻¹, uⁿ
    "y_prev", "y_cur",                # C uⁿ⁻¹, C uⁿ
    "lo", "hi", "slo", "shi",         # the bounds now (moved with the support, or as at rest)
    "law_state", "active", "active_prev",
    "stats",      # [max nodal violation, max (g1−u)⁺ sampled, max (u−g2)⁺ sampled, φ now]
    "counters",   # [impacts, steps in contact, law iterations, step where it stopped,
                  #  impact events written, first saved row held in the Series buffers]
    "work",       # Σ over the steps of [damping, load input, contact, friction] work
                  # (energy units)
    "impact",     # per constrained value: [start step, approach velocity, peak |λ|,
                  #  Σ λΔt, max violation, first step off (−1: in contact), and in two
                  #  planes the angle on the hole, the normal and tangential approach
                  #  velocities, the slip Σ|u_t|Δt and the friction impulse Σ|p_t|] of
                  #  the event under way (start −1: none)
    "pos",        # two planes: each row's node (v, w) at states n−1 and n (m × 4)
    "rowwork",    # two planes: per row, Σ contact work, Σ |F_n||v_t|Δt, Σ friction work
    "hk",         # scratch (4) of hole_kinematics
    "sectors",    # two planes: per row, Σ |F_n||v_t|Δt per 30° sector of the hole (m × 12)
    "fc",         # friction (Moreau–Jean): per round hole's first row [p_n, p_t, u_n, u_t,
                  # n_y, n_z] of the step (contact.friction.nsgs); none without
    "r_e",                            # the law's explicit force (see contact.base)
    "x", "yf", "mu", "Ku", "d", "dy", # the step's free solution (then uⁿ⁺¹), C x, μ, K uⁿ,
                                      # scratch (n), C(uⁿ⁺¹ − uⁿ⁻¹)
    "ez",                             # the massless rows' explicit force of the step
])
Series = namedtuple("Series", ["obs", "obsv", "energy", "work", "lam", "frames_u", "frames_v",
                               "frames_f", "events", "resid", "bound"])
# resid: friction's residual; bound: the a-priori bound of each saved row's energy (Run)


def saved_series(system, Orows, rows: int, nframes: int) -> Series:
    """A scheme's saved-series buffers: ``rows`` rows (observed points ``Orows``) and
    ``nframes`` field frames; values not yet computed are NaN, bounds +inf."""
    n, m, nobs = system.n, system.C.shape[0], Orows.shape[0]
    return Series(np.full((rows, nobs), np.nan), np.full((rows, nobs), np.nan),
                  np.full(rows, np.nan), np.zeros((rows, 4)), np.zeros((rows, m)),
                  np.full((nframes, n), np.nan), np.full((nframes, n), np.nan),
                  np.zeros((nframes, m)), np.zeros((max(4096, 4 * m), len(EVENT_COLUMNS))),
                  np.zeros(rows), np.full(rows, np.inf))

# H: the load at the quasi-static massless rows, (1−2β)fⁿ + βfⁿ⁻¹ there (0 rows: none)
Inputs = namedtuple("Inputs", ["G", "phi", "H"], defaults=(np.zeros((0, 0)),))
WORK_TERMS = ("damping", "input", "contact")   # the columns of State.work and Series.work
FRICTION = 3           # ... and the friction work's (runs with friction only)
NC_COLUMNS = 11        # Ops.Nc's columns
FRICTION_COLUMN = 9    # ... the one of a round hole's or a face's μ (the β-scheme's law)
TANGENT_COLUMN = 10    # ... a face with friction's tangent row (its pair is −1)
SECTORS = 12           # the hole's angular sectors of the normal work (State.sectors)
EVENT_COLUMNS = ("value", "start_step", "end_step", "velocity", "peak_force", "impulse",
                 "max_violation", "angle", "normal_velocity", "tangential_velocity", "slip",
                 "friction_impulse")
IMPACT_FIELDS = 11     # State.impact's columns
FAILED, UNSTABLE, EVENTS_FULL = 1, 2, 3
# State.counters by name (the compiled loops index them by these numbers)
IMPACTS, CONTACT_STEPS, ITERATIONS, STOPPED_AT, EVENTS_WRITTEN, ROW0 = range(6)


# Called from compiled code only, and out of line: branches that most runs never take (or
# take once per event) are compiled once, small, instead of being copied into the loop.
internal = njit(cache=True, _nrt=False, no_cpython_wrapper=True, no_cfunc_wrapper=True)


@internal
def massless_force(Zr, Zp, Zi, Zx, beta, Ku, u_prev, H, row, ez):
    """ez ← (1−2β) K_Z uⁿ + β K_Z uⁿ⁻¹ − H_Z (Z the quasi-static massless rows, K_Z their
    rows of K as CSR (Zp, Zi, Zx), Ku = K uⁿ).  Added to the β-scheme's right-hand side
    Δt²(Gⁿ − K uⁿ) on Z it gives βΔt²(f^{n+1} − K(2uⁿ − uⁿ⁻¹)): the row K u^{n+1} =
    f^{n+1} + Cᵀλ times β, so that A stays M + βΔt²K (symmetric, banded).  It is the
    rows' part of the contact force that the energy sees (β λ^{n+1} + ez), see
    scheme.operators."""
    for q in range(Zr.size):
        s = 0.0
        for p in range(Zp[q], Zp[q + 1]):
            s += Zx[p] * u_prev[Zi[p]]
        s = (1.0 - 2.0 * beta) * Ku[Zr[q]] + beta * s
        if H.shape[0]:
            s -= H[row, q]
        ez[q] = s


@internal
def massless_work(Zr, ez, d, mu, Cp, Ci, Cx, beta, dt):
    """The step's contact work on the quasi-static massless rows, δ = ``d``: the energy
    sees β λ^{n+1} + ez there, and finish_step counts λ^{n+1} (the law's μ is Δt²λ^{n+1},
    W and D carry the β)."""
    s = 0.0
    for q in range(Zr.size):
        s += ez[q] * d[Zr[q]]
    for j in range(mu.size):
        if mu[j] != 0.0:
            c = 0.0
            for p in range(Cp[j], Cp[j + 1]):
                c += Cx[p] * d[Ci[p]]
            s += (beta - 1.0) * mu[j] / (dt * dt) * c
    return 0.5 * s


# The helpers inlined into the loop read the tuples' fields they use before their first
# loop or branch: a tuple used in one block only is an SSA value, one used across blocks
# a stack copy of the whole struct in every helper (compile time, docs/design.md).
@njit(cache=True, inline="always")
def free_step(ops, st, Gn, H, row, massless):
    """st.x ← the step without contact, st.yf ← C x, st.Ku ← K uⁿ (reused by the energy);
    ``Gn``: the load coefficients Gⁿ of this step; st.r_e: the law's explicit force;
    ``H[row]``: the load at the quasi-static massless rows (see massless_force)."""
    dt, Kb, Kj, Bb, Bj, loads, Achol = ops.dt, ops.Kb, ops.Kj, ops.Bb, ops.Bj, ops.loads, \
        ops.Achol
    Cp, Ci, Cx = ops.Cp, ops.Ci, ops.Cx
    Zr, Zp, Zi, Zx, beta = ops.Zr, ops.Zp, ops.Zi, ops.Zx, ops.beta
    x, u_cur, u_prev, Ku, r_e, d, yf = st.x, st.u_cur, st.u_prev, st.Ku, st.r_e, st.d, st.yf
    dt2 = dt * dt
    rows_matvec(Kb, Kj, u_cur, Ku, 1.0, np.bool_(False))
    for i in range(x.size):
        s = -Ku[i]
        for k in range(Gn.size):
            s += Gn[k] * loads[i, k]
        x[i] = dt2 * s
    for r in range(r_e.size):
        if r_e[r] != 0.0:
            for p in range(Cp[r], Cp[r + 1]):
                x[Ci[p]] += dt2 * Cx[p] * r_e[r]
    if Bb.shape[0]:
        for i in range(d.size):
            d[i] = u_cur[i] - u_prev[i]
        rows_matvec(Bb, Bj, d, x, -dt, np.bool_(True))
    if massless is not None:
        massless_force(Zr, Zp, Zi, Zx, beta, Ku, u_prev, H, row, massless)
        for q in range(Zr.size):
            x[Zr[q]] += dt2 * massless[q]
    band_solve(Achol, x)
    for i in range(x.size):
        x[i] += 2.0 * u_cur[i] - u_prev[i]
    csr_product(Cp, Ci, Cx, x, yf)


@njit(cache=True, inline="always")
def finish_step(ops, st, Gn, massless):
    """uⁿ⁺¹ = x_free + W μ; the step's damping and load work (below); shift
    (uⁿ⁻¹, uⁿ) ← (uⁿ, uⁿ⁺¹) and their constrained values, st.dy ← C(uⁿ⁺¹ − uⁿ⁻¹); then
    μ ← the whole contact force (the law's explicit part added) and its work.

    The scheme's energy identity, from its equation times (uⁿ⁺¹ − uⁿ⁻¹)ᵀ/Δt²:
        ½E_β^{n+1} − ½E_β^n + δᵀBδ/(4Δt) = ½ Gⁿ·Lᵀδ + ½ λᵀCδ,   δ = uⁿ⁺¹ − uⁿ⁻¹,
    (L the load vectors), so the saved energy, the damping work and the load and contact
    work add up to round-off at every step (``st.work``)."""
    dt, Wt, Bb, Bj, loads, Cp, Ci, Cx = ops.dt, ops.Wt, ops.Bb, ops.Bj, ops.loads, ops.Cp, \
        ops.Ci, ops.Cx
    Zr, beta = ops.Zr, ops.beta
    x, mu, d, u_prev, u_cur, work = st.x, st.mu, st.d, st.u_prev, st.u_cur, st.work
    dy, y_prev, y_cur, r_e, rowwork = st.dy, st.y_prev, st.y_cur, st.r_e, st.rowwork
    if Wt.shape[0] == mu.size:  # else an x-space law wrote uⁿ⁺¹ into x (no W)
        add_columns(Wt, mu, x)
    for i in range(x.size):
        d[i] = x[i] - u_prev[i]
    if Bb.shape[0]:
        work[0] += rows_dot(Bb, Bj, d, d) / (4.0 * dt)
    for k in range(Gn.size):
        s = 0.0
        for i in range(x.size):
            s += loads[i, k] * d[i]
        work[1] += 0.5 * Gn[k] * s
    if massless is not None:    # quasi-static massless rows
        work[2] += massless_work(Zr, massless, d, mu, Cp, Ci, Cx, beta, dt)
    for i in range(x.size):
        u_prev[i] = u_cur[i]
        u_cur[i] = x[i]
    for j in range(mu.size):
        dy[j] = -y_prev[j]
        y_prev[j] = y_cur[j]
    csr_product(Cp, Ci, Cx, u_cur, y_cur)
    for j in range(mu.size):
        dy[j] += y_cur[j]
    dt2 = dt * dt
    for j in range(r_e.size):   # the contact force: explicit and implicit parts
        if r_e[j] != 0.0:
            mu[j] += dt2 * r_e[j]
    for j in range(mu.size):
        if mu[j] != 0.0:
            work[2] += 0.5 * mu[j] / dt2 * dy[j]
    if rowwork.shape[0]:          # two planes: each row's share
        for j in range(mu.size):
            rowwork[j, 0] += 0.5 * mu[j] / dt2 * dy[j]


@njit(cache=True)
def energy_beta(Eb, Ej, u_prev, u_cur, Ku, d):
    """E_β = δᵀ(M/Δt² + βK)δ + uⁿᵀ K uⁿ⁻¹,  δ = uⁿ − uⁿ⁻¹ (exactly conserved without contact).

    (``Eb``, ``Ej``) is M/Δt² + βK in the row layout; ``Ku`` is K uⁿ⁻¹, left by the step.
    """
    for i in range(d.size):
        d[i] = u_cur[i] - u_prev[i]
    s = rows_dot(Eb, Ej, d, d)
    for i in range(d.size):
        s += u_cur[i] * Ku[i]
    return s


@njit(cache=True, inline="always")
def record(n, ops, st, out, lands):
    """Diagnostics after state n: penetration (every step), saved series, frames.
    ``lands``: None, or Ops.Nc in a run with a broached hole (see run_steps)."""
    dt, disks, pair, Sp, Si, Sx, Op, Oi, Ox, Eb, Ej = ops.dt, ops.disks, ops.pair, ops.Sp, \
        ops.Si, ops.Sx, ops.Op, ops.Oi, ops.Ox, ops.Eb, ops.Ej
    save_every, frame_every = ops.save_every, ops.frame_every
    stats, u_cur, u_prev, y_cur, lo, hi, slo, shi = st.stats, st.u_cur, st.u_prev, st.y_cur, \
        st.lo, st.hi, st.slo, st.shi
    counters, Ku, d, work, mu = st.counters, st.Ku, st.d, st.work, st.mu
    obs, obsv, energy, out_work, lam, frames_u, frames_v, frames_f = out.obs, out.obsv, \
        out.energy, out.work, out.lam, out.frames_u, out.frames_v, out.frames_f
    for r in range(y_cur.size):
        if lands is not None and broached(pair, lands, r):   # its box is no bound: violation's
            continue
        v = max(lo[r] - y_cur[r], y_cur[r] - hi[r])
        if v > stats[0]:
            stats[0] = v
    for r in disks:           # round holes: beyond the circle (a loop of its own: 1 µs a
        v = violation(pair, lands, lo, hi, y_cur, r)   # step on 40 box rows)
        if v > stats[0]:
            stats[0] = v
    for r in range(slo.size):
        s = 0.0
        for p in range(Sp[r], Sp[r + 1]):
            s += Sx[p] * u_cur[Si[p]]
        if slo[r] - s > stats[1]:
            stats[1] = slo[r] - s
        if s - shi[r] > stats[2]:
            stats[2] = s - shi[r]
    dt2 = dt * dt
    if n % save_every == 0:
        k = n // save_every - counters[5]   # the buffers hold rows from counters[5] on
        for r in range(Op.size - 1):
            s = 0.0
            sv = 0.0
            for p in range(Op[r], Op[r + 1]):
                s += Ox[p] * u_cur[Oi[p]]
                sv += Ox[p] * (u_cur[Oi[p]] - u_prev[Oi[p]])
            obs[k, r] = s
            obsv[k, r] = sv / dt
        energy[k] = 0.5 * energy_beta(Eb, Ej, u_prev, u_cur, Ku, d)
        for c in range(4):
            out_work[k, c] = work[c]
        for j in range(mu.size):
            lam[k, j] = mu[j] / dt2
    if n % frame_every == 0:
        k = n // frame_every
        for i in range(u_cur.size):
            frames_u[k, i] = u_cur[i]
            frames_v[k, i] = (u_cur[i] - u_prev[i]) / dt
        for j in range(mu.size):
            frames_f[k, j] = mu[j] / dt2


@njit(cache=True, inline="always")
def call_law(law, ops, st):
    """One call of a compiled law on the state's free step."""
    return law(ops.D, st.yf, st.y_cur, st.y_prev, st.lo, st.hi, ops.params, st.law_state,
               st.mu, st.active)


@njit(cache=True, inline="always")
def move_bounds(ops, st, phi):
    """The bounds at t_{n+1}: at rest plus shift·φ(t_{n+1}) (obstacles that move with a
    support, seen in the lifted variable)."""
    shift, lo, hi, sshift, slo, shi = ops.shift, ops.lo, ops.hi, ops.sshift, ops.slo, ops.shi
    lo_t, hi_t, slo_t, shi_t = st.lo, st.hi, st.slo, st.shi
    st.stats[3] = phi
    for j in range(shift.size):
        lo_t[j] = lo[j] + shift[j] * phi
        hi_t[j] = hi[j] + shift[j] * phi
    for r in range(sshift.size):
        slo_t[r] = slo[r] + sshift[r] * phi
        shi_t[r] = shi[r] + sshift[r] * phi


@njit(cache=True, inline="always")
def broached(pair, Nc, j):
    """Whether the value j is a row of a broached hole's pair (Ops.Nc's lands)."""
    return pair[j] != 0 and Nc.shape[0] > 0 and Nc[j, 6] > 0.0


@njit(cache=True, inline="always")
def violation(pair, lands, lo, hi, y, j):
    """How far the value y[j] is beyond its bounds (≤ 0: within); a round hole's first
    row: its pair's distance beyond the circle (the box [lo, hi] is the disk's square);
    a broached hole's: max over its lands' φ of p·e(φ) − r (contact.lands.land_excess;
    its box is no bound: the lobes reach beyond it).  ``lands``: Ops.Nc in a run with a
    broached hole, else None (no broached code compiled).
    (Arrays, not the State: passing the tuple costs its reference counts, 5 µs a step
    in run_steps_python, measured.)"""
    if lands is not None and broached(pair, lands, j):
        b = pair[j]
        return land_excess(y[j] - 0.5 * (lo[j] + hi[j]), y[b] - 0.5 * (lo[b] + hi[b]),
                           0.5 * (hi[j] - lo[j]), lands[j, 6], lands[j, 7], lands[j, 8])
    v = max(lo[j] - y[j], y[j] - hi[j])
    if pair[j] > 0:
        b = pair[j]
        pa = y[j] - 0.5 * (lo[j] + hi[j])
        pb = y[b] - 0.5 * (lo[b] + hi[b])
        v = max(v, np.hypot(pa, pb) - 0.5 * (hi[j] - lo[j]))
    return v


@njit(cache=True, inline="always")
def row_force(pair, mu, j):
    """|μ| of the value j's contact (a round hole's first row: of its pair; its second: 0)."""
    if pair[j] > 0:
        return np.hypot(mu[j], mu[pair[j]])
    if pair[j] < 0:
        return 0.0
    return abs(mu[j])


@internal
def write_event(events, counters, j, e):
    """Event row k of the buffer from the value j's State.impact row ``e`` (then free)."""
    k = counters[4]
    events[k, 0] = j
    events[k, 1] = e[0]
    events[k, 2] = e[5]
    for c in range(1, 5):
        events[k, c + 2] = e[c]
    for c in range(6, IMPACT_FIELDS):
        events[k, c + 1] = e[c]
    counters[4] = k + 1
    e[0] = -1.0


@njit(cache=True, inline="always")
def node_position(Np, Ni, Nx, Nc, u, phi, j, out):
    """out ← the value j's node (v, w) at ``u`` (uⁿ⁺¹) minus its hole's centre at φ."""
    for c in range(2):
        s = 0.0
        for p in range(Np[2 * j + c], Np[2 * j + c + 1]):
            s += Nx[p] * u[Ni[p]]
        out[c] = s
    out[2] = out[0] - (Nc[j, 0] + Nc[j, 2] * phi)
    out[3] = out[1] - (Nc[j, 1] + Nc[j, 3] * phi)


@njit(cache=True, inline="always")
def normal_of(Nc, j, px, py, lands):
    """The unit normal of the value j's wall at the offset (px, py) from the centre
    (``lands``: as hole_kinematics')."""
    nx, ny = Nc[j, 4], Nc[j, 5]
    if lands is not None and Nc[j, 6] > 0.0:     # a broached hole: its arc's or line's
        return land_normal(px, py, Nc[j, 6], Nc[j, 7], Nc[j, 8])
    if nx == 0.0 and ny == 0.0:          # a round hole: radial
        r = np.hypot(px, py)
        if r == 0.0:
            return 1.0, 0.0
        return px / r, py / r
    return nx, ny


@njit(cache=True, inline="always")
def friction_split(mu, dy, at, work, rowwork, ev, a, b, dt):
    """The β-scheme with Coulomb friction (contact.round_hole_friction), after the step:
    the round hole (a, b)'s tangential work ½ λ_t s/Δt² (t the wall's tangent at y^{n+1},
    μ_t = t·μ_p, s = t·(y^{n+1} − y^{n−1}) = t·dy) moves from the contact's column to the
    friction's (FRICTION, rowwork's column 2); the event under way gets the slip |s|/2
    (= |u_t|Δt, u_t = s/(2Δt)) and the impulse |μ_t|/Δt.  ``at``: (y^{n+1}, lo, hi)."""
    y, lo, hi = at
    pa = y[a] - 0.5 * (lo[a] + hi[a])
    pb = y[b] - 0.5 * (lo[b] + hi[b])
    rho = np.hypot(pa, pb)
    if rho == 0.0 or (mu[a] == 0.0 and mu[b] == 0.0):
        return
    ta, tb = -pb / rho, pa / rho
    _to_friction(ta * mu[a] + tb * mu[b], ta * dy[a] + tb * dy[b], work, rowwork, ev, a, dt)


@njit(cache=True)
def land_friction_split(pair, Nc, mu, dy, at, work, rowwork, ev, a, dt):
    """friction_split for a broached hole's pair (a, pair[a]): its contacts' (one, two at
    a lobe's corner: contact.lands.land_split) tangential work ½ λ_t s/Δt² moves from the
    contact's column to the friction's.  ``at``: (y^{n+1}, lo, hi)."""
    y, lo, hi = at
    b = pair[a]
    if mu[a] == 0.0 and mu[b] == 0.0:
        return
    p = (y[a] - 0.5 * (lo[a] + hi[a]), y[b] - 0.5 * (lo[b] + hi[b]))
    count, _, t1, s1, _, t2, s2 = land_split(
        (mu[a], mu[b]), p, (dy[a], dy[b]), 0.5 * (hi[a] - lo[a]),
        Nc[a, FRICTION_COLUMN], (Nc[a, 6], Nc[a, 7], Nc[a, 8]))
    _to_friction(t1, s1, work, rowwork, ev, a, dt)
    if count == 2:
        _to_friction(t2, s2, work, rowwork, ev, a, dt)


@njit(cache=True, inline="always")
def face_friction_split(mu, dy, work, rowwork, ev, t, dt):
    """friction_split for a face with friction: its tangent row t's work ½ μ_t s/Δt²
    (s = dy[t], the step's slip along t·(v, w); the face's outward tangent is ±t, the
    product the same) moves from the contact's column to the friction's; the face's
    event under way gets the slip |s|/2 and the impulse |μ_t|/Δt."""
    if mu[t] == 0.0:
        return
    _to_friction(mu[t], dy[t], work, rowwork, ev, t, dt)


@njit(cache=True, inline="always")
def _to_friction(mt, s, work, rowwork, ev, row, dt):
    """A contact's tangential work ½ μ_t s/Δt² moves from the contact's column to the
    friction's (and in row ``row`` of rowwork); the event under way gets the slip |s|/2
    and the impulse |μ_t|/Δt."""
    w = 0.5 * mt * s / (dt * dt)
    work[2] -= w
    work[FRICTION] += w
    if rowwork.shape[0]:
        rowwork[row, 0] -= w
        rowwork[row, 2] += w
    if ev[0] >= 0.0:
        ev[9] += 0.5 * abs(s)
        ev[10] += abs(mt) / dt


@njit(cache=True, inline="always")
def track_holes(ops, st, step, p, lands, friction, slid):
    """hole_kinematics of the state after step (its arrays read off the tuples here: the
    out-of-line function takes arrays, not the tuples' structs, which cost its compile
    ~1 CPU s more); ``slid``: hole_kinematics' ``slid``."""
    hole_kinematics(ops.pair, ops.Nc, (ops.Np, ops.Ni, ops.Nx), (st.u_cur, st.stats[3]),
                    (st.mu, st.dy, st.y_cur, st.lo, st.hi),
                    (st.work, st.rowwork, st.impact, st.pos, st.sectors, slid), step, ops.dt,
                    p, lands, friction)


@internal
def hole_kinematics(pair, Nc, nodes, at, force, tallies, step, dt, p, lands, friction):
    """Two planes, after state step+1: every row's node position, its impact angle and
    velocities when a contact starts, and its work rates' sums (State.pos, rowwork,
    sectors: |F_n||v_t|Δt with F_n the force's normal part, in the sector the wall's
    normal points to).  ``nodes``: Ops' (Np, Ni, Nx); ``at``: (uⁿ⁺¹, φ(t_{n+1})); ``force``:
    State's (mu, dy, y_cur, lo, hi); ``tallies``: State's (work, rowwork, impact, pos,
    sectors) and ``slid``: per row the |F_n||v_t|Δt its scheme found itself (NaN: none),
    or empty (the β-scheme: none; Moreau–Jean gives its rows with friction theirs,
    moreau_jean.mj_steps).  ``lands``: None (no broached hole: their code is not
    compiled), or Ops.Nc; ``friction``: None (no row with Coulomb's μ in Nc's
    FRICTION_COLUMN: the friction splits are not compiled, `friction_of_ops`), or Ops.Nc."""
    Np, Ni, Nx = nodes
    u, phi = at
    mu, dy, y_cur, lo, hi = force
    work, rowwork, impact, pos, sectors, slid = tallies
    for j in range(mu.size):
        if pair[j] < 0:
            continue
        if friction is not None:
            if lands is not None and pair[j] > 0 and Nc[j, FRICTION_COLUMN] > 0.0 \
                    and Nc[j, 6] > 0.0:
                land_friction_split(pair, Nc, mu, dy, (y_cur, lo, hi), work, rowwork,
                                    impact[j], j, dt)
            elif pair[j] > 0 and Nc[j, FRICTION_COLUMN] > 0.0:
                friction_split(mu, dy, (y_cur, lo, hi), work, rowwork, impact[j], j,
                               pair[j], dt)
            elif Nc[j, FRICTION_COLUMN] > 0.0:     # a face with friction
                face_friction_split(mu, dy, work, rowwork, impact[j],
                                    int(Nc[j, TANGENT_COLUMN]), dt)
        node_position(Np, Ni, Nx, Nc, u, phi, j, p)
        ev = impact[j]
        nx, ny = normal_of(Nc, j, p[2], p[3], lands)
        if ev[0] == step + 1:            # a contact starts: where and how fast before it
            vx = (pos[j, 2] - pos[j, 0]) / dt
            vy = (pos[j, 3] - pos[j, 1]) / dt
            # a face row's lower face (μ > 0: n·p ≥ lo) faces −n
            sign = -1.0 if pair[j] == 0 and mu[j] > 0.0 else 1.0
            ev[6] = np.arctan2(p[3], p[2])
            ev[7] = sign * (vx * nx + vy * ny)
            ev[8] = sign * (-vx * ny + vy * nx)
        f = abs(mu[j]) if pair[j] == 0 else abs(mu[j] * nx + mu[pair[j]] * ny)
        if f != 0.0:                     # |F_n||v_t|Δt, v_t of the central difference
            vx = (p[2] - pos[j, 0]) / (2.0 * dt)
            vy = (p[3] - pos[j, 1]) / (2.0 * dt)
            w = f / (dt * dt) * abs(-vx * ny + vy * nx) * dt
            if slid.size and not np.isnan(slid[j]):
                w = slid[j]
            rowwork[j, 1] += w
            # the sector the wall's outward normal points to: in a round hole the node's
            # angle; on a broached hole's land edge (the node in a lobe's corner) the edge's;
            # a face row bounds two opposite faces, n·p ≤ hi (μ < 0 there) and n·p ≥ lo
            if Nc[j, 4] == 0.0 and Nc[j, 5] == 0.0 and (lands is None or Nc[j, 6] <= 0.0):
                angle = np.arctan2(p[3], p[2])
            elif pair[j] == 0 and mu[j] > 0.0:
                angle = np.arctan2(-ny, -nx)
            else:
                angle = np.arctan2(ny, nx)
            k = int((angle + np.pi) / (2.0 * np.pi) * SECTORS)
            sectors[j, min(max(k, 0), SECTORS - 1)] += w
        # the offsets from the hole's centre, which a moving support may move: the slip
        # and the approach are relative to the hole (the lifted u's were the frame's)
        pos[j, 0], pos[j, 1] = pos[j, 2], pos[j, 3]
        pos[j, 2], pos[j, 3] = p[2], p[3]


def switch(ops, column: int):
    """One of the loop's code switches: Ops.Nc when some row has Nc[:, column] > 0, else
    None (numba prunes the branches of a None argument: their code is not compiled)."""
    Nc = ops.Nc
    return Nc if Nc.shape[0] and bool((Nc[:, column] > 0.0).any()) else None


def friction_of_ops(ops):
    """The loop's ``friction`` argument (run_steps, hole_kinematics): Ops.Nc when some row
    has Coulomb's μ in Nc's FRICTION_COLUMN (the β-scheme's law takes friction), else
    None: a run without one compiles none of the friction splits."""
    return switch(ops, FRICTION_COLUMN)


@njit(cache=True, inline="always")
def track_impacts(ops, st, out, step, lands):
    """Contact bookkeeping after state step+1: impacts counted when a value enters
    contact; an event (State.impact) owns its value's contact force λ (the total: a
    law's explicit part included) from its first state to the second state off the
    obstacle, or to the value's next impact, then it becomes one row (EVENT_COLUMNS).
    Why two states: a law's explicit force reads yⁿ and yⁿ⁻¹, so a spring's β-weighted
    force trails the contact by up to two states; Σ impulse is then Σ λΔt of the run
    (exact laws: λ = 0 off contact, the same rows).  Returns EVENTS_FULL when the event
    buffer has no room left for another row.  ``lands``: as violation's."""
    dt, pair = ops.dt, ops.pair
    counters, ev, active, active_prev, y_prev, y_cur, dy, mu, fc, lo, hi = st.counters, \
        st.impact, st.active, st.active_prev, st.y_prev, st.y_cur, st.dy, st.mu, st.fc, \
        st.lo, st.hi
    events = out.events
    any_active = False
    for j in range(active.size):
        a = active[j]
        if a and not active_prev[j]:
            counters[0] += 1
            if ev[j, 0] >= 0.0:          # the last contact's trailing force ends here
                write_event(events, counters, j, ev[j])
            ev[j, 0] = step + 1
            # approach velocity (yⁿ − yⁿ⁻¹)/Δt, with yⁿ⁻¹ = yⁿ⁺¹ − dy
            ev[j, 1] = (y_prev[j] - y_cur[j] + dy[j]) / dt
            ev[j, 2] = 0.0
            ev[j, 3] = 0.0
            ev[j, 4] = 0.0
            ev[j, 5] = -1.0
            for c in range(6, 9):
                ev[j, c] = np.nan
            ev[j, 9] = 0.0
            ev[j, 10] = 0.0
        elif active_prev[j] and not a:
            ev[j, 5] = step + 1          # the first state off the obstacle
        if ev[j, 0] >= 0.0:
            if mu[j] != 0.0 or pair[j] > 0:
                # a round hole's force is its pair's, its impulse Σ|λ|Δt
                lam = mu[j] / (dt * dt) if pair[j] == 0 else row_force(pair, mu, j) / (dt * dt)
                ev[j, 2] = max(ev[j, 2], abs(lam))
                ev[j, 3] += lam * dt
            if fc.shape[0] and pair[j] > 0:     # friction: slip and its impulse
                ev[j, 9] += abs(fc[j, 3]) * dt
                ev[j, 10] += abs(fc[j, 1])
            if a:
                ev[j, 4] = max(ev[j, 4], violation(pair, lands, lo, hi, y_cur, j))
            elif step + 1 > ev[j, 5]:    # the second state off: no force can trail further
                write_event(events, counters, j, ev[j])
        active_prev[j] = a
        any_active = any_active or a
    if any_active:
        counters[1] += 1
    return EVENTS_FULL if counters[4] + active.size > events.shape[0] else 0


@njit(cache=True, inline="always")
def stop_code(ops, st, out, step, full):
    """After the diagnostics of state step+1: UNSTABLE when its saved energy is non-finite
    or above its row's bound, else ``full`` (EVENTS_FULL when the event buffer must be
    emptied before the next step, else 0); counters[3] ← step+1 when the loop must stop."""
    counters, save_every, energy, bound = st.counters, ops.save_every, out.energy, out.bound
    k = (step + 1) // save_every - counters[5]
    if (step + 1) % save_every == 0 and not abs(energy[k]) <= bound[k]:
        counters[3] = step + 1
        return UNSTABLE
    if full:
        counters[3] = step + 1
    return full


# Compiled without numba's reference counting: the loop allocates nothing, and the
# refcount operations on the named tuples' arrays cost 0.6 µs of a 1.3 µs step (measured).
# nogil: the output pipeline writes the last chunk's rows while this computes the next.
# No C entry wrapper: it is never passed as a first-class function.
@njit(cache=True, _nrt=False, nogil=True, no_cfunc_wrapper=True)
def run_steps(law, explicit, ops, st, out, n0, n1, inputs, holes, massless, lands):
    """Steps n = n0..n1−1 (computing uⁿ⁺¹) with a compiled law: the bounds at t_{n+1},
    the law's explicit force, the free step, the law, then `finish_step`, the impact
    events, the diagnostics and `stop_code`.  ``inputs`` (Inputs) hold Gⁿ and φ(t_{n+1})
    at row n − n0.  ``holes``: None, or (two planes with holes) the scratch of
    `hole_kinematics` and its ``friction`` (None, or Ops.Nc when some row has Coulomb's
    μ there: `friction_of_ops`); ``massless``: None, or State.ez (quasi-static massless
    rows); ``lands``: None, or Ops.Nc when a broached hole is among the holes
    (`lands_of`).  numba prunes the
    branch of a None argument before typing it, so a run without holes, massless rows,
    broached holes or friction does not compile their code (0.5, 0.15 and, with
    friction, 3 CPU s of a first run).

    Returns 0, FAILED (the law failed at step counters[3]), UNSTABLE (the energy saved
    at state counters[3] is non-finite or above its row's Series.bound) or EVENTS_FULL
    (stopped after state counters[3] for the caller to take the impact events).
    """
    for step in range(n0, n1):
        Gn = inputs.G[step - n0]
        move_bounds(ops, st, inputs.phi[step - n0])
        explicit(st.y_cur, st.y_prev, st.lo, st.hi, ops.params, st.r_e)
        free_step(ops, st, Gn, inputs.H, step - n0, massless)
        its = call_law(law, ops, st)
        if its < 0:
            st.counters[3] = step + 1
            return FAILED
        st.counters[2] += its
        finish_step(ops, st, Gn, massless)
        full = track_impacts(ops, st, out, step, lands)
        if holes is not None:
            track_holes(ops, st, step, holes[0], lands, holes[1], holes[0][:0])
        record(step + 1, ops, st, out, lands)
        code = stop_code(ops, st, out, step, full)
        if code:
            return code
    return 0


def lands_of(ops):
    """The loop's ``lands`` argument (run_steps): Ops.Nc when some row belongs to a broached
    hole (Nc's column 6, its lands, > 0; contact.lands), else None: a run without one
    compiles none of their code."""
    return switch(ops, 6)


@njit(cache=True)
def inside(y, lo, hi) -> bool:
    """lo ≤ y ≤ hi everywhere."""
    for i in range(y.size):
        if not lo[i] <= y[i] <= hi[i]:
            return False
    return True


class PythonLaw:
    """The law solved in Python that `run_steps_python` calls (one run at a time per
    process), the state's arrays it reads and writes (the same memory as the compiled
    loop's: nothing is boxed per step), and the error it raised, if any."""
    solver = None
    state = None
    error = None


def _solve_in_python() -> int:
    st = PythonLaw.state
    try:
        m, its = PythonLaw.solver.solve(st.x, st.yf, st.lo, st.hi)
    except Exception as e:        # handed back to the run, which raises it with the step
        PythonLaw.error = e
        return -1
    st.mu[:] = m
    return its


@njit(cache=True)
def python_law() -> int:
    """`_solve_in_python` from compiled code.  A function of its own: an object-mode block
    inside `run_steps_python` made each of its steps with a call 11-14 µs slower, though
    the call alone costs 0.55 µs in a small loop (why, not found).  OSQP on flat J = 40
    took 25 µs a step, 5.1× the active set; a Python law returning μ = 0 took 17.6 ms
    for 1,000 calls against 6.1 ms without the block, 7.3 ms with the block here."""
    with objmode(its="int64"):
        its = _solve_in_python()
    return its


@njit(cache=True)
def run_steps_python(ops, st, out, n0, n1, inputs, free_inside, holes,
                     massless, lands):
    """The same steps as `run_steps` with the law solved in Python (`PythonLaw.solver`,
    e.g. OSQP or daqp, given the step's bounds): the compiled loop calls it for μ when
    the free step leaves its bounds.  When it does not and ``free_inside`` (the law's:
    ContactLaw.free_inside), μ = 0 is the step's exact solution (the unconstrained
    minimiser is feasible) and the engine is not called: its calls are then exactly the
    steps in contact (counters[CONTACT_STEPS])."""
    for step in range(n0, n1):
        Gn = inputs.G[step - n0]
        move_bounds(ops, st, inputs.phi[step - n0])
        free_step(ops, st, Gn, inputs.H, step - n0, massless)
        if free_inside and inside(st.yf, st.lo, st.hi):
            its = 0
            st.mu[:] = 0.0
        else:
            its = python_law()
        if its < 0:
            st.counters[3] = step + 1
            return FAILED
        for j in range(st.mu.size):
            st.active[j] = st.mu[j] != 0.0
        st.counters[2] += its
        finish_step(ops, st, Gn, massless)
        full = track_impacts(ops, st, out, step, lands)
        if holes is not None:
            track_holes(ops, st, step, holes[0], lands, holes[1], holes[0][:0])
        record(step + 1, ops, st, out, lands)
        code = stop_code(ops, st, out, step, full)
        if code:
            return code
    return 0
