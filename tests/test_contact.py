"""The contact solvers of one step: Lemma 4.1, the exact active-set method, OSQP, daqp.

References are independent of the code under test: an exhaustive enumeration of the
3^m active sets (numpy), daqp on the full QP in x, and the KKT conditions checked in
x with A, F, C themselves (never through D or W).
"""
import itertools

import daqp
import numpy as np
import pytest
import scipy.sparse as sp

from skfem_beam import SolverError, beam_system, scenes, solve
from skfem_beam.contact.active_set import box_qp, box_qp_pdas
from skfem_beam.contact.daqp_solver import DAQPSolver
from skfem_beam.contact.osqp_solver import OSQPSolver
from skfem_beam.contact.projection import project
from skfem_beam.methods import PositionLevel


# ---------------------------------------------------------------- random step problems
def banded_spd(rng, n):
    """A = M + c K as in the scheme: a tridiagonal mass-like M and a bilaplacian K."""
    e = np.ones(n)
    M = sp.diags([e[:-1] / 6, 2 * e / 3 * rng.uniform(0.8, 1.2, n), e[:-1] / 6], [-1, 0, 1])
    B = sp.diags([e[:-1], -2 * e, e[:-1]], [-1, 0, 1])
    return (M + 10 ** rng.uniform(-3, 1) * (B @ B) + 1e-3 * sp.eye(n)).tocsc()


def constraint_rows(rng, m, kind):
    """Hermite: rows of the identity (values out of value/slope pairs); B-spline: the
    nodal values (1/6, 2/3, 1/6) of consecutive coefficients."""
    if kind == "hermite":
        n = 2 * m + 2
        return sp.csr_matrix((np.ones(m), (np.arange(m), 2 * np.arange(m) + 2)), shape=(m, n))
    n = m + 3
    rows = np.repeat(np.arange(m), 3)
    cols = (np.arange(m)[:, None] + np.arange(1, 4)).ravel()
    vals = np.tile([1 / 6, 2 / 3, 1 / 6], m)
    return sp.csr_matrix((vals, (rows, cols)), shape=(m, n))


def step_problem(rng, m, kind="hermite", one_sided=0.1):
    C = constraint_rows(rng, m, kind)
    A = banded_spd(rng, C.shape[1])
    g = rng.uniform(0.05, 1.0, m)
    lo, hi = -g.copy(), g.copy()
    lo[rng.random(m) < one_sided] = -np.inf
    hi[(rng.random(m) < one_sided) & np.isfinite(lo)] = np.inf
    Ad = A.toarray()
    W = np.linalg.solve(Ad, C.T.toarray())
    D = np.ascontiguousarray(C @ W)
    return A, C, lo, hi, D, W


def free_data(rng, A, C, amplitude):
    x_free = amplitude * rng.standard_normal(A.shape[0])
    return x_free, A @ x_free, np.ascontiguousarray(C @ x_free)


def kkt(A, F, C, lo, hi, x, mu):
    """Residuals of the step QP's KKT conditions, each relative to its own scale:
    stationarity Ax − F = Cᵀμ; feasibility; μ > 0 only at lo, μ < 0 only at hi."""
    y = C @ x
    s = np.abs(np.r_[lo[np.isfinite(lo)], hi[np.isfinite(hi)]]).max()
    g = A @ x - F
    stat = np.abs(g - C.T @ mu).max() / max(np.abs(F).max(), np.abs(g).max())
    feas = max(0.0, (lo - y).max(), (y - hi).max()) / s
    dist = np.where(mu > 0, np.abs(y - lo), np.where(mu < 0, np.abs(y - hi), 0.0))
    comp = np.nan_to_num(dist, nan=np.inf, posinf=np.inf).max() / s
    return stat, feas, comp


def enumerate_reference(D, yf, lo, hi):
    """The exact solution by trying every active set (small m): the unique one whose
    μ has the right signs and whose y lies in the box."""
    m = yf.size
    best = (np.inf, None)
    for pattern in itertools.product((-1, 0, 1), repeat=m):
        st = np.array(pattern)
        b = np.where(st < 0, lo, hi)
        if not np.isfinite(b[st != 0]).all():
            continue
        idx = np.flatnonzero(st)
        mu = np.zeros(m)
        if idx.size:
            mu[idx] = np.linalg.solve(D[np.ix_(idx, idx)], b[idx] - yf[idx])
        y = yf + D @ mu
        free = st == 0
        r = max(0.0, (lo - y)[free].max(initial=0), (y - hi)[free].max(initial=0),
                (st * mu * np.diag(D)).max())
        if r < best[0]:
            best = (r, mu)
    return best[1]


