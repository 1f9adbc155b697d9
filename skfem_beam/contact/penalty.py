"""Normal compliance (penalty): the obstacles are one-sided springs of stiffness κ = 1/ε.

Inside the β-scheme the spring force r(y) = −κ[(y − hi)⁺ − (lo − y)⁺] is weighted like
the elastic force: β r(y^{n+1}) + (1−2β) r(yⁿ) + β r(y^{n−1}).  The explicit part
(1−2β) r(yⁿ) + β r(y^{n−1}) is the law's ``explicit``: it enters the step's load; the
implicit part makes the step a piecewise-linear monotone equation in y:
y = y_free + D μ,  μ = Δt² β r(y),  solved exactly by a semi-smooth Newton iteration
(finite for piecewise-linear monotone maps; one step when m = 1).  The contact force
recorded is the whole β-weighted spring force.

A support's damping c (``damping``, Kelvin–Voigt: a dashpot beside the spring) adds
−c ẏ on the values whose spring is compressed at tₙ, with ẏ = (y^{n+1} − y^{n−1})/(2Δt)
as the scheme takes B's (so μ gains −(cΔt/2)(y^{n+1} − y^{n−1}) there).  Its activity
is that of tₙ, known before the step: the equation stays piecewise linear, continuous
and monotone (with the activity of t_{n+1} the dashpot would switch on with a jump
c·ẏ and Newton could cycle).  Like every linear Kelvin–Voigt contact, it also pulls
while the support unloads.

In a round hole (a disk pair of rows, contact.round_hole) the spring is radial:
r(y_p) = −κ(|y_p − c| − r)⁺ (y_p − c)/|y_p − c|, the gradient of a convex energy, so the
implicit step is the minimiser of a strictly convex function and Newton solves it
(`disk_compliance_solve`); a dashpot there is not modelled (refused).

The start step weights the spring at u⁰ by ½(1−2β) instead (see scheme.run).

``implicit=True`` takes the whole spring force at t_{n+1} instead (weights 1, 0, 0): the
step is then min ½|x − x_free|²_A + ½Δt²κ·dist²(Cx, K), the Moreau–Yosida regularisation
of the exact step, which it approaches at rate 1/κ as κ → ∞ (at the same Δt and mesh);
the β-weighted springs do not: their limit keeps the β-weighted forces of uⁿ and uⁿ⁻¹
and returns the energy an exact (e = 0) contact takes (docs/design.md §1, *Springs →
exact contact*).  It dissipates where the springs act: a check of the limit, not a
spring model.
"""
import numpy as np
from numba import njit

from ..checks import check_nonnegative, check_positive
from ..errors import InputError
from .active_set import data_scale
from .base import ContactLaw, compiled_explicit, compiled_law
from .round_hole import disk_params, kinds_of, radial

DISKS_AT = 5      # params[DISKS_AT:]: the disk pairs (round_hole.disk_params)


@njit(cache=True)
def spring(y, lo, hi, stiffness):
    """The one-sided springs' force r(y) = −κ[(y − hi)⁺ − (lo − y)⁺] on one value."""
    return -stiffness * (max(y - hi, 0.0) - max(lo - y, 0.0))


@njit(cache=True)
def damped(y, lo, hi):
    """The dashpot acts: the spring is compressed (y beyond its bound) at tₙ."""
    return y > hi or y < lo


