"""Exact solutions the numerical results are tested against."""
from __future__ import annotations

import bisect
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import polynomial as _P
from scipy.optimize import brentq
from scipy.special import comb

# roots of 1 + cos(βL) cosh(βL) = 0: the clamped–free Euler–Bernoulli beam
CANTILEVER_BETA_L = (1.87510407, 4.69409113, 7.85475744, 10.99554073)


def cantilever_beta_l(count: int) -> np.ndarray:
    """The first ``count`` roots βₙL of 1 + cos x cosh x = 0, to machine precision."""
    f = lambda x: np.cos(x) + 1.0 / np.cosh(x)  # noqa: E731  (same roots, no overflow)
    return np.array([brentq(f, (n + 0.5) * np.pi - 1.0, (n + 0.5) * np.pi + 0.5, xtol=1e-15)
                     for n in range(count)])


def cantilever_omegas(L: float, k2: float, count: int = 4) -> np.ndarray:
    """Angular eigenfrequencies ωₙ = (βₙL)² √k² / L² of u_tt + k² u_xxxx = 0, clamped–free."""
    return cantilever_beta_l(count) ** 2 * np.sqrt(k2) / L**2


def cantilever_mode(x, L: float, n: int) -> np.ndarray:
    """Mode shape n (0-based), normalised to 1 at the free end x = L."""
    bl = cantilever_beta_l(n + 1)[n]
    s = bl * np.asarray(x, dtype=float) / L
    sigma = (np.cosh(bl) + np.cos(bl)) / (np.sinh(bl) + np.sin(bl))
    phi = lambda z: np.cosh(z) - np.cos(z) - sigma * (np.sinh(z) - np.sin(z))  # noqa: E731
    return phi(s) / phi(bl)


# ---------------------------------------------------------------------------------------
# The impacting bar (Do, Raupp & Feijoo, Example 1 and its generalisations)
#
# Non-dimensional form (ξ = x/L, τ = ct/L, c = √(a/ρ), w = u/L), elastic bar (b = 0),
# uniform data u0, v0, f:
#
#     w_ττ = w_ξξ + f̃,  f̃ = fL/a,   w(ξ,0) = g = u0/L,  w_τ(ξ,0) = v = v0/c,
#     w_ξ(1,τ) = 0,     at ξ = 0:  elastic  w_ξ = κ min(w, 0), κ = kL/a   (a u_x = k u
#                                  while in contact, free otherwise);
#                                  rigid    w ≥ 0, R = −w_ξ ≥ 0, R·w = 0.
#
# d'Alembert: w = F(ξ−τ) + G(ξ+τ) + f̃τ²/2.  The data give F, G on [0, 1]; the free end
# reflects F into G: G(s) = F(2−s) + v for s ≥ 1; the obstacle turns the incoming G into
# the outgoing p(τ) = F(−τ) through the law at ξ = 0, with U = w(0,τ) = p + G + f̃τ²/2:
#
#     free:            p' = G'
#     elastic contact: p' + κp = G' − κG − κf̃τ²/2      (the Robin condition w_ξ = κw)
#     rigid contact:   p = −G − f̃τ²/2                  (U = 0), R = −2G' − f̃τ
#
# Every piece of p and G is P(s) + e^{−κs}Q(s) (s = τ − τ₀, P, Q polynomials): the
# data are polynomial, the Robin law adds the exponentials and each round trip (Δτ = 2)
# raises the degree of Q by one.  Switching times (separation, new contact) are roots
# of U or R, found by bracketing and Brent's method.  The regions R_I, R_II, R_III of
# the paper are the first pieces (see bar_elastic_paper).
# ---------------------------------------------------------------------------------------