# ---------------------------------------------------------------- Lemma 4.1
@pytest.mark.parametrize("seed", range(3))
def test_lemma_4_1_single_constraint_is_a_projection(seed):
    """One constrained value: clip(y_free) (Lemma 4.1) is the QP's solution, as found by
    box_qp, daqp (reduced and on the full QP in x) and the enumeration, to 1e-12."""
    rng = np.random.default_rng(seed)
    worst, active = 0.0, 0
    for _ in range(40):
        n = int(rng.integers(3, 30))
        Q = rng.standard_normal((n, n))
        Ad = Q @ Q.T + n * np.eye(n) * rng.uniform(0.01, 1)
        c = rng.standard_normal((1, n))
        lo, hi = np.array([-rng.uniform(0.1, 1)]), np.array([rng.uniform(0.1, 1)])
        r = rng.random()
        if r < 0.15:                 # a one-sided obstacle
            lo[0] = -np.inf
        elif r < 0.3:
            hi[0] = np.inf
        F = 3 * rng.standard_normal(n)
        x_free = np.linalg.solve(Ad, F)
        W = np.linalg.solve(Ad, c.T)
        D = c @ W
        yf = c @ x_free
        mu_p = np.zeros(1)
        project(np.diag(D).copy(), yf, lo, hi, mu_p)
        x_p = x_free + W @ mu_p
        active += mu_p[0] != 0
        mu_b = np.zeros(1)
        assert box_qp(D, yf, lo, hi, np.zeros(1, np.int8), mu_b) > 0
        mu_d, _ = DAQPSolver(lo, hi, D) \
            .solve(x_free, yf)
        mu_e = enumerate_reference(D, yf, lo, hi)
        x_q, _, flag, _ = daqp.solve(Ad, -F, c, np.minimum(hi, 1e30), np.maximum(lo, -1e30),
                                     np.zeros(1, np.intc), primal_tol=1e-13)
        assert flag == 1
        scale = np.abs(x_p).max()
        for mu in (mu_b, mu_d, mu_e):
            worst = max(worst, np.abs(x_free + W @ mu - x_p).max() / scale)
        worst = max(worst, np.abs(x_q - x_p).max() / scale)
    assert worst <= 1e-12
    assert 10 <= active <= 30           # both cases, in contact and free, were tried


def test_lemma_4_1_decoupled_constraints():
    """Several values with a diagonal D (decoupled): the projection solves each alone."""
    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(50):
        m = int(rng.integers(2, 6))
        D = np.diag(rng.uniform(0.1, 10, m))
        yf = 2 * rng.standard_normal(m)
        lo, hi = -rng.uniform(0.1, 1, m), rng.uniform(0.1, 1, m)
        mu_p, mu_b = np.zeros(m), np.zeros(m)
        project(np.diag(D).copy(), yf, lo, hi, mu_p)
        box_qp(D, yf, lo, hi, rng.integers(-1, 2, m).astype(np.int8), mu_b)
        mu_e = enumerate_reference(D, yf, lo, hi)
        scale = max(1.0, np.abs(mu_p).max())
        worst = max(worst, np.abs(mu_b - mu_p).max() / scale, np.abs(mu_e - mu_p).max() / scale)
    assert worst <= 1e-12


