"""The x-space contact engines (skfem_beam/contact/sparse_qp.py) on the plate: the same run
as the compiled active set (which uses W = A⁻¹Cᵀ and D = C W) before the second impact,
contact exact at the vertices, the scheme's energy identity closed; and the beam's C
(not a selector) refused."""
import numpy as np
import pytest
import scipy.sparse as sp

from skfem_beam import InputError
from skfem_beam.contact import registry, sparse_qp
from skfem_beam.contact.sparse_qp import COUNTS, SelectorQP, selected_unknowns
from skfem_beam.methods import PositionLevel
from skfem_beam.plate import Plate, plate_space
from skfem_beam.plate.system import PlateInitial, PlateObstacle, Pressure, plate_system
from skfem_beam.scheme import solve

DT, T = 1e-4, 0.03


def closure(r):
    """energy − energy[0] + damping work − input work − contact work (0 by the identity)."""
    w = r.work
    return r.energy - r.energy[0] + w["damping"] - w["input"] - w["contact"]


@pytest.fixture(scope="module")
def plate():
    """A simply supported 1 × 1 m steel plate (12 × 12 BFS, 121 contact vertices)
    deflected upwards by 10 kPa, released at rest onto a flat obstacle under the whole
    plate at half its static centre deflection; and the compiled active set's run."""
    space = plate_space(Plate(nx=12, ny=12))
    start = PlateInitial(static=Pressure(1e4))
    free = plate_system(space, initial=start)
    w_max = float(free.observe["w(0.5,0.5)"] @ free.u0)
    system = plate_system(space, obstacles=[PlateObstacle(g1=-0.5 * w_max)], initial=start)
    return system, w_max, solve(system, DT, T, method=PositionLevel("active-set"))


@pytest.mark.parametrize("law, chol", [("osqp-sparse", "auto"), ("pdas-sparse", "auto"),
                                       ("clarabel-sparse", "auto"), ("pdas-sparse", "cholmod")])
def test_an_x_space_engine_runs_the_active_sets_plate(plate, law, chol, monkeypatch):
    """(auto: the band at 12 × 12; cholmod: CHOLMOD forced from 0 unknowns)"""
    if chol == "cholmod":
        monkeypatch.setattr(sparse_qp, "CHOLMOD_MIN_N", 0)
    system, w_max, ref = plate
    r = solve(system, DT, T, method=PositionLevel(law))
    assert r.success and r.solver == law and r.impacts > 0
    starts = np.sort(ref.impact_events["t_start"])
    second = starts[starts > starts[0] + 5 * DT]
    before = ref.t < (second[0] if second.size else np.inf)
    scale = np.abs(ref.frames_u).max()
    frames = ref.frames_t < (second[0] if second.size else np.inf)
    assert np.abs(r.frames_u[frames] - ref.frames_u[frames]).max() <= 1e-10 * scale
    w, w_ref = r.observed["w(0.5,0.5)"], ref.observed["w(0.5,0.5)"]
    assert np.abs(w[before] - w_ref[before]).max() <= 1e-10 * w_max
    y = r.frames_u @ system.C.T
    assert (y - system.lo).min() >= -1e-12 * w_max
    assert r.max_nodal_violation <= 1e-12 * w_max
    assert np.abs(closure(r)).max() <= 1e-9 * np.abs(r.energy).max()


def test_the_beams_osqp_law_runs_the_benchmarks_plate_as_the_active_set():
    """The OSQP law of the beam (W and D built) on the benchmark's 20 × 20 plate pressed onto
    the obstacle under it: it called the step QP "dual infeasible" at step 16 when it scaled
    the unknowns by A's mean diagonal (the twists' curvature fell below OSQP's eps_dinf);
    scaled each by its own diagonal, it gives the active set's run to round-off."""
    from skfem_beam.plate.bench import DT as dt, systems
    system = systems(20)[1]
    runs = [solve(system, dt, 30 * dt, method=PositionLevel(law), progress=False)
            for law in ("osqp", "active-set")]
    assert all(r.success for r in runs) and runs[0].solver == "osqp"
    assert runs[0].contact_fraction > 0.5
    scale = np.abs(runs[1].frames_u).max()
    assert np.abs(runs[0].frames_u - runs[1].frames_u).max() <= 1e-10 * scale
    assert runs[0].max_nodal_violation <= 1e-12 * scale


