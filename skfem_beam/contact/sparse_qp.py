"""Contact engines in x-space for many contacts (the plate): no W = A⁻¹Cᵀ, no D = C W.

The step QP  min ½uᵀAu − Fᵀu,  lo ≤ Cu ≤ hi  (F = A x_free) is solved for u itself.  Where
each row of C selects one unknown (the plate: w at a vertex), an active set S pins those
unknowns at their bounds b_S, and the step on S is one solve with

    A_S = A with the rows and columns of S replaced by the identity,
    A_S u = F − A[:, S] b_S  off S,   u_S = b_S,

whose Cholesky factor, in any fixed ordering, lies in the pattern of A's (A's band, or
CHOLMOD's fill of A); then μ = C(A u − F) (Δt² × the nodal forces, the scheme's
multipliers: A u = A x_free + Cᵀμ).  This is exact to round-off on S; the KKT check and
the set's update are those of the primal-dual active set method (Hintermüller,
Ito & Kunisch 2003): with c = diag(A) on S's rows (so that c·gap is a force)

    lower active  if  μ_j + c_j (lo_j − u_j) > 0,   upper active  if  μ_j + c_j (hi_j − u_j) < 0,

iterated until S repeats.

How a set is solved (`SelectorQP`; docs/plate.md, "Which engine at which size"): the
Cholesky factor G of A_{S0} of an earlier set S0 is kept, and G is either

- CHOLMOD's (through cvxopt.cholmod, `SparseCholesky`) from CHOLMOD_MIN_N unknowns: the
  symbolic factorisation (AMD ordering, supernodal) once per run on A's lower triangle,
  a set's pinned rows and columns kept as explicit zeros so the pattern never changes,
  one numeric factorisation per set (40 × 40: 14 ms against dpbtrf's 61; 80 × 80: 122
  against 1,854), cholmod.solve for the solves; or
- the band's below (`BandCholesky`: LAPACK dpbtrf/dpbtrs on one thread), where it is as
  fast and has no symbolic step;

and

1. inexact sweeps first: GUESS_ITERATIONS iterations of CG on A_S, preconditioned by the
   kept factor (A_{S0}⁻¹A_S is the identity plus a rank ≤ 2|S Δ S0|), from the last
   iterate, give μ and the next set; up to GUESS_SWEEPS of them, until the set repeats
   (only where a factorisation costs many solves: a banded factor of at most
   GUESS_MAX_BYTES, past which dpbtrs streams the factor from memory, a factorisation
   costs 13 solves instead of 45, and they do not pay: measured at 80 × 80, 2.1 s a step
   with them against 1.2 s without; never with CHOLMOD, whose numeric factorisation
   costs 10–20 of its solves);
2. then exact sweeps from that set: with P = S ∖ S0 (newly pinned), Q = S0 ∖ S (freed),
   the block elimination of A_S over the kept factor needs G⁻¹z_j for j ∈ P ∪ Q
   (z_j = e_j or A's column j), one solve each, cached until S0 changes, and a
   dense |P ∪ Q| Schur complement; when the cache would pass MAX_COLUMNS columns the set
   becomes the new S0 (one factorisation).  u_S = b_S is then set exactly.

In the bench's scene (a plate bouncing on a flat obstacle) the set changes by 50–200 of
1,521 vertices a step at 40 × 40: the inexact sweeps bring the factorisations from 3.7 a
step (one per exact sweep) to about 1, the rest is solves.

Engines (registered laws, ``x_space = True``: the scheme builds neither W nor D for them
and takes u^{n+1} from the engine, contact/registry.py):

- ``pdas-sparse``: the primal-dual active set, warm-started from the last step's set;
- ``osqp-sparse``: OSQP on the Jacobi-scaled problem finds the set (factorised once per
  run, q and the bounds updated each step, warm-started, to OSQP_EPS), the active set
  method above finishes it exactly (it also repairs the rows a loose OSQP misreads);
- ``clarabel-sparse``: Clarabel's interior point finds the set (a cold solve each step:
  Clarabel has no warm start), the same exact finish.

Why OSQP needs the Jacobi scaling here: the plate's unknowns mix w, slopes and the twist
u_xy, whose diagonals of A differ by 10⁷ (20 × 20: 1.1e-7 … 7.4, mean 1.7).  Scaled by the
mean diagonal (the beam's OSQP law), the twist directions have curvature ~1e-7 < OSQP's
eps_dinf = 1e-4, and OSQP reports the step QP "dual infeasible" (unbounded) at the first
contacts.  With x = s·J x̂, J = diag(A)^{-1/2}, P̂ = J A J/… has a unit diagonal.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from ..errors import InputError, SolverError
from .base import ContactLaw
from .osqp_solver import warm_again, warm_state

MAX_SWEEPS = 100   # active-set updates of one step before it gives up (SolverError)
# the engines' tolerances in scaled units: loose enough to find the set fast, the exact
# finish repairing the rows it misreads.  OSQP at 1e-3 (one run each of plate.bench's
# scene): 21 → 11.7 ms a step at 20 × 20, 288 → 118 ms at 40 × 40, 6.9 → 1.1 s at
# 80 × 80 against 1e-6, with 1.0 → 1.03 and 1.0 → 1.9 exact sweeps a contact step;
# Clarabel gains less and misreads more at 1e-3 (40 × 40: 669 → 549 ms, 2.0 → 6.7 sweeps)
OSQP_EPS = 1e-3
CLARABEL_EPS = 1e-6
GUESS_SWEEPS = 10  # inexact sweeps (PCG with the kept factor) before the exact ones
GUESS_ITERATIONS = 4   # PCG iterations of an inexact sweep
GUESS_MAX_BYTES = 32e6   # inexact sweeps only where the banded factor has at most these
CHOLMOD_MIN_N = 4000     # unknowns from which A_S is factored by CHOLMOD, not the band
# the one tally of every SelectorQP's factorisations, banded solves (columns), exact and
# inexact sweeps, finished steps and cached columns G⁻¹z_j so far in this process
# (plate.bench resets and reads it; a test takes one call's share by difference)
COUNTS = {"factors": 0, "solves": 0, "sweeps": 0, "guesses": 0, "steps": 0, "columns": 0}
MAX_COLUMNS = 16   # cached columns G⁻¹z_j (one banded solve each) before A_S is refactored


def selected_unknowns(C) -> np.ndarray:
    """The unknown each row of C selects (one entry 1.0 per row, distinct columns); an
    InputError for any other C (these engines need a selector)."""
    C = sp.csr_matrix(C)
    cols = C.indices
    if not (np.all(np.diff(C.indptr) == 1) and np.all(C.data == 1.0)
            and np.unique(cols).size == cols.size):
        raise InputError("the x-space contact engines need constraints that each select one "
                         "unknown (the plate's w at a vertex); use active-set, osqp or daqp")
    return cols.astype(np.int64)


class BandCholesky:
    """G = A_S's banded Cholesky: LAPACK dpbtrf for a set, dpbtrs for each solve (on the
    caller's one thread, `_one_thread`; OpenBLAS's threads took 0.2–1.2 s at 40 × 40 on
    two busy cores against 45 ms on one).  A_S = A with the pinned rows and columns
    replaced by the identity has A's band."""
    name = "band"

    def __init__(self, A):
        coo = sp.triu(A).tocoo()                 # A's upper band in LAPACK's layout
        self.n = A.shape[0]
        self.kd = int((coo.col - coo.row).max()) if coo.nnz else 0
        self.lap = np.zeros((self.kd + 1, self.n))   # lap[kd − o, j] = A[j − o, j]
        self.lap[self.kd + coo.row - coo.col, coo.col] = coo.data
        self.L = None

    def pinned_band(self, pinned: np.ndarray) -> np.ndarray:
        """The upper band of A_S in LAPACK's layout (kd + 1, n)."""
        kd, n = self.kd, self.n
        lap = self.lap.copy()
        lap[:, pinned] = 0.0                          # column j pinned
        o = np.arange(1, kd + 1)
        rows = pinned[:, None] + o[None, :]           # row i pinned: A[i, i + o]
        offs = np.broadcast_to(kd - o, rows.shape)
        keep = rows < n
        lap[offs[keep], rows[keep]] = 0.0
        lap[kd, pinned] = 1.0
        return lap

    def factor(self, pinned: np.ndarray) -> None:
        self.L, info = scipy.linalg.lapack.dpbtrf(self.pinned_band(pinned), lower=0,
                                                  overwrite_ab=1)
        if info != 0:
            raise SolverError(f"the banded Cholesky of A_S failed (dpbtrf info {info})")
        self.L = np.asfortranarray(self.L)

    def solve(self, b: np.ndarray) -> np.ndarray:
        x, info = scipy.linalg.lapack.dpbtrs(self.L, b, lower=0)
        if info != 0:
            raise SolverError(f"dpbtrs info {info}")
        return x


