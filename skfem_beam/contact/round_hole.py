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
from numba import njit, types

from ..errors import InputError
from .active_set import data_scale
from .base import ContactLaw, compiled_law
from .lands import (PIECE_CORNER, PIECE_LINE, corner_candidate, land_excess, line_candidate,
                    lobe_geometry, piece_holds, piece_of)

internal = njit(cache=True)   # also called from Python: the start step runs the law uncompiled
# called from compiled code only: no Python or C entry (the entries were 0.5 of the
# broached law's 4.4 CPU s of compile; the tests call them through tests/conftest.compiled)
inner = njit(cache=True, no_cpython_wrapper=True, no_cfunc_wrapper=True)

MAX_SWEEPS = 20000
SWEEP_TOL = 1e-14        # a sweep moved no value y by more than this × the data's scale
#                          (a few ulps: the values are recomputed with that round-off)


@njit(cache=True)
def radial(ya, yb, lo_a, hi_a, lo_b, hi_b):
    """(p_a, p_b, |p|, r): the pair's offset from its hole's centre and the radius (the
    centre is the middle of the pair's box [lo, hi], the radius its half-width)."""
    pa, pb = ya - 0.5 * (lo_a + hi_a), yb - 0.5 * (lo_b + hi_b)
    return pa, pb, np.hypot(pa, pb), 0.5 * (hi_a - lo_a)


@inner
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


@inner
def land_project(a, b, d, za, zb, r, lands, half, angle, root, out):
    """A broached block (contact.lands): out[0:2] ← μ of z's projection onto K in the
    metric D⁻¹ (D = [[a, b], [b, d]]); returns its piece (0: z in K, μ = 0).  K is convex,
    so the projection is the cheapest feasible point among the pieces' own projections:
    the disk's (the circle lies in K, so it is always feasible; it is K's projection
    when it falls on a land), each lobe line's when it falls on its segment, and the
    corners (each in K).  Cost: (p − z)ᵀD⁻¹(p − z) = μᵀDμ."""
    if land_excess(za, zb, r, lands, half, angle) <= 0.0:
        out[0], out[1] = 0.0, 0.0
        return 0
    disk_root(a, b, d, za, zb, r, root)      # z ∉ K ⊇ disk: |z| > r
    t = root[2]
    out[0], out[1] = -t * root[0], -t * root[1]
    best = -t * ((root[0] - za) * root[0] + (root[1] - zb) * root[1])
    code = 1
    cand = np.empty(2)
    for k in range(int(lands)):
        if lobe_geometry(k, lands, half, angle)[2] <= 0.0:
            break                             # full lands: no lobes, K is the disk
        for which in range(3):
            kind, x, y, t_lo, t_hi = piece_of(2 + 3 * k + which, r, lands, half, angle)
            if kind == PIECE_LINE:
                cost = line_candidate(a, b, d, za, zb, r, x, y, t_lo, t_hi, cand)
            else:
                cost = corner_candidate(a, b, d, za, zb, x, y, cand)
            if cost < best:
                best, code = cost, 2 + 3 * k + which
                out[0], out[1] = cand[0], cand[1]
    return code


@inner
def _piece_rows(D, act, k, i, ab, offset, mu, code, lands, F, J):
    """Rows i, i+1 of the polish for a broached block on a line (e·p = r and μ ∥ e) or a
    corner (p = q): both linear in μ.  ``ab``: the block's rows (a, b); ``offset``: its
    (p_a, p_b, r); ``mu``: its (μ_a, μ_b).  Returns False for an arc (the disk's rows)."""
    (a, b), (pa, pb, r), (mua, mub) = ab, offset, mu
    kind, x, y, _, _ = piece_of(code, r, lands[0], lands[1], lands[2])
    if kind == PIECE_LINE:
        F[i] = x * pa + y * pb - r
        F[i + 1] = mua * y - mub * x
        for q in range(k):
            J[i, q] = x * D[a, act[q]] + y * D[b, act[q]]
            J[i + 1, q] = 0.0
        J[i + 1, i] += y
        J[i + 1, i + 1] -= x
        return True
    if kind == PIECE_CORNER:
        F[i] = pa - x
        F[i + 1] = pb - y
        for q in range(k):
            J[i, q] = D[a, act[q]]
            J[i + 1, q] = D[b, act[q]]
        return True
    return False


@inner
def _active_rows(kind, piece, mu, act):
    """The polish's unknowns: box rows and round blocks with μ ≠ 0 on their first row (as
    before broached holes), broached blocks on a piece (either row may carry μ)."""
    k = 0
    for j in range(kind.size):
        if kind[j] >= 0 and (mu[j] != 0.0 or (kind[j] > 0 and piece[j] > 0)):
            act[k] = j
            k += 1
            if kind[j] > 0:
                act[k] = kind[j]            # its second row
                k += 1
    return k