class _ExpPoly:
    """P(s) + e^{−κs} Q(s) on [t0, t1], s = τ − t0 (ascending coefficient arrays)."""

    __slots__ = ("t0", "t1", "P", "Q", "kappa")

    def __init__(self, t0, t1, P, Q=(0.0,), kappa=0.0):
        self.t0, self.t1, self.kappa = float(t0), float(t1), float(kappa)
        self.P = np.atleast_1d(np.asarray(P, dtype=float))
        self.Q = np.atleast_1d(np.asarray(Q, dtype=float))

    def __call__(self, t):
        s = np.asarray(t, dtype=float) - self.t0
        out = _P.polyval(s, self.P)
        if np.any(self.Q):
            out = out + np.exp(-self.kappa * s) * _P.polyval(s, self.Q)
        return out

    def deriv(self) -> "_ExpPoly":
        return _ExpPoly(self.t0, self.t1, _P.polyder(self.P),
                        _P.polysub(_P.polyder(self.Q), self.kappa * self.Q), self.kappa)

    def __add__(self, other: "_ExpPoly") -> "_ExpPoly":
        assert other.t0 == self.t0
        return _ExpPoly(self.t0, self.t1, _P.polyadd(self.P, other.P),
                        _P.polyadd(self.Q, other.Q), self.kappa)

    def scale(self, c: float) -> "_ExpPoly":
        return _ExpPoly(self.t0, self.t1, c * self.P, c * self.Q, self.kappa)

    def rebase(self, t0: float, t1: float | None = None) -> "_ExpPoly":
        """The same function written in s' = τ − t0 (Taylor coefficients at the new origin)."""
        d = t0 - self.t0
        return _ExpPoly(t0, self.t1 if t1 is None else t1, _taylor(self.P, d),
                        _taylor(self.Q, d) * np.exp(-self.kappa * d), self.kappa)

    def moved(self, shift: float, add: float = 0.0) -> "_ExpPoly":
        """τ ↦ f(τ − shift) + add, on the interval moved by ``shift``."""
        P = self.P.copy()
        P[0] += add
        return _ExpPoly(self.t0 + shift, self.t1 + shift, P, self.Q, self.kappa)


def _taylor(c: np.ndarray, d: float) -> np.ndarray:
    """Coefficients of c(s + d) in s: out_j = Σ_{m≥j} C(m, j) d^{m−j} c_m."""
    n = c.size
    m = np.arange(n)
    e = m[None, :] - m[:, None]                     # m − j
    B = np.where(e >= 0, comb(m[None, :], m[:, None]) * float(d) ** np.maximum(e, 0), 0.0)
    return B @ c


def _robin_solve(q: _ExpPoly, p0: float) -> _ExpPoly:
    """p' + κp = q, p(t0) = p0, exactly: polynomial part by Σ(−1)ʲq⁽ʲ⁾/κʲ⁺¹, the resonant
    e^{−κs}Q part by ∫₀ˢQ, the homogeneous part C e^{−κs}."""
    k = q.kappa
    Pp, cur, sign = np.zeros(max(q.P.size, 1)), q.P, 1.0
    for j in range(q.P.size):
        Pp[:cur.size] += sign * cur / k ** (j + 1)
        cur = _P.polyder(cur) if cur.size > 1 else np.zeros(1)
        sign = -sign
    Qp = _P.polyint(q.Q)          # lower bound 0: Qp(0) = 0
    Qp[0] += p0 - Pp[0]
    return _ExpPoly(q.t0, q.t1, Pp, Qp, k)


class _Piecewise:
    """A function of τ made of _ExpPoly pieces that follow each other."""

    def __init__(self):
        self.pieces: list[_ExpPoly] = []
        self.starts: list[float] = []

    def append(self, piece: _ExpPoly):
        self.pieces.append(piece)
        self.starts.append(piece.t0)

    def piece_at(self, t: float) -> _ExpPoly:
        return self.pieces[max(bisect.bisect_right(self.starts, t) - 1, 0)]

    def __call__(self, t, der: int = 0):
        t = np.asarray(t, dtype=float)
        idx = np.clip(np.searchsorted(np.array(self.starts), t, side="right") - 1, 0,
                      len(self.pieces) - 1)
        out = np.empty(t.shape)
        for i in np.unique(idx):
            fn = self.pieces[i]
            for _ in range(der):
                fn = fn.deriv()
            sel = idx == i
            out[sel] = fn(t[sel])
        return out


