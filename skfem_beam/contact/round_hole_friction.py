"""Coulomb friction in round holes at position level: the β-scheme's step with exact
contact at the nodes (|y_p − c| ≤ r to round-off) and Coulomb's law on the step's slip.

At a round hole the node's pair y_p = (v, w) at t_{n+1} satisfies |y_p − c| ≤ r.  The
step's multiplier μ_p (Δt² × the contact force) is split along the wall's outward normal
n = (y_p − c)/r at y_p^{n+1} and its tangent t = (−n_w, n_v):

    μ_p = −λ_n n + λ_t t,   λ_n ≥ 0,  λ_n (|y_p − c| − r) = 0,
    |λ_t| ≤ μ_f λ_n;  |λ_t| < μ_f λ_n ⇒ s = 0;  s ≠ 0 ⇒ λ_t = −μ_f λ_n sign(s),

with the slip s = t·(y_p^{n+1} − y_p^{n−1}), i.e. 2Δt × the β-scheme's consistent
tangential velocity.  Why that one: the scheme's energy identity is its equation times
(u^{n+1} − u^{n−1}) (kernels.finish_step), so a step's friction work is exactly
½ λ_t s/Δt² = −½ μ_f |λ_n| |s|/Δt² ≤ 0: dissipative at every step, not only on average
(the backward increment y^{n+1} − y^n would stick without the two-step memory but
leaves the sign of the step's friction work open).

**One contact** (its block with the other multipliers fixed): z = ỹ_p − c the block's
free offset, q = y_p^{n−1} − c the slip's reference, D = D_pp; p = y_p − c = z + Dμ_p.

- separation: |z| ≤ r, μ_p = 0;
- stick (s = 0 ⇔ p ∥ q): p = r q/|q|, μ_p = D⁻¹(p − z), kept if it lies in the cone;
- slip with sign σ = sign(s): λ_t = −σμ_f λ_n makes μ_p = −τ G_σ p, G_σ = I + σμ_f R
  (R the rotation by +90°, R n = t), τ = λ_n/r ≥ 0, so p = (I + τ D G_σ)⁻¹ z with
  |p| = r: a 1-D root in τ (`slip_root`; det(I + τDG_σ) = 1 + τ tr D + τ² det D(1 + μ_f²)
  > 0, so p(τ) is smooth; safeguarded Newton on 1/|p| − 1/r), kept if σ s ≥ 0.

The normal is that of the unknown y^{n+1}: the closed forms above solve for it (no
fixed point).

**A flat face with friction** (a polygonal hole's, Hole.faces/regular/polygon): its row
y_j = n·y_p (lo ≤ y_j ≤ hi, antiparallel faces in one row) comes with its tangent row
y_T = t·y_p, t = R n, bounds ±∞ (two_planes; StepData.tangents).  At the bound it
violates (hi: outward normal n, σ = 1; lo: −n, σ = −1) the outward tangent is σt, and

    μ_j = −σλ_n,  μ_T = σλ_t,  s = σ(y_T^{n+1} − y_T^{n−1}),

the same law as above.  With the others fixed the block [[a, b], [b, d]] = D on (j, T) is
linear (`coulomb_face`): separation lo ≤ ỹ_j ≤ hi, μ = 0; stick y_j = c (the bound),
y_T = y_T^{n−1}: a 2×2 solve, kept in the cone; slip with sign ς: λ_t = −ςμ_f λ_n is
μ_T = ςμ_f μ_j, so μ_j = (c − ỹ_j)/(a + ςμ_f b), kept if ςs ≥ 0.  Corners (two faces of a
node active) are two blocks coupled through D.

**Several contacts** (and frictionless box rows beside them): block Gauss–Seidel, each
block exact with the others fixed, until a sweep moves no value by more than round-off
(as round_hole.land_cone_solve, without its Newton polish).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ..errors import InputError
from .base import ContactLaw, compiled_law
from .lands import (corner_forces, corner_candidate, land_excess, lobe_geometry, lobe_slips,
                    on_land, piece_of)
from .round_hole import (MAX_SWEEPS, SWEEP_TOL, box_row, broached, check_radii, contact_flags,
                         disk_params, disk_root, kinds_of, land_cone_solve, land_params,
                         land_project, radial, sweep_start)

internal = njit(cache=True)

SEPARATE, STICK, SLIP_FORWARD, SLIP_BACKWARD, FRICTIONLESS, FALLBACK, CORNER = range(7)


@njit(cache=True)
def _slip_point(M, za, zb, t, out):
    """out[0:2] ← p = (I + tM)⁻¹z, out[2] ← d|p|/dt (M = (M00, M01, M10, M11))."""
    n00, n01, n10, n11 = 1.0 + t * M[0], t * M[1], t * M[2], 1.0 + t * M[3]
    det = n00 * n11 - n01 * n10
    pa, pb = (n11 * za - n01 * zb) / det, (-n10 * za + n00 * zb) / det
    ma, mb = M[0] * pa + M[1] * pb, M[2] * pa + M[3] * pb       # dp/dt = −N⁻¹ M p
    da, db = -(n11 * ma - n01 * mb) / det, -(-n10 * ma + n00 * mb) / det
    norm = np.hypot(pa, pb)
    out[0], out[1], out[2] = pa, pb, (pa * da + pb * db) / norm
    return norm


@njit(cache=True)
def slip_root(a, b, d, za, zb, r, g, out):
    """τ ≥ 0 with |p(τ)| = r, p(τ) = (I + τ D G)⁻¹z, D = [[a, b], [b, d]], G = [[1, −g],
    [g, 1]] (|z| > r): out[0:2] ← p; returns τ.  Safeguarded Newton on ψ = 1/|p| − 1/r
    (< 0 at τ = 0, > 0 for τ large) inside a bracket found by doubling."""
    M = np.array([a + b * g, b - a * g, b + d * g, d - b * g])
    w = np.empty(3)
    lo, hi = 0.0, (np.hypot(za, zb) / r - 1.0) / (0.5 * (a + d))
    for _ in range(200):
        if _slip_point(M, za, zb, hi, w) < r:
            break
        lo, hi = hi, 2.0 * hi
    t = lo
    for _ in range(200):
        norm = _slip_point(M, za, zb, t, w)
        psi = 1.0 / norm - 1.0 / r
        if psi == 0.0:
            break
        if psi < 0.0:
            lo = max(lo, t)
        else:
            hi = min(hi, t)
        dpsi = -w[2] / (norm * norm)
        t_new = t - psi / dpsi if dpsi > 0.0 else 0.5 * (lo + hi)
        if not lo < t_new < hi:
            t_new = 0.5 * (lo + hi)
        if abs(t_new - t) <= 1e-16 * t_new or hi - lo <= 1e-16 * hi:
            t = t_new
            break
        t = t_new
    _slip_point(M, za, zb, t, w)
    out[0], out[1] = w[0], w[1]
    return t


@njit(cache=True)
def coulomb_disk(D2, z, q, r, f, out):
    """One contact's μ_p into out[0:2] and p = y_p − c into out[2:4] (module docstring);
    ``D2`` = (a, b, d) the block D_pp, ``z``, ``q`` = (free offset, slip reference), r the
    radius, f Coulomb's μ.  Returns the case (SEPARATE, STICK, SLIP_FORWARD: s > 0,
    SLIP_BACKWARD, FRICTIONLESS: f = 0 or q = 0, FALLBACK: no case held)."""
    a, b, d = D2
    za, zb = z
    qa, qb = q
    if za * za + zb * zb <= r * r:
        out[0], out[1], out[2], out[3] = 0.0, 0.0, za, zb
        return SEPARATE
    nq = np.hypot(qa, qb)
    if f > 0.0 and nq > 0.0:                                # stick, then slip either way
        for case in (STICK, SLIP_FORWARD, SLIP_BACKWARD):
            if _disk_case(D2, z, q, r, f, case, out):
                return case
    root = np.empty(3)
    disk_root(a, b, d, za, zb, r, root)                     # frictionless
    out[0], out[1], out[2], out[3] = -root[2] * root[0], -root[2] * root[1], root[0], root[1]
    return FRICTIONLESS if f == 0.0 or nq == 0.0 else FALLBACK


@njit(cache=True)
def coulomb_face(D2, yj, yt, qt, lo, hi, f, out):
    """One face's (μ_j, μ_T) into out[0:2] (module docstring): ``D2`` = (a, b, d) the block
    D on (j, T), ``yj``, ``yt`` its free values (the others' μ fixed), ``qt`` = y_T^{n−1},
    [lo, hi] the face row's bounds, f Coulomb's μ.  Returns the case (as coulomb_disk's;
    FRICTIONLESS: f = 0; FALLBACK: no case held, the frictionless projection)."""
    a, b, d = D2
    if lo <= yj <= hi:
        out[0], out[1] = 0.0, 0.0
        return SEPARATE
    sg, c = (1.0, hi) if yj > hi else (-1.0, lo)
    if f > 0.0:
        det = a * d - b * b                                  # stick: y_j = c, y_T = q
        mj = (d * (c - yj) - b * (qt - yt)) / det
        mt = (-b * (c - yj) + a * (qt - yt)) / det
        if -sg * mj >= 0.0 and abs(mt) <= f * (-sg * mj):
            out[0], out[1] = mj, mt
            return STICK
        for varsigma in (1.0, -1.0):                         # slip with s of sign ς
            g = varsigma * f
            den = a + g * b
            if den <= 0.0:
                continue
            mj = (c - yj) / den
            s = sg * (yt + (b + g * d) * mj - qt)
            if varsigma * s >= 0.0:
                out[0], out[1] = mj, g * mj
                return SLIP_FORWARD if varsigma > 0.0 else SLIP_BACKWARD
    out[0], out[1] = (c - yj) / a, 0.0                      # frictionless
    return FRICTIONLESS if f == 0.0 else FALLBACK


@njit(cache=True)
def _disk_case(D2, z, q, r, f, case, out):
    """The contact's candidate of ``case`` alone (STICK: p ∥ q; SLIP_FORWARD,
    SLIP_BACKWARD: slip with s of sign ±), μ_p into out[0:2], p into out[2:4]; returns
    whether its conditions hold (on a broached hole's arc a later case may hold where the
    first one's point is off the lands)."""
    a, b, d = D2
    za, zb = z
    qa, qb = q
    if case == STICK:
        nq = np.hypot(qa, qb)
        pa, pb = r * qa / nq, r * qb / nq
        det = a * d - b * b
        ma = (d * (pa - za) - b * (pb - zb)) / det
        mb = (-b * (pa - za) + a * (pb - zb)) / det
        ln = -(pa * ma + pb * mb) / r
        lt = (-pb * ma + pa * mb) / r
        out[0], out[1], out[2], out[3] = ma, mb, pa, pb
        return ln >= 0.0 and abs(lt) <= f * ln
    sigma = 1.0 if case == SLIP_FORWARD else -1.0
    g = sigma * f
    root = np.empty(3)
    tau = slip_root(a, b, d, za, zb, r, g, root)
    pa, pb = root[0], root[1]
    out[0], out[1] = -tau * (pa - g * pb), -tau * (pb + g * pa)
    out[2], out[3] = pa, pb
    return sigma * ((pb * qa - pa * qb) / r) >= 0.0          # s = t·(p − q) = −t·q


@njit(cache=True)
def coulomb_line(D2, z, q, r, f, piece, out):
    """A lobe's line (``piece`` = piece_of's (kind, e_x, e_y, t_lo, t_hi)) as a face: the
    row e·p ≤ r and its tangent row t·p (t = R e), coulomb_face's cases in that frame (each
    on its own: with D anisotropic more than one may hold, and the segment takes the one
    on it).  out[0:2] ← μ_p = μ_j e + μ_T t; returns the case, −1 when z does not cross
    the line or no case holds with its point on the segment (1e-12 r of slack)."""
    a, b, d = D2
    _, ex, ey, t_lo, t_hi = piece
    tx, ty = -ey, ex
    yj = ex * z[0] + ey * z[1]
    if yj <= r:
        return -1
    dex, dey, dtx, dty = a * ex + b * ey, b * ex + d * ey, a * tx + b * ty, b * tx + d * ty
    a, b, d = ex * dex + ey * dey, tx * dex + ty * dey, tx * dtx + ty * dty
    yt, qt = tx * z[0] + ty * z[1], tx * q[0] + ty * q[1]
    for case in (STICK, SLIP_FORWARD, SLIP_BACKWARD):
        if case == STICK:                   # y_j = r, y_T = q_T
            det = a * d - b * b
            mj, mt = (d * (r - yj) - b * (qt - yt)) / det, (-b * (r - yj) + a * (qt - yt)) / det
            holds = -mj >= 0.0 and abs(mt) <= f * -mj
        else:                               # λ_t = −ςμ_f λ_n: μ_T = ςμ_f μ_j
            g = f if case == SLIP_FORWARD else -f
            mj = (r - yj) / (a + g * b) if a + g * b > 0.0 else 0.0
            mt = g * mj
            holds = a + g * b > 0.0 and g * (yt + b * mj + d * mt - qt) >= 0.0
        pt = yt + b * mj + d * mt
        if holds and t_lo - 1e-12 * r <= pt <= t_hi + 1e-12 * r:
            out[0], out[1] = mj * ex + mt * tx, mj * ey + mt * ty
            return case
    return -1


@njit(cache=True)
def coulomb_corner(D2, z, q, r, f, k, land, out):
    """Lobe k's corner c as the block's point: μ_p = D⁻¹(c − z), kept (True) if it is two
    faces' Coulomb forces (lands.corner_forces, the slips s_i = t_i·(c − q))."""
    lands, half, angle = land
    _, cx, cy, _, _ = piece_of(4 + 3 * k, r, lands, half, angle)
    corner_candidate(D2[0], D2[1], D2[2], z[0], z[1], cx, cy, out)
    phi1, phi2, _ = lobe_geometry(k, lands, half, angle)
    s1, s2 = lobe_slips(phi1, phi2, cx - q[0], cy - q[1])
    return corner_forces(out[0], out[1], (s1, s2), f, (phi1, phi2), 1e-12 * r)[0]


@njit(cache=True)
def coulomb_lands(D2, z, q, r, f, land, out):
    """One broached contact's μ_p into out[0:2] (module docstring): separation if z is in
    K; else the first piece whose Coulomb law holds: the arc (coulomb_disk's cases, each
    on its own, the first whose point is on a land), a lobe's line (coulomb_line), a
    lobe's corner (coulomb_corner); none: the frictionless projection (land_project; FRICTIONLESS when f = 0, else FALLBACK)."""
    lands, half, angle = land
    if land_excess(z[0], z[1], r, lands, half, angle) <= 0.0:
        out[0], out[1] = 0.0, 0.0
        return SEPARATE
    if f > 0.0:
        for case in (STICK, SLIP_FORWARD, SLIP_BACKWARD):   # the arc: the first on a land
            if np.hypot(q[0], q[1]) > 0.0 and _disk_case(D2, z, q, r, f, case, out) \
                    and on_land(out[2], out[3], lands, half, angle):
                return case
        for k in range(int(lands)):
            if lobe_geometry(k, lands, half, angle)[2] <= 0.0:
                break                            # full lands: no lobes
            for which in range(2):
                case = coulomb_line(D2, z, q, r, f,
                                    piece_of(2 + 3 * k + which, r, lands, half, angle), out)
                if case >= 0:
                    return case
            if coulomb_corner(D2, z, q, r, f, k, land, out):
                return CORNER
    land_project(D2[0], D2[1], D2[2], z[0], z[1], r, lands, half, angle, np.empty(3), out)
    return FRICTIONLESS if f == 0.0 else FALLBACK


@internal
def _face_block(D, y, y_prev, lo, hi, fric, mu, j, t, local):
    """Face j's exact Coulomb block (its tangent row t) with the others fixed; returns
    its change."""
    yj = y[j] - D[j, j] * mu[j] - D[j, t] * mu[t]
    yt = y[t] - D[t, j] * mu[j] - D[t, t] * mu[t]
    coulomb_face((D[j, j], D[j, t], D[t, t]), yj, yt, y_prev[t], lo[j], hi[j], fric[j],
                 local)
    return _set_pair(D, y, mu, j, t, local)


@internal
def _disk_block(D, y, y_prev, bounds, fric, lands, mu, a, b, local):
    """Disk (a, b)'s exact Coulomb block with the others fixed (a broached one's:
    coulomb_lands; ``lands`` None: every disk round); returns its change."""
    lo, hi = bounds
    ya = y[a] - D[a, a] * mu[a] - D[a, b] * mu[b]
    yb = y[b] - D[b, a] * mu[a] - D[b, b] * mu[b]
    za, zb, _, r = radial(ya, yb, lo[a], hi[a], lo[b], hi[b])
    qa, qb, _, _ = radial(y_prev[a], y_prev[b], lo[a], hi[a], lo[b], hi[b])
    if lands is not None and lands[a, 0] > 0.0:
        coulomb_lands((D[a, a], D[a, b], D[b, b]), (za, zb), (qa, qb), r, fric[a],
                      (lands[a, 0], lands[a, 1], lands[a, 2]), local)
    else:
        coulomb_disk((D[a, a], D[a, b], D[b, b]), (za, zb), (qa, qb), r, fric[a], local)
    return _set_pair(D, y, mu, a, b, local)


@internal
def _set_pair(D, y, mu, a, b, local):
    """Rows a, b's multipliers set to ``local``, y = yf + Dμ updated; returns the largest
    change of y[a], y[b]."""
    da, db = local[0] - mu[a], local[1] - mu[b]
    if da != 0.0 or db != 0.0:
        for i in range(y.size):
            y[i] += D[i, a] * da + D[i, b] * db
        mu[a], mu[b] = local[0], local[1]
    return max(abs(D[a, a] * da + D[a, b] * db), abs(D[b, a] * da + D[b, b] * db))


@internal
def friction_cone_solve(D, yf, y_prev, lo, hi, kind, fric, mu, active, tangent, lands):
    """The step's μ for boxes, faces and round disks with Coulomb friction ``fric`` (per
    disk first row and face row; ``kind`` as round_hole.cone_solve's, a face's tangent
    row −1; ``tangent[j]`` a face j's tangent row, −1 none; ``y_prev`` = C u^{n−1}, the
    slip's reference; ``lands`` as land_cone_solve's, None: every disk round).  Returns
    the sweeps (< 0: no convergence)."""
    m = yf.size
    y, scale, blocks = sweep_start(yf, lo, hi, kind, mu)
    local = np.empty(4)
    for sweeps in range(1, MAX_SWEEPS + 1):
        change = 0.0
        for j in range(m):
            if kind[j] == 0 and tangent[j] >= 0:
                change = max(change, _face_block(D, y, y_prev, lo, hi, fric, mu, j,
                                                 tangent[j], local))
            elif kind[j] == 0:
                change = max(change, box_row(D, y, lo, hi, mu, j))
            elif kind[j] > 0:
                change = max(change, _disk_block(D, y, y_prev, (lo, hi), fric, lands, mu,
                                                 j, kind[j], local))
        if blocks == 1 or change <= SWEEP_TOL * scale:
            break
    else:
        return -1
    contact_flags(kind, mu, active)
    return sweeps


@internal
def friction_rows(params, m):
    """(kind, fric, tangent) from the law's params: [q, a0, b0, ..., μ_0, ..., μ_{q−1},
    k, j0, t0, ..., μ'_0, ..., μ'_{k−1}] (μ per disk, then the k faces with friction:
    their rows, tangent rows and μ; kind −1 at a tangent row)."""
    fric = np.zeros(m)
    tangent = np.full(m, -1, np.int64)
    q = int(params[0])
    for p in range(q):
        fric[int(params[1 + 2 * p])] = params[1 + 2 * q + p]
    kind = kinds_of(params, m)
    at = 1 + 3 * q
    k = int(params[at]) if params.size > at else 0
    for p in range(k):
        j, t = int(params[at + 1 + 2 * p]), int(params[at + 2 + 2 * p])
        tangent[j] = t
        kind[t] = -1
        fric[j] = params[at + 1 + 2 * k + p]
    return kind, fric, tangent


@internal
def friction_lands(params, m):
    """land_cone_solve's ``lands`` from the broached kernel's params: friction_rows' then
    3 numbers per disk (lands, half width, angle; round_hole.land_params)."""
    lands = np.zeros((m, 3))
    q = int(params[0])
    at = 2 + 3 * q + 3 * int(params[1 + 3 * q])
    for p in range(q):
        a = int(params[1 + 2 * p])
        for c in range(3):
            lands[a, c] = params[at + 3 * p + c]
    return lands


# Four kernels, one chosen by setup, so that a run compiles the solve it calls only: with
# friction somewhere (μ > 0 at a disk or a face) friction_cone_solve, else the frictionless
# law's land_cone_solve (the same numbers as the round-hole law); broached holes or round
# ones only (lands None: none of the lands' code).  One kernel with both solves behind a
# branch on the params compiled both: land_cone_solve's polish and its np.linalg.solve
# cost a friction scene's first run ~10 CPU s of a ~22 s law (bench.cold_compile).
@compiled_law
def round_hole_friction_kernel(D, yf, y_cur, y_prev, lo, hi, params, state, mu, active):
    kind, fric, tangent = friction_rows(params, yf.size)
    return friction_cone_solve(D, yf, y_prev, lo, hi, kind, fric, mu, active, tangent, None)


@compiled_law
def round_hole_frictionless_kernel(D, yf, y_cur, y_prev, lo, hi, params, state, mu, active):
    # no friction anywhere: the frictionless law's own solve (the same numbers)
    kind, _, _ = friction_rows(params, yf.size)
    return land_cone_solve(D, yf, lo, hi, kind, None, mu, active)


@compiled_law
def broached_friction_kernel(D, yf, y_cur, y_prev, lo, hi, params, state, mu, active):
    m = yf.size
    kind, fric, tangent = friction_rows(params, m)
    return friction_cone_solve(D, yf, y_prev, lo, hi, kind, fric, mu, active, tangent,
                               friction_lands(params, m))


@compiled_law
def broached_frictionless_kernel(D, yf, y_cur, y_prev, lo, hi, params, state, mu, active):
    # no friction anywhere: the broached round-hole law's own solve (the same numbers)
    m = yf.size
    kind, _, _ = friction_rows(params, m)
    return land_cone_solve(D, yf, lo, hi, kind, friction_lands(params, m), mu, active)


class RoundHoleFriction(ContactLaw):
    """Exact contact in round holes and on flat faces with Coulomb friction at position
    level (module docstring); with μ = 0 everywhere it is the round-hole law, bit for
    bit."""
    name = "round-hole-friction"
    kernel = round_hole_friction_kernel
    round_holes = True
    friction = True
    # why its kernel returns a failure, for the run's one line (it said nothing): measured
    # from μ ≈ 50 on the shipped tubes, none up to 30; a smaller dt failed sooner (μ = 100:
    # t = 0.27 s at dt = 1e-4, 0.024 s at 2.5e-5); and a polygon hole of 128 sides or
    # more at μ = 0.3 (a whirl: 16 to 64 sides run, within 1 % of the round hole's forces)
    failure = ("its block Gauss–Seidel sweeps did not converge (a very large Coulomb μ "
               "couples the holes' normal and tangential forces strongly: check μ; the "
               "shipped tubes run up to μ = 30, and a smaller dt does not help; a polygon "
               "hole of 128 sides or more fails so at μ = 0.3 already: give it as the round "
               "hole it approaches, or 64 sides)")

    @staticmethod
    def _rows(step):
        """(μ per row, the faces' (row, tangent row) pairs, μ > 0 at some disk or face:
        friction_rows' fric > 0 at some row, the kernels)."""
        fric = np.asarray(step.friction, dtype=float)
        if fric.size == 0:
            fric = np.zeros(step.lo.size)
        tangents = np.asarray(step.tangents, dtype=np.int64).reshape(-1, 2)
        frictional = bool(np.any(fric[step.disks[:, 0]] > 0) or np.any(fric[tangents[:, 0]] > 0))
        return fric, tangents, frictional

    def kernels_for(self, step):
        frictional = self._rows(step)[2]
        if broached(step):        # round holes only: no lands' code
            return (broached_friction_kernel if frictional else broached_frictionless_kernel,)
        return (round_hole_friction_kernel if frictional else round_hole_frictionless_kernel,)

    def setup(self, step, first=False):
        check_radii(step)
        fric, tangents, _ = self._rows(step)
        if np.any(np.delete(fric, np.concatenate([step.disks[:, 0], tangents[:, 0]])) > 0):
            raise InputError("Coulomb friction acts at round holes and at a hole's faces "
                             "(with their tangent rows) only")
        params = np.concatenate([disk_params(step.disks), fric[step.disks[:, 0]],
                                 [float(tangents.shape[0])], tangents.ravel().astype(float),
                                 fric[tangents[:, 0]]])
        self.kernel, = self.kernels_for(step)
        if broached(step):
            return np.concatenate([params, land_params(step.lands)])
        return params
