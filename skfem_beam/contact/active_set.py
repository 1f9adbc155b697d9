"""Exact active-set solver for the step problem in the contact values y (compiled).

The step is the box QP  min ½(y − y_f)ᵀD⁻¹(y − y_f)  s.t.  lo ≤ y ≤ hi,  whose KKT
conditions are  y = y_f + Dμ,  μ_i ≥ 0 at lo,  μ_i ≤ 0 at hi,  μ_i = 0 inside.

Method: the dual active-set method of Goldfarb & Idnani (1983) written in μ, so D⁻¹
is never formed.  Every iterate is the minimiser on a working set W (y_W on its
bounds, μ_W = D_WW⁻¹(b_W − y_f,W)) with correctly signed μ_W; the most violated bound
is added, and W-members whose multiplier would change sign on the way are dropped
(partial steps).  Each full step strictly increases the dual objective, so no
working set repeats: the method is finite and cannot cycle, whatever the degeneracy.
The box's normals are unit vectors and D is SPD, so adding is always possible.

Warm start: W is taken from ``state`` (last step's contacts), wrong-signed
multipliers are dropped one at a time until W is dual feasible, and the
Goldfarb–Idnani iteration continues from there.  Should round-off ever stall it,
the iteration cap restarts it cold (W = ∅), the textbook method.

Linear algebra: the Cholesky factor L of D_WW is kept and updated — O(k²) to add a
bound (one forward solve gives both the new row and the Schur complement), O(k²) to
drop one (a rank-one update of the trailing block) — instead of refactoring, O(k³).
μ and y are recomputed from L at the top of every iteration, so increments never
accumulate round-off; the answer is exact to round-off.
"""
import numpy as np
from numba import njit

from ..errors import SolverError
from .base import ContactLaw, compiled_law

# tolerances in units of y, relative to the data's scale: the round-off of
# y = y_f + Dμ is a few ulps of max(|y_f|, |b|); 1e-13 leaves ~500 ulps of margin.
REL_TOL = 1e-13
# exact finish of an external engine (osqp, daqp): the KKT residual, relative to the
# bounds' scale, beyond which the engine's active set is wrong, not merely grazing
REPAIR_TOL = 1e-6

# The helpers below are called from compiled code only: no Python or C entry wrappers
# to build (a cold start compiles them once each, with the law)
internal = njit(cache=True, no_cpython_wrapper=True, no_cfunc_wrapper=True)


@njit(cache=True)      # also called from Python (the round-hole law's start step)
def data_scale(yf, lo, hi):
    """The data's scale: the largest |y_free| and finite |bound| (1 if all are 0)."""
    s = 0.0
    for i in range(yf.size):
        s = max(s, abs(yf[i]))
        if np.isfinite(lo[i]):
            s = max(s, abs(lo[i]))
        if np.isfinite(hi[i]):
            s = max(s, abs(hi[i]))
    return s if s > 0.0 else 1.0


@internal
def _forward(L, k, D, W, p, w):
    """w ← L⁻¹ D[W, p]; returns the Schur complement D_pp − wᵀw."""
    s2 = 0.0
    for a in range(k):
        s = D[W[a], p]
        for b in range(a):
            s -= L[a, b] * w[b]
        w[a] = s / L[a, a]
        s2 += w[a] * w[a]
    return D[p, p] - s2


@internal
def _backward(L, k, w, z):
    """z ← L⁻ᵀ w."""
    for a in range(k - 1, -1, -1):
        s = w[a]
        for b in range(a + 1, k):
            s -= L[b, a] * z[b]
        z[a] = s / L[a, a]


@internal
def _drop(L, k, j, W, v):
    """Remove position j from W and its row/column from L (rank-one update of the
    trailing block: L₃₃'L₃₃'ᵀ = L₃₃L₃₃ᵀ + l₃₂l₃₂ᵀ)."""
    for a in range(j + 1, k):
        v[a - j - 1] = L[a, j]
    for a in range(j, k - 1):            # shift rows up and trailing columns left
        W[a] = W[a + 1]
        for b in range(j):
            L[a, b] = L[a + 1, b]
        for b in range(j, a + 1):
            L[a, b] = L[a + 1, b + 1]
    n = k - 1 - j
    for c in range(n):                   # cholupdate of the (n × n) trailing block
        a = j + c
        r = np.hypot(L[a, a], v[c])
        cs = r / L[a, a]
        sn = v[c] / L[a, a]
        L[a, a] = r
        for e in range(c + 1, n):
            b = j + e
            L[b, a] = (L[b, a] + sn * v[e]) / cs
            v[e] = cs * v[e] - sn * L[b, a]


