"""From a beam scene to the semi-discrete system the integrator steps:

    M ü + B u̇ + K u = Σ_k a_k(t) b_k + Cᵀλ,   lo ≤ C u ≤ hi   (λ: nodal contact forces)

The same object (:class:`~skfem_beam.system.SemiDiscrete`, importable from here too)
serves the beam (Hermite or B-spline, B = 0) and the bar (P1 or P2, with Kelvin–Voigt damping),
so there is one time scheme for all scenes.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Callable, NamedTuple

import numpy as np
import scipy.sparse as sp

import scipy.sparse.linalg as spla

from .constraints import check_start, constraint_rows, friction, moving_bounds
from .checks import check_choice
from .errors import InputError
from .modes import beam_space, modes
from .problem import BeamProblem, lifting, lifting_d, lifting_dd
from .spaces import has_rigid_motion
from .spaces.ends import fixed_dofs
from .spaces.hermite import five_point_slope
from .spaces.redistribution import massless_dofs, redistribute, rigid_modes
from .system import Lifting, SceneView, SemiDiscrete
from .timefunctions import Constant
from .two_planes import plane_problems


def static_lifting(space, at: float, k2: float) -> np.ndarray:
    """Full coefficients of the discrete static lifting: u = 1 at the node ``at``, every
    other fixed value and slope 0, and a(h, w) = 0 for every w of V_h (when the fixed
    conditions leave a rigid motion, a(h, w) + s(h, w) = 0 with s = k2/L⁴ instead)."""
    value, slope = fixed_dofs(space.J, space.ends, space.support_nodes)
    x = space.nodes
    G = sp.vstack([space.point_rows(x[value], 0, full=True),
                   space.point_rows(x[slope], 1, full=True)]).toarray()
    e = np.zeros(G.shape[0])
    e[int(np.abs(x[value] - at).argmin())] = 1.0
    c_p = np.linalg.lstsq(G, e, rcond=None)[0]          # any function meeting the conditions
    Mf, Sf = space.full_matrices()
    L = x[-1] - x[0]
    Af = k2 * Sf + (k2 / L**4 if has_rigid_motion(space) else 0.0) * Mf
    T = space.T
    z = spla.spsolve((T.T @ Af @ T).tocsc(), -(T.T @ (Af @ c_p)))
    return c_p + T @ z


def _evaluator(space, c: np.ndarray, derivative: int) -> Callable:
    """x ↦ d^k/dx^k of the full-space function with coefficients c, for x of any shape."""
    def f(x):
        x = np.asarray(x, dtype=float)
        return (space.point_rows(x.ravel(), derivative, full=True) @ c).reshape(x.shape)
    return f


def _lifting(problem: BeamProblem, space) -> tuple[Lifting, list, list]:
    """The lifting and its load terms (profiles or vectors, times) f = −m(h,·)φ'' − a(h,·)φ."""
    sup, L, k2 = problem.support, problem.beam.L, problem.beam.k2
    if problem.lifting == "paper":
        # f = f̃ − h φ'' − k² h φ, with h = −8/L⁴
        lift = Lifting("paper", lambda x: lifting(x, L), lambda x: lifting_d(x, L),
                       lambda x: lifting_dd(x, L), sup)
        return lift, [lambda x: -lifting(x, L), lambda x: np.full(np.shape(x), 8 * k2 / L**4)], \
            [sup.phi_dd, sup.phi]
    c = static_lifting(space, sup.at, k2)
    Mf, Sf = space.full_matrices()
    lift = Lifting("static", *(_evaluator(space, c, k) for k in range(3)), sup)
    # a(h, ·) vanishes on V_h up to round-off (or is the shift's s·m(h, ·)): kept, exact
    return lift, [-(space.T.T @ (Mf @ c)), -(k2 * (space.T.T @ (Sf @ c)))], \
        [sup.phi_dd, sup.phi]


def _damping_relative(problem: BeamProblem, space, B) -> np.ndarray:
    """The load column (time φ') that makes the damping act on the motion relative to the
    quasi-static one, r φ (r the static lifting), whatever the lifting: with the paper's h
    (not r: h(L) = 0) B u_t damped part of the support's own motion, and a damped run
    depended on the lifting chosen (47 % of the tip's φ = 0 component, 2 % of its
    amplitude: the pipe at ω = 20, ζ = 0.02).  −B y, y the M-projection of h − r (which
    vanishes at the support: it lies in V_h)."""
    sup, L = problem.support, problem.beam.L
    c = static_lifting(space, sup.at, problem.beam.k2)
    Mf, _ = space.full_matrices()
    diff = space.load_vector(lambda x: lifting(x, L)) - space.T.T @ (Mf @ c)
    return -(B @ spla.spsolve(space.M.tocsc(), diff))


def _load_columns(problem: BeamProblem, space, profiles, times):
    """Load vectors: profiles (functions of x: (b, φᵢ); arrays: already vectors), then
    the problem's loads in the mass-normalised units (÷ ρA_ref, docs/design.md §1)."""
    beam, ld = problem.beam, problem.load
    profiles, times = list(profiles), list(times)
    for b, a in ld.terms:
        profiles.append(b)
        times.append(a)
    rho = beam.rho_S
    for b, a in ld.forces:
        profiles.append(lambda x, b=b: np.asarray(b(x), dtype=float) / rho)
        times.append(a)
    for x, a in ld.points:
        profiles.append(space.point_rows([x]).toarray().ravel() / rho)
        times.append(a)
    if ld.g:
        profiles.append(lambda x: -ld.g * beam.factors(x)[0])
        times.append(Constant(1.0))
    cols = [b if isinstance(b, np.ndarray) else space.load_vector(b) for b in profiles]
    return (np.column_stack(cols) if cols else np.zeros((space.n, 0))), times


def _initial(problem: BeamProblem, space, lift: Lifting | None):
    """(u0, v0): interpolated u0, L²-projected v0; in the fixed frame, minus h φ(0), h φ'(0).
    With no u0 the beam starts at rest in its static shape on the support at φ(0) (ũ =
    h_s φ(0), h_s the static lifting): flat in the fixed frame it missed a support that
    starts away from 0, and the interpolant dropped the gap, a kink whose strain energy grew
    as J³."""
    ini = problem.initial
    u0f, du0f, v0f = (_shaped(name, getattr(ini, name)) for name in ("u0", "du0", "v0"))
    if ini.fixed_frame and lift is not None:
        p0, dp0 = float(lift.motion.phi(0.0)), float(lift.motion.phi_d(0.0))
        zero = lambda x: np.zeros(np.shape(x))  # noqa: E731
        vt = v0f or zero
        if u0f is None and p0 != 0.0 and lift.kind == "paper":
            c = static_lifting(space, lift.motion.at, problem.beam.k2)
            hs, dhs = _evaluator(space, c, 0), _evaluator(space, c, 1)
            u0f = lambda x: (hs(x) - lift.h(x)) * p0  # noqa: E731
            du0f = lambda x: (dhs(x) - lift.h_d(x)) * p0  # noqa: E731
        elif u0f is not None:
            ut = u0f
            dut = du0f or five_point_slope(ut, 1e-3 * problem.beam.L)
            dh = lift.h_d
            u0f = lambda x: ut(x) - lift.h(x) * p0  # noqa: E731
            du0f = lambda x: dut(x) - dh(x) * p0  # noqa: E731
            _meets_support(problem, u0f, p0)
        v0f = lambda x: vt(x) - lift.h(x) * dp0  # noqa: E731
    elif u0f is not None:
        _meets_support(problem, u0f, 0.0)
    u0 = space.interpolate(u0f, du0f) if u0f is not None else np.zeros(space.n)
    # initial velocity: L² projection (v0 need not be in V: the first paper's v0 = −2h has
    # v0(0) = −2 ≠ 0; (2.1) asks for convergence in H, which the L² projection gives best)
    v0 = space.project(v0f) if v0f is not None else np.zeros(space.n)
    if not (np.isfinite(u0).all() and np.isfinite(v0).all()):
        raise InputError("the initial state u0, v0 is not finite")
    return u0, v0


def _shaped(name: str, f):
    """The profile ``f`` of InitialState, its values checked: of x's shape (or one that
    broadcasts to it), else one line naming it (numpy's broadcast error came from inside
    the projection)."""
    if f is None:
        return None

    def checked(x):
        values = f(x)
        shape = np.shape(values)
        try:
            ok = np.broadcast_shapes(shape, np.shape(x)) == np.shape(x)
        except ValueError:
            ok = False
        if not ok:
            raise InputError(f"InitialState {name}(x) returned shape {shape} for x of shape "
                             f"{np.shape(x)}: a profile is a vectorised function of x, one "
                             "value per x")
        return values
    return checked


def _meets_support(problem: BeamProblem, u, p0: float) -> None:
    """Refuse an initial displacement that misses what holds the beam at t = 0 (``u``: the
    relative u0, zero there; ``p0``: φ(0), the moving support's start): the interpolant
    dropped the gap, a kink whose strain energy grew as J³.  (A slope it sets itself: a
    table's spline cannot be told its end slope.)"""
    L = problem.beam.L
    held = [x for x, e in ((0.0, problem.ends[0]), (L, problem.ends[1]))
            if e in ("clamped", "pinned")] + list(problem.supports)
    scale = max(abs(p0), float(np.abs(np.asarray(u(np.linspace(0.0, L, 41)))).max()))
    for x in held:
        gap = float(np.asarray(u(np.array([x])), dtype=float).ravel()[0])
        # 1e-12 L: a sine's φ(0) at phase π is 2.4e-17, round-off, not a start
        if not abs(gap) <= 1e-6 * scale + 1e-12 * L:
            raise InputError(
                f"[initial] the start misses what holds the beam at x={x:g} at t = 0 by "
                f"{gap:.3g} m (the support is at {p0 if x == problem.support.at else 0.0:g} m "
                "there): start the beam on it (u0, mode), or give no initial displacement "
                "(it then starts at rest on its supports)")


class _Plane(NamedTuple):
    """One bending plane's part of a beam's system (its own stiffness, loads, start)."""
    problem: BeamProblem
    space: object
    lift: Lifting | None
    loads: np.ndarray
    times: list
    u0: np.ndarray
    v0: np.ndarray
    M: sp.csr_matrix
    K: sp.csr_matrix
    B: sp.csr_matrix | None
    observe: dict
    x_obs: float | None


def beam_system(problem: BeamProblem, samples_per_element: int = 20,
                mass: str = "consistent") -> SemiDiscrete:
    """Discretise a beam scene (the papers' V_h, K_h of (8), loads with the lifting), in one
    bending plane or two (skfem_beam.two_planes): the planes' systems stacked
    block-diagonally, every obstacle a row at a node (skfem_beam.constraints).  ``mass``:
    "consistent", or "redistributed" (no inertia where the constraints act,
    skfem_beam.spaces.redistribution; one plane), from which the damping is built too."""
    if not isinstance(problem, BeamProblem):
        raise InputError(f"beam_system needs a BeamProblem, not {type(problem).__name__} "
                         "(a plate's system is skfem_beam.plate.plate_system)")
    one_plane = plane_problems(problem)
    spaces = [beam_space(p) for p in one_plane]
    rows = constraint_rows(problem, spaces[0])
    C, lo, hi, x_c = rows.arrays()
    sampler = spaces[0].sampler(np.linspace(0.0, 1.0, samples_per_element + 1))
    s_lo, s_hi = problem.obstacles.bounds(sampler.x)
    keep = np.isfinite(s_lo) | np.isfinite(s_hi)     # penetration samples: flat obstacles
    check_choice("beam_system mass", mass, ("consistent", "redistributed"))
    if mass == "redistributed" and problem.planes == 2:
        raise InputError("a redistributed mass is for one plane; planes = 2 takes the "
                         "consistent mass")
    massless = massless_dofs(C) if mass == "redistributed" else None
    planes = [_plane(p, space, massless) for p, space in zip(one_plane, spaces)]
    lift = next((p.lift for p in planes if p.lift is not None), None)
    motion, shift, s_shift, centres = moving_bounds(problem, lift, rows, sampler.x[keep])
    u0 = np.concatenate([p.u0 for p in planes])
    check_start(C @ u0, rows, motion, shift)
    return SemiDiscrete(
        M=_block_diagonal([p.M for p in planes]),
        K=_block_diagonal([p.K for p in planes]), C=C, lo=lo, hi=hi, x_contact=x_c,
        loads=_load_blocks([p.loads for p in planes]),
        load_time=[a for p in planes for a in p.times], u0=u0,
        v0=np.concatenate([p.v0 for p in planes]), observe=_observe(problem, planes),
        B=_block_diagonal([p.B for p in planes]), space=planes[0].space,
        sample_x=sampler.x[keep],
        sample_E=rows.in_plane(sampler.E0[np.flatnonzero(keep)].tocsr(), 0),
        sample_lo=s_lo[keep], sample_hi=s_hi[keep], meta=_meta(problem, planes),
        view=_view(problem, planes, lift), bound_motion=motion, bound_shift=shift,
        sample_shift=s_shift, planes=problem.planes,
        **_row_fields(problem, spaces[0], rows, x_c, centres))


def _plane(problem: BeamProblem, space, massless=None) -> _Plane:
    """One plane's lifting, loads, initial state, mass, stiffness, damping and observed
    row; ``massless``: None, or the dofs whose mass is redistributed away (one plane)."""
    lift, profiles, times = _lifting(problem, space) if problem.support.moves \
        else (None, [], [])
    loads, times = _load_columns(problem, space, profiles, times)
    u0, v0 = _initial(problem, space, lift)
    K = _stiffness(problem, space)
    M = space.M if massless is None else \
        redistribute(space.M, K, massless, rigid_modes(space))
    B = damping_matrix(problem.damping, M, K)
    if B is not None and lift is not None and lift.kind == "paper":
        loads = np.column_stack([loads, _damping_relative(problem, space, B)])
        times = times + [problem.support.phi_d]
    observe, x_obs = _observation(problem, space)
    return _Plane(problem, space, lift, loads, times, u0, v0, M, K, B, observe, x_obs)


def _block_diagonal(blocks):
    """The planes' matrices as diag(A₁, A₂) (one plane: A₁ itself; None: none)."""
    if len(blocks) == 1 or all(b is None for b in blocks):
        return blocks[0]
    return sp.block_diag(blocks, format="csr")


def _in_block(vector: np.ndarray, plane: int, planes: int) -> np.ndarray:
    """One plane's vector as a vector of all the unknowns (zero in the other plane)."""
    zero = np.zeros(vector.shape[0])
    return np.concatenate([vector if k == plane else zero for k in range(planes)])


def _load_blocks(loads: list) -> np.ndarray:
    """Each plane's load columns, zero in the other plane: [[L₁, 0], [0, L₂]]."""
    return np.hstack([np.vstack([a if j == k else np.zeros_like(a) for j in range(len(loads))])
                      for k, a in enumerate(loads)])


def _observe(problem: BeamProblem, planes: list) -> dict:
    """Each plane's observed rows (two planes: the names end in _v, _w), and with holes
    the orbit (v, w) at every hole node."""
    count, space = len(planes), planes[0].space
    suffixes = PLANE_SUFFIXES if count == 2 else ("",)
    observe = {f"{key}{suffix}": _in_block(row, k, count)
               for k, (p, suffix) in enumerate(zip(planes, suffixes))
               for key, row in p.observe.items()}
    nodes = problem.nodes
    for x in sorted({float(nodes[i]) for h in problem.holes
                     for i in np.flatnonzero(h.acts_at(nodes, problem.beam.L))}):
        ev = space.nodal[_node_of(nodes, x)].toarray().ravel()
        for k, suffix in enumerate(suffixes):
            observe[f"hole_{x:g}_displacement{suffix}"] = _in_block(ev, k, count)
    return observe


def _node_of(nodes: np.ndarray, x: float) -> int:
    return int(np.abs(nodes - x).argmin())


def _meta(problem: BeamProblem, planes: list) -> dict:
    beam = problem.beam
    meta = {"kind": "beam", "L": beam.L, "k2": beam.k2, "rho_S": beam.rho_S,
            "element": problem.element, "J": problem.J, "problem": problem}
    if len(planes) == 2:
        meta.update(planes=2, k2_w=planes[1].problem.beam.k2, n_plane=planes[0].space.n)
    return meta


def _view(problem: BeamProblem, planes: list, lift: Lifting | None) -> SceneView:
    """What the output needs; the lifting moves with the whole support (two planes: each
    plane's lifting moved with its share)."""
    beam, sup = problem.beam, problem.support
    paper = sup if problem.planes == 1 and problem.lifting == "paper" else None
    view = SceneView("beam", beam.L, beam.k2, paper, problem.obstacles, beam.rho_S, beam.EI,
                     None if lift is None else replace(lift, motion=sup), planes[0].x_obs)
    if len(planes) == 1:
        return view
    return replace(view, planes=2, direction=sup.direction,
                   k2_w=planes[1].problem.beam.k2, holes=problem.holes)


def _row_fields(problem: BeamProblem, space, rows, x_c, centres) -> dict:
    """SemiDiscrete's per-row fields: one plane, the obstacle giving each bound; two
    planes, the holes' (disks, lands, friction, tangent rows) and each row's node values
    and centre (SemiDiscrete's two-plane fields)."""
    if problem.planes == 1:
        return {"row_obstacle": problem.obstacles.owners(x_c)}
    nodal = [space.nodal[_node_of(problem.nodes, x)] for x in x_c]
    row_nodes = sp.vstack([sp.vstack([rows.in_plane(e, 0), rows.in_plane(e, 1)])
                           for e in nodal], format="csr") if nodal \
        else sp.csr_matrix((0, 2 * rows.n))
    return {"disks": np.array([d[:2] for d in rows.disks], dtype=np.int64).reshape(-1, 2),
            "lands": np.array(rows.lands, dtype=float).reshape(-1, 3)
            if any(land[0] > 0 for land in rows.lands) else None,
            "friction": friction(rows),
            "tangents": np.array([f[:2] for f in rows.faces], dtype=np.int64).reshape(-1, 2),
            "row_nodes": row_nodes, "row_centres": centres}


def _stiffness(problem: BeamProblem, space) -> sp.csr_matrix:
    """The stiffness k2·S."""
    k2 = problem.beam.k2
    with np.errstate(over="ignore", invalid="ignore"):
        K = (k2 * space.S).tocsr()
    if not np.isfinite(K.data).all():
        raise InputError(f"k2={k2:g} on this mesh gives a stiffness outside floating-point range")
    return K


def damping_matrix(damping, M, K):
    """B of a :class:`~skfem_beam.problem.Damping` (None, or none: None) with the mass M
    the run uses (a beam's or a plate's): a redistributed mass's massless rows get no
    mass-proportional or modal damping (built from the consistent mass they did, and the
    condensed modes' ratios were off by up to 2.5 % Rayleigh, 11 % modal, at J = 20)."""
    if damping is None or damping.none:
        return None
    B = (damping.alpha * M + damping.alpha_K * K).tocsr()
    return B + modal_damping(M, K, damping.modal) if damping.modal else B


def _observation(problem: BeamProblem, space):
    """({"tip_displacement": row}, x): the observed value's row (the tip, or the node of
    :func:`observed_node`) and its x (None at the tip)."""
    node = observed_node(problem, space)
    row = space.C[-1] if node is None else space.nodal[node]
    observe = {"tip_displacement": np.asarray(row.toarray()).ravel()}
    return observe, None if node is None else float(space.nodes[node])


def modal_damping(M, K, zeta: float) -> sp.csr_matrix:
    """M Φ diag(2ζω) Φᵀ M: the damping matrix giving every mode of K φ = ω²Mφ the ratio
    ζ (Φ mass-normalised, ΦᵀMΦ = I).  Dense.  The modes come from the inverted pencil
    M v = μ(K + sM)v, μ = 1/(ω² + s), whose error is relative to the lowest modes (see
    modes.py); the small shift s makes K + sM definite when the beam has rigid motions,
    which then get ω = 0 and no damping."""
    import scipy.linalg as sla
    Md, Kd = M.toarray(), K.toarray()
    s = 1e-8 * np.trace(Kd) / np.trace(Md)
    mu, V = sla.eigh(Md, Kd + s * Md)
    if not np.all(mu > 0):      # a redistributed mass: its massless directions, μ = 0, have
        keep = mu > 1e-12 * mu.max()        # M φ = 0 and take no damping
        mu, V = mu[keep], V[:, keep]
    omega = np.sqrt(np.maximum(1.0 / mu - s, 0.0))
    MPhi = Md @ (V / np.sqrt(mu))
    return sp.csr_matrix((MPhi * (2.0 * zeta * omega)) @ MPhi.T)


def observed_node(problem: BeamProblem, space) -> int | None:
    """The node the default series observes where the end at L is held (pinned,
    clamped: its value is prescribed, so its series would be identically zero): the node
    of largest first-mode amplitude (a uniform pinned–pinned beam: mid-span).  None: the
    tip x = L, whose value is free."""
    if space.nodes.size - 1 in space.value_nodes:
        return None
    values = np.abs(space.nodal @ modes(problem, 1).vectors[:, 0])
    return int(np.argmax(values))


def add_probes(system: SemiDiscrete, xs) -> list[dict]:
    """Observe a beam at each abscissa of ``xs``: three observer rows per x, in the lifted
    variable u, ``probe_<x>_displacement`` (u(x)), ``probe_<x>_moment`` (k²·EI(x)/EI_ref·u'';
    at an inner node of a Hermite mesh the mean of both sides: :func:`_both_sides`)
    and ``probe_<x>_shear`` (−k²·EI(x)/EI_ref·u''', the shear σ̃ of docs/design.md §1; u'''
    is constant on a cubic element, taken on the element to the right of a node).
    :func:`skfem_beam.output.probes.probe_columns` adds the lifting h(x)φ(t) and the units.
    Returns the probes (also kept in ``system.meta["probes"]``); x outside [0, L], twice,
    or on a bar is refused in one line."""
    problem = system.meta.get("problem")
    if system.meta.get("kind") != "beam" or problem is None:
        raise InputError("probes need a beam (bending moment and shear); this is a "
                         f"{system.meta.get('kind', 'unknown')} system")
    space, L, k2 = system.space, problem.beam.L, problem.beam.k2
    probes = system.meta.setdefault("probes", [])
    for x in np.atleast_1d(np.asarray(xs, dtype=float)).tolist():
        if not 0.0 <= x <= L:
            raise InputError(f"probe x={x:.10g} is outside the beam [0, L={L:.10g}]")
        name = f"probe_{x:g}"
        if any(p["name"] == name for p in probes):
            raise InputError(f"probe x={x:g} is given twice")
        e = min(int(np.searchsorted(space.nodes, x, side="right")) - 1, space.J - 1)
        a, b = float(space.nodes[e]), float(space.nodes[e + 1])
        ei = float(problem.beam.factors(0.5 * (a + b))[1])   # EI of that element
        rows = [space.point_rows([x], k).toarray().ravel() for k in (0, 2, 3)]
        both = _both_sides(space, problem, x)
        for suffix, k2_p, pad in plane_rows(system, k2):
            system.observe[f"{name}_displacement{suffix}"] = pad(rows[0])
            system.observe[f"{name}_moment{suffix}"] = k2_p * ei * pad(rows[1]) \
                if both is None else k2_p * pad(both)
            system.observe[f"{name}_shear{suffix}"] = -k2_p * ei * pad(rows[2])
        probes.append({"name": name, "x": x, "element": (a, b), "EI_factor": ei})
    return probes


def _both_sides(space, problem, x: float):
    """At an inner node, where u'' (Hermite) or EI (a step) jumps, the row of the mean of
    both sides' EI(x)/EI_ref·u'', as the bending_moment field takes it (the probe read the
    right side's: 0.52 against the field's 0.39 N·m; on a B-spline beam's step −3.6
    against −7.4 N·m); else None (a B-spline's u'' is continuous: only EI may jump)."""
    n = space.nodes
    j = int(np.argmin(np.abs(n - x)))
    if not 0 < j < len(n) - 1 or abs(n[j] - x) > 1e-12 * problem.beam.L:
        return None
    ei = [float(problem.beam.factors(0.5 * (n[k] + n[k + 1]))[1]) for k in (j - 1, j)]
    if getattr(space, "name", "") != "hermite":
        if ei[0] == ei[1]:
            return None
        return 0.5 * (ei[0] + ei[1]) * space.point_rows([n[j]], 2).toarray().ravel()
    left, right = (space.point_rows([n[j]], 2, side=s).toarray().ravel()
                   for s in ("left", "right"))
    return 0.5 * (ei[0] * left + ei[1] * right)


PLANE_SUFFIXES = ("_v", "_w")      # a two-plane column's name ends with its plane


def plane_rows(system, k2: float):
    """(suffix, k2, pad) per plane: one plane ("", k2, rows as they are); two planes the
    first and second plane's suffix ("_v", "_w"), k2, and rows placed in [v; w]."""
    if system.planes == 1:
        return [("", k2, lambda r: r)]
    n = system.meta["n_plane"]
    zero = np.zeros(n)
    return [("_v", k2, lambda r: np.concatenate([r, zero])),
            ("_w", system.meta["k2_w"], lambda r: np.concatenate([zero, r]))]
