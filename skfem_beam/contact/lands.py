"""A broached hole's set K and its pieces, for the round-hole law's blocks.

A broached hole (holes.Hole.broached) has ``lands`` arcs of the drilled circle, each
2·half wide, centred at angle + 2πk/lands.  The tube centre's offset p from the hole's
centre may be anywhere in

    K = {p : p·e(φ) ≤ r for every φ on a land},   e(φ) = (cos φ, sin φ):

over a land K's wall is the circle's arc; in lobe k (between land k and land k+1) it is
the tangent line at land k's end (normal e(φ₁), φ₁ = θ_k + half), then the tangent line
at land k+1's start (e(φ₂), φ₂ = θ_k + step − half), meeting in the corner
q_k = r e(θ_k + step/2)/cos δ, δ = step/2 − half (step = 2π/lands, θ_k = angle + k·step).
A piece is coded as an int: 0 none (inside), 1 an arc, 2 + 3k lobe k's first line,
3 + 3k its second line, 4 + 3k its corner.

The block's projection onto K in the metric D⁻¹ (round_hole.land_project) takes the
cheapest of the pieces' candidates; its polish (round_hole._polish) writes the active
piece's two equations: an arc's are the disk's, a line's e·p = r with μ ∥ −e, a
corner's p = q.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

PIECE_ARC, PIECE_LINE, PIECE_CORNER = 1, 2, 3
# called from compiled code only: no Python or C entry (round_hole.inner)
inner = njit(cache=True, no_cpython_wrapper=True, no_cfunc_wrapper=True)


@inner
def nearest_land(pa, pb, lands, angle):
    """(k, off): the land nearest p's direction and p's angle from its centre, in
    [−π/lands, π/lands]."""
    step = 2.0 * np.pi / lands
    off = np.arctan2(pb, pa) - angle
    k = math.floor(off / step + 0.5)
    return k, off - step * k


@njit(cache=True)
def land_excess(pa, pb, r, lands, half, angle):
    """max over the lands' φ of p·e(φ) − r: how far p lies beyond K (≤ 0: inside; in a
    land's direction it is |p| − r).  holes.land_excess is the same arithmetic."""
    rho = np.hypot(pa, pb)
    off = nearest_land(pa, pb, lands, angle)[1]
    return rho * np.cos(max(abs(off) - half, 0.0)) - r


@inner
def lobe_geometry(k, lands, half, angle):
    """(φ₁, φ₂, δ) of lobe k: its first and second lines' normal angles, half its angle."""
    step = 2.0 * np.pi / lands
    theta = angle + k * step
    return theta + half, theta + step - half, 0.5 * step - half


@inner
def piece_of(code, r, lands, half, angle):
    """(kind, x, y, t_lo, t_hi) of the piece ``code``: PIECE_ARC; PIECE_LINE with its unit
    normal (x, y) and the segment's tangential coordinates p·(−y, x) ∈ [t_lo, t_hi];
    PIECE_CORNER with the corner (x, y)."""
    if code == 1:
        return PIECE_ARC, 0.0, 0.0, 0.0, 0.0
    k, which = (code - 2) // 3, (code - 2) % 3
    phi1, phi2, delta = lobe_geometry(k, lands, half, angle)
    reach = r * np.tan(delta)           # tangent point to corner, along the line
    if which == 0:                      # from land k's end towards the corner
        return PIECE_LINE, np.cos(phi1), np.sin(phi1), 0.0, reach
    if which == 1:                      # from the corner to land k+1's start
        return PIECE_LINE, np.cos(phi2), np.sin(phi2), -reach, 0.0
    m = 0.5 * (phi1 + phi2)
    reach = r / np.cos(delta)           # the corner's distance from the centre
    return PIECE_CORNER, reach * np.cos(m), reach * np.sin(m), 0.0, 0.0


@inner
def line_candidate(a, b, d, za, zb, r, ex, ey, t_lo, t_hi, out):
    """The projection of z onto the line p·e = r in the metric D⁻¹ (D = [[a, b], [b, d]]):
    p = z − sDe, s = (e·z − r)/eᵀDe, μ = −se.  If p lies on the segment [t_lo, t_hi]
    (tangential coordinate, 1e-12 r of slack: the segments then overlap their
    neighbours' ends) out[0:2] ← μ and returns its cost μᵀDμ; else inf (outside K)."""
    dex, dey = a * ex + b * ey, b * ex + d * ey
    ede = ex * dex + ey * dey
    s = (ex * za + ey * zb - r) / ede
    pa, pb = za - s * dex, zb - s * dey
    t = -ey * pa + ex * pb
    if t < t_lo - 1e-12 * r or t > t_hi + 1e-12 * r:
        return np.inf
    out[0], out[1] = -s * ex, -s * ey
    return s * s * ede


@inner
def corner_candidate(a, b, d, za, zb, qa, qb, out):
    """The corner q as the block's value: μ = D⁻¹(q − z) in out[0:2]; returns its cost
    (q − z)·μ = μᵀDμ (a corner of K is always in K)."""
    det = a * d - b * b
    ga, gb = qa - za, qb - zb
    ma, mb = (d * ga - b * gb) / det, (a * gb - b * ga) / det
    out[0], out[1] = ma, mb
    return ga * ma + gb * mb