@internal
def _grow(L, k, m):
    c = min(m, 2 * k + 8)
    L2 = np.empty((c, c))
    for a in range(k):
        for b in range(a + 1):
            L2[a, b] = L[a, b]
    return L2


@internal
def _multipliers(L, k, W, yf, lo, hi, state, w, z, mu):
    """μ_W = D_WW⁻¹ (b_W − y_f,W) by the two triangular solves."""
    for a in range(k):
        i = W[a]
        w[a] = (lo[i] if state[i] < 0 else hi[i]) - yf[i]
    for a in range(k):
        s = w[a]
        for b in range(a):
            s -= L[a, b] * w[b]
        w[a] = s / L[a, a]
    _backward(L, k, w, z)
    for a in range(k):
        mu[W[a]] = z[a]


@internal
def _values(D, W, k, yf, mu, y):
    """y = y_f + D[:, W] μ_W (D symmetric: read contiguous rows)."""
    for i in range(y.size):              # loops, not slice assignment: compiles in 1/10 the time
        y[i] = yf[i]
    for a in range(k):
        j = W[a]
        c = mu[j]
        for i in range(y.size):
            y[i] += D[j, i] * c


@internal
def _factor_set(L, D, W, state, lo, hi, w):
    """L ← the Cholesky factor of D_WW, W the rows with ``state`` ≠ 0 in index order
    (by appending: _forward); a row whose bound is infinite or that depends numerically
    on those before it leaves the set (state 0).  Returns k = |W|."""
    # np.int64(·), not a bare literal, for the values passed to the helpers below: a
    # literal start gives each helper a second compile for Literal[int] (1.3 s cold)
    k = np.int64(0)
    for i in range(state.size):
        b = lo[i] if state[i] < 0 else hi[i]
        if state[i] == 0 or not np.isfinite(b):
            state[i] = 0
            continue
        schur = _forward(L, k, D, W, i, w)
        if schur <= 1e-14 * D[i, i]:     # numerically dependent: leave it out
            state[i] = 0
            continue
        for b2 in range(k):
            L[k, b2] = w[b2]
        L[k, k] = np.sqrt(schur)
        W[k] = i
        k += 1
    return k


@internal
def _gi(D, yf, lo, hi, state, mu, maxit):
    m = yf.size
    tol = REL_TOL * data_scale(yf, lo, hi)
    k0 = 0
    for i in range(m):
        k0 += state[i] != 0
    # L grows on demand: an m×m buffer per call would cost more than the solve
    L = np.empty((min(m, 2 * k0 + 8), min(m, 2 * k0 + 8)))
    W = np.empty(m, np.int64)
    w = np.empty(m)
    z = np.empty(m)
    v = np.empty(m)
    y = np.empty(m)
    k = _factor_set(L, D, W, state, lo, hi, w)   # warm start: factor D_WW
    for i in range(mu.size):
        mu[i] = 0.0
    changes = 0
    for it in range(1, maxit + 1):
        for a in range(k):
            mu[W[a]] = 0.0
        _multipliers(L, k, W, yf, lo, hi, state, w, z, mu)
        # dual feasibility (a warm start, or round-off at a grazing bound, can violate
        # it): drop the worst; any wrong sign counts, so returned signs are exact
        worst, wv = np.int64(-1), 0.0
        for a in range(k):
            i = W[a]
            t = state[i] * mu[i] * D[i, i]   # > 0: wrong sign, in units of y
            if t > wv:
                worst, wv = a, t
        if worst >= 0:
            i = W[worst]
            mu[i] = 0.0
            state[i] = 0
            _drop(L, k, worst, W, v)
            k -= 1
            changes += 1
            continue
        _values(D, W, k, yf, mu, y)
        p, pv = np.int64(-1), tol       # most violated bound
        for i in range(m):
            if state[i] == 0:
                t = max(lo[i] - y[i], y[i] - hi[i])
                if t > pv:
                    p, pv = i, t
        if p < 0:
            return changes + 1
        sp = -1 if y[p] < lo[p] else 1
        bp = lo[p] if sp < 0 else hi[p]
        yp = y[p]
        mup = 0.0
        state[p] = sp
        while True:                      # Goldfarb–Idnani step for p
            schur = _forward(L, k, D, W, p, w)
            if schur <= 1e-14 * D[p, p]:
                return -1
            _backward(L, k, w, z)        # z = D_WW⁻¹ D_Wp: dμ_W/dμ_p = −z
            full = (bp - yp) / schur
            tau, block = 1.0, np.int64(-1)
            for a in range(k):
                i = W[a]
                d = -z[a] * full * state[i]   # growth of the wrong-sign part
                if d > 0.0:
                    t = max(0.0, -state[i] * mu[i] / d)
                    if t < tau:
                        tau, block = t, a
            step = tau * full
            for a in range(k):
                mu[W[a]] -= z[a] * step
            mup += step
            yp += schur * step
            if block < 0:                # full step: p joins W
                if k == L.shape[0]:
                    L = _grow(L, k, m)
                for b2 in range(k):
                    L[k, b2] = w[b2]
                L[k, k] = np.sqrt(schur)
                W[k] = p
                k += 1
                mu[p] = mup
                changes += 1
                break
            i = W[block]                 # partial step: the blocking bound leaves
            mu[i] = 0.0
            state[i] = 0
            _drop(L, k, block, W, v)
            k -= 1
            changes += 1
    return -1


