"""A beam scene's parsed keys → a BeamProblem: the beam ([material] with [section],
[mass_normalised] or [[segments]], [mass] added), its ends, supports, obstacles, motion,
loads, [damping] and [initial] state (two planes: each plane's load and start)."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..checks import MAX_ELEMENTS, check_count, check_finite, check_positive
from ..errors import InputError
from ..problem import Beam, BeamProblem, Damping, InitialState, Plane
from .forcing import loads_of, support_of
from .obstacles import obstacles_and_holes
from .parts import in_section, material_of, need, plane_count, section_of
from .read import Tables


def _beam(data: dict) -> Beam:
    """The beam of [material] + [section], [mass_normalised] or [[segments]], with its
    [mass] added (kg/m, e.g. the fluid's hydrodynamic mass)."""
    beam = _structure(data)
    added = data.get("mass", {}).get("added")
    return beam if added is None else beam.with_added_mass(added)


def _structure(data: dict) -> Beam:
    mn, segs = data.get("mass_normalised"), data.get("segments")
    forms = [k for k in ("mass_normalised", "segments") if k in data] + \
        (["material/section"] if "material" in data or "section" in data else [])
    if len(forms) != 1:
        raise InputError("a beam needs one of [material] with [section], [mass_normalised] "
                         f"(k2, rho_S) or [[segments]] (got {', '.join(forms) or 'none'})")
    if segs is not None:
        if "geometry" in data:
            raise InputError("[[segments]] give the length: leave out [geometry]")
        return Beam.stepped([(check_positive(f"[segments.{i}] length", s.get("length", math.nan)),
                              material_of(s.get("material", {}), f"segments.{i}.material"),
                              section_of(s.get("section", {}), f"segments.{i}.section"))
                             for i, s in enumerate(segs)])
    L = need(data.get("geometry", {}), ("L",), "geometry")["L"]
    if mn is not None:
        return Beam(L, need(mn, ("k2",), "mass_normalised")["k2"], mn.get("rho_S"))
    return Beam.physical(L, material_of(data.get("material", {}), "material"),
                         section_of(data.get("section", {}), "section"))


def damping_of(data: dict) -> Damping:
    """[damping] (a beam's or a plate's): its refusals name the section ("zeta=2 must be
    below 1" named none)."""
    return in_section("damping", _damping_of, d=data.get("damping"))


def _damping_of(d: dict | None) -> Damping:
    if d is None:
        return Damping()
    if "modal" in d:
        if len(d) > 1:
            raise InputError("[damping] modal = ζ (every mode) stands alone: not with "
                             f"{', '.join(k for k in d if k != 'modal')}")
        return Damping(modal=d["modal"])
    if set(d) & {"zeta", "f1", "f2"}:
        if set(d) & {"alpha", "alpha_K"}:
            raise InputError("[damping] give zeta, f1, f2 or alpha, alpha_K, not both")
        return Damping.ratio(**need(d, ("zeta", "f1", "f2"), "damping"))
    return Damping(d.get("alpha", 0.0), d.get("alpha_K", 0.0))


def _spline(d: dict, name: str, value: str, L: float):
    """(f, f') of a {x, u} table over the beam [0, L]: a not-a-knot cubic spline."""
    pairs = need(d, ("x", value), f"initial.{name}")
    x = np.asarray(pairs["x"], dtype=float)
    tol = 1e-9 * L      # a table over half the beam, extrapolated, gave 4.4 mm at its tip
    if x.size and (abs(x.min()) > tol or abs(x.max() - L) > tol):
        raise InputError(f"[initial.{name}] x runs from {x.min():g} to {x.max():g} m: the "
                         f"table must cover the beam, 0 to L = {L:g} m (beyond its ends a "
                         "spline is extrapolated)")
    try:
        from scipy.interpolate import CubicSpline
        s = CubicSpline(x, np.asarray(pairs[value], dtype=float), bc_type="not-a-knot")
    except ValueError as e:
        raise InputError(f"[initial.{name}] table x = [...], {value} = [...]: {e}") from None
    return s, s.derivative()


def _initial(data: dict, problem: BeamProblem) -> BeamProblem:
    ini = data.get("initial", {})
    fixed = ini.get("fixed_frame", True)
    if "amplitude" in ini and "mode" not in ini:     # it was read and ignored
        raise InputError("[initial] amplitude scales a mode shape: it needs mode = k")
    if "mode" in ini and "amplitude" not in ini:     # it started the beam 1 m out
        raise InputError(f"[initial] mode = {ini['mode']!r} needs amplitude (m): the mode "
                         "shape's largest displacement")
    if "mode" in ini:
        if "u0" in ini:
            raise InputError("[initial] give mode or u0, not both")
        u0, du0 = _mode_shape(problem, ini["mode"], ini["amplitude"])
    elif "u0" in ini:
        u0, du0 = _spline(ini["u0"], "u0", "u", problem.beam.L)
    else:
        u0 = du0 = None
    v0 = _spline(ini["v0"], "v0", "v", problem.beam.L)[0] if "v0" in ini else None
    return replace(problem, initial=InitialState(u0, v0, du0, fixed_frame=fixed),
                   second=replace(problem.second,
                                  initial=_initial_w(data, fixed, problem.beam.L)))


def _initial_w(data: dict, fixed: bool, L: float) -> InitialState | None:
    """The second plane's start: [initial] u0_w = {x, u}, v0_w = {x, v} (None: at rest)."""
    ini = data.get("initial", {})
    given = [k for k in ("u0_w", "v0_w") if k in ini]
    if not given:
        return None
    if plane_count(data) != 2:
        raise InputError(f"[initial] {', '.join(given)} start the second plane: they need "
                         "planes = 2")
    u0, du0 = _spline(ini["u0_w"], "u0_w", "u", L) if "u0_w" in ini else (None, None)
    v0 = _spline(ini["v0_w"], "v0_w", "v", L)[0] if "v0_w" in ini else None
    return InitialState(u0, v0, du0, fixed_frame=fixed)


def _mode_shape(problem: BeamProblem, k, amplitude):
    """amplitude × the k-th mode shape (its largest |u| 1, on 50 samples per element)."""
    from ..modes import modes
    if isinstance(k, bool) or not isinstance(k, int) or k < 1:
        raise InputError(f"[initial] mode={k!r} must be a whole number ≥ 1")
    m = modes(problem, k, samples_per_element=50)
    v = m.vectors[:, k - 1] * (float(amplitude) / np.abs(m.shapes[:, k - 1]).max())
    space = m.space

    def shape(derivative):
        return lambda x: np.asarray(space.point_rows(np.ravel(x), derivative) @ v).reshape(
            np.shape(x))
    return shape(0), shape(1)


def _supports_x(data: dict) -> tuple:
    """[[supports]] x (BeamProblem checks where they lie; its refusals name supports[i],
    the file's [supports.i])."""
    return tuple(check_finite(f"[supports.{i}] x", s.get("x", math.nan))
                 for i, s in enumerate(data.get("supports", [])))


def beam_problem(data: dict, reader: Tables) -> BeamProblem:
    beam = _beam(data)
    ends = data.get("ends", {})
    mesh = data.get("mesh", {})
    if "J" in mesh and "nodes" in mesh:     # J was read and the nodes' elements ran
        raise InputError("[mesh] give J (a uniform mesh) or nodes, not both")
    obstacles, holes = obstacles_and_holes(data, beam.L)
    load, load_w = loads_of(data, reader, beam.L)
    try:
        problem = BeamProblem(
            beam, obstacles, support_of(data, beam.L, reader), load,
            J=check_count("[mesh] J", mesh.get("J", 19), most=MAX_ELEMENTS),
            element=mesh.get("element", "hermite"), nodes=mesh.get("nodes"),
            ends=(ends.get("left", "clamped"), ends.get("right", "free")),
            supports=_supports_x(data),
            damping=damping_of(data), planes=plane_count(data), holes=holes,
            second=Plane(load=load_w))
    except InputError as e:     # the mesh's refusals name its keys alone ("nodes must ...")
        text = str(e)
        if text.startswith("supports["):        # supports[1] x=...: the file's [supports.1]
            k, _, rest = text[len("supports["):].partition("]")
            raise InputError(f"[supports.{k}]{rest}") from None
        if not text.startswith(("nodes ", "element=")):
            raise
        raise InputError(f"[mesh] {e}") from None
    if problem.element == "bspline" and beam.steps:
        from ..cli import warn
        warn(f"element = \"bspline\" on a beam whose section steps at x = "
             f"{', '.join(f'{x:g}' for x in beam.steps)}: cubic B-splines are C² and cannot "
             "follow the jump of u'' there, so they converge at first order (frequencies "
             "off by 1–4 % at J = 20); element = \"hermite\" converges at h⁴")
    return _initial(data, problem)