class SparseCholesky:
    """G = A_S's sparse Cholesky: CHOLMOD (supernodal, its AMD ordering) through
    cvxopt.cholmod.  The symbolic factorisation is made once, on A's lower triangle; a
    set's pinned rows and columns keep their entries as explicit zeros (1 on the
    diagonal), so the pattern never changes and each set is one numeric factorisation;
    cholmod.solve for the solves."""
    name = "cholmod"

    def __init__(self, A):
        import cvxopt
        from cvxopt import cholmod
        self.cvxopt, self.cholmod = cvxopt, cholmod
        low = sp.tril(A, format="csc")
        low.sort_indices()
        self.n = A.shape[0]
        self.data = low.data.copy()
        self.rows = low.indices.astype(np.int64)
        self.cols = np.repeat(np.arange(self.n, dtype=np.int64), np.diff(low.indptr))
        self.diag = self.rows == self.cols
        m = cvxopt.matrix
        self.M = cvxopt.spmatrix(m(self.data), m(self.rows), m(self.cols), (self.n, self.n))
        if not np.array_equal(np.asarray(self.M.CCS[1]).ravel(), low.indices):
            raise SolverError("cvxopt reordered A's lower triangle")   # (values by position)
        self.F = cholmod.symbolic(self.M)

    def factor(self, pinned: np.ndarray) -> None:
        mask = np.zeros(self.n, dtype=bool)
        mask[pinned] = True
        values = self.data.copy()
        row_pinned = mask[self.rows]
        values[row_pinned | mask[self.cols]] = 0.0
        values[row_pinned & self.diag] = 1.0
        self.M.V = self.cvxopt.matrix(values)
        try:
            self.cholmod.numeric(self.M, self.F)
        except ArithmeticError as e:
            raise SolverError(f"the sparse Cholesky of A_S failed (CHOLMOD: {e})") from e

    def solve(self, b: np.ndarray) -> np.ndarray:
        x = self.cvxopt.matrix(b)
        self.cholmod.solve(self.F, x)
        x = np.array(x)
        return x.ravel() if b.ndim == 1 else x