def test_auto_takes_pdas_sparse_where_w_would_pass_its_budget(plate, monkeypatch):
    """auto: the compiled active set while W = A⁻¹Cᵀ fits in registry.W_BUDGET bytes,
    pdas-sparse past it (chosen before W is built), the same run to the bit as naming it."""
    system, _, _ = plate
    fits = 8.0 * system.n * system.C.shape[0]
    monkeypatch.setattr(registry, "W_BUDGET", fits)
    assert solve(system, DT, 10 * DT).solver == "active-set"
    monkeypatch.setattr(registry, "W_BUDGET", fits - 1.0)
    r = solve(system, DT, T)
    named = solve(system, DT, T, method=PositionLevel("pdas-sparse"))
    assert r.solver == "pdas-sparse" and r.impacts > 0
    assert np.array_equal(r.frames_u, named.frames_u)


@pytest.mark.parametrize("chol", ["band", "cholmod"])
def test_the_engines_need_a_selector_and_the_exact_finish_is_exact(chol):
    with pytest.raises(InputError, match="select one unknown"):
        selected_unknowns(sp.csr_matrix([[1.0, -1.0, 0.0]]))
    rng = np.random.default_rng(0)
    n = 30
    B = sp.random(n, n, density=0.1, random_state=1)
    A = sp.csr_matrix(B @ B.T + n * sp.eye(n))
    A = sp.csr_matrix(A.multiply(abs(sp.eye(n, k=0) + sum(sp.eye(n, k=k) + sp.eye(n, k=-k)
                                                         for k in range(1, 4))) > 0))
    C = sp.csr_matrix((np.ones(10), (np.arange(10), np.arange(0, 30, 3))), shape=(10, n))
    qp = SelectorQP(A, C, chol=chol)
    assert qp.G.name == chol
    x = rng.normal(size=n)
    lo, hi = np.full(10, -0.1), np.full(10, 0.1)
    state = np.zeros(10, np.int8)
    u = x.copy()
    mu, sweeps = qp.finish(u, lo, hi, state)
    y = u[qp.dof]
    assert np.all(y >= lo) and np.all(y <= hi)
    assert np.allclose(A @ u, A @ x + C.T @ mu, rtol=0, atol=1e-12 * np.abs(A @ x).max())
    assert np.all(mu[state < 0] > 0) and np.all(mu[state > 0] < 0) and np.all(mu[state == 0] == 0)
    assert np.array_equal(y[state < 0], lo[state < 0]) and np.array_equal(y[state > 0],
                                                                          hi[state > 0])


@pytest.mark.parametrize("chol", ["band", "cholmod"])
def test_the_kept_factor_solves_as_a_fresh_factorisation(chol):
    """pdas-sparse's kept factor of A_{S0} (inexact PCG sweeps, then the Schur complement
    on S Δ S0 or a refactorisation), banded or CHOLMOD's, against a fresh banded Cholesky
    of A_S for every set (and a fresh CHOLMOD factorisation, which must agree with it):
    the same u to 1e-10, the same sets and μ, the bounds held exactly, over 12 steps of a
    10 × 10 plate whose contact region moves across it."""
    space = plate_space(Plate(nx=10, ny=10))
    shapes = [plate_system(space, initial=PlateInitial(static=Pressure(1e4, region=r))).u0
              for r in (None, (0.0, 0.5, 0.0, 1.0), (0.5, 1.0, 0.0, 1.0))]
    system = plate_system(space, obstacles=[PlateObstacle(g1=-1.0)])
    A = system.M + 0.5 * DT**2 * system.K
    fast = SelectorQP(A, system.C, max_columns=8, chol=chol)
    fresh = SelectorQP(A, system.C, update=False, chol="band")
    other = SelectorQP(A, system.C, update=False, chol="cholmod")
    y_s = system.C @ shapes[0]
    lo = np.full(system.C.shape[0], 0.4 * y_s.max())
    hi = np.full_like(lo, np.inf)
    state_fast = np.zeros(lo.size, np.int8)
    state_fresh = state_fast.copy()
    changes = 0
    used = {"fast": dict.fromkeys(COUNTS, 0), "fresh": dict.fromkeys(COUNTS, 0)}

    def finish(name, qp, u, state):        # the call, and its share of sparse_qp's tally
        before = dict(COUNTS)
        out = qp.finish(u, lo, hi, state)
        for key in COUNTS:
            used[name][key] += COUNTS[key] - before[key]
        return out
    for k in range(12):
        t = 0.5 * k
        x = (1.3 + 0.4 * np.sin(t)) * shapes[0] + 1.5 * np.cos(t) * shapes[1] \
            + 1.5 * np.sin(t) * shapes[2]
        before = state_fast.copy()
        u, v = x.copy(), x.copy()
        mu, _ = finish("fast", fast, u, state_fast)
        mu_ref, _ = finish("fresh", fresh, v, state_fresh)
        w, state_other = x.copy(), state_fast.copy()
        other.finish(w, lo, hi, state_other)                # from the final set: 1 sweep
        assert np.array_equal(state_other, state_fast)
        assert np.abs(w - v).max() <= 1e-10 * np.abs(v).max()
        changes += int(np.count_nonzero(state_fast != before))
        assert np.array_equal(state_fast, state_fresh)
        assert np.abs(u - v).max() <= 1e-10 * np.abs(v).max()
        assert np.abs(mu - mu_ref).max() <= 1e-9 * np.abs(mu_ref).max()
        y = u[fast.dof]
        assert np.all(y >= lo)                              # no penetration at all
        assert np.array_equal(y[state_fast < 0], lo[state_fast < 0])
    # the set moved, and both the Schur complement and refactorisations were used
    fast, fresh = used["fast"], used["fresh"]
    assert changes > 50 and fast["columns"] > 0 and fast["factors"] > 1
    assert (fast["guesses"] > 0) == (chol == "band")     # inexact sweeps: the band's only
    assert fast["factors"] < fresh["factors"]