@njit(cache=True)
def compliance_solve(D, yf, lo, hi, c, state, mu, d, y_cur, y_prev):
    """Solve y = yf − c·D·[(y − hi)⁺ − (lo − y)⁺] − d·D·δ(y − y_prev) (c = Δt²βκ ≥ 0; the
    dashpot d = cΔt/2 on the values compressed at tₙ, δ their indicator: `damped`) for
    μ = (y − yf) in D-scaled form; ``state`` (−1/0/+1) is the warm start.  Returns
    iterations (< 0: failed)."""
    m = yf.size
    if c == 0.0:
        mu[:] = 0.0
        return 0
    y = yf.copy()
    for it in range(1, 60 + 4 * m):
        # Newton system on the current pattern: y + c D P (y − b) + d D δ (y − y_prev) = yf
        Amat = np.eye(m)
        rhs = yf.copy()
        for j in range(m):
            if state[j] != 0:
                b = hi[j] if state[j] > 0 else lo[j]
                for i in range(m):
                    Amat[i, j] += c * D[i, j]
                    rhs[i] += c * D[i, j] * b
            if d != 0.0 and damped(y_cur[j], lo[j], hi[j]):
                for i in range(m):
                    Amat[i, j] += d * D[i, j]
                    rhs[i] += d * D[i, j] * y_prev[j]
        y = np.linalg.solve(Amat, rhs)
        changed = False
        for j in range(m):
            s = 1 if y[j] > hi[j] else (-1 if y[j] < lo[j] else 0)
            if s != state[j]:
                state[j] = s
                changed = True
        if not changed:
            break
    else:
        return -1
    # μ with y = yf + D μ: μ = −c·[(y − hi)⁺ − (lo − y)⁺] − d·δ(y − y_prev)
    for j in range(m):
        mu[j] = -c * (max(y[j] - hi[j], 0.0) - max(lo[j] - y[j], 0.0))
        if d != 0.0 and damped(y_cur[j], lo[j], hi[j]):
            mu[j] -= d * (y[j] - y_prev[j])
    return it


@njit(cache=True)
def disk_spring(ya, yb, lo_a, hi_a, lo_b, hi_b, stiffness):
    """The radial spring's force (r_a, r_b) on a pair in its round hole."""
    pa, pb, rho, rad = radial(ya, yb, lo_a, hi_a, lo_b, hi_b)
    if rho <= rad:
        return 0.0, 0.0
    f = -stiffness * (rho - rad) / rho
    return f * pa, f * pb


@compiled_explicit
def penalty_explicit(y_cur, y_prev, lo, hi, params, r):
    """r = w_cur r(yⁿ) + w_prev r(yⁿ⁻¹): (1−2β) and β in a step, ½(1−2β) and 0 at the start."""
    stiffness, w_cur, w_prev = params[0], params[2], params[3]
    for j in range(r.size):
        r[j] = w_cur * spring(y_cur[j], lo[j], hi[j], stiffness) \
            + w_prev * spring(y_prev[j], lo[j], hi[j], stiffness)
    for p in range(int(params[DISKS_AT]) if params.size > DISKS_AT else 0):
        a, b = int(params[DISKS_AT + 1 + 2 * p]), int(params[DISKS_AT + 2 + 2 * p])
        fa, fb = disk_spring(y_cur[a], y_cur[b], lo[a], hi[a], lo[b], hi[b], stiffness)
        ga, gb = disk_spring(y_prev[a], y_prev[b], lo[a], hi[a], lo[b], hi[b], stiffness)
        r[a] = w_cur * fa + w_prev * ga
        r[b] = w_cur * fb + w_prev * gb
    return 0


@njit(cache=True)
def _springs(y, lo, hi, c, kind, mu_y, Jm):
    """μ(y) = c·r(y) of every row (radial on the disks of ``kind``) and, if Jm has rows,
    its Jacobian ∂μ/∂y."""
    m = y.size
    for j in range(m):
        mu_y[j] = 0.0
    if Jm.shape[0]:
        Jm[:, :] = 0.0
    for j in range(m):
        if kind[j] == 0:
            if y[j] > hi[j] or y[j] < lo[j]:
                mu_y[j] = spring(y[j], lo[j], hi[j], c)
                if Jm.shape[0]:
                    Jm[j, j] = -c
        elif kind[j] > 0:
            a, b = j, kind[j]
            mu_y[a], mu_y[b] = disk_spring(y[a], y[b], lo[a], hi[a], lo[b], hi[b], c)
            pa, pb, rho, rad = radial(y[a], y[b], lo[a], hi[a], lo[b], hi[b])
            if rho > rad and Jm.shape[0]:
                f, ea, eb, g = 1.0 - rad / rho, pa / rho, pb / rho, rad / rho
                Jm[a, a] = -c * (f + g * ea * ea)
                Jm[b, b] = -c * (f + g * eb * eb)
                Jm[a, b] = Jm[b, a] = -c * g * ea * eb