def cholesky_kind(n: int, kind: str = "auto") -> str:
    """"band" or "cholmod"; "auto": CHOLMOD from CHOLMOD_MIN_N unknowns, the band below
    (docs/plate.md, "Which engine at which size")."""
    if kind == "auto":
        return "cholmod" if n >= CHOLMOD_MIN_N else "band"
    return kind


def cholesky(A, kind: str = "auto"):
    """A_S's Cholesky for SelectorQP (`cholesky_kind`)."""
    kind = cholesky_kind(A.shape[0], kind)
    if kind == "band":
        return BandCholesky(A)
    if kind == "cholmod":
        return SparseCholesky(A)
    raise InputError(f"unknown Cholesky '{kind}' (band, cholmod or auto)")


_CONTROLLER = None


def _one_thread():
    """A context with BLAS on one thread (threadpoolctl; the controller made once)."""
    global _CONTROLLER
    from threadpoolctl import ThreadpoolController
    if _CONTROLLER is None:
        _CONTROLLER = ThreadpoolController()
    return _CONTROLLER.limit(limits=1, user_api="blas")


class SelectorQP:
    """The step QP with C a selector: ``finish(x, lo, hi, state)`` overwrites x (x_free on
    entry) with the exact solution from the active set ``state`` (int8: −1 lower, +1
    upper, 0 free; updated in place to the final set) and returns (μ, sweeps).

    ``update=True`` (the default): the sets are solved with a kept factor of A_{S0} of an
    earlier set S0 and a Schur complement on the difference S Δ S0 (`solve_on_set`);
    ``update=False``: a fresh Cholesky of A_S for every new set (the reference the tests
    compare with).  ``max_columns``: the cached columns G⁻¹z_j after which the next set
    becomes the new S0 (refactored).  ``chol``: G's kind, "band", "cholmod" or "auto"
    (`cholesky_kind`: CHOLMOD from CHOLMOD_MIN_N unknowns)."""

    def __init__(self, A, C, update: bool = True, max_columns: int = MAX_COLUMNS,
                 guess_sweeps: int = GUESS_SWEEPS, chol: str = "auto"):
        self.A = sp.csr_matrix(A, dtype=float)
        self.A.sort_indices()
        self.dof = selected_unknowns(C)
        self.c = self.A.diagonal()[self.dof]
        self.n = self.A.shape[0]
        self.update, self.max_columns = update, int(max_columns)
        self.G = cholesky(self.A, chol)         # the factor of A_S for a set
        self.guess_sweeps = int(guess_sweeps) if update and self.guesses_pay() else 0
        self.key = None                         # the set G factors (update=False)
        # the kept base S0 (update=True)
        self.side0 = None                       # S0 as a state (int8 per row)
        self.Y = None                           # (n, max_columns): G⁻¹ z_j, Fortran order
        self.col = {}                           # row j → its column of Y
        self.batches = []                       # the rows of each add_columns since S0
        self.y0 = None                          # G⁻¹(F − A u_{S0})|F0 of this step

    def guesses_pay(self) -> bool:
        """Inexact sweeps pay where a factorisation costs many solves: the band while its
        factor stays in cache (dpbtrf = 45 dpbtrs at 40 × 40, 8.6 MB; 13 at 80 × 80,
        68 MB); not with CHOLMOD (a numeric factorisation costs 10–20 of its solves;
        measured at 40 × 40: 259 ms a step without them against 334 with; docs/plate.md)."""
        if isinstance(self.G, BandCholesky):
            return 8.0 * self.n * (self.G.kd + 1) <= GUESS_MAX_BYTES
        return False

    def factor(self, pinned: np.ndarray) -> None:
        """G ← the Cholesky factor of A_S for the pinned unknowns (kept for the last set,
        update=False)."""
        key = pinned.tobytes()
        if key != self.key:
            self.G.factor(pinned)
            self.key = key
            COUNTS["factors"] += 1

    # -- the kept factor and the Schur complement on S Δ S0 (update=True) ------------
    def rebase(self, state: np.ndarray) -> None:
        """S0 ← the set ``state``: factor A_{S0}, empty the cache of columns."""
        self.side0 = state.copy()
        self.key = None
        self.factor(self.dof[state != 0])
        if self.Y is None:
            self.Y = np.zeros((self.n, self.max_columns), order="F")
        self.col = {}
        self.batches = []
        self.y0 = None

    def gsolve(self, b: np.ndarray) -> np.ndarray:
        """G⁻¹b with G = A_S's factor (b: a vector or Fortran-ordered columns)."""
        COUNTS["solves"] += 1 if b.ndim == 1 else b.shape[1]
        return self.G.solve(b)

    def base_values(self, lo, hi) -> np.ndarray:
        """This step's values of S0's rows on their sides (0 off S0 and where infinite)."""
        b0 = np.where(self.side0 < 0, lo, np.where(self.side0 > 0, hi, 0.0))
        return np.where(np.isfinite(b0), b0, 0.0)

    def add_columns(self, rows: np.ndarray) -> None:
        """Cache G⁻¹z_j for the rows j: z_j = e_j off S0 (j newly pinned), A's column j
        with S0's rows zeroed on S0 (j newly freed or moved)."""
        if not rows.size:
            return
        R = np.zeros((self.n, rows.size), order="F")
        in0 = self.side0 != 0
        base = np.zeros(self.n, dtype=bool)
        base[self.dof[in0]] = True
        A = self.A
        for i, j in enumerate(rows):
            d = self.dof[j]
            if in0[j]:
                sl = slice(A.indptr[d], A.indptr[d + 1])
                idx, val = A.indices[sl], A.data[sl]       # column d = row d (symmetric)
                keep = ~base[idx]
                R[idx[keep], i] = val[keep]
            else:
                R[d, i] = 1.0
        first = len(self.col)
        self.batches.append(np.array(rows, dtype=np.int64))
        self.Y[:, first:first + rows.size] = self.gsolve(R)
        COUNTS["columns"] += rows.size
        for i, j in enumerate(rows):
            self.col[int(j)] = first + i

    def checkpoint(self) -> dict:
        """What the next steps' round-off depends on: S0 and the batches of columns
        cached since (a resume that refactored on its own first set summed otherwise)."""
        if self.side0 is None:
            return {}
        sizes = np.array([b.size for b in self.batches], dtype=np.int64)
        return {"side0": self.side0.copy(), "batch_sizes": sizes,
                "batch_rows": np.concatenate(self.batches) if self.batches
                else np.zeros(0, np.int64)}

    def restore(self, saved: dict) -> None:
        """S0 factored again and its columns solved again, batch by batch: the same bits."""
        if "side0" not in saved:
            return
        with _one_thread():          # as finish: OpenBLAS's threads sum in another order
            self.rebase(np.asarray(saved["side0"], dtype=np.int8))
            rows = np.asarray(saved["batch_rows"], dtype=np.int64)
            for part in np.split(rows, np.cumsum(saved["batch_sizes"])[:-1]):
                self.add_columns(part)

    def solve_updated(self, F, lo, hi, state, u) -> None:
        """u ← the minimiser with ``state`` pinned, from G = A_{S0}'s factor:

        with ub = the bounds on S and v = u − ub (v_S = 0), Q = S0 ∖ S (freed),
        P = S ∖ S0 (newly pinned), Z = [A_{F0,Q}, E_P] and y = G⁻¹(F − A ub)|F0,
        v_F0 = y − G⁻¹Z z,  (diag(A_QQ, 0) − Zᵀ G⁻¹Z) z = [(F − A ub)_Q; 0] − Zᵀy,
        v_Q = z_Q: the block elimination of A_F v_F = (F − A ub)_F over F = F0 ∖ P ∪ Q.
        y itself is y0 = G⁻¹(F − A u0)|F0 (u0: S0's bounds, one solve a step) plus cached
        columns (G⁻¹A_{F0,j} = e_j for j ∈ P)."""
        on = state != 0
        in0 = self.side0 != 0
        b_all = np.where(state < 0, lo, hi)
        b0 = self.base_values(lo, hi)
        Q = np.flatnonzero(in0 & ~on)
        P = np.flatnonzero(on & ~in0)
        moved = np.flatnonzero(in0 & on & (b_all != b0))
        need = np.concatenate([Q, P, moved])
        new = np.array([j for j in need if int(j) not in self.col], dtype=np.int64)
        if len(self.col) + new.size > self.max_columns:
            self.rebase(state)
            return self.solve_updated(F, lo, hi, state, u)
        self.add_columns(new)
        if self.y0 is None:                    # this step's base solve
            u0 = np.zeros(self.n)
            u0[self.dof[in0]] = b0[in0]
            r = F - self.A @ u0
            r[self.dof[in0]] = 0.0
            self.y0 = self.gsolve(r)
        k = len(self.col)
        Y = self.Y[:, :k]
        coef = np.zeros(k)                     # y = y0 + Y coef − Σ_P e_j b_j
        for j in Q:
            coef[self.col[int(j)]] += b0[j]
        for j in moved:
            coef[self.col[int(j)]] += b0[j] - b_all[j]
        y = self.y0 + Y @ coef
        dP = self.dof[P]
        y[dP] -= b_all[P]
        ub = np.zeros(self.n)
        ub[self.dof[on]] = b_all[on]
        K = np.concatenate([Q, P])
        if K.size:
            dQ = self.dof[Q]
            AQ = self.A[dQ]
            Zt = sp.vstack([AQ, sp.csr_matrix((np.ones(P.size), (np.arange(P.size), dP)),
                                              shape=(P.size, self.n))], format="csr")
            cols = np.array([self.col[int(j)] for j in K], dtype=np.int64)
            YK = Y[:, cols]
            S = -(Zt @ YK)
            S[:Q.size, :Q.size] += AQ[:, dQ].toarray()
            h = -(Zt @ y)
            h[:Q.size] += F[dQ] - AQ @ ub
            z = np.linalg.solve(S, h)
            y -= YK @ z
            y[dQ] = z[:Q.size]
        u[:] = ub + y
        u[self.dof[on]] = b_all[on]            # exactly on the bounds

    def solve_fresh(self, F, lo, hi, state, u) -> None:
        """u ← the minimiser with ``state`` pinned, from a fresh factor of A_S."""
        on = state != 0
        pinned = self.dof[on]
        b = np.where(state[on] < 0, lo[on], hi[on])
        ub = np.zeros(u.size)
        ub[pinned] = b
        rhs = F - self.A @ ub
        rhs[pinned] = b
        self.factor(pinned)
        u[:] = self.gsolve(rhs)
        u[pinned] = b                           # exactly on the bounds

    def solve_on_set(self, F, lo, hi, state, u) -> np.ndarray:
        """u ← the minimiser with the set ``state`` pinned; returns μ = C(Au − F)."""
        if self.update:
            self.solve_updated(F, lo, hi, state, u)
        else:
            self.solve_fresh(F, lo, hi, state, u)
        return self.multipliers(F, state, u)

    def multipliers(self, F, state, u) -> np.ndarray:
        """μ = C(Au − F) on the set ``state``'s rows, 0 off it."""
        mu = (self.A @ u - F)[self.dof]
        mu[state == 0] = 0.0
        return mu

    def finish(self, x, lo, hi, state):
        with _one_thread():
            return self._finish(x, lo, hi, state)

    def guess(self, F, lo, hi, state, u) -> None:
        """u ← an approximation of the minimiser on ``state`` (inexact sweeps): PCG on
        A_F v_F = (F − A ub)_F from u, preconditioned by the kept factor of A_{S0},
        GUESS_ITERATIONS iterations."""
        on = state != 0
        pinned = self.dof[on]
        b = np.where(state[on] < 0, lo[on], hi[on])
        free = np.ones(self.n)
        free[pinned] = 0.0
        u[pinned] = b
        r = free * (F - self.A @ u)
        z = free * self.gsolve(r)
        p = z.copy()
        rz = r @ z
        for _ in range(GUESS_ITERATIONS):
            if rz <= 0.0:
                break
            q = free * (self.A @ p)
            alpha = rz / (p @ q)
            u += alpha * p
            r -= alpha * q
            z = free * self.gsolve(r)
            rz, rz_old = r @ z, rz
            p = z + (rz / rz_old) * p

    def update_set(self, mu, y, lo, hi, state) -> np.ndarray:
        """The next set (primal-dual rule, module docstring) from μ and y = u[dof], of
        ``state``'s type."""
        new = np.zeros_like(state)
        new[mu + self.c * (lo - y) > 0] = -1
        new[mu + self.c * (hi - y) < 0] = 1
        return new

    def _finish(self, x, lo, hi, state):
        F = self.A @ x
        COUNTS["steps"] += 1
        if self.update:
            if self.side0 is None:
                self.rebase(state)
            self.y0 = None                      # a new F: a new base solve
            if self.guess_sweeps:               # inexact sweeps find a set first
                u = x.copy()
                seen = {state.tobytes()}
                for _ in range(self.guess_sweeps):
                    self.guess(F, lo, hi, state, u)
                    mu = self.multipliers(F, state, u)
                    new = self.update_set(mu, u[self.dof], lo, hi, state)
                    if new.tobytes() in seen:
                        break
                    seen.add(new.tobytes())
                    state[:] = new
                    COUNTS["guesses"] += 1
        seen = {state.tobytes()}
        for sweep in range(1, MAX_SWEEPS + 1):
            mu = self.solve_on_set(F, lo, hi, state, x)
            new = self.update_set(mu, x[self.dof], lo, hi, state)
            COUNTS["sweeps"] += 1
            if np.array_equal(new, state):
                return mu, sweep
            if new.tobytes() in seen:
                raise SolverError(f"the active set cycles after {sweep} sweeps")
            seen.add(new.tobytes())
            state[:] = new
        raise SolverError(f"no active set after {MAX_SWEEPS} sweeps")