# ---------------------------------------------------------------- the exact method
def small_box_problem(rng, trial: int):
    """(D, y_f, lo, hi) of 1 to 5 coupled rows, some one-sided; every tenth degenerate
    (free values exactly on a bound)."""
    m = int(rng.integers(1, 6))
    Q = rng.standard_normal((m, m))
    D = Q @ Q.T + rng.uniform(0.01, 1) * np.eye(m)
    yf = 2 * rng.standard_normal(m)
    lo, hi = -rng.random(m), rng.random(m)
    lo[rng.random(m) < 0.2] = -np.inf
    if trial % 10 == 0:
        yf[: m // 2 + 1] = hi[: m // 2 + 1]
    return D, yf, lo, hi


def test_box_qp_matches_enumeration_from_any_warm_start():
    rng = np.random.default_rng(11)
    worst, most = 0.0, 0
    for trial in range(200):
        D, yf, lo, hi = small_box_problem(rng, trial)
        m = yf.size
        state = rng.integers(-1, 2, m).astype(np.int8)
        mu = np.zeros(m)
        its = box_qp(D, yf, lo, hi, state, mu)
        assert its > 0
        most = max(most, its)
        ref = enumerate_reference(D, yf, lo, hi)
        worst = max(worst, np.abs(mu - ref).max() / max(1.0, np.abs(ref).max()))
        # the state returned is the active set of μ, and re-solving from it takes one pass
        assert ((state != 0) | (mu == 0)).all()
        again = np.zeros(m)
        assert box_qp(D, yf, lo, hi, state, again) == 1
    assert worst <= 1e-12
    assert most <= 2 * 5 + 1          # a few passes, not a search


def test_box_qp_large_cold_and_warm():
    """m up to 160 from scratch (the finite Goldfarb–Idnani path) and warm-started
    from a perturbed active set: KKT in x to 1e-10, and the same answer both ways."""
    rng = np.random.default_rng(3)
    for m, kind in [(40, "hermite"), (160, "hermite"), (80, "bspline"), (160, "bspline")]:
        A, C, lo, hi, D, W = step_problem(rng, m, kind)
        x_free, F, yf = free_data(rng, A, C, 2.0)
        st = np.zeros(m, np.int8)
        mu = np.zeros(m)
        assert box_qp(D, yf, lo, hi, st, mu) > 0
        assert np.count_nonzero(mu) >= m // 4          # many contacts
        stat, feas, comp = kkt(A, F, C, lo, hi, x_free + W @ mu, mu)
        assert max(stat, feas, comp) <= 1e-10
        flip = rng.random(m) < 0.3
        st[flip] = rng.integers(-1, 2, flip.sum())
        mu2 = np.zeros(m)
        assert box_qp(D, yf, lo, hi, st, mu2) > 0
        assert np.abs(mu2 - mu).max() <= 1e-12 * np.abs(mu).max()


def test_the_primal_dual_start_gives_goldfarb_idnanis_answer():
    """box_qp_pdas (the active set's path from PDAS_MIN rows on) against box_qp: small
    problems from any warm start (degenerate ones too) against the enumeration, and steps
    of 300 coupled rows, one- and two-sided, whose set moves by many rows a step: the same
    μ to 1e-12, KKT in x to 1e-10, and fewer passes than Goldfarb–Idnani's one per row."""
    rng = np.random.default_rng(19)
    for trial in range(200):
        D, yf, lo, hi = small_box_problem(rng, trial)
        m = yf.size
        mu = np.zeros(m)
        assert box_qp_pdas(D, yf, lo, hi, rng.integers(-1, 2, m).astype(np.int8), mu) > 0
        ref = enumerate_reference(D, yf, lo, hi)
        assert np.abs(mu - ref).max() <= 1e-12 * max(1.0, np.abs(ref).max())
    for kind, one_sided in (("hermite", 0.1), ("bspline", 1.0)):
        A, C, lo, hi, D, W = step_problem(rng, 300, kind, one_sided)
        x_free, _, _ = free_data(rng, A, C, 2.0)
        st_gi, st_pd = np.zeros(300, np.int8), np.zeros(300, np.int8)
        passes = [0, 0]
        for step in range(8):
            x_free = x_free + 0.5 * rng.standard_normal(x_free.size)
            F, yf = A @ x_free, np.ascontiguousarray(C @ x_free)
            mu_gi, mu_pd = np.zeros(300), np.zeros(300)
            passes[0] += box_qp(D, yf, lo, hi, st_gi, mu_gi)
            passes[1] += box_qp_pdas(D, yf, lo, hi, st_pd, mu_pd)
            assert np.abs(mu_pd - mu_gi).max() <= 1e-12 * np.abs(mu_gi).max()
            assert max(kkt(A, F, C, lo, hi, x_free + W @ mu_pd, mu_pd)) <= 1e-10
        assert passes[1] < passes[0] / 3, passes


# ---------------------------------------------------------------- the three engines
@pytest.mark.parametrize("kind", ["hermite", "bspline"])
@pytest.mark.parametrize("m", [5, 20, 80])
def test_engines_agree_on_random_step_sequences(m, kind):
    """box_qp, OSQP and daqp on a run of related steps (their warm starts in play):
    μ agree to 1e-8 relative and each satisfies the KKT conditions to 1e-10."""
    rng = np.random.default_rng(100 * m + len(kind))
    A, C, lo, hi, D, W = step_problem(rng, m, kind)
    osqp_s = OSQPSolver(A, C, lo, hi, D)
    daqp_s = DAQPSolver(lo, hi, D)
    st = np.zeros(m, np.int8)
    x_free, _, _ = free_data(rng, A, C, 2.0)
    worst_diff, worst_kkt, active = 0.0, 0.0, 0
    for step in range(12):
        x_free = x_free + 0.3 * rng.standard_normal(x_free.size)   # the next step's data
        F = A @ x_free
        yf = np.ascontiguousarray(C @ x_free)
        mu_b = np.zeros(m)
        assert box_qp(D, yf, lo, hi, st, mu_b) > 0
        mu_o, _ = osqp_s.solve(x_free, yf)
        mu_d, _ = daqp_s.solve(x_free, yf)
        scale = np.abs(mu_b).max()
        active = max(active, np.count_nonzero(mu_b))
        for mu in (mu_o, mu_d):
            worst_diff = max(worst_diff, np.abs(mu - mu_b).max() / scale)
        for mu in (mu_b, mu_o, mu_d):
            worst_kkt = max(worst_kkt, *kkt(A, F, C, lo, hi, x_free + W @ mu, mu))
    assert active >= max(2, m // 4)
    assert worst_diff <= 1e-8
    assert worst_kkt <= 1e-10
    assert daqp_s.repairs == 0


def test_grazing_contacts_are_decided_exactly():
    """Bounds moved onto (or within 1e-13..1e-9 of) the free values' solution: the
    degenerate case where an ε-accurate engine cannot tell active from inactive.
    box_qp and daqp stay exact; OSQP is exact (its set repaired by the exact finish) or
    raises SolverError, never silently wrong."""
    rng = np.random.default_rng(21)
    worst, osqp_ok, n = 0.0, 0, 0
    for _ in range(30):
        m = int(rng.choice([5, 20, 40]))
        A, C, lo, hi, D, W = step_problem(rng, m, rng.choice(["hermite", "bspline"]), 0.0)
        x_free, F, yf = free_data(rng, A, C, 1.0)
        st, mu = np.zeros(m, np.int8), np.zeros(m)
        box_qp(D, yf, lo, hi, st, mu)
        y = yf + D @ mu
        free = np.flatnonzero(st == 0)
        if free.size == 0:
            continue
        for i in rng.choice(free, size=max(1, free.size // 2), replace=False):
            off = rng.choice([0.0, 1e-13, -1e-13, 1e-11, -1e-9])
            if y[i] > 0:
                hi[i] = y[i] + off * hi[i]
            else:
                lo[i] = y[i] + off * lo[i]
        n += 1
        mu_b = np.zeros(m)
        assert box_qp(D, yf, lo, hi, np.zeros(m, np.int8), mu_b) > 0
        mu_d, _ = DAQPSolver(lo, hi, D).solve(x_free, yf)
        results = [mu_b, mu_d]
        try:
            results.append(OSQPSolver(A, C, lo, hi, D).solve(x_free, yf)[0])
            osqp_ok += 1
        except SolverError:
            pass
        scale = np.abs(mu_b).max()
        for mu in results:
            worst = max(worst, np.abs(mu - mu_b).max() / scale,
                        *kkt(A, F, C, lo, hi, x_free + W @ mu, mu))
    assert worst <= 1e-10
    assert osqp_ok >= 0.9 * n


def test_osqp_is_quiet_and_free_steps_are_exact(capfd):
    """Nothing on the terminal (OSQP 1.x prints "Polishing not needed" with polishing on);
    a step without contact gives μ = 0."""
    rng = np.random.default_rng(5)
    A, C, lo, hi, D, W = step_problem(rng, 10, one_sided=0.0)
    s = OSQPSolver(A, C, lo, hi, D)
    x_free, _, yf = free_data(rng, A, C, 1e-3)      # well inside the box
    mu, its = s.solve(x_free, yf)
    assert its > 0 and np.count_nonzero(mu) == 0
    out = capfd.readouterr().out
    assert len(out) == 0


def test_engine_failures_raise_solver_error():
    rng = np.random.default_rng(6)
    A, C, lo, hi, D, W = step_problem(rng, 20)
    x_free, _, yf = free_data(rng, A, C, 2.0)
    s = OSQPSolver(A, C, lo, hi, D)
    s.prob.update_settings(max_iter=1)
    with pytest.raises(SolverError, match="OSQP"):
        s.solve(x_free, yf)
    d = DAQPSolver(lo, hi, D)
    d.model.settings = {"iter_limit": 1}
    with pytest.raises(SolverError, match="daqp"):
        d.solve(x_free, yf)


# ---------------------------------------------------------------- a run, every solver
@pytest.mark.parametrize("solver", ["osqp", "daqp"])
def test_python_engines_are_called_only_on_steps_in_contact(solver):
    """A free step inside its bounds has μ = 0 exactly, so the compiled loop does not call
    the engine: its calls after the start step (solved when the run is built) are the
    steps in contact, and the run equals the active set's (flat obstacles, J = 40)."""
    from skfem_beam import methods
    from skfem_beam.scheme.kernels import CONTACT_STEPS
    from skfem_beam.scheme.solve import drive
    from skfem_beam.scheme.stepping import Stepping
    system = beam_system(scenes.flat_obstacles(J=40))
    runs = {}
    for name in (solver, "active-set"):
        runs[name] = methods.PositionLevel(name).build(system, Stepping(1e-3, 0.3, frames=300))
    engine, calls = runs[solver].pysolver, []
    engine_solve = engine.solve
    engine.solve = lambda *a: calls.append(1) or engine_solve(*a)
    for run in runs.values():
        drive(run, progress=False)
    in_contact = int(runs[solver].st.counters[CONTACT_STEPS])
    assert 30 < in_contact < 200
    assert len(calls) == in_contact
    a, b = runs[solver].result(), runs["active-set"].result()
    assert a.impacts == b.impacts > 0
    assert np.abs(a.frames_u - b.frames_u).max() <= 1e-10 * np.abs(b.frames_u).max()



def test_a_python_law_with_a_force_inside_its_bounds_is_called_every_step():
    """``free_inside = False`` (a law whose force does not vanish between the bounds): the
    loop calls its solver on every step, in contact or not."""
    from skfem_beam.contact.daqp_solver import DAQP
    from skfem_beam.scheme import Run
    from skfem_beam.scheme.beta import BetaScheme
    from skfem_beam.scheme.solve import drive
    from skfem_beam.scheme.stepping import Stepping

    class Everywhere(DAQP):
        name = "daqp-everywhere"
        free_inside = False
    run = Run(BetaScheme(beam_system(scenes.flat_obstacles(J=40)), Stepping(1e-3, 0.3),
              Everywhere()))
    engine, calls = run.pysolver, []
    engine_solve = engine.solve
    engine.solve = lambda *a: calls.append(1) or engine_solve(*a)
    drive(run, progress=False)
    assert len(calls) == run.n - 1 == 299


@pytest.mark.parametrize("element", ["hermite", "bspline"])
def test_all_solvers_give_the_same_run(element):
    """200 steps of the convex-obstacle scene: every solver, every step, to 1e-8."""
    sysm = beam_system(scenes.convex_obstacles(J=40, element=element))
    runs = {s: solve(sysm, dt=1e-3, T=0.2, beta=0.5, method=PositionLevel(s), frames=200)
            for s in ["active-set", "osqp", "daqp"]}
    ref = runs["active-set"]
    assert ref.frames_u.shape[0] == 201 and ref.impacts > 0
    assert np.count_nonzero(ref.contact_force) > 0
    u_scale = np.abs(ref.frames_u).max()
    f_scale = np.abs(ref.contact_force).max()
    for name, r in runs.items():
        assert r.success and r.impacts == ref.impacts
        assert r.max_nodal_violation <= 1e-10
        assert np.abs(r.frames_u - ref.frames_u).max() <= 1e-8 * u_scale
        assert np.abs(r.contact_force - ref.contact_force).max() <= 1e-8 * f_scale