@inner
def _still_holds(D, yf, lo, hi, kind, lands, piece, mu, mu_new, tol):
    """Whether μ_new keeps the active set's signs and the inactive constraints."""
    y = plus_matvec(yf, D, mu_new)
    for j in range(yf.size):
        if kind[j] == 0:
            if (mu[j] > 0.0 and mu_new[j] <= 0.0) or (mu[j] < 0.0 and mu_new[j] >= 0.0):
                return False
            if mu[j] == 0.0 and (y[j] < lo[j] - tol or y[j] > hi[j] + tol):
                return False
        elif kind[j] > 0:
            a, b = j, kind[j]
            pa, pb, rho, r = radial(y[a], y[b], lo[a], hi[a], lo[b], hi[b])
            if lands is not None and lands[j, 0] > 0.0:
                if piece[j] > 0:
                    if not piece_holds(piece[j], pa, pb, mu_new[a], mu_new[b], r,
                                       lands[j, 0], lands[j, 1], lands[j, 2], tol):
                        return False
                elif land_excess(pa, pb, r, lands[j, 0], lands[j, 1], lands[j, 2]) > tol:
                    return False
            elif mu[a] != 0.0 or mu[b] != 0.0:
                if mu_new[a] * pa + mu_new[b] * pb >= 0.0:    # must push inwards
                    return False
            elif rho > r + tol:
                return False
    return True


@internal
def solve_numpy(J, F):
    """F ← J⁻¹F by np.linalg.solve; False where it raises (J or F not finite, J singular)."""
    try:
        F[:] = np.linalg.solve(J, F)
    except Exception:   # noqa: BLE001  (numba: a singular matrix)
        return False
    return True


# LAPACK's dgesv through numba's own entry point: the routine np.linalg.solve calls, on the
# same copies (J in Fortran order, F), so the same bits, without np.linalg.solve's checks'
# and error messages' compile (~4 CPU s of a round-hole scene's first run, the law's
# callees in bench.cold_compile: _check_finite_matrix, _inv_err_handler, str and repr).
# These are numba's internals: a numba without them gets solve_numpy (the same bits,
# compiled more slowly).  tests/test_round_hole_gesv.py holds gesv to np.linalg.solve.
try:
    from numba.np.linalg import F_INT_nbtype, F_INT_nptype, ensure_lapack
    ensure_lapack()
    _xgesv = types.ExternalFunction("numba_xgesv", types.intc(
        types.char, types.intp, types.intp, types.CPointer(types.float64), types.intp,
        types.CPointer(F_INT_nbtype), types.CPointer(types.float64), types.intp))
except (ImportError, AttributeError):
    _xgesv = None


# BLAS dgemv the same way: the call numba's ``D @ x`` makes (C order: 't', n, m, lda = n;
# numba.np.linalg.call_xxgemv), so the same bits, without compiling np.dot's generic
# matrix-vector code (0.5 CPU s of a round-hole law's first compile, bench.cold_compile:
# dot_2_impl and dot_3).  tests/test_round_hole_gesv.py holds it to D @ x.
try:
    from numba.np.linalg import ensure_blas
    ensure_blas()
    _dptr = types.CPointer(types.float64)
    _xxgemv = types.ExternalFunction("numba_xxgemv", types.intc(
        types.char, types.char, types.intp, types.intp, _dptr, _dptr, types.intp, _dptr,
        _dptr, _dptr))
except (ImportError, AttributeError):
    _xxgemv = None


@internal
def matvec_numpy(D, x):
    return D @ x


if _xxgemv is None:
    matvec = matvec_numpy
else:
    @inner
    def matvec(D, x):
        """D @ x for D C-contiguous (m × n) and x contiguous: BLAS dgemv, as numba's D @ x."""
        m, n = D.shape
        out = np.zeros(m)
        if m == 0 or n == 0:
            return out
        one, zero = np.zeros(1), np.zeros(1)    # not np.ones: a compile of its own (0.15 s)
        one[0] = 1.0
        _xxgemv(100, 116, n, m, one.ctypes, D.ctypes, n, x.ctypes, zero.ctypes,
                out.ctypes)                  # 100, 116: ord('d'), ord('t')
        # one and zero used after the call: numba frees an array after its last use
        return out if one.size + zero.size > 0 else out


if _xgesv is None:
    gesv = solve_numpy
else:
    @inner
    def gesv(J, F):
        """F ← J⁻¹F (J square, k × k, C order); False (F undefined) where np.linalg.solve
        raises: J or F not finite, J singular."""
        k = F.size
        for i in range(k):
            if not np.isfinite(F[i]):
                return False
            for q in range(k):
                if not np.isfinite(J[i, q]):
                    return False
        a = J.T.copy()                       # J in Fortran order
        ipiv = np.empty(k, F_INT_nptype)
        r = _xgesv(100, k, 1, a.ctypes, k, ipiv.ctypes, F.ctypes, k)        # 100: ord('d')
        # a and ipiv used after the call: numba frees an array after its last use
        return r == 0 and a.size + ipiv.size > 0