@njit(cache=True)
def box_qp(D, yf, lo, hi, state, mu):
    """Solve y = yf + Dμ, lo ≤ y ≤ hi with complementarity exactly; ``state`` (int8:
    −1 at lo, +1 at hi, 0 free) is the warm start and is updated.  Returns the
    iterations (1 + bounds added or dropped), < 0 if it failed (never observed)."""
    m = yf.size
    free = True                          # the common step: no contact, none before
    for i in range(m):
        if state[i] != 0 or not lo[i] <= yf[i] <= hi[i]:
            free = False
            break
    if free:
        for i in range(mu.size):
            mu[i] = 0.0
        return 1
    warm = 3 * m + 20                    # generous: a warm start needs a few
    its = _gi(D, yf, lo, hi, state, mu, warm)
    if its < 0:                          # cold restart: plain Goldfarb–Idnani
        for i in range(state.size):
            state[i] = 0
        its = _gi(D, yf, lo, hi, state, mu, 20 * m + 100)
        if its > 0:
            its += warm
    return its


@internal
def _pdas(D, yf, lo, hi, state, mu, maxit):
    """The primal–dual active set (Hintermüller, Ito & Kunisch 2003) from ``state``:
    each iteration solves D_WW μ_W = b_W − y_f,W on the whole working set W, then drops
    every wrong-signed μ and adds every violated bound at once.  Returns its iterations
    when the set repeats (μ, state: the solution, to _gi's tolerances), 0 when it has not
    within ``maxit`` (it can cycle; state is then its last set)."""
    m = yf.size
    tol = REL_TOL * data_scale(yf, lo, hi)
    W = np.empty(m, np.int64)
    w = np.empty(m)
    z = np.empty(m)
    y = np.empty(m)
    L = np.empty((1, 1))
    for it in range(1, maxit + 1):
        k0 = 0
        for i in range(m):
            k0 += state[i] != 0
        if L.shape[0] < k0:
            L = np.empty((k0, k0))
        k = _factor_set(L, D, W, state, lo, hi, w)
        for i in range(m):
            mu[i] = 0.0
        _multipliers(L, k, W, yf, lo, hi, state, w, z, mu)
        _values(D, W, k, yf, mu, y)
        changed = False
        for i in range(m):
            if state[i] != 0:
                if state[i] * mu[i] > 0.0:      # wrong sign: leaves the set
                    state[i] = 0
                    mu[i] = 0.0
                    changed = True
            elif y[i] < lo[i] - tol:
                state[i] = -1
                changed = True
            elif y[i] > hi[i] + tol:
                state[i] = 1
                changed = True
        if not changed:
            return it
    return 0


# from this many constrained values on (a plate's vertices), the active-set law first
# runs the primal–dual active set: the set of a plate pressed on an obstacle moves by
# tens to hundreds of rows a step, which Goldfarb–Idnani adds one at a time (each a pass
# over the m rows), and the primal–dual rule all at once (docs/plate.md)
PDAS_MIN = 256
PDAS_MAXIT = 30


@njit(cache=True)
def box_qp_pdas(D, yf, lo, hi, state, mu):
    """`box_qp`, the primal–dual active set first: its set when it repeats, else
    Goldfarb–Idnani from its last set (finite, exact)."""
    for i in range(yf.size):
        if state[i] != 0 or not lo[i] <= yf[i] <= hi[i]:
            its = _pdas(D, yf, lo, hi, state, mu, PDAS_MAXIT)
            if its > 0:
                return its
            its = box_qp(D, yf, lo, hi, state, mu)
            return its + PDAS_MAXIT if its > 0 else its
    for i in range(mu.size):
        mu[i] = 0.0
    return 1