def _first_root(fun, a: float, b: float, kappa: float, tol: float, skip: float = 0.0
                ) -> float | None:
    """First τ in (a + skip, b] where ``fun`` (≥ 0 just after a) turns negative, or None."""
    grid = [np.linspace(a, b, 1025), a + (b - a) * np.geomspace(1e-10, 1.0, 80)]
    if kappa > 0:
        layer = np.geomspace(1e-4 / kappa, 40.0 / kappa, 200)
        grid.append(a + layer[layer < b - a])
    grid = np.unique(np.concatenate(grid))
    if skip:   # start the search at a + skip: a switch right there is returned as such
        grid = grid[grid >= a + skip]
    vals = fun(grid)
    bad = np.flatnonzero(vals[1:] < -tol) + 1
    if bad.size == 0:
        return None
    i = int(bad[0])
    lo, hi = grid[i - 1], grid[i]
    if vals[i - 1] <= 0.0:   # bracket degenerate at the start: the switch is immediate
        return lo
    return brentq(lambda s: float(fun(np.array([s]))[0]), lo, hi, xtol=1e-15, rtol=1e-15)


class BarWaves:
    """The exact non-dimensional solution w(ξ, τ) of the bar (see the comment above).

    ``kappa``: κ = kL/a of the elastic obstacle, or None for the rigid one.
    """

    def __init__(self, kappa: float | None, g: float, v: float, f: float, tau_end: float):
        self.kappa, self.g, self.v, self.f = kappa, float(g), float(v), float(f)
        k = 0.0 if kappa is None else float(kappa)
        self._k = k
        self.tol = 1e-13 * max(abs(v), abs(g), abs(f), 1.0)
        self.G = _Piecewise()
        self.G.append(_ExpPoly(0.0, 2.0, [g / 2, v / 2], kappa=k))   # data, reflected at ξ=1
        self.p = _Piecewise()
        self.contact_intervals: list[list[float]] = []
        self._march(float(tau_end) + 1.0)

    # the load term f̃τ²/2 written around t0
    def _load(self, t0, t1) -> _ExpPoly:
        f = self.f
        return _ExpPoly(t0, t1, [f * t0**2 / 2, f * t0, f / 2], kappa=self._k)

    def _candidate(self, contact: bool, G: _ExpPoly, p0: float) -> _ExpPoly:
        load = self._load(G.t0, G.t1)
        if not contact:
            return G + _ExpPoly(G.t0, G.t1, [p0 - G(G.t0)], kappa=self._k)
        if self.kappa is None:
            return (G + load).scale(-1.0)
        q = G.deriv() + (G + load).scale(-self._k)
        return _robin_solve(q, p0)

    def _starts_in_contact(self, t: float, p0: float) -> bool:
        """The law at ξ = 0 just after τ = t, from U(t) and, at U = 0, the sign of the first
        non-zero derivative of the free motion U = 2G − G(t) + p0 + f̃τ²/2."""
        G = self.G.piece_at(t).rebase(t)
        U = p0 + G(t) + self.f * t**2 / 2
        tol = self._tol(t)
        if U < -tol:
            return True
        if U > tol:
            return False
        Ufree = G.scale(2.0) + self._load(t, G.t1)
        for _ in range(4):
            Ufree = Ufree.deriv()
            d = float(Ufree(t))
            if abs(d) > tol:
                return d < 0
        return False

    def _tol(self, t: float) -> float:
        """Round-off of U = p + G + f̃τ²/2: its terms grow like f̃τ²/2 and cancel."""
        return self.tol * (1.0 + abs(self.f) * t * t)

    def _march(self, tau_end: float):
        t, p0 = 0.0, self.g / 2          # p(0) = F(0)
        contact = self._starts_in_contact(t, p0)
        eps = 1e-10                      # switches closer than this are round-off
        skip = 0.0                       # > 0: ignore events just after t (see below)
        immediate = False                # the last pass switched the law without a piece
        for _ in range(100000):
            if t >= tau_end:
                return
            if len(self.p.pieces) > 20000:   # the count grows ~ quadratically with τ
                raise RuntimeError(f"the exact bar solution needs more than 20000 pieces "
                                   f"by τ = ct/L = {t:.4g}; use a shorter T")
            G = self.G.piece_at(t).rebase(t)
            cand = self._candidate(contact, G, p0)
            U = cand + G + self._load(t, G.t1)
            if contact and self.kappa is None:   # rigid: leave when R = −U'_free < 0
                Gd = G.deriv()
                fun = lambda s, Gd=Gd: -2 * Gd(s) - self.f * s  # noqa: E731
            elif contact:                        # elastic: leave when U > 0
                fun = lambda s, U=U: -U(s)  # noqa: E731
            else:                                # free: hit when U < 0
                fun = U
            tol = self._tol(t)
            te = _first_root(fun, t, G.t1, self._k, tol, skip)
            forced, skip = skip > 0, 0.0
            if te is not None and te <= t + eps and not forced:
                # an immediate switch; if the other law also switches at once, U and R
                # both vanish to round-off (grazing): stay free and look past it
                if immediate:
                    contact, skip, immediate = False, eps, False
                else:
                    contact, immediate = not contact, True
                continue
            immediate = False
            switched = te is not None and te < G.t1 - eps   # no sliver pieces at the end
            te = max(te, t + eps) if switched else G.t1
            piece = _ExpPoly(t, te, cand.P, cand.Q, self._k)
            self.p.append(piece)
            self.G.append(piece.moved(2.0, add=self.v))   # G(s) = p(s−2) + v
            if contact:
                self._mark_contact(t, te)
            p0, t = float(piece(te)), te
            # at an event the law switches; at the end of a piece of G it is decided again
            contact = (not contact) if switched else self._starts_in_contact(t, p0)
        raise RuntimeError("too many switches in the exact bar solution")

    def _mark_contact(self, t0, t1):
        if self.contact_intervals and abs(self.contact_intervals[-1][1] - t0) < 1e-15:
            self.contact_intervals[-1][1] = t1
        else:
            self.contact_intervals.append([t0, t1])

    # --- the solution ---------------------------------------------------------------
    def _F(self, xi, der=0):
        xi = np.asarray(xi, dtype=float)
        data = [self.g / 2 - self.v * xi / 2, np.full(xi.shape, -self.v / 2),
                np.zeros(xi.shape)][der]
        inner = self.p(-np.minimum(xi, 0.0), der) * (-1.0) ** der
        return np.where(xi >= 0, data, inner)

    def w(self, xi, tau):
        xi, tau = np.broadcast_arrays(np.asarray(xi, float), np.asarray(tau, float))
        return self._F(xi - tau) + self.G(xi + tau) + self.f * tau**2 / 2

    def w_tau(self, xi, tau):
        xi, tau = np.broadcast_arrays(np.asarray(xi, float), np.asarray(tau, float))
        return -self._F(xi - tau, 1) + self.G(xi + tau, 1) + self.f * tau

    def w_xi(self, xi, tau):
        xi, tau = np.broadcast_arrays(np.asarray(xi, float), np.asarray(tau, float))
        return self._F(xi - tau, 1) + self.G(xi + tau, 1)

    def reaction(self, tau):
        """R = −w_ξ(0, τ), from the law at ξ = 0 (non-dimensional, units of a)."""
        tau = np.asarray(tau, dtype=float)
        if self.kappa is not None:
            return self.kappa * np.maximum(-self.w(0.0, tau), 0.0)
        R = -self.w_xi(0.0, tau)
        inside = np.zeros(tau.shape, dtype=bool)
        for a, b in self.contact_intervals:
            inside |= (tau > a) & (tau < b)
        return np.where(inside, R, 0.0)


