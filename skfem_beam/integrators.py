"""The contact-implicit β-family of Dumont & Paoli (γ = 1/2, β ∈ [0, 1/2]).

Each step solves  u^{n+1} = argmin_{lo ≤ Cu ≤ hi} ½uᵀAu − Fⁿᵀu  with

    A  = M + Δt/2 B + Δt² β K
    Fⁿ = (2M − Δt²(1−2β)K) uⁿ − (M − Δt/2 B + Δt² β K) uⁿ⁻¹ + Δt² Gⁿ
    Gⁿ = β f^{n+1} + (1−2β) fⁿ + β f^{n−1},   fⁿ = (1/Δt)∫_{tₙ}^{tₙ+Δt} f dt

(B = 0 for the beam: the papers' scheme; B is Kelvin–Voigt damping for the bar).
One implementation: the compiled loop `_run` is made of `free_step`, a compiled
contact solve and `finish_step`; solvers that live in Python (OSQP, daqp) call the
same two compiled functions around their own solve.
"""
from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse
import scipy.sparse.linalg
from numba import njit

from .contact import COMPILED, choose_solver, python_solver
from .contact.active_set import box_qp
from .contact.penalty import compliance_solve, spring_force
from .contact.projection import project
from .errors import InputError, SolverError
from .linalg import Banded, band_solve, rows_dot, rows_matvec2
from .problem import check_beta, check_positive
from .semidiscrete import SemiDiscrete
from .stability import kappa_h, linear_limit

_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(4)
FAILED, UNSTABLE = 1, 2


@dataclass
class Result:
    """What a run returns, in the spirit of ``scipy.integrate.solve_ivp``.

    ``t``: saved times; ``observed[name]`` and ``velocity[name]``: observed values and
    their backward-difference velocities (uⁿ − uⁿ⁻¹)/Δt; ``energy``: ½E_β^n (the
    discrete energy of DESIGN.md, halved so that it tends to ½|u̇|² + ½a(u,u));
    ``contact_force``: nodal contact forces λ (saved × m, force per unit mass per
    length, m²/s² for the beam); ``frames_t``, ``frames_u``, ``frames_v`` (backward
    difference velocity), ``frames_force`` (λ): decimated coefficient vectors; ``status``: "success" or "unstable"; ``message`` says why.
    """
    t: np.ndarray
    observed: dict
    velocity: dict
    energy: np.ndarray
    contact_force: np.ndarray
    frames_t: np.ndarray
    frames_u: np.ndarray
    frames_v: np.ndarray
    frames_force: np.ndarray
    status: str
    message: str
    steps: int
    dt: float
    T: float
    beta: float
    solver: str
    wall_time_s: float
    max_nodal_violation: float
    max_penetration: float
    max_penetration_below: float
    max_penetration_above: float
    impacts: int
    contact_fraction: float
    qp_iterations: int
    system: SemiDiscrete = field(repr=False)

    @property
    def success(self) -> bool:
        return self.status == "success"


@njit(cache=True)
def free_step(M2, Am, Achol, loads, g, u_prev, u_cur, dt2, Cp, Ci, Cx, x, yf, r_expl):
    """x ← A⁻¹Fⁿ (the step without contact) and yf ← C x.

    ``r_expl``: explicit part of a penalty force on the constrained values (zero for
    Signorini), added to the load as Δt² Cᵀ r_expl.
    """
    rows_matvec2(M2, u_cur, Am, u_prev, x)
    for k in range(g.size):
        c = dt2 * g[k]
        for i in range(x.size):
            x[i] += c * loads[i, k]
    for r in range(r_expl.size):
        if r_expl[r] != 0.0:
            for p in range(Cp[r], Cp[r + 1]):
                x[Ci[p]] += dt2 * Cx[p] * r_expl[r]
    band_solve(Achol, x)
    for r in range(yf.size):
        s = 0.0
        for p in range(Cp[r], Cp[r + 1]):
            s += Cx[p] * x[Ci[p]]
        yf[r] = s


@njit(cache=True)
def finish_step(x, W, mu, u_prev, u_cur):
    """uⁿ⁺¹ = x_free + W μ; shift (uⁿ⁻¹, uⁿ) ← (uⁿ, uⁿ⁺¹)."""
    for j in range(mu.size):
        if mu[j] != 0.0:
            for i in range(x.size):
                x[i] += W[i, j] * mu[j]
    u_prev[:] = u_cur
    u_cur[:] = x


