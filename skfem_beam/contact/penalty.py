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

Each obstacle may have its own stiffness and damping (``stiffness``, ``damping``: one
number, or one per obstacle, in the order of ``Obstacles.parts``): a row's lower bound g1
then has the stiffness of the obstacle that gives it and its upper bound g2 that of its
own (StepData.obstacle), so κ and c in r(y) are per row and side.  The kernels read them
per row and side always (params[rows_at(params):], see ``row_params``): with one number
every row holds it, the same arithmetic as a scalar.  Round holes take one number.

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
def sided_spring(y, lo, hi, k_lo, k_hi):
    """r(y) = −(κ_hi (y − hi)⁺ − κ_lo (lo − y)⁺): each bound its own obstacle's stiffness
    (with κ_lo = κ_hi = κ the bits of `spring`: at most one term is nonzero)."""
    return -(k_hi * max(y - hi, 0.0) - k_lo * max(lo - y, 0.0))


@njit(cache=True)
def rows_at(params):
    """Where the per-row constants start: after [κ, c, w_cur, w_prev, d, q, pairs (2q)]."""
    return DISKS_AT + 1 + 2 * int(params[DISKS_AT])


@njit(cache=True)
def damped(y, lo, hi):
    """The dashpot acts: the spring is compressed (y beyond its bound) at tₙ."""
    return y > hi or y < lo


@njit(cache=True)
def compliance_solve(D, yf, lo, hi, c, state, mu, d, y_cur, y_prev, rows):
    """Solve y = yf − D·[c_hi (y − hi)⁺ − c_lo (lo − y)⁺] − D·d δ(y − y_prev) (c = Δt²βκ ≥ 0
    per row and side; the dashpot d = cΔt/2 on the values compressed at tₙ, δ their
    indicator: `damped`, d that of the side compressed) for μ = (y − yf) in D-scaled form;
    ``rows`` = [κ_lo, κ_hi, c_lo, c_hi, d_lo, d_hi] (m each; row_params), ``c``, ``d``
    their largest (c = 0: no spring, d = 0: no dashpot); ``state`` (−1/0/+1) is the warm
    start.  Returns iterations (< 0: failed)."""
    m = yf.size
    if c == 0.0:
        mu[:] = 0.0
        return 0
    c_lo, c_hi = rows[2 * m:3 * m], rows[3 * m:4 * m]
    d_lo, d_hi = rows[4 * m:5 * m], rows[5 * m:6 * m]
    y = yf.copy()
    for it in range(1, 60 + 4 * m):
        # Newton system on the current pattern: y + c D P (y − b) + d D δ (y − y_prev) = yf
        Amat = np.eye(m)
        rhs = yf.copy()
        for j in range(m):
            if state[j] != 0:
                b, cj = (hi[j], c_hi[j]) if state[j] > 0 else (lo[j], c_lo[j])
                for i in range(m):
                    Amat[i, j] += cj * D[i, j]
                    rhs[i] += cj * D[i, j] * b
            if d != 0.0 and damped(y_cur[j], lo[j], hi[j]):
                dj = d_hi[j] if y_cur[j] > hi[j] else d_lo[j]
                for i in range(m):
                    Amat[i, j] += dj * D[i, j]
                    rhs[i] += dj * D[i, j] * y_prev[j]
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
    # μ with y = yf + D μ: μ = −[c_hi (y − hi)⁺ − c_lo (lo − y)⁺] − d·δ(y − y_prev)
    for j in range(m):
        mu[j] = sided_spring(y[j], lo[j], hi[j], c_lo[j], c_hi[j])
        if d != 0.0 and damped(y_cur[j], lo[j], hi[j]):
            mu[j] -= (d_hi[j] if y_cur[j] > hi[j] else d_lo[j]) * (y[j] - y_prev[j])
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
    m = r.size
    rows = params[rows_at(params):]
    k_lo, k_hi = rows[:m], rows[m:2 * m]
    for j in range(m):
        r[j] = w_cur * sided_spring(y_cur[j], lo[j], hi[j], k_lo[j], k_hi[j]) \
            + w_prev * sided_spring(y_prev[j], lo[j], hi[j], k_lo[j], k_hi[j])
    for p in range(int(params[DISKS_AT])):
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
    if params[DISKS_AT] > 0:
        kind = kinds_of(params[DISKS_AT:], m)
        its = disk_compliance_solve(D, yf, lo, hi, params[1], kind, mu)
        for i in range(m):   # in contact: the spring is compressed at y^{n+1}
            if kind[i] == 0:
                active[i] = mu[i] != 0.0
            else:
                active[i] = kind[i] > 0 and (mu[i] != 0.0 or mu[kind[i]] != 0.0)
        return its
    its = compliance_solve(D, yf, lo, hi, params[1], state, mu, params[4], y_cur, y_prev,
                           params[rows_at(params):])
    for i in range(m):   # in contact: the spring is compressed at y^{n+1}
        y = yf[i]
        for j in range(m):
            y += D[i, j] * mu[j]
        active[i] = y < lo[i] or y > hi[i]
    return its