@dataclass(frozen=True)
class BarData:
    """An elastic bar's uniform physical data, as :class:`BarExact` takes them: stiffness
    a, density ρ, length L, initial velocity v0, ``obstacle`` 'rigid' or 'elastic'
    (spring k), load f and gap u0, the obstacle at x = 0."""
    a: float
    rho: float
    L: float
    v0: float
    obstacle: str = "rigid"
    k: float | None = None
    f: float = 0.0
    u0: float = 0.0


class BarExact:
    """Exact solution of an elastic bar (b = 0) with uniform data (:class:`BarData`) up
    to T, in physical units.

    u(x, t) = L·w(x/L, ct/L); R(t) = −a u_x(0, t) the obstacle reaction per unit area.
    Valid for any a, ρ, L, k > 0, f, v0 and gap u0 ≥ 0 (u0 < 0 is allowed for the
    elastic obstacle).
    """

    def __init__(self, bar: BarData, T):
        obstacle, k, f, u0, v0 = bar.obstacle, bar.k, bar.f, bar.u0, bar.v0
        self.a, self.rho, self.L = float(bar.a), float(bar.rho), float(bar.L)
        self.c = np.sqrt(self.a / self.rho)
        kappa = None if obstacle == "rigid" else float(k) * self.L / self.a
        if obstacle == "rigid" and u0 < 0:
            raise ValueError("u0 < 0 violates the rigid obstacle")
        self.waves = BarWaves(kappa, u0 / self.L, v0 / self.c, f * self.L / self.a,
                              self.c * float(T) / self.L)
        self.obstacle, self.k = obstacle, k

    @classmethod
    def of(cls, bar, T):
        """The exact solution of a :class:`skfem_beam.bar.Bar` up to T, or None where none
        is known (see :func:`exact_of`: it may be a :class:`RodExact`)."""
        return exact_of(bar, T)

    def _tau(self, t):
        return self.c * np.asarray(t, dtype=float) / self.L

    def u(self, x, t):
        return self.L * self.waves.w(np.asarray(x, float) / self.L, self._tau(t))

    def velocity(self, x, t):
        return self.c * self.waves.w_tau(np.asarray(x, float) / self.L, self._tau(t))

    def strain(self, x, t):
        return self.waves.w_xi(np.asarray(x, float) / self.L, self._tau(t))

    def contact_force(self, t):
        return self.a * self.waves.reaction(self._tau(t))

    def contact_intervals(self) -> list[tuple[float, float]]:
        s = self.L / self.c
        return [(a * s, b * s) for a, b in self.waves.contact_intervals]

    def energy(self, t, points: int = 4001) -> dict:
        """Kinetic ½∫ρu_t², strain ½∫a u_x², obstacle ½k(U⁻)² at times t (trapezoid in x
        on ``points`` abscissae; the fields are piecewise smooth)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        x = np.linspace(0.0, self.L, points)
        X, Tm = np.meshgrid(x, t)
        trapezoid = getattr(np, "trapezoid", None) or np.trapz   # numpy < 2 has trapz only
        kin = 0.5 * self.rho * trapezoid(self.velocity(X, Tm) ** 2, x, axis=1)
        strain = 0.5 * self.a * trapezoid(self.strain(X, Tm) ** 2, x, axis=1)
        U = self.u(0.0, t)
        obst = 0.5 * self.k * np.maximum(-U, 0.0) ** 2 if self.obstacle == "elastic" \
            else np.zeros(t.shape)
        return {"kinetic": kin, "strain": strain, "obstacle": obst,
                "total": kin + strain + obst}


# the paper's Example 1 (a = ρ = L = 1, v0 = −1, f = 0): closed forms --------------------

def bar_rigid_u0(t):
    """u(0, t) = max(t − 2, 0): in contact on (0, 2), then it leaves at speed 1."""
    return np.maximum(np.asarray(t, dtype=float) - 2.0, 0.0)


def bar_rigid_uL(t):
    """u(1, t) = −t for t ≤ 1, t − 2 after (the reflected wave reaches the free end)."""
    t = np.asarray(t, dtype=float)
    return np.where(t <= 1.0, -t, t - 2.0)


def bar_rigid_force(t):
    """R(t) = 1 on (0, 2) (= ρc|v0|), 0 after."""
    t = np.asarray(t, dtype=float)
    return np.where((t > 0) & (t < 2), 1.0, 0.0)


def bar_elastic_paper(x, t, k):
    """The paper's regions R_I, R_II, R_III (Example 1, spring k), where they hold:
    R_I: x > t; R_II: x < t, x + t < 2; R_III: x + t > 2, t − x < 2.  NaN elsewhere."""
    x, t = np.broadcast_arrays(np.asarray(x, float), np.asarray(t, float))
    with np.errstate(over="ignore"):
        r1 = -t
        r2 = -x + (np.exp(k * (x - t)) - 1.0) / k
        r3 = t + (np.exp(k * (2 - x - t)) + np.exp(k * (x - t))) / k - 2 * (1 + 1 / k)
    out = np.full(x.shape, np.nan)
    out = np.where(x > t, r1, out)
    out = np.where((x <= t) & (x + t < 2), r2, out)
    out = np.where((x + t >= 2) & (t - x < 2) & (x <= t), r3, out)
    return out


# ---------------------------------------------------------------------------------------
# The periodic rod: u_tt = c² u_xx on (0, L), clamped at x = L, rigid obstacle at x = 0
# (u(0, t) ≥ 0, R = −a u_x(0, t) ≥ 0, R·u(0, t) = 0), released at rest from u0 = d(1 − x/L).
#
# Non-dimensional (ξ = x/L, τ = ct/L, w = u/d): w0 = 1 − ξ, w_τ(ξ, 0) = 0.  d'Alembert
# w = F(ξ − τ) + G(ξ + τ); at rest F = G = (1 − s)/2 on [0, 1].  Three rules carry F, G:
#
#   clamp at ξ = 1:        G(1 + τ) = −F(1 − τ)                 (w(1, τ) = 0)
#   free at ξ = 0:         F(−τ) = G(τ) + const                   (w_ξ(0, τ) = 0)
#   contact at ξ = 0:      F(−τ) = −G(τ)                          (w(0, τ) = 0)
#   contact while R = −w_ξ(0) = −2G'(τ) ≥ 0; free while U = w(0) = F(−τ) + G(τ) ≥ 0.
#
# τ ∈ [0, 1]: free, U = 2G = 1 − τ: the released end runs to the obstacle at speed 1
#   (u_t = −cd/L) and arrives at τ = 1.
# τ ∈ [1, 2]: G(τ) = −F(2 − τ) = (1 − τ)/2 continues to fall: a free end would go below 0,
#   so contact, F(−τ) = (τ − 1)/2, R = −2G' = 1 > 0 (R = a·d/L dimensional).
# τ ∈ [2, 3]: G(τ) = −F(2 − τ) = (τ − 3)/2 now rises, R = −1 < 0: release at τ = 2, free,
#   F(−τ) = G(τ) + 1 = (τ − 1)/2, U = τ − 2 ≥ 0.
# At τ = 3: w(ξ, 3) = F(ξ − 3) + G(ξ + 3) = (2 − ξ)/2 − ξ/2 = 1 − ξ and w_τ = 0: the data
# again.  So w is 3-periodic in τ (period 3L/c), F and G on one period are the tables
#
#   F: s = −3, −1, 0, 1 → 1, 0, ½, 0          G: s = 0, 2, 3, 4 → ½, −½, 0, −½
#
# (piecewise linear, slopes ±½).  Hence w_τ² + w_ξ² = 2(F'² + G'²) = 1 everywhere: the
# energy ½∫(ρu_t² + a u_x²) = ½ a d²/L at all times (1/8 for a = L = 1, d = ½).
# ---------------------------------------------------------------------------------------

class RodExact:
    """The exact periodic rod (comment above), per unit cross-section, in physical units:
    modulus ``a``, density ``rho``, length ``L``, initial gap ``d`` = u0(0) ≥ 0; ``T`` the
    horizon of :meth:`contact_intervals`.  On a characteristic the derivatives are the
    values just after t (F' from the left, G' from the right): at t = 0 the end at the
    obstacle is already released, σ(0) = 0 and u_t(0) = −cd/L."""

    _F = (np.array([-3.0, -1.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.5, 0.0]))
    _G = (np.array([0.0, 2.0, 3.0, 4.0]), np.array([0.5, -0.5, 0.0, -0.5]))

    def __init__(self, a=1.0, rho=1.0, L=1.0, d=0.5, T=3.0):
        self.a, self.rho, self.L, self.d = float(a), float(rho), float(L), float(d)
        if not self.d >= 0:
            raise ValueError("d = u0(0) < 0 violates the rigid obstacle")
        self.c = np.sqrt(self.a / self.rho)
        self.T = float(T)
        self.period = 3.0 * self.L / self.c

    def _args(self, x, t):
        xi = np.asarray(x, dtype=float) / self.L
        tau = np.mod(self.c * np.asarray(t, dtype=float) / self.L, 3.0)
        xi, tau = np.broadcast_arrays(xi, tau)
        return xi - tau, xi + tau

    @staticmethod
    def _slope(table, s, side):
        """The slope of the piecewise-linear table at s, from the ``side`` at a break."""
        nodes, values = table
        i = np.clip(np.searchsorted(nodes, s, side=side) - 1, 0, nodes.size - 2)
        return (np.diff(values) / np.diff(nodes))[i]

    def _slopes(self, x, t):
        """F'(ξ − τ), G'(ξ + τ) just after t (ξ − τ decreases, ξ + τ increases in time)."""
        s1, s2 = self._args(x, t)
        return self._slope(self._F, s1, "left"), self._slope(self._G, s2, "right")

    def u(self, x, t):
        s1, s2 = self._args(x, t)
        return self.d * (np.interp(s1, *self._F) + np.interp(s2, *self._G))

    def velocity(self, x, t):
        dF, dG = self._slopes(x, t)
        return self.d * self.c / self.L * (dG - dF)

    def strain(self, x, t):
        dF, dG = self._slopes(x, t)
        return self.d / self.L * (dF + dG)

    def contact_force(self, t):
        """R = a·d/L while in contact (ct/L ∈ [1, 2) mod 3, the value just after t), else 0."""
        tau = np.mod(self.c * np.asarray(t, dtype=float) / self.L, 3.0)
        return np.where((tau >= 1.0) & (tau < 2.0), self.a * self.d / self.L, 0.0)

    def contact_intervals(self) -> list[tuple[float, float]]:
        """(L/c, 2L/c) + m·3L/c for every start ≤ T (none when d = 0: nothing moves)."""
        s = self.L / self.c
        count = int(np.floor((self.T / s - 1.0) / 3.0 + 1e-12)) + 1 if self.d > 0 else 0
        return [((1 + 3 * m) * s, (2 + 3 * m) * s) for m in range(max(count, 0))]

    def energy(self, t, points: int = 4001) -> dict:
        """Kinetic ½∫ρu_t², strain ½∫a u_x² (midpoint rule on ``points`` cells; the
        densities are piecewise constant) and their total, ½ a d²/L at every t."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        x = (np.arange(points) + 0.5) * self.L / points
        X, Tm = np.meshgrid(x, t)
        kin = 0.5 * self.rho * (self.velocity(X, Tm) ** 2).sum(axis=1) * self.L / points
        strain = 0.5 * self.a * (self.strain(X, Tm) ** 2).sum(axis=1) * self.L / points
        return {"kinetic": kin, "strain": strain, "obstacle": np.zeros(t.shape),
                "total": kin + strain}