@inner
def plus_matvec(yf, D, mu):
    """yf + D μ (a loop: the array expression compiled a kernel of its own)."""
    y = matvec(D, mu)
    for i in range(y.size):
        y[i] = yf[i] + y[i]
    return y


@inner
def _polish(D, yf, lo, hi, kind, lands, piece, mu, tol):
    """Newton on the active set's KKT equations (boxes on their bound, disks on their
    circle with μ_p ∥ −(y_p − c), broached blocks on their piece: _piece_rows), from the
    Gauss–Seidel μ; returns False (μ unchanged) when the system is singular or the
    result leaves the active set's signs."""
    m = yf.size
    act = np.zeros(m, np.int64)
    k = _active_rows(kind, piece, mu, act)
    if k == 0:
        return True
    mu_new = mu.copy()
    for _ in range(3):
        y = plus_matvec(yf, D, mu_new)
        F = np.zeros(k)
        J = np.zeros((k, k))
        i = k - k       # 0, typed int64: a literal 0 compiled _piece_rows a second time
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
                if lands is not None and piece[a] > 0 and _piece_rows(
                        D, act, k, i, (a, b), (pa, pb, r), (mu_new[a], mu_new[b]), piece[a],
                        lands[a], F, J):
                    i += 2
                    continue
                F[i] = 0.5 * (pa * pa + pb * pb - r * r) / r
                F[i + 1] = mu_new[a] * pb - mu_new[b] * pa
                for q in range(k):
                    J[i, q] = (pa * D[a, act[q]] + pb * D[b, act[q]]) / r
                    J[i + 1, q] = mu_new[a] * D[b, act[q]] - mu_new[b] * D[a, act[q]]
                J[i + 1, i] += pb
                J[i + 1, i + 1] -= pa
                i += 2
        if not gesv(J, F):                  # F ← J⁻¹F
            return False
        for q in range(k):
            mu_new[act[q]] -= F[q]
    # keep it only if the signs and the inactive constraints still hold
    if not _still_holds(D, yf, lo, hi, kind, lands, piece, mu, mu_new, tol):
        return False
    for j in range(m):
        mu[j] = mu_new[j]
    return True


@inner
def _block(D, y, lo, hi, kind, lands, piece, mu, a, root, out):
    """The disk block a's new μ in out[0:2] (module docstring; a broached block:
    land_project, its piece kept in piece[a] for the polish)."""
    b = kind[a]
    ya = y[a] - D[a, a] * mu[a] - D[a, b] * mu[b]
    yb = y[b] - D[b, a] * mu[a] - D[b, b] * mu[b]
    za, zb, _, r = radial(ya, yb, lo[a], hi[a], lo[b], hi[b])
    if lands is not None and lands[a, 0] > 0.0:
        piece[a] = land_project(D[a, a], D[a, b], D[b, b], za, zb, r, lands[a, 0],
                                lands[a, 1], lands[a, 2], root, out)
    elif za * za + zb * zb <= r * r:
        out[0], out[1] = 0.0, 0.0
    else:
        disk_root(D[a, a], D[a, b], D[b, b], za, zb, r, root)
        out[0], out[1] = -root[2] * root[0], -root[2] * root[1]


@internal
def cone_solve(D, yf, lo, hi, kind, mu, active):
    """The step's μ for boxes and round disks: land_cone_solve without broached holes."""
    return land_cone_solve(D, yf, lo, hi, kind, None, mu, active)


@internal
def land_cone_solve(D, yf, lo, hi, kind, lands, mu, active):
    """The step's μ for boxes, disks and broached holes (module docstring).  ``kind[j]``:
    0 a box row, b > 0 the first row of a disk whose second row is b, −1 a disk's second
    row; ``lands[j]`` of a disk's first row: (lands, half width, angle) of a broached hole
    (lands 0: round); ``lands`` None: every disk round, and then numba compiles none of
    the broached holes' code (it prunes a None argument's branches: a round-hole scene's
    first run compiles less).  Returns the sweeps (< 0: no convergence)."""
    m = yf.size
    y, scale, blocks = sweep_start(yf, lo, hi, kind, mu)
    root, new = np.empty(3), np.empty(2)
    piece = np.zeros(m, np.int64)
    tol = 1e-13 * scale
    for sweeps in range(1, MAX_SWEEPS + 1):
        change = 0.0
        for j in range(m):
            if kind[j] == 0:
                change = max(change, box_row(D, y, lo, hi, mu, j))
            elif kind[j] > 0:
                a, b = j, kind[j]
                _block(D, y, lo, hi, kind, lands, piece, mu, a, root, new)
                da, db = new[0] - mu[a], new[1] - mu[b]
                if da != 0.0 or db != 0.0:
                    for i in range(m):
                        y[i] += D[i, a] * da + D[i, b] * db
                    mu[a], mu[b] = new[0], new[1]
                change = max(change, abs(D[a, a] * da + D[a, b] * db),
                             abs(D[b, a] * da + D[b, b] * db))
        if blocks == 1 or change <= SWEEP_TOL * scale:
            break
    else:
        return -1
    if blocks > 1:
        _polish(D, yf, lo, hi, kind, lands, piece, mu, tol)
    contact_flags(kind, mu, active)
    return sweeps