class XSpaceSolver:
    """The Python-solver protocol of contact.base for an x-space engine: ``solve(x, y_free,
    lo, hi)`` overwrites x (x_free) with u^{n+1} and returns (μ, iterations: the engine's
    plus the exact finish's sweeps).  ``find(x, lo, hi)`` (a subclass's): the engine's
    guess of the set in ``self.state``; none here: the last step's set (pdas-sparse)."""

    def __init__(self, A, C, lo, hi):
        self.qp = SelectorQP(A, C)
        self.state = np.zeros(self.qp.dof.size, dtype=np.int8)
        self.sweeps = 0

    def find(self, x, lo, hi) -> int:
        return 0

    def solve(self, x, y_free, lo=None, hi=None):
        its = self.find(x, lo, hi)
        mu, sweeps = self.qp.finish(x, lo, hi, self.state)
        self.sweeps += sweeps
        return mu, its + sweeps

    def checkpoint(self) -> dict:
        return {"active": self.state.copy(),
                **{f"qp_{k}": v for k, v in self.qp.checkpoint().items()}}

    def restore(self, saved: dict) -> None:
        if "active" in saved:
            self.state[:] = saved["active"]
        self.qp.restore({k[3:]: v for k, v in saved.items() if k.startswith("qp_")})


def jacobi_scaled(A, dof, lo, hi):
    """(P̂ = J A J, j = diag(J), s): x = s·J x̂ with J = diag(A)^{-1/2} and s the largest
    finite |bound|; the bounds of x̂ at the selected unknowns are bound/(s j)."""
    j = 1.0 / np.sqrt(A.diagonal())
    finite = np.abs(np.concatenate([lo[np.isfinite(lo)], hi[np.isfinite(hi)]]))
    s = float(finite.max()) if finite.size and finite.max() > 0 else 1.0
    J = sp.diags(j)
    return sp.csc_matrix(J @ A @ J), j, s