class Oriented:
    """An exact solution (per unit cross-section, obstacle at x = 0) seen in the bar's own
    frame: mirrored (x → L − x, u → −u) when the obstacle is at x = L, and forces and
    energies times the cross-section A when the bar has one."""

    def __init__(self, exact, L: float, mirrored: bool, section: float = 1.0):
        self.exact, self.L, self.mirrored, self.section = exact, float(L), mirrored, section

    def _x(self, x):
        x = np.asarray(x, dtype=float)
        return self.L - x if self.mirrored else x

    def u(self, x, t):
        u = self.exact.u(self._x(x), t)
        return -u if self.mirrored else u

    def velocity(self, x, t):
        v = self.exact.velocity(self._x(x), t)
        return -v if self.mirrored else v

    def strain(self, x, t):     # d/dx[−w(L − x)] = w'(L − x): the strain keeps its sign
        return self.exact.strain(self._x(x), t)

    def contact_force(self, t):
        return self.section * self.exact.contact_force(t)

    def contact_intervals(self):
        return self.exact.contact_intervals()

    def energy(self, t, points: int = 4001) -> dict:
        return {k: self.section * v for k, v in self.exact.energy(t, points).items()}


def exact_of(bar, T: float):
    """The exact solution of a :class:`skfem_beam.bar.Bar` up to T, or None.

    Known (elastic bar, b = 0): a free far end with uniform u0, v0 and f
    (:class:`BarExact`), and the periodic rod (:class:`RodExact`: far end clamped, rigid
    obstacle, f = 0, v0 = 0, u0 a table linear from the gap d at the obstacle to 0 at
    the clamp).  Either end and a cross-section A are handled by :class:`Oriented`.
    """
    if bar.b != 0:
        return None
    left = bar.obstacle_at == "left"
    sign, A = (1.0 if left else -1.0), bar.section
    if bar.far_end == "free":
        if not (isinstance(bar.u0, float) and isinstance(bar.v0, float)):
            return None
        ex = BarExact(BarData(bar.a, bar.rho, bar.L, sign * bar.v0, bar.obstacle, bar.k / A,
                              sign * bar.f, sign * bar.u0), T)
    else:
        d = _rod_gap(bar, sign)
        if d is None or bar.obstacle != "rigid" or bar.f != 0 or bar.v0 != 0.0:
            return None
        ex = RodExact(bar.a, bar.rho, bar.L, d, T)
    return ex if left and bar.A is None else Oriented(ex, bar.L, not left, A)