class Penalty(ContactLaw):
    """Normal compliance: the obstacles are one-sided springs of stiffness ``stiffness``
    (in the units of the semi-discrete equation: per unit mass for the beam): one number,
    or one per obstacle (``Obstacles.parts`` in order; the system's rows then need
    StepData.obstacle), and so ``damping``."""
    name = "penalty"
    kernel = penalty_kernel
    explicit = penalty_explicit
    round_holes = True
    springs = True
    # why its kernel returns a failure, for the run's one line (it said nothing)
    failure = ("its set of compressed springs did not settle (it cycles when the springs are "
               "stiff for the step: a smaller dt or stiffness, or exact contact, --law position)")

    def __init__(self, stiffness, damping=0.0, implicit: bool = False):
        self.stiffness = _per_obstacle("stiffness", stiffness, check_positive)
        self.damping = _per_obstacle("damping", damping, check_nonnegative)
        self.implicit = bool(implicit)

    def setup(self, step, first=False):
        beta, k = step.beta, np.max(self.stiffness)
        w_cur, w_prev = (0.5 * (1 - 2 * beta), 0.0) if first else (1 - 2 * beta, beta)
        if self.implicit:           # the whole force at t_{n+1} (module docstring)
            beta, w_cur, w_prev = 1.0, 0.0, 0.0
        k_lo, k_hi, c_lo, c_hi = self.row_params(step)
        params = np.array([k, step.dt ** 2 * beta * k, w_cur, w_prev,
                           0.5 * step.dt * np.max(self.damping)])
        rows = [k_lo, k_hi, step.dt ** 2 * beta * k_lo, step.dt ** 2 * beta * k_hi,
                0.5 * step.dt * c_lo, 0.5 * step.dt * c_hi]
        if not step.disks.size:
            return np.concatenate([params, [0.0], *rows])
        if np.any(self.damping):
            raise InputError("a support's damping (a dashpot) in a round hole is not "
                             "modelled: leave out [[obstacles]] damping")
        if self.stiffness.size > 1:
            raise InputError("round holes take one stiffness for all the obstacles")
        return np.concatenate([params, disk_params(step.disks), *rows])

    def stored(self, step, y, lo, hi) -> float:
        """The springs' energy at the values y of the rows (bounds lo, hi): ½κ(pen)² summed
        (a run that starts on compressed springs gives it to the structure)."""
        k_lo, k_hi, _, _ = self.row_params(step)
        below, above = np.maximum(lo - y, 0.0), np.maximum(y - hi, 0.0)
        return 0.5 * float(np.sum(k_lo * below * below) + np.sum(k_hi * above * above))

    def row_params(self, step):
        """(κ_lo, κ_hi, c_lo, c_hi) per constrained row: the stiffness and damping of the
        obstacle giving its g1 and its g2 (StepData.obstacle; one number: every row)."""
        m = step.lo.size
        if self.stiffness.size == 1 and self.damping.size == 1:
            k, c = np.full(m, self.stiffness[0]), np.full(m, self.damping[0])
            return k, k, c, c
        owner = np.asarray(step.obstacle, dtype=np.int64).reshape(-1, 2)
        n = max(self.stiffness.size, self.damping.size)
        if owner.shape[0] != m:
            raise InputError("a stiffness per obstacle needs the system's obstacle of each "
                             "constrained row (one-plane beams' flat obstacles); give one "
                             "stiffness for all")
        if owner.max(initial=-1) >= n:
            raise InputError(f"{n} stiffnesses for {owner.max() + 1} obstacles: give one per "
                             "obstacle (or one for all)")
        k = np.broadcast_to(self.stiffness, (n,))
        c = np.broadcast_to(self.damping, (n,))
        pick = lambda v, i: np.where(i >= 0, v[np.maximum(i, 0)], v[0])  # noqa: E731
        return (pick(k, owner[:, 0]), pick(k, owner[:, 1]), pick(c, owner[:, 0]),
                pick(c, owner[:, 1]))

    def __repr__(self) -> str:
        def fmt(v):
            return f"{v[0]:g}" if v.size == 1 else f"[{', '.join(f'{x:g}' for x in v)}]"
        return f"Penalty(stiffness={fmt(self.stiffness)}, damping={fmt(self.damping)})"


def _per_obstacle(name: str, value, check) -> np.ndarray:
    """One number or one per obstacle, each checked (``check``), as a 1-d float array."""
    values = np.atleast_1d(np.asarray(value, dtype=float)).ravel()
    if values.size == 0:
        raise InputError(f"{name}: give one number or one per obstacle")
    return np.array([check(f"{name}[{i}]" if values.size > 1 else name, v)
                     for i, v in enumerate(values.tolist())])