class OSQPSparse(XSpaceSolver):
    """OSQP on the Jacobi-scaled step QP (module docstring), set up once per run."""

    def __init__(self, A, C, lo, hi):
        super().__init__(A, C, lo, hi)
        self.qp.guess_sweeps = 0             # OSQP finds the set
        import osqp
        A = self.qp.A
        P, self.j, self.s = jacobi_scaled(A, self.qp.dof, lo, hi)
        self.qmat = sp.csr_matrix(sp.diags(-self.j / self.s) @ A)   # q̂ = −J A x / s
        n, m = A.shape[0], self.qp.dof.size
        self.E = sp.csc_matrix((np.ones(m), (np.arange(m), self.qp.dof)), shape=(m, n))
        self.lo, self.hi = np.array(lo, dtype=float), np.array(hi, dtype=float)
        self._solved = osqp.SolverStatus.OSQP_SOLVED
        self.prob = osqp.OSQP()
        self.prob.setup(sp.triu(P, format="csc"), np.zeros(n), self.E, *self.scaled_bounds(),
                        verbose=False, eps_abs=OSQP_EPS, eps_rel=OSQP_EPS, polishing=False,
                        warm_starting=True, max_iter=100000)

    def checkpoint(self) -> dict:
        return {**super().checkpoint(),
                **{f"osqp_{k}": v for k, v in warm_state(self.prob._solver).items()}}

    def restore(self, saved: dict) -> None:
        super().restore(saved)
        warm_again(self.prob._solver, {k[5:]: v for k, v in saved.items()
                                       if k.startswith("osqp_")})

    def scaled_bounds(self):
        js = self.j[self.qp.dof] * self.s
        return self.lo / js, self.hi / js

    def find(self, x, lo, hi) -> int:
        if not (np.array_equal(lo, self.lo) and np.array_equal(hi, self.hi)):
            self.lo[:], self.hi[:] = lo, hi
            lo_s, hi_s = self.scaled_bounds()
            self.prob.update(l=lo_s, u=hi_s)
        self.prob.update(q=self.qmat @ x)
        r = self.prob.solve(raise_error=False)
        if r.info.status_val != self._solved:
            raise SolverError(f"OSQP returned status '{r.info.status}' after {r.info.iter} "
                              f"iterations")
        lo_s, hi_s = self.scaled_bounds()
        z = r.x[self.qp.dof]
        self.state[:] = 0
        self.state[hi_s - z < r.y] = 1
        self.state[z - lo_s < -r.y] = -1
        return int(r.info.iter)