@njit(cache=True)
def solve_on_set(D, yf, lo, hi, state, mu):
    """μ on the working set given by ``state`` (exact: D_WW μ_W = b_W − y_f,W, μ = 0
    elsewhere).  Returns the KKT residual in units of y: the largest of the box
    violation and the wrong-signed |μ_i|·D_ii (0 when the set is optimal)."""
    m = yf.size
    idx = np.flatnonzero(state != 0)
    for i in range(mu.size):
        mu[i] = 0.0
    if idx.size:
        rhs = np.empty(idx.size)
        for a in range(idx.size):
            i = idx[a]
            rhs[a] = (lo[i] if state[i] < 0 else hi[i]) - yf[i]
        Dw = np.empty((idx.size, idx.size))
        for a in range(idx.size):
            for b in range(idx.size):
                Dw[a, b] = D[idx[a], idx[b]]
        sol = np.linalg.solve(Dw, rhs)
        for a in range(idx.size):
            mu[idx[a]] = sol[a]
    res = 0.0
    for i in range(m):
        y = yf[i]
        for a in range(idx.size):
            y += D[i, idx[a]] * mu[idx[a]]
        if state[i] == 0:
            res = max(res, lo[i] - y, y - hi[i])
        else:
            res = max(res, state[i] * mu[i] * D[i, i])
    return res


@njit(cache=True)
def finish_on_duals(D, yf, lo, hi, duals, state, mu):
    """``state`` ← sign pattern of an engine's multipliers (> 0: upper bound active,
    < 0: lower; OSQP's and daqp's convention), then `solve_on_set`."""
    for i in range(yf.size):
        state[i] = 1 if duals[i] > 0.0 else (-1 if duals[i] < 0.0 else 0)
    return solve_on_set(D, yf, lo, hi, state, mu)


def bound_scale(lo, hi) -> float:
    """The largest finite |bound| (1 if there is none): the length scale of y."""
    b = np.concatenate([np.abs(lo[np.isfinite(lo)]), np.abs(hi[np.isfinite(hi)])])
    s = float(b.max()) if b.size else 0.0
    return s if s > 0 else 1.0


def exact_finish(D, yf, lo, hi, duals, state, mu, scale, engine, tol=REPAIR_TOL) -> int:
    """μ exactly on the active set of an engine's multipliers ``duals``.

    An engine accurate to ε cannot classify a constraint whose multiplier or gap is
    below ε (grazing contact), and the exact μ on its set may then leave y outside the
    box or a multiplier with the wrong sign by that much.  Any such residual is
    handed to `box_qp`, warm-started from the engine's set, which decides those
    constraints exactly.  Returns the number of such repairs (0 or 1); a residual
    above tol·scale (REPAIR_TOL unless the engine says) means the engine's answer was
    wrong: SolverError."""
    return repair(finish_on_duals(D, yf, lo, hi, duals, state, mu), D, yf, lo, hi, state, mu,
                  scale, engine, tol)


def repair(res, D, yf, lo, hi, state, mu, scale, engine, tol=REPAIR_TOL) -> int:
    """What `exact_finish` does with the KKT residual ``res`` of μ on an engine's set."""
    if res <= 0.0:
        return 0
    if res > tol * scale:
        raise SolverError(f"{engine}'s active set violates the KKT conditions by "
                          f"{res:.3g} (scale {scale:.3g}): not a solution")
    if box_qp(D, yf, lo, hi, state, mu) < 0:
        raise SolverError(f"the exact finish after {engine} failed")
    return 1


@compiled_law
def active_set_kernel(D, yf, y_cur, y_prev, lo, hi, params, state, mu, active):
    its = box_qp(D, yf, lo, hi, state, mu)
    for i in range(mu.size):
        active[i] = mu[i] != 0.0
    return its


@compiled_law
def active_set_pdas_kernel(D, yf, y_cur, y_prev, lo, hi, params, state, mu, active):
    its = box_qp_pdas(D, yf, lo, hi, state, mu)
    for i in range(mu.size):
        active[i] = mu[i] != 0.0
    return its


class ActiveSet(ContactLaw):
    """The exact compiled dual active set (any m, coupled or not); from PDAS_MIN rows on,
    the primal–dual active set first."""
    name = "active-set"
    kernel = active_set_kernel

    def kernels_for(self, step):
        return (active_set_pdas_kernel if step.C.shape[0] >= PDAS_MIN else active_set_kernel,)

    def setup(self, step, first=False):
        self.kernel, = self.kernels_for(step)
        return np.zeros(0)