def test_a_large_w_is_announced_on_stderr(plate, monkeypatch, capsys):
    """W = A⁻¹Cᵀ past operators.SAY_W_BYTES: one line saying its size before it is built
    (and how to build none); below it, nothing."""
    from skfem_beam.scheme import operators
    system, _, _ = plate
    size = 8.0 * system.n * system.C.shape[0]
    monkeypatch.setattr(operators, "SAY_W_BYTES", size + 1.0)
    solve(system, DT, 2 * DT)
    assert "building W" not in capsys.readouterr().err
    monkeypatch.setattr(operators, "SAY_W_BYTES", size)
    solve(system, DT, 2 * DT)
    err = capsys.readouterr().err.splitlines()
    said = [line for line in err if line.startswith("building W")]
    assert said == [f"building W = A⁻¹Cᵀ for the contact law: {system.C.shape[0]} columns, "
                    f"{size * 1e-9:.2f} GB (solver pdas-sparse builds none) …"]


def test_the_active_sets_primal_dual_start_runs_the_same_plate(monkeypatch):
    """From PDAS_MIN constrained values on (a 20 × 20 plate: 361) the active-set law starts
    each step with the primal–dual active set; with it off (Goldfarb–Idnani alone) the
    bench's plate, pressed onto the obstacle under the whole plate, runs the same to
    round-off, contact exact, with a fifth of the passes or fewer (measured: 95 against 702
    over 40 steps)."""
    from skfem_beam.contact import active_set
    from skfem_beam.plate import bench
    _, pressed = bench.systems(20)
    runs = []
    for minimum in (active_set.PDAS_MIN, 10**9):
        monkeypatch.setattr(active_set, "PDAS_MIN", minimum)
        runs.append(solve(pressed, bench.DT, 40 * bench.DT, method=PositionLevel("active-set")))
    pd, gi = runs
    assert pd.success and gi.success and pd.contact_fraction > 0.5
    scale = np.abs(gi.frames_u).max()
    assert np.abs(pd.frames_u - gi.frames_u).max() <= 1e-10 * scale
    assert pd.max_nodal_violation <= 1e-15 * scale
    assert np.abs(closure(pd)).max() <= 1e-9 * np.abs(pd.energy).max()
    assert 5 * pd.qp_iterations <= gi.qp_iterations


@pytest.mark.parametrize("law", ["pdas-sparse", "osqp-sparse", "clarabel-sparse"])
def test_an_x_space_run_resumes_bit_for_bit(law):
    """A resumed x-space run continues bit for bit: its checkpoint keeps the kept factor's
    set S0 and the batches of columns cached since, which the restore factors and solves
    again on one thread (a resume that refactored on its own first set summed otherwise:
    5e-18 J of energy at step 415 of plate_disk.toml)."""
    from skfem_beam.scenefile import example, load
    scene = load(example("plates/plate_disk"), [f"contact.law={law}"])
    system, stepping, method = scene.problem.system, scene.stepping, scene.method
    whole = method.build(system, stepping)
    whole.advance(480)
    first = method.build(system, stepping)
    first.advance(400)
    again = method.build(system, stepping)
    again.restore(first.checkpoint())
    again.advance(480)
    assert whole.u_cur.tobytes() == again.u_cur.tobytes()
    assert whole.u_prev.tobytes() == again.u_prev.tobytes()