class ClarabelSparse(XSpaceSolver):
    """Clarabel's interior point on the Jacobi-scaled step QP: the finite bounds as
    nonnegative slacks, the data updated each step (its factorisation's symbolic part
    kept), no warm start (an interior point has none)."""

    def __init__(self, A, C, lo, hi):
        super().__init__(A, C, lo, hi)
        self.qp.guess_sweeps = 0             # Clarabel finds the set
        import clarabel
        A = self.qp.A
        P, self.j, self.s = jacobi_scaled(A, self.qp.dof, lo, hi)
        self.qmat = sp.csr_matrix(sp.diags(-self.j / self.s) @ A)
        n, m = A.shape[0], self.qp.dof.size
        self.up, self.dn = np.flatnonzero(np.isfinite(hi)), np.flatnonzero(np.isfinite(lo))
        rows = np.concatenate([self.up, self.dn])
        sign = np.concatenate([np.ones(self.up.size), -np.ones(self.dn.size)])
        G = sp.csc_matrix((sign, (np.arange(rows.size), self.qp.dof[rows])),
                          shape=(rows.size, n))
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        settings.presolve_enable = False     # (data updates need the rows kept)
        settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = CLARABEL_EPS
        self.solver = clarabel.DefaultSolver(sp.triu(P, format="csc"), np.zeros(n), G,
                                             self.rhs(lo, hi), [clarabel.NonnegativeConeT(
                                                 rows.size)], settings)
        self._solved = clarabel.SolverStatus.Solved

    def rhs(self, lo, hi) -> np.ndarray:
        js = self.j[self.qp.dof] * self.s
        return np.concatenate([hi[self.up] / js[self.up], -lo[self.dn] / js[self.dn]])

    def find(self, x, lo, hi) -> int:
        self.solver.update(q=self.qmat @ x, b=self.rhs(lo, hi))
        r = self.solver.solve()
        if r.status != self._solved:
            raise SolverError(f"Clarabel returned status {r.status} after {r.iterations} "
                              f"iterations")
        z, slack = np.asarray(r.z), np.asarray(r.s)
        active = z > slack
        self.state[:] = 0
        self.state[self.up[active[:self.up.size]]] = 1
        self.state[self.dn[active[self.up.size:]]] = -1
        return int(r.iterations)


class XSpaceLaw(ContactLaw):
    """A law solved in Python in x-space (module docstring): the scheme builds neither W
    nor D for it, and its solver writes u^{n+1}."""
    x_space = True
    engine = XSpaceSolver

    def solver(self, step):
        return self.engine(step.A, step.C, step.lo, step.hi)


class PDASSparse(XSpaceLaw):
    """The primal-dual active set in x-space, warm-started from the last step's set."""
    name = "pdas-sparse"


class OSQPSparseLaw(XSpaceLaw):
    """OSQP (Jacobi-scaled) finds the set, the active set method finishes it exactly."""
    name = "osqp-sparse"
    engine = OSQPSparse


class ClarabelSparseLaw(XSpaceLaw):
    """Clarabel finds the set, the active set method finishes it exactly."""
    name = "clarabel-sparse"
    engine = ClarabelSparse