@inner
def piece_holds(code, pa, pb, mua, mub, r, lands, half, angle, tol):
    """Whether the block's value p with multiplier μ still satisfies the KKT conditions of
    its piece after the polish: μ pushes inwards (an arc: μ·p < 0, p on a land; a line:
    μ = −se with s > 0, p on the segment; a corner: μ = −(s₁e₁ + s₂e₂), s₁, s₂ > 0)."""
    kind, x, y, t_lo, t_hi = piece_of(code, r, lands, half, angle)
    if kind == PIECE_ARC:
        off = nearest_land(pa, pb, lands, angle)[1]
        return mua * pa + mub * pb < 0.0 and abs(off) <= half + tol / r
    if kind == PIECE_LINE:
        t = -y * pa + x * pb
        return mua * x + mub * y < 0.0 and t_lo - tol <= t <= t_hi + tol
    k = (code - 2) // 3
    phi1, phi2, _ = lobe_geometry(k, lands, half, angle)
    c1, s1, c2, s2 = np.cos(phi1), np.sin(phi1), np.cos(phi2), np.sin(phi2)
    det = c1 * s2 - s1 * c2             # −μ = s₁e₁ + s₂e₂, by Cramer's rule
    w1 = (-mua * s2 + mub * c2) / det
    w2 = (-c1 * mub + s1 * mua) / det
    return w1 > 0.0 and w2 > 0.0


@njit(cache=True)
def land_normal(pa, pb, lands, half, angle):
    """The outward unit normal of K's wall nearest p: radial over a land; in a lobe, the
    line of the nearest land's end (the lobe's corner lies on its bisector, so the
    nearest land's line is the one p faces)."""
    step = 2.0 * np.pi / lands
    k, off = nearest_land(pa, pb, lands, angle)
    if abs(off) <= half:
        rho = np.hypot(pa, pb)
        if rho == 0.0:
            return 1.0, 0.0
        return pa / rho, pb / rho
    phi = angle + step * k + (half if off > 0.0 else -half)
    return np.cos(phi), np.sin(phi)


@inner
def on_land(pa, pb, lands, half, angle):
    """Whether p's direction lies on a land (1e-12 rad of slack)."""
    return abs(nearest_land(pa, pb, lands, angle)[1]) <= half + 1e-12


@inner
def lobe_slips(phi1, phi2, va, vb):
    """(t₁·v, t₂·v): v along the tangents t_i = (−sin φ_i, cos φ_i) of a lobe's two lines."""
    return (-np.sin(phi1) * va + np.cos(phi1) * vb, -np.sin(phi2) * va + np.cos(phi2) * vb)


@inner
def corner_forces(mua, mub, slips, f, phis, tol):
    """A corner's multiplier as two faces' Coulomb forces: −μ = λ₁g₁ + λ₂g₂ with
    g_i = e_i + σ_i f t_i (e_i = e(φ_i), t_i = R e_i; σ_i = sign(s_i), either sign when
    |s_i| ≤ tol: that face may stick).  Returns (whether some choice has λ₁, λ₂ ≥ 0,
    λ₁, λ_t1, λ₂, λ_t2), λ_ti = −σ_i f λ_i."""
    s1, s2 = slips
    c1, n1, c2, n2 = np.cos(phis[0]), np.sin(phis[0]), np.cos(phis[1]), np.sin(phis[1])
    for choice in range(4):
        g1 = np.sign(s1) if abs(s1) > tol else (1.0 if choice % 2 == 0 else -1.0)
        g2 = np.sign(s2) if abs(s2) > tol else (1.0 if choice < 2 else -1.0)
        ax, ay = c1 - g1 * f * n1, n1 + g1 * f * c1
        bx, by = c2 - g2 * f * n2, n2 + g2 * f * c2
        det = ax * by - ay * bx
        if det == 0.0:
            continue
        l1 = (-mua * by + mub * bx) / det
        l2 = (-ax * mub + ay * mua) / det
        if l1 >= 0.0 and l2 >= 0.0:
            return True, l1, -g1 * f * l1, l2, -g2 * f * l2
    return False, 0.0, 0.0, 0.0, 0.0


@njit(cache=True)
def land_split(mu2, p, slip, r, f, land):
    """A broached block's multiplier μ (``mu2``) at the offset p from the centre, with the
    step's y^{n+1} − y^{n−1} (``slip``), as its contacts' (λ_n, λ_t, s): at a lobe's
    corner (p within 1e-9 r) two faces (corner_forces), else one with the normal
    land_normal(p).  Returns (contacts: 1 or 2, λ_n, λ_t, s of the first, of the second)."""
    lands, half, angle = land
    k, off = nearest_land(p[0], p[1], lands, angle)
    if abs(off) > half:
        phi1, phi2, delta = lobe_geometry(k if off > 0.0 else k - 1, lands, half, angle)
        reach = r / np.cos(delta)
        mid = 0.5 * (phi1 + phi2)
        if np.hypot(p[0] - reach * np.cos(mid), p[1] - reach * np.sin(mid)) <= 1e-9 * r:
            s1, s2 = lobe_slips(phi1, phi2, slip[0], slip[1])
            ok, l1, t1, l2, t2 = corner_forces(mu2[0], mu2[1], (s1, s2), f, (phi1, phi2),
                                               1e-12 * r)
            if ok:
                return 2, l1, t1, s1, l2, t2, s2
    nx, ny = land_normal(p[0], p[1], lands, half, angle)
    return (1, -(nx * mu2[0] + ny * mu2[1]), -ny * mu2[0] + nx * mu2[1],
            -ny * slip[0] + nx * slip[1], 0.0, 0.0, 0.0)
