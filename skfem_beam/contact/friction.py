"""Coulomb friction in round holes, at velocity level (Moreau–Jean's impulses).

At a round hole the node's velocity change is D_pp P (D the Delassus matrix of
Moreau–Jean's step), with the impulse P = −p_n n + p_t t: n the outward normal of the wall
at the predicted position y_θ = yⁿ + (1−θ)Δt vⁿ, t = (−n_z, n_y) the tangent
(counter-clockwise), p_n ≥ 0 the wall's push, p_t the friction.  The contact is in
Moreau–Jean's index set when y_θ (or yⁿ) reaches the wall; there the outward velocity

    u_n = n·v^{n+1} + κ(|yⁿ − c| − r)⁺/(θΔt),   κ = DRIFT = 0.1,

must not be positive (e = 0).  The second term takes back a tenth of the node's
penetration a step.  Why: on a curved wall the velocity law n·v^{n+1} ≤ 0 alone lets a
sliding node drift out by (v_tΔt)²/(2r) a step, and that adds up (5.8 r in one second of
the shipped tube's whirl, measured); taking all of it back in one step (or aiming the
step's end position at the wall) turns the correction into a bounce (the contact work
came out positive, +5.3 in the same run).  With κ = 0.1 that run penetrates at most
1.3 % of r (the index set's O(Δt) penetration at impacts, then taken back), and a node
pressed on the wall sits on it to 2e-16 r.  With u_t = t·v^{n+1}, the local
problem is

    u_n = q_n − W_nn p_n + W_nt p_t,   u_t = q_t − W_nt p_n + W_tt p_t
    Signorini   p_n ≥ 0,  u_n ≤ 0,  p_n u_n = 0
    Coulomb     |p_t| ≤ μ p_n;  |p_t| < μ p_n ⇒ u_t = 0;  u_t ≠ 0 ⇒ p_t = −μ p_n sign(u_t)

(W = [n t]ᵀ D_pp [n t]).  One contact is solved exactly by its four cases (`coulomb`):
separation (q_n ≤ 0), stick (u = 0 solved; the impulse must lie in the cone), slip either
way (p_t = ∓μp_n, u_n = 0 gives p_n; u_t must have the sign).  Several contacts (and any
frictionless box rows beside them, as Moreau–Jean's box problem) by non-smooth
Gauss–Seidel (`nsgs`), each block exact with the others fixed, until a sweep changes no
impulse by more than ``tol`` relative to the largest: the final sweep's change is the
step's residual (0 with one block: exact).  Siconos' 2-D friction solver is the check on
recorded problems (tests/test_friction.py).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .round_hole import radial

SEPARATE, STICK, SLIP_FORWARD, SLIP_BACKWARD = 0, 1, 2, 3
MAX_SWEEPS = 10000
DRIFT = 0.1


@njit(cache=True)
def coulomb(Wnn, Wnt, Wtt, qn, qt, mu, out):
    """One contact's (p_n, p_t) into out[0:2] and (u_n, u_t) into out[2:4] (module
    docstring); returns the case (SEPARATE, STICK, SLIP_FORWARD: u_t > 0, SLIP_BACKWARD)."""
    if qn <= 0.0:                              # moving away or along: no impulse
        out[0], out[1], out[2], out[3] = 0.0, 0.0, qn, qt
        return SEPARATE
    if mu == 0.0:                              # frictionless: the normal alone
        pn = qn / Wnn
        out[0], out[1], out[2], out[3] = pn, 0.0, 0.0, qt - Wnt * pn
        return SLIP_FORWARD if out[3] >= 0.0 else SLIP_BACKWARD
    det = Wnn * Wtt - Wnt * Wnt
    pn = (qn * Wtt - Wnt * qt) / det           # stick: u_n = u_t = 0
    pt = (Wnt * qn - Wnn * qt) / det
    if pn >= 0.0 and abs(pt) <= mu * pn:
        out[0], out[1], out[2], out[3] = pn, pt, 0.0, 0.0
        return STICK
    for s in (1.0, -1.0):                      # slip with u_t of sign s: p_t = −sμp_n
        pn = qn / (Wnn + s * mu * Wnt)
        ut = qt - Wnt * pn - s * mu * Wtt * pn
        if pn >= 0.0 and s * ut >= 0.0:
            out[0], out[1], out[2], out[3] = pn, -s * mu * pn, 0.0, ut
            return SLIP_FORWARD if s > 0 else SLIP_BACKWARD
    # not reached for μ below the uniqueness bound of W (never observed): stick's normal
    pn = qn / Wnn
    out[0], out[1], out[2], out[3] = pn, 0.0, 0.0, qt - Wnt * pn
    return STICK


@njit(cache=True)
def nsgs(D, rows, step, out):
    """Moreau–Jean's impulses for ``rows`` = (kind, fric, lo, hi): disks with friction
    fric (per disk first row; ``kind`` as round_hole.cone_solve's) and box rows (velocity
    bounds set here from the predicted values, as Moreau–Jean's index set does, with its
    restitution e); ``step`` = (wf, yv, yp, ynow, e, tol, theta_dt): the free velocities,
    C vⁿ, C y_θ, C yⁿ, e, the tolerance and θΔt; ``out`` = (p, fc, lo_e, hi_e): the
    impulses per row, fc[j] ← [p_n, p_t, u_n, u_t, n_y, n_z] of each disk's first row j,
    and the box rows' velocity bounds.  Returns (sweeps, residual); sweeps < 0: no
    convergence to ``tol``."""
    kind, fric, lo, hi = rows
    wf, yv, yp, ynow, e, tol, theta_dt = step
    p, fc, lo_e, hi_e = out
    m = wf.size
    inf = np.inf
    U = wf.copy()                   # velocities of the rows with the impulses so far
    gap = np.zeros(m)               # a disk's (|y_θ − c| − r)⁺/(θΔt)
    on = np.zeros(m, np.bool_)      # ... in the index set
    for j in range(m):
        p[j] = 0.0
        lo_e[j], hi_e[j] = -inf, inf
        if kind[j] == 0:
            lo_e[j] = 0.0 if yp[j] <= lo[j] else -inf
            hi_e[j] = 0.0 if yp[j] >= hi[j] else inf
        elif kind[j] > 0:
            b = kind[j]
            ny, nz, rho, r = radial(yp[j], yp[b], lo[j], hi[j], lo[b], hi[b])
            fc[j, 4], fc[j, 5] = (ny / rho, nz / rho) if rho > 0.0 else (1.0, 0.0)
            fc[j, 0] = fc[j, 1] = 0.0
            now = radial(ynow[j], ynow[b], lo[j], hi[j], lo[b], hi[b])[2]
            gap[j] = DRIFT * max(now - r, 0.0) / theta_dt
            on[j] = rho >= r or now >= r
    local = np.empty(4)
    blocks = 0
    for j in range(m):
        if (kind[j] == 0 and (lo_e[j] == 0.0 or hi_e[j] == 0.0)) or (kind[j] > 0 and on[j]):
            blocks += 1
    residual = 0.0
    for sweep in range(1, MAX_SWEEPS + 1):
        change, size = 0.0, 0.0
        for j in range(m):
            if kind[j] == 0:
                if lo_e[j] == -inf and hi_e[j] == inf:
                    continue
                v = U[j] - D[j, j] * p[j] + e * yv[j]
                new = (min(max(v, lo_e[j]), hi_e[j]) - v) / D[j, j]
                d = new - p[j]
                if d != 0.0:
                    for i in range(m):
                        U[i] += D[i, j] * d
                    p[j] = new
                change, size = max(change, abs(d)), max(size, abs(new))
            elif kind[j] > 0 and on[j]:
                a, b = j, kind[j]
                ny, nz = fc[j, 4], fc[j, 5]
                ty, tz = -nz, ny
                # the block's velocity without its own impulse, in (n, t)
                ua = U[a] - D[a, a] * p[a] - D[a, b] * p[b]
                ub = U[b] - D[b, a] * p[a] - D[b, b] * p[b]
                qn = ny * ua + nz * ub + gap[j]
                qt = ty * ua + tz * ub
                Dn0, Dn1 = D[a, a] * ny + D[a, b] * nz, D[b, a] * ny + D[b, b] * nz
                Dt0, Dt1 = D[a, a] * ty + D[a, b] * tz, D[b, a] * ty + D[b, b] * tz
                coulomb(ny * Dn0 + nz * Dn1, ny * Dt0 + nz * Dt1, ty * Dt0 + tz * Dt1,
                        qn, qt, fric[j], local)
                fc[j, 0], fc[j, 1] = local[0], local[1]
                na, nb = -local[0] * ny + local[1] * ty, -local[0] * nz + local[1] * tz
                da, db = na - p[a], nb - p[b]
                if da != 0.0 or db != 0.0:
                    for i in range(m):
                        U[i] += D[i, a] * da + D[i, b] * db
                    p[a], p[b] = na, nb
                change = max(change, abs(da), abs(db))
                size = max(size, abs(na), abs(nb))
        residual = change / size if size > 0.0 else 0.0
        if blocks <= 1:
            residual = 0.0             # one block: exact in one sweep
            break
        if residual <= tol:
            break
    else:
        return -MAX_SWEEPS, residual
    for j in range(m):                 # the velocities after the step, in (n, t)
        if kind[j] > 0:
            b = kind[j]
            ny, nz = fc[j, 4], fc[j, 5]
            fc[j, 2] = ny * U[j] + nz * U[b] + gap[j]
            fc[j, 3] = -nz * U[j] + ny * U[b]
    return sweep, residual