@njit(cache=True)
def energy_beta(Eb, Kb, u_prev, u_cur, d):
    """E_β = δᵀ(M/Δt² + βK)δ + uⁿᵀ K uⁿ⁻¹,  δ = uⁿ − uⁿ⁻¹ (exactly conserved without contact).

    ``Eb`` is M/Δt² + βK and ``Kb`` is K, both in row layout.
    """
    for i in range(d.size):
        d[i] = u_cur[i] - u_prev[i]
    return rows_dot(Eb, d, d) + rows_dot(Kb, u_cur, u_prev)


@njit(cache=True)
def record(n, save_every, frame_every, u_prev, u_cur, mu, dt, Eb, Kb, dt2,
           Op, Oi, Ox, Ep, Ei, Ex, slo, shi, C_y, lo, hi,
           obs, obsv, energy, lam, frames, frames_v, frames_f, stats, d):
    """Diagnostics after state n: penetration (every step), saved series, frames.

    stats: [max nodal violation, max (g1−u)⁺ sampled, max (u−g2)⁺ sampled, steps in contact]
    """
    for r in range(C_y.size):
        v = max(lo[r] - C_y[r], C_y[r] - hi[r])
        if v > stats[0]:
            stats[0] = v
    for r in range(slo.size):
        s = 0.0
        for p in range(Ep[r], Ep[r + 1]):
            s += Ex[p] * u_cur[Ei[p]]
        if slo[r] - s > stats[1]:
            stats[1] = slo[r] - s
        if s - shi[r] > stats[2]:
            stats[2] = s - shi[r]
    if n % save_every == 0:
        k = n // save_every
        for r in range(Op.size - 1):
            s = 0.0
            sv = 0.0
            for p in range(Op[r], Op[r + 1]):
                s += Ox[p] * u_cur[Oi[p]]
                sv += Ox[p] * (u_cur[Oi[p]] - u_prev[Oi[p]])
            obs[k, r] = s
            obsv[k, r] = sv / dt
        energy[k] = 0.5 * energy_beta(Eb, Kb, u_prev, u_cur, d)
        for j in range(mu.size):
            lam[k, j] = mu[j] / dt2
    if n % frame_every == 0:
        k = n // frame_every
        for i in range(u_cur.size):
            frames[k, i] = u_cur[i]
            frames_v[k, i] = (u_cur[i] - u_prev[i]) / dt
        for j in range(mu.size):
            frames_f[k, j] = mu[j] / dt2


@njit(cache=True)
def _penalty_explicit(beta, kappa, y_cur, y_prev, lo, hi, r_cur, r_prev, r_expl):
    """(1−2β) r(yⁿ) + β r(y^{n−1}) of the spring force r (see contact.penalty)."""
    spring_force(y_cur, lo, hi, kappa, r_cur)
    spring_force(y_prev, lo, hi, kappa, r_prev)
    for j in range(r_expl.size):
        r_expl[j] = (1 - 2 * beta) * r_cur[j] + beta * r_prev[j]


