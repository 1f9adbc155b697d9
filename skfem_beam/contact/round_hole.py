"""Exact contact in round holes: the step's problem with second-order-cone constraints.

A round hole at a node bounds the node's pair y_p = (v, w): |y_p − c| ≤ r.  The scheme's
step problem stays  min ½(y − y_f)ᵀD⁻¹(y − y_f)  over the constraints, now disks (pairs
of rows, ``StepData.disks``; their box [lo, hi] is the disk's bounding square, so c and
r are read from it and move with a support as every bound does) and boxes lo ≤ y ≤ hi
(every other row).  Its KKT conditions:

    y = y_f + Dμ,   μ_p = −s (y_p − c)/r  with s ≥ 0, s·(|y_p − c| − r) = 0   (disks)
                    μ_j ≥ 0 at lo, ≤ 0 at hi, 0 inside                          (boxes)

**One block** (a disk with the other multipliers fixed) has a closed form up to a 1-D
root: with ỹ the block's value without its own μ and z = ỹ − c outside the disk,
y_p − c = (I + tD_pp)⁻¹ z with t ≥ 0 the root of |(I + tD_pp)⁻¹z| = r.  In D_pp's
eigenbasis that is the trust-region secular equation; 1/|p(t)| − 1/r is concave and
increasing in t, so Newton from t = 0 climbs to the root monotonically, to round-off
(`disk_root`).  A round tube (I_z = I) with one constrained node has D_pp = d·I and the
root is t = (|z|/r − 1)/d.

**Several blocks** (two baffles, a hole over a span, a hole with flat bars): block
Gauss–Seidel over the blocks (each block exactly as above; a box row is its projection,
Lemma 4.1), which converges for SPD D (a block coordinate descent of the strictly convex
problem), until a sweep moves no value by more than round-off; then a Newton step on the
active set's KKT equations removes what the linear rate left (`polish`).  Checked
against Clarabel (an interior-point conic solver) on recorded step problems
(tests/test_two_planes.py).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ..errors import InputError
from .active_set import data_scale
from .base import ContactLaw, compiled_law

internal = njit(cache=True)   # also called from Python: the start step runs the law uncompiled

MAX_SWEEPS = 20000
SWEEP_TOL = 1e-14        # a sweep moved no value y by more than this × the data's scale
#                          (a few ulps: the values are recomputed with that round-off)


@njit(cache=True)
def radial(ya, yb, lo_a, hi_a, lo_b, hi_b):
    """(p_a, p_b, |p|, r): the pair's offset from its hole's centre and the radius (the
    centre is the middle of the pair's box [lo, hi], the radius its half-width)."""
    pa, pb = ya - 0.5 * (lo_a + hi_a), yb - 0.5 * (lo_b + hi_b)
    return pa, pb, np.hypot(pa, pb), 0.5 * (hi_a - lo_a)


@njit(cache=True)
def disk_root(a, b, d, z0, z1, r, out):
    """The point p = (I + tD)⁻¹z on the circle |p| = r (D = [[a, b], [b, d]] SPD, |z| > r):
    out[0:2] ← p, out[2] ← t.  Returns the Newton iterations."""
    # D's eigenbasis: Q = [[cs, −sn], [sn, cs]], eigenvalues l0, l1
    if b == 0.0:
        l0, l1, cs, sn = a, d, 1.0, 0.0
    else:
        h = 0.5 * (a - d)
        g = np.sqrt(h * h + b * b)
        l0, l1 = 0.5 * (a + d) + g, 0.5 * (a + d) - g
        # eigenvector of l0: (b, l0 − a), normalised (or (l0 − d, b), the better of the two)
        if abs(l0 - d) >= abs(l0 - a):
            vx, vy = l0 - d, b
        else:
            vx, vy = b, l0 - a
        nv = np.hypot(vx, vy)
        cs, sn = vx / nv, vy / nv
    q0 = cs * z0 + sn * z1
    q1 = -sn * z0 + cs * z1
    nz = np.hypot(q0, q1)
    if l0 == l1:                      # isotropic: the closed form
        t = (nz / r - 1.0) / l0
        its = 0
    else:
        t = 0.0
        its = 0
        for its in range(1, 100):
            p0, p1 = q0 / (1.0 + t * l0), q1 / (1.0 + t * l1)
            norm = np.hypot(p0, p1)
            # ψ(t) = 1/|p| − 1/r, ψ' = Σ p_k² l_k/(1 + t l_k) / |p|³
            dpsi = (p0 * p0 * l0 / (1.0 + t * l0) + p1 * p1 * l1 / (1.0 + t * l1)) / norm**3
            step = (1.0 / r - 1.0 / norm) / dpsi
            t_new = t + step
            if not t_new > t or step <= 1e-16 * t_new:
                t = max(t, t_new)
                break
            t = t_new
    p0, p1 = q0 / (1.0 + t * l0), q1 / (1.0 + t * l1)
    out[0] = cs * p0 - sn * p1
    out[1] = sn * p0 + cs * p1
    out[2] = t
    return its


@internal
def _polish(D, yf, lo, hi, kind, mu, tol):
    """Newton on the active set's KKT equations (boxes on their bound, disks on their
    circle with μ_p ∥ −(y_p − c)), from the Gauss–Seidel μ; returns False (μ unchanged)
    when the system is singular or the result leaves the active set's signs."""
    m = yf.size
    act = np.zeros(m, np.int64)
    k = 0
    for j in range(m):
        if mu[j] != 0.0 and kind[j] >= 0:   # box rows and disk first rows
            act[k] = j
            k += 1
            if kind[j] > 0:
                act[k] = kind[j]            # its second row
                k += 1
    if k == 0:
        return True
    mu_new = mu.copy()
    for _ in range(3):
        y = yf + D @ mu_new
        F = np.zeros(k)
        J = np.zeros((k, k))
        i = 0
        while i < k:
            j = act[i]
            if kind[j] == 0:                 # a box row on its bound
                bound = lo[j] if mu_new[j] > 0.0 else hi[j]
                F[i] = y[j] - bound
                for q in range(k):
                    J[i, q] = D[j, act[q]]
                i += 1
            else:
                a, b = j, kind[j]
                pa, pb, _, r = radial(y[a], y[b], lo[a], hi[a], lo[b], hi[b])
                F[i] = 0.5 * (pa * pa + pb * pb - r * r) / r
                F[i + 1] = mu_new[a] * pb - mu_new[b] * pa
                for q in range(k):
                    J[i, q] = (pa * D[a, act[q]] + pb * D[b, act[q]]) / r
                    J[i + 1, q] = mu_new[a] * D[b, act[q]] - mu_new[b] * D[a, act[q]]
                J[i + 1, i] += pb
                J[i + 1, i + 1] -= pa
                i += 2
        try:
            delta = np.linalg.solve(J, F)
        except Exception:   # noqa: BLE001  (numba: a singular matrix)
            return False
        for q in range(k):
            mu_new[act[q]] -= delta[q]
    # keep it only if the signs and the inactive constraints still hold
    y = yf + D @ mu_new
    for j in range(m):
        if kind[j] == 0:
            if (mu[j] > 0.0 and mu_new[j] <= 0.0) or (mu[j] < 0.0 and mu_new[j] >= 0.0):
                return False
            if mu[j] == 0.0 and (y[j] < lo[j] - tol or y[j] > hi[j] + tol):
                return False
        elif kind[j] > 0:
            a, b = j, kind[j]
            pa, pb, rho, r = radial(y[a], y[b], lo[a], hi[a], lo[b], hi[b])
            if mu[a] != 0.0 or mu[b] != 0.0:
                if mu_new[a] * pa + mu_new[b] * pb >= 0.0:    # must push inwards
                    return False
            elif rho > r + tol:
                return False
    for j in range(m):
        mu[j] = mu_new[j]
    return True


@internal
def cone_solve(D, yf, lo, hi, kind, mu, active):
    """The step's μ for boxes and disks (module docstring).  ``kind[j]``: 0 a box row,
    b > 0 the first row of a disk whose second row is b, −1 a disk's second row.
    Returns the sweeps (< 0: no convergence)."""
    m = yf.size
    y = yf.copy()
    for j in range(m):
        mu[j] = 0.0
    root = np.empty(3)
    scale = data_scale(yf, lo, hi)
    tol = 1e-13 * scale
    blocks = 0
    for j in range(m):
        if kind[j] >= 0:
            blocks += 1
    for sweeps in range(1, MAX_SWEEPS + 1):
        change = 0.0
        for j in range(m):
            if kind[j] == 0:
                yt = y[j] - D[j, j] * mu[j]
                target = min(max(yt, lo[j]), hi[j])
                new = (target - yt) / D[j, j]
                dj = new - mu[j]
                if dj != 0.0:
                    for i in range(m):
                        y[i] += D[i, j] * dj
                    mu[j] = new
                change = max(change, abs(D[j, j] * dj))
            elif kind[j] > 0:
                a, b = j, kind[j]
                ya = y[a] - D[a, a] * mu[a] - D[a, b] * mu[b]
                yb = y[b] - D[b, a] * mu[a] - D[b, b] * mu[b]
                za, zb, _, r = radial(ya, yb, lo[a], hi[a], lo[b], hi[b])
                if za * za + zb * zb <= r * r:
                    na, nb = 0.0, 0.0
                else:
                    disk_root(D[a, a], D[a, b], D[b, b], za, zb, r, root)
                    na, nb = -root[2] * root[0], -root[2] * root[1]
                da, db = na - mu[a], nb - mu[b]
                if da != 0.0 or db != 0.0:
                    for i in range(m):
                        y[i] += D[i, a] * da + D[i, b] * db
                    mu[a], mu[b] = na, nb
                change = max(change, abs(D[a, a] * da + D[a, b] * db),
                             abs(D[b, a] * da + D[b, b] * db))
        if blocks == 1 or change <= SWEEP_TOL * scale:
            break
    else:
        return -1
    if blocks > 1:
        _polish(D, yf, lo, hi, kind, mu, tol)
    for j in range(m):
        if kind[j] > 0:
            active[j] = mu[j] != 0.0 or mu[kind[j]] != 0.0
        elif kind[j] < 0:
            active[j] = False
        else:
            active[j] = mu[j] != 0.0
    return sweeps


def disk_kinds(m: int, disks) -> np.ndarray:
    """The ``kind`` array of cone_solve for m rows and the disk pairs (q, 2)."""
    kind = np.zeros(m, np.int64)
    for a, b in np.asarray(disks, dtype=np.int64).reshape(-1, 2):
        kind[a], kind[b] = b, -1
    return kind


@internal
def kinds_of(params, m):
    """cone_solve's ``kind`` from the law's params: [q, a0, b0, a1, b1, ...]."""
    kind = np.zeros(m, np.int64)
    q = int(params[0])
    for p in range(q):
        a, b = int(params[1 + 2 * p]), int(params[2 + 2 * p])
        kind[a] = b
        kind[b] = -1
    return kind


@compiled_law
def round_hole_kernel(D, yf, y_cur, y_prev, lo, hi, params, state, mu, active):
    return cone_solve(D, yf, lo, hi, kinds_of(params, yf.size), mu, active)


def disk_params(disks) -> np.ndarray:
    """[q, a0, b0, a1, b1, ...]: the disk pairs as a law's float constants."""
    d = np.asarray(disks, dtype=float).reshape(-1, 2)
    return np.concatenate([[float(d.shape[0])], d.ravel()])


class RoundHole(ContactLaw):
    """Exact contact in round holes (and any box rows beside them): block Gauss–Seidel
    with the disk's closed form, finished by Newton (module docstring)."""
    name = "round-hole"
    kernel = round_hole_kernel
    round_holes = True

    def setup(self, step, first=False):
        if step.disks.size and np.any(np.abs((step.hi - step.lo)[step.disks[:, 0]]
                                             - (step.hi - step.lo)[step.disks[:, 1]])
                                      > 1e-12 * (step.hi - step.lo)[step.disks[:, 0]]):
            raise InputError("a round hole's two rows must have the same radius")
        return disk_params(step.disks)