def _rod_gap(bar, sign: float):
    """d if u0, seen from the obstacle's end (ξ = distance to it), is d(1 − ξ/L) exactly
    (a number 0, or a table that is that line on [0, L]); else None."""
    u0, L = bar.u0, bar.L
    if isinstance(u0, float):
        return 0.0 if u0 == 0.0 else None
    if not hasattr(u0, "x"):          # a function: linearity cannot be checked exactly
        return None
    inside = [x for x in u0.x if 0.0 < x < L]
    xi = np.array([0.0, *inside, L])          # abscissae measured in the bar's frame
    dist = xi if sign > 0 else L - xi         # distance to the obstacle
    w = sign * u0(xi)                         # the rod's displacement in its own frame
    d = float(w[dist.argmin()])
    if np.abs(w - d * (1.0 - dist / L)).max() > 1e-12 * max(abs(d), 1e-300):
        return None
    return d


def whirl_force(plane, b, row, r: float, omega: float, dt: float, beta: float) -> float:
    """The contact force |λ| of the β-scheme's steady whirl in a round hole.

    A beam bending alike in two planes (``plane`` = (M, K, B): mass, stiffness and
    damping of one plane; B may be None), loaded by the rotating force b·(cos ωt, sin ωt)
    (b the load vector of one plane, in the system's units) and held at one node (``row``, the node's value
    row) in the round hole of radius r centred on the axis, whirls on the wall: in
    complex form v + iw = A·e^{iωtₙ} at every step, and the nodal contact force is
    λⁿ = −(Λ/r)·(v, w)ⁿ at the node, of constant magnitude Λ.  Substituted in the
    scheme's step (kernels.free_step, with the load windows of BetaScheme.load_averages),
    with z = e^{iωΔt} and s = sin²(ωΔt/2):

        Z A = g·b − (Λ/r)·z·A_i·e,   Z = −(4s/Δt²)M + (i sin(ωΔt)/Δt)B + (1 − 4βs)K,
        g = (1 − 4βs)(z − 1)/(iωΔt)      (the forward window's average of e^{iωt}),

    (λ acts at the new state n+1: the factor z).  So A_i = g(Z⁻¹b)_i / (1 + (Λ/r)z(Z⁻¹)_ii),
    and |A_i| = r is the quadratic |r + Λ z (Z⁻¹)_ii|² = |g (Z⁻¹b)_i|² in Λ; its positive
    root is returned (NaN when the force does not reach the wall: no whirl on it)."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    M, K, B = plane
    s = np.sin(0.5 * omega * dt) ** 2
    Z = -(4 * s / dt**2) * sp.csc_matrix(M) + (1 - 4 * beta * s) * sp.csc_matrix(K)
    if B is not None:
        Z = Z + 1j * np.sin(omega * dt) / dt * sp.csc_matrix(B)
    Z = sp.csc_matrix(Z, dtype=complex)
    z = np.exp(1j * omega * dt)
    g = (1 - 4 * beta * s) * (z - 1) / (1j * omega * dt)
    e = np.asarray(row, dtype=float).ravel()
    Hb = spla.spsolve(Z, np.asarray(b, dtype=complex))
    He = spla.spsolve(Z, e.astype(complex))
    h, a = z * (e @ He), abs(g * (e @ Hb))
    # Λ²|h|² + 2rΛ Re h + r² − a² = 0
    qa, qb, qc = abs(h) ** 2, 2 * r * h.real, r * r - a * a
    disc = qb * qb - 4 * qa * qc
    if qc >= 0 or disc < 0:
        return float("nan")
    return float((-qb + np.sqrt(disc)) / (2 * qa))