@njit(cache=True)
def disk_compliance_solve(D, yf, lo, hi, c, kind, mu):
    """y = yf + D μ(y) with μ = c·r(y) (c = Δt²β, r the one-sided springs: radial on the
    disks of ``kind``, round_hole.cone_solve's), by Newton on G(y) = y − yf − D μ(y), the
    step halved until |G| decreases (μ is the gradient of a concave function, so G = 0
    has one root; a full step may overshoot the kink where a spring starts).
    Returns iterations (< 0: failed)."""
    m = yf.size
    y = yf.copy()
    scale = data_scale(yf, lo, hi)
    mu_y, Jm, none = np.zeros(m), np.zeros((m, m)), np.zeros((0, 0))
    _springs(y, lo, hi, c, kind, mu_y, Jm)
    G = y - yf - D @ mu_y
    gn = np.abs(G).max()
    its = 0
    for its in range(1, 200):
        if gn <= 1e-15 * scale:
            break
        dy = np.linalg.solve(np.eye(m) - D @ Jm, G)
        t = 1.0
        for _ in range(60):
            trial = y - t * dy
            _springs(trial, lo, hi, c, kind, mu_y, none)
            Gt = trial - yf - D @ mu_y
            if np.abs(Gt).max() < gn or t < 1e-12:
                break
            t *= 0.5
        if np.abs(trial - y).max() <= 1e-16 * scale:
            y = trial
            break
        y = trial
        _springs(y, lo, hi, c, kind, mu_y, Jm)
        G = y - yf - D @ mu_y
        gn = np.abs(G).max()
    else:
        return -1
    _springs(y, lo, hi, c, kind, mu, none)
    return its


@compiled_law
def penalty_kernel(D, yf, y_cur, y_prev, lo, hi, params, state, mu, active):
    """The implicit springs (params[1] = Δt²βκ) and dashpots (params[4] = cΔt/2, on the
    values compressed at tₙ): y = yf + Dμ."""
    m = yf.size
    if params.size > DISKS_AT and params[DISKS_AT] > 0:
        kind = kinds_of(params[DISKS_AT:], m)
        its = disk_compliance_solve(D, yf, lo, hi, params[1], kind, mu)
        for i in range(m):   # in contact: the spring is compressed at y^{n+1}
            if kind[i] == 0:
                active[i] = mu[i] != 0.0
            else:
                active[i] = kind[i] > 0 and (mu[i] != 0.0 or mu[kind[i]] != 0.0)
        return its
    its = compliance_solve(D, yf, lo, hi, params[1], state, mu, params[4], y_cur, y_prev)
    for i in range(m):   # in contact: the spring is compressed at y^{n+1}
        y = yf[i]
        for j in range(m):
            y += D[i, j] * mu[j]
        active[i] = y < lo[i] or y > hi[i]
    return its


class Penalty(ContactLaw):
    """Normal compliance: the obstacles are one-sided springs of stiffness ``stiffness``
    (in the units of the semi-discrete equation: per unit mass for the beam)."""
    name = "penalty"
    kernel = penalty_kernel
    explicit = penalty_explicit
    round_holes = True
    springs = True

    def __init__(self, stiffness: float, damping: float = 0.0, implicit: bool = False):
        self.stiffness = check_positive("stiffness", stiffness)
        self.damping = check_nonnegative("damping", damping)
        self.implicit = bool(implicit)

    def setup(self, step, first=False):
        beta, k = step.beta, self.stiffness
        w_cur, w_prev = (0.5 * (1 - 2 * beta), 0.0) if first else (1 - 2 * beta, beta)
        if self.implicit:           # the whole force at t_{n+1} (module docstring)
            beta, w_cur, w_prev = 1.0, 0.0, 0.0
        params = np.array([k, step.dt ** 2 * beta * k, w_cur, w_prev,
                           0.5 * step.dt * self.damping])
        if not step.disks.size:
            return params
        if self.damping:
            raise InputError("a support's damping (a dashpot) in a round hole is not "
                             "modelled: leave out [[obstacles]] damping")
        return np.concatenate([params, disk_params(step.disks)])

    def __repr__(self) -> str:
        return f"Penalty(stiffness={self.stiffness:g}, damping={self.damping:g})"