@inner
def sweep_start(yf, lo, hi, kind, mu):
    """A Gauss–Seidel's start: (y = y_f, the data's scale, the number of blocks: box
    rows and disks), μ ← 0."""
    for j in range(yf.size):
        mu[j] = 0.0
    blocks = 0
    for j in range(yf.size):
        if kind[j] >= 0:
            blocks += 1
    return yf.copy(), data_scale(yf, lo, hi), blocks


@inner
def box_row(D, y, lo, hi, mu, j):
    """Box row j's projection (Lemma 4.1) with the others fixed; returns its change."""
    yt = y[j] - D[j, j] * mu[j]
    new_j = (min(max(yt, lo[j]), hi[j]) - yt) / D[j, j]
    dj = new_j - mu[j]
    if dj != 0.0:
        for i in range(y.size):
            y[i] += D[i, j] * dj
        mu[j] = new_j
    return abs(D[j, j] * dj)


@inner
def contact_flags(kind, mu, active):
    """The values in contact: a disk's first row when its μ_p ≠ 0, never its second row,
    a box row when its μ ≠ 0."""
    for j in range(mu.size):
        if kind[j] > 0:
            active[j] = mu[j] != 0.0 or mu[kind[j]] != 0.0
        elif kind[j] < 0:
            active[j] = False
        else:
            active[j] = mu[j] != 0.0


def check_radii(step) -> None:
    """A round hole's two rows (its box [lo, hi]) must have the same radius."""
    width = step.hi - step.lo
    first, second = step.disks[:, 0], step.disks[:, 1]
    if step.disks.size and np.any(np.abs(width[first] - width[second]) > 1e-12 * width[first]):
        raise InputError("a round hole's two rows must have the same radius")


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


@internal
def lands_of(params, m):
    """land_cone_solve's ``lands`` from the law's params: after the disk pairs, 3 numbers
    per disk (lands, half width, angle; land_params), none: every disk round."""
    lands = np.zeros((m, 3))
    q = int(params[0])
    at = 1 + 2 * q
    if params.size > at:
        for p in range(q):
            a = int(params[1 + 2 * p])
            for c in range(3):
                lands[a, c] = params[at + 3 * p + c]
    return lands


@compiled_law
def round_hole_kernel(D, yf, y_cur, y_prev, lo, hi, params, state, mu, active):
    return land_cone_solve(D, yf, lo, hi, kinds_of(params, yf.size), None, mu, active)


@compiled_law
def broached_hole_kernel(D, yf, y_cur, y_prev, lo, hi, params, state, mu, active):
    m = yf.size
    return land_cone_solve(D, yf, lo, hi, kinds_of(params, m), lands_of(params, m), mu,
                           active)


def broached(step) -> bool:
    """Some hole of the step is broached (StepData.lands: lands > 0)."""
    return bool(step.lands.size and np.any(step.lands[:, 0] > 0))


def disk_params(disks) -> np.ndarray:
    """[q, a0, b0, a1, b1, ...]: the disk pairs as a law's float constants."""
    d = np.asarray(disks, dtype=float).reshape(-1, 2)
    return np.concatenate([[float(d.shape[0])], d.ravel()])


def land_params(lands) -> np.ndarray:
    """The disks' (lands, half width, angle), (q, 3), flattened: after disk_params."""
    return np.asarray(lands, dtype=float).reshape(-1, 3).ravel()


class RoundHole(ContactLaw):
    """Exact contact in round holes (and any box rows beside them): block Gauss–Seidel
    with the disk's closed form, finished by Newton (module docstring)."""
    name = "round-hole"
    kernel = round_hole_kernel
    round_holes = True

    def kernels_for(self, step):
        # round holes only: no lands' code
        return (broached_hole_kernel if broached(step) else round_hole_kernel,)

    def setup(self, step, first=False):
        check_radii(step)
        self.kernel, = self.kernels_for(step)
        if broached(step):
            return np.concatenate([disk_params(step.disks), land_params(step.lands)])
        return disk_params(step.disks)