@njit(cache=True)
def _run(n0, n1, mode, kappa, save_every, frame_every, dt, beta,
         M2, Am, Achol, Eb, Kb, loads, G,
         Cp, Ci, Cx, lo, hi, W, D, Ddiag, state, active_prev,
         Ep, Ei, Ex, slo, shi, Op, Oi, Ox,
         u_prev, u_cur, obs, obsv, energy, lam, frames, frames_v, frames_f, stats, counters,
         Ebound):
    """Steps n = n0..n1−1 (computing u^{n+1}).

    mode: 0 no constraint, 1 projection, 2 active set, 3 penalty (stiffness kappa).
    counters: [impacts, steps in contact, QP iterations, step where it stopped].
    Returns 0, FAILED (a contact solve failed at counters[3]) or UNSTABLE (the energy
    saved at state counters[3] is non-finite or above Ebound).
    """
    n = u_cur.size
    m = lo.size
    dt2 = dt * dt
    x = np.empty(n)
    yf = np.empty(m)
    mu = np.zeros(m)
    cy = np.empty(m)
    d = np.empty(n)
    r_expl = np.zeros(m)
    r_a = np.empty(m)
    r_b = np.empty(m)
    y_prev = np.empty(m)
    for step in range(n0, n1):
        if mode == 3:
            _values(Cp, Ci, Cx, u_cur, cy)
            _values(Cp, Ci, Cx, u_prev, y_prev)
            _penalty_explicit(beta, kappa, cy, y_prev, lo, hi, r_a, r_b, r_expl)
        free_step(M2, Am, Achol, loads, G[step - n0], u_prev, u_cur, dt2, Cp, Ci, Cx, x, yf,
                  r_expl)
        if mode == 3:
            its = compliance_solve(D, yf, lo, hi, dt2 * beta * kappa, state, mu)
            if its < 0:
                counters[3] = step + 1
                return FAILED
            counters[2] += its
        elif mode == 1:
            project(Ddiag, yf, lo, hi, mu)
        elif mode == 2:
            its = box_qp(D, yf, lo, hi, state, mu)
            if its < 0:
                counters[3] = step + 1
                return FAILED
            counters[2] += its
        finish_step(x, W, mu, u_prev, u_cur)
        _values(Cp, Ci, Cx, u_cur, cy)
        any_active = False
        for j in range(m):
            # in contact: a Signorini multiplier, or a spring that is compressed
            a = mu[j] != 0.0 if mode != 3 else (cy[j] < lo[j] or cy[j] > hi[j])
            if a and not active_prev[j]:
                counters[0] += 1
            active_prev[j] = a
            any_active = any_active or a
            if mode == 3:   # the contact force of a spring is the total β-weighted force
                mu[j] += dt2 * r_expl[j]
        if any_active:
            counters[1] += 1
        record(step + 1, save_every, frame_every, u_prev, u_cur, mu, dt, Eb, Kb, dt2,
               Op, Oi, Ox, Ep, Ei, Ex, slo, shi, cy, lo, hi,
               obs, obsv, energy, lam, frames, frames_v, frames_f, stats, d)
        if (step + 1) % save_every == 0 and not abs(energy[(step + 1) // save_every]) <= Ebound:
            counters[3] = step + 1
            return UNSTABLE
    return 0


@njit(cache=True)
def _values(Cp, Ci, Cx, u, y):
    for r in range(y.size):
        s = 0.0
        for p in range(Cp[r], Cp[r + 1]):
            s += Cx[p] * u[Ci[p]]
        y[r] = s


def time_averages(fun, t0: np.ndarray, dt: float) -> np.ndarray:
    """(1/Δt)∫_{t0}^{t0+Δt} a(s) ds by 4-point Gauss–Legendre (exact to O((ωΔt)⁸))."""
    s = t0[:, None] + 0.5 * dt * (1.0 + _GAUSS_X[None, :])
    return (np.asarray(fun(s), dtype=float) * _GAUSS_W).sum(axis=1) / 2.0


def _csr(a):
    a = a.tocsr()
    return (a.indptr.astype(np.int64), a.indices.astype(np.int64), a.data.astype(float))


def solve(system: SemiDiscrete, dt: float, T: float, beta: float = 0.5, solver: str = "auto",
          stiffness: float | None = None, save_every: int = 1, frames: int = 200,
          progress: bool | None = None, chunk: int = 20000, load_window: str = "forward",
          growth_limit: float = 10.0) -> Result:
    """Integrate ``system`` over [0, T] with step ``dt``: the one entry point.

    ``solver`` names the contact solver (see :mod:`skfem_beam.contact`); with
    ``stiffness`` = κ the obstacles are instead one-sided springs (normal compliance,
    κ in the units of the semi-discrete equation, i.e. per unit mass for the beam).
    ``load_window``: fⁿ averages f over [tₙ, tₙ+Δt] ("forward", the papers' choice) or
    over [tₙ−Δt/2, tₙ+Δt/2] ("centered").  The forward window lags the load by Δt/2,
    which makes a forced run first order in Δt; the centred one keeps it second order.

    The run stops with status "unstable" when the discrete energy exceeds
    ``growth_limit`` × the a-priori bound (√E¹ + Σ‖Gⁿ‖_{M⁻¹}Δt)² or a value turns
    non-finite; what was computed up to the last good chunk is returned.
    """
    dt = check_positive("dt", dt)
    T = check_positive("T", T)
    beta = check_beta(beta)
    if isinstance(save_every, bool) or int(save_every) != save_every or save_every < 1:
        raise InputError(f"save_every={save_every!r} must be a whole number ≥ 1")
    N = int(math.ceil(T / dt - 1e-9))
    if N < 2:
        raise InputError(f"dt={dt:g} must be at most T/2={T / 2:g}")
    save_every = int(save_every)
    frame_every = max(1, N // max(1, int(frames)))

    M, K, B = system.M, system.K, system.B
    A = M + dt**2 * beta * K + (0.5 * dt * B if B is not None else 0)
    Am = M + dt**2 * beta * K - (0.5 * dt * B if B is not None else 0)
    M2 = 2 * M - dt**2 * (1 - 2 * beta) * K
    Ab = Banded(A, factor=True)
    M2b, Amb, Eb, Kb = Banded(M2), Banded(Am), Banded(M / dt**2 + beta * K), Banded(K)

    C = system.C.tocsr()
    m = C.shape[0]
    W = np.zeros((system.n, m))
    for j in range(m):
        col = C[j].toarray().ravel()
        band_solve(Ab.chol, col)
        W[:, j] = col
    D = np.ascontiguousarray((C @ W).reshape(m, m))
    if stiffness is None:
        name = choose_solver(solver, D)
        mode = COMPILED.get(name, -1)
        kappa = 0.0
    else:
        kappa = check_positive("stiffness", stiffness)
        name, mode = "penalty", 3
    pysolver = python_solver(name, A, C, system.lo, system.hi, D, W, dt) if mode < 0 else None

    # load: time averages fⁿ for n = 0..N, then Gⁿ = βf^{n+1} + (1−2β)fⁿ + βf^{n−1}
    nK = system.loads.shape[1]
    if load_window not in ("forward", "centered"):
        raise InputError(f"load_window={load_window!r} is not one of: forward, centered")
    shift = 0.5 * dt if load_window == "centered" else 0.0

    def load_coefficients(n0, n1):
        """Gⁿ for n = n0..n1−1 (computed per chunk: memory stays flat in T)."""
        t = np.arange(n0 - 1, n1 + 1) * dt - shift
        f = np.column_stack([time_averages(a, t, dt) for a in system.load_time])
        return np.ascontiguousarray(beta * f[2:] + (1 - 2 * beta) * f[1:-1] + beta * f[:-2])

    # start: u⁰, and u¹ = u⁰ + Δt v⁰ + Δt²/2 a⁰ (second order), kept in K_h
    u_prev = system.u0.astype(float).copy()
    f0 = system.loads @ np.array([float(a(np.array([0.0]))[0]) for a in system.load_time]) \
        if nK else np.zeros(system.n)
    rhs = f0 - K @ u_prev - (B @ system.v0 if B is not None else 0)
    a0 = scipy.sparse.linalg.spsolve(M.tocsc(), rhs)
    u1 = u_prev + dt * system.v0 + 0.5 * dt**2 * a0
    y1 = C @ u1
    if m and ((y1 < system.lo).any() or (y1 > system.hi).any()):
        # project u¹ onto K_h in the A-norm: one contact step with F = A u¹
        x = u1.copy()
        mu = np.zeros(m)
        st = np.zeros(m, dtype=np.int8)
        if box_qp(D, y1, system.lo, system.hi, st, mu) < 0:
            raise SolverError("could not place u¹ inside the obstacles")
        u1 = x + W @ mu
    u_cur = u1

    nsave = N // save_every + 1
    nobs = len(system.observe)
    Orows = scipy.sparse.csr_matrix(np.vstack(list(system.observe.values()))) if nobs \
        else scipy.sparse.csr_matrix((0, system.n))
    obs = np.full((nsave, nobs), np.nan)
    obsv = np.full((nsave, nobs), np.nan)
    energy = np.full(nsave, np.nan)
    lam = np.zeros((nsave, m))
    fr = np.full((N // frame_every + 1, system.n), np.nan)
    frv = np.full_like(fr, np.nan)
    frf = np.zeros((fr.shape[0], m))
    stats = np.zeros(4)
    counters = np.zeros(4, dtype=np.int64)
    state = np.zeros(m, dtype=np.int8)
    active_prev = np.zeros(m, dtype=np.bool_)

    Op, Oi, Ox = _csr(Orows)
    Cp, Ci, Cx = _csr(C)
    if system.sample_E is not None and system.sample_E.shape[0]:
        Ep, Ei, Ex = _csr(system.sample_E)
        slo = np.ascontiguousarray(system.sample_lo, dtype=float)
        shi = np.ascontiguousarray(system.sample_hi, dtype=float)
    else:
        Ep, Ei, Ex = np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros(0)
        slo = shi = np.zeros(0)
    lo = np.ascontiguousarray(system.lo, dtype=float)
    hi = np.ascontiguousarray(system.hi, dtype=float)
    Ddiag = np.ascontiguousarray(np.diag(D)) if m else np.zeros(0)
    d = np.empty(system.n)
    loads = np.ascontiguousarray(system.loads, dtype=float)

    # states 0 and 1 (E_β needs two states: the energy saved at t = 0 is E_β¹)
    obs[0] = Orows @ u_prev
    obsv[0] = Orows @ system.v0
    record(1, save_every, frame_every, u_prev, u_cur, np.zeros(m), dt, Eb.rows, Kb.rows,
           dt**2, Op, Oi, Ox, Ep, Ei, Ex, slo, shi, C @ u_cur, lo, hi,
           obs, obsv, energy, lam, fr, frv, frf, stats, d)
    fr[0], frv[0] = u_prev, system.v0

    E1 = 0.5 * energy_beta(Eb.rows, Kb.rows, u_prev, u_cur, d)
    energy[0] = E1
    Minv_norm = np.sqrt(np.array([lv @ scipy.sparse.linalg.spsolve(M.tocsc(), lv)
                                  for lv in loads.T])) if nK else np.zeros(0)
    work = 0.0   # Σ‖Gⁿ‖_{M⁻¹}Δt so far: the a-priori energy bound grows with it

    status, message = "success", "the run reached T"
    show = sys.stderr.isatty() if progress is None else progress
    bar = None
    if show and N > 10 * chunk:
        from tqdm import tqdm
        bar = tqdm(total=N, unit="step", unit_scale=True, leave=False)
    wall = 0.0
    last_good = N
    if pysolver is None:   # load the compiled kernel outside the timed loop (zero steps)
        _run(1, 1, mode, kappa, save_every, frame_every, dt, beta, M2b.rows, Amb.rows, Ab.chol,
             Eb.rows, Kb.rows, loads, np.zeros((0, nK)), Cp, Ci, Cx, lo, hi, W, D, Ddiag, state,
             active_prev, Ep, Ei, Ex, slo, shi, Op, Oi, Ox, u_prev, u_cur, obs, obsv, energy,
             lam, fr, frv, frf, stats, counters, 0.0)
    for n0 in range(1, N, chunk):
        n1 = min(N, n0 + chunk)
        t0 = time.perf_counter()
        G = load_coefficients(n0, n1) if nK else np.zeros((n1 - n0, 0))
        work += float((np.abs(G) @ Minv_norm).sum()) * dt if nK else 0.0
        # the bound grows with n: its chunk-end value is the loosest for the chunk
        Ebound = growth_limit * (math.sqrt(abs(E1)) + work) ** 2 + 1e-300
        if pysolver is None:
            code = _run(n0, n1, mode, kappa, save_every, frame_every, dt, beta,
                        M2b.rows, Amb.rows, Ab.chol, Eb.rows, Kb.rows, loads, G,
                        Cp, Ci, Cx, lo, hi, W, D, Ddiag, state, active_prev,
                        Ep, Ei, Ex, slo, shi, Op, Oi, Ox,
                        u_prev, u_cur, obs, obsv, energy, lam, fr, frv, frf, stats, counters,
                        Ebound)
        else:
            code = _python_chunk(pysolver, n0, n1, save_every, frame_every, dt, beta,
                                 M2b, Amb, Ab, Eb, Kb, loads, G, Cp, Ci, Cx, lo, hi, W,
                                 active_prev, Ep, Ei, Ex, slo, shi, Op, Oi, Ox,
                                 u_prev, u_cur, obs, obsv, energy, lam, fr, frv, frf, stats,
                                 counters,
                                 Ebound)
        wall += time.perf_counter() - t0
        if bar is not None:
            bar.update(n1 - n0)
        if code == FAILED:
            k = int(counters[3])
            raise SolverError(f"the {name} contact solver failed at step {k} (t={k * dt:.6g} s)")
        if code == UNSTABLE:
            k = int(counters[3])
            limit = linear_limit(kappa_h(system), beta)
            status = "unstable"
            message = (f"unstable at step {k} (t={k * dt:.6g} s): energy "
                       f"{energy[k // save_every]:.3g} exceeds {Ebound:.3g}; dt={dt:g} s, "
                       f"beta={beta:g}, linear stability limit 2/√(κ_h(1−4β)) = {limit:.4g} s")
            last_good = (k // save_every - 1) * save_every
            break
    if bar is not None:
        bar.close()

    if status != "success":
        keep = last_good // save_every + 1
        obs, obsv, energy, lam = obs[:keep], obsv[:keep], energy[:keep], lam[:keep]
        nf = last_good // frame_every + 1
        fr, frv, frf = fr[:nf], frv[:nf], frf[:nf]
    steps = last_good
    t = np.arange(obs.shape[0]) * save_every * dt
    names = list(system.observe)
    return Result(
        t=t, observed={k: obs[:, i] for i, k in enumerate(names)},
        velocity={k: obsv[:, i] for i, k in enumerate(names)}, energy=energy,
        contact_force=lam, frames_t=np.arange(fr.shape[0]) * frame_every * dt, frames_u=fr,
        frames_v=frv, frames_force=frf,
        status=status, message=message, steps=steps, dt=dt, T=N * dt, beta=beta, solver=name,
        wall_time_s=wall, max_nodal_violation=float(max(stats[0], 0.0)),
        max_penetration=float(max(stats[1], stats[2], stats[0], 0.0)),
        max_penetration_below=float(stats[1]), max_penetration_above=float(stats[2]),
        impacts=int(counters[0]), contact_fraction=float(counters[1]) / max(1, steps - 1),
        qp_iterations=int(counters[2]), system=system)


def _python_chunk(pysolver, n0, n1, save_every, frame_every, dt, beta, M2b, Amb, Ab, Eb, Kb,
                  loads, G, Cp, Ci, Cx, lo, hi, W, active_prev, Ep, Ei, Ex, slo, shi,
                  Op, Oi, Ox, u_prev, u_cur, obs, obsv, energy, lam, fr, frv, frf, stats,
                  counters,
                  Ebound):
    """The same step as `_run`, with the contact solve done by a Python-level engine."""
    n, m = u_cur.size, lo.size
    x, yf, d = np.empty(n), np.empty(m), np.empty(n)
    no_spring = np.zeros(m)
    dt2 = dt * dt
    for step in range(n0, n1):
        free_step(M2b.rows, Amb.rows, Ab.chol, loads, G[step - n0], u_prev, u_cur, dt2,
                  Cp, Ci, Cx, x, yf, no_spring)
        try:
            mu, its = pysolver.solve(x, yf)
        except SolverError as e:
            raise SolverError(f"step {step + 1} (t={(step + 1) * dt:.6g} s): {e}") from None
        counters[2] += its
        finish_step(x, W, mu, u_prev, u_cur)
        active = mu != 0.0
        counters[0] += int(np.count_nonzero(active & ~active_prev))
        active_prev[:] = active
        counters[1] += int(active.any())
        cy = np.array([Cx[Cp[j]:Cp[j + 1]] @ u_cur[Ci[Cp[j]:Cp[j + 1]]] for j in range(m)])
        record(step + 1, save_every, frame_every, u_prev, u_cur, mu, dt, Eb.rows,
               Kb.rows, dt2, Op, Oi, Ox, Ep, Ei, Ex, slo, shi, cy, lo, hi,
               obs, obsv, energy, lam, fr, frv, frf, stats, d)
        if (step + 1) % save_every == 0 and not abs(energy[(step + 1) // save_every]) <= Ebound:
            counters[3] = step + 1
            return UNSTABLE
    return 0
