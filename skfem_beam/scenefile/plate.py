"""A plate's scene file (``kind = "plate"``) → the plate's objects (:mod:`skfem_beam.plate`):
the :class:`~skfem_beam.plate.Plate` from [geometry], [section], [material], [edges] and
[mesh]; its :class:`~skfem_beam.plate.PlateObstacle` from [[obstacles]], its
:class:`~skfem_beam.plate.Pressure` from [[loads]] (each with a time function of the
beam's, :mod:`.forcing`), its start from [initial], the probes from [output] and the
method from [contact] (the one vocabulary, :func:`skfem_beam.methods.make`).  Every value
is checked here or by the object it builds, in one line naming its key."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import methods
from ..checks import check_choice, check_count, check_finite, check_positive
from ..contact import SOLVERS
from ..errors import InputError
from ..plate.model import EDGES, ELEMENTS, MAX_PLATE_SIDE, SUPPORTS, MeshPlate, Plate
from ..scheme import Stepping
from .beam import damping_of
from .forcing import _time_function, warn_aliased, warn_tables
from .parts import named_section, need, stepping_of, warn_implausible
from .read import Parsed, Tables
from .schema import OUTPUT_DEFAULTS, PLATE_KEYS

PLATE_WORDS = methods.Words(solver="[contact] solver = ", massless="[mesh] massless = ",
                            law="[contact] law = ", restitution="[contact] restitution = ",
                            theta="[contact] theta = ", param="[contact] ",
                            stiffness="[contact] stiffness = ")
TIME_FORMS = ("amplitude", "omega", "phase", "value", "sines", "table", "random", "psd")


@dataclass(frozen=True)
class PlateSetup:
    """What a plate scene builds: its finite element ``space``, the ``system`` the scheme
    steps (None for ``modes``), the ``probes`` (x, y) whose w is written."""
    space: object
    system: object = None
    probes: tuple = ()


@dataclass(frozen=True)
class PlateScene:
    """A plate scene file read into the plate's objects (as :class:`.build.Scene` for a
    beam): ``problem`` a :class:`PlateSetup`, ``method`` the run's method, ``stepping``
    the time grid, ``output`` the [output] keys with their defaults, ``text``/``files``/
    ``data`` as a beam scene's; ``meshes`` the mesh file's bytes ([geometry] mesh: path
    as written → {"sha256", "base64"}, :meth:`.read.Tables.mesh`), stored with the run;
    ``beta``: the β summary.json records (the β-scheme method's, or for Moreau–Jean
    [time] beta or its default)."""
    kind: str
    problem: PlateSetup
    stepping: Stepping | None
    method: object = None
    output: dict = field(default_factory=dict)
    text: str = ""
    files: dict = field(default_factory=dict)
    data: dict = field(default_factory=dict)
    meshes: dict = field(default_factory=dict)

    @property
    def beta(self) -> float:
        return methods.recorded_beta(self.method, self.data.get("time", {}).get("beta"))


def plate_of(data: dict, base=None):
    """[geometry] a, b (a rectangle) or mesh (a file meshio reads, relative to ``base``:
    the scene file's folder, or its :class:`~.read.Tables`, which keep the file's bytes and
    give a resumed run its stored copy), [section] thickness, [material] E, rho, nu, [edges],
    [mesh]."""
    g = data.get("geometry", {})
    if "mesh" in g:
        return _mesh_plate(data, base)
    g = need(g, ("a", "b"), "geometry")
    for key, value in g.items():
        check_positive(f"[geometry] {key}", value)
    h, m = _section_material(data)
    edges = data.get("edges", {})
    for edge, support in edges.items():
        if edge not in EDGES:
            raise InputError(f"[edges] {edge!r} is not an edge of the rectangle: "
                             f"{', '.join(EDGES)}")
        check_choice(f"[edges] {edge}", support, SUPPORTS)
    mesh = data.get("mesh", {})
    element = check_choice("[mesh] element", mesh.get("element", "bfs"), ELEMENTS)
    nx, ny = (check_count(f"[mesh] {k}", mesh.get(k, 8), most=MAX_PLATE_SIDE)
              for k in ("nx", "ny"))
    return Plate(a=g["a"], b=g["b"], h=h, E=m["E"], rho=m["rho"], nu=m["nu"],
                 edges={e: edges.get(e, "free") for e in EDGES}, element=element,
                 nx=nx, ny=ny)


def _section_material(data: dict) -> tuple:
    """(h, {E, rho, nu}) from [section] and [material], checked."""
    h = need(data.get("section", {}), ("thickness",), "section")["thickness"]
    check_positive("[section] thickness", h)
    m = need(data.get("material", {}), ("E", "rho", "nu"), "material")
    check_positive("[material] E", m["E"])
    check_positive("[material] rho", m["rho"])
    if not -1.0 < m["nu"] < 0.5:
        raise InputError(f"[material] nu={m['nu']!r} must lie in (-1, 0.5)")
    warn_implausible(m, "material")
    return h, m


def _mesh_plate(data: dict, base) -> MeshPlate:
    """A plate on the triangles of [geometry] mesh, its [edges] by the file's boundary
    names."""
    from pathlib import Path

    from ..plate.meshfile import read_plate_mesh
    g = data["geometry"]
    if set(g) - {"mesh"}:
        raise InputError("[geometry] give a, b (a rectangle) or mesh (a file), not both")
    name = g["mesh"]
    if not isinstance(name, str):
        raise InputError(f"[geometry] mesh = {name!r} must be a file name (a string)")
    grid = data.get("mesh", {})
    element = grid.get("element", "argyris")
    if element == "bfs":
        raise InputError("[mesh] element = 'bfs' needs the rectangle's grid ([geometry] a, "
                         "b); a mesh file's plate takes morley or argyris")
    element = check_choice("[mesh] element", element, tuple(e for e in ELEMENTS if e != "bfs"))
    if "nx" in grid or "ny" in grid:
        raise InputError("[mesh] nx, ny are the rectangle's grid; a mesh file's plate has "
                         "its own triangles")
    h, m = _section_material(data)
    if isinstance(base, Tables):
        path = base.mesh(name)
    else:
        path = Path(name) if Path(name).is_absolute() or base is None else Path(base) / name
    mesh = read_plate_mesh(path, name)
    edges = data.get("edges", {})
    for edge, support in edges.items():
        if edge not in mesh.boundaries:
            raise InputError(f"[edges] {edge!r} is not a boundary of the mesh {name}; it has: "
                             f"{', '.join(mesh.boundaries) or '(no named lines)'}")
        check_choice(f"[edges] {edge}", support, SUPPORTS)
    return MeshPlate(mesh, h=h, E=m["E"], rho=m["rho"], nu=m["nu"], edges=dict(edges),
                     element=element)


def _region(value, space, where: str, area: bool) -> tuple:
    """region = [x0, y0, x1, y1] (m) on the plate (a mesh file's: in its bounding box),
    as (x0, x1, y0, y1) (plate.system.checked_region: ``area``, a load's, has both sides
    and a quadrature point; an obstacle's may be a line of vertices, and holds one)."""
    from ..plate.system import checked_region
    if len(value) != 4:
        raise InputError(f"{where} = {value!r} must be [x0, y0, x1, y1] (m)")
    x0, y0, x1, y1 = value
    return checked_region(where, (x0, x1, y0, y1), space, area, written=value)


def _point(value, plate: Plate, where: str) -> tuple[float, float]:
    """A point [x, y] (m) on the plate (a mesh file's: in its bounding box; the callers
    then ask for a vertex)."""
    if len(value) != 2:
        raise InputError(f"{where} = {value!r} must be a point [x, y] (m)")
    x, y = value
    bx0, bx1, by0, by1 = plate.box
    tol = 1e-9 * plate.size
    if not (bx0 - tol <= x <= bx1 + tol and by0 - tol <= y <= by1 + tol):
        raise InputError(f"{where} = {value!r} is off {plate.outline()} (m)")
    return float(x), float(y)


def obstacles_of(data: dict, space) -> list:
    """[[obstacles]] g1, g2 (m, at least one) over region or at points (a point must be
    a vertex of the mesh)."""
    from ..plate.system import PlateObstacle, bounds_act, vertex_index
    out = []
    for i, d in enumerate(data.get("obstacles", [])):
        where = f"obstacles.{i}"
        if "g1" not in d and "g2" not in d:
            raise InputError(f"[{where}] needs g1 and/or g2 (m)")
        if sum(k in d for k in ("region", "points", "disk")) > 1:
            raise InputError(f"[{where}] give one of region, disk, points")
        region = _region(d["region"], space, f"{where}.region", area=False) \
            if "region" in d else None
        points = tuple(_point(p, space.plate, f"{where}.points[{k}]")
                       for k, p in enumerate(d.get("points", [])))
        for k, (x, y) in enumerate(points):
            _vertex(space, x, y, f"{where}.points[{k}]", vertex_index)
        if "points" in d and not points:
            raise InputError(f"[{where}] points = [] names no vertex")
        g1, g2 = (_g(d[k], f"{where}.{k}") if k in d else default
                  for k, default in (("g1", -np.inf), ("g2", np.inf)))
        if not bounds_act(g1, g2):
            raise InputError(f"[{where}] g1 = -inf and g2 = inf: it would never act (give a "
                             "finite g1 and/or g2, m)")
        disk = _disk(d["disk"], space, f"{where}.disk") if "disk" in d else None
        out.append(PlateObstacle(g1, g2, region, points if "points" in d else None, disk))
    return out


def _disk(value, space, where: str) -> tuple:
    """disk = [xc, yc, r] (m): its centre on the plate (in a mesh's bounding box), r > 0,
    at least one vertex within it."""
    from ..plate.system import disk_vertices
    if not isinstance(value, list) or len(value) != 3:
        raise InputError(f"[{where.rsplit('.', 1)[0]}] disk = [xc, yc, r] (m): got {value!r}")
    xc, yc = _point(value[:2], space.plate, f"{where} centre")
    r = check_positive(f"{where} r", value[2])
    if not disk_vertices(space, (xc, yc, r)).any():
        raise InputError(f"{where} = [{xc:g}, {yc:g}, {r:g}] holds no vertex of the mesh: "
                         "a larger r, or a vertex within it")
    return xc, yc, r


def _g(value, where: str):
    """A plate's obstacle g(x, y): a number; { poly = [[c00, c01, ...], [c10, ...], ...],
    about = [x0, y0] }, Σ c_ij (x − x0)^i (y − y0)^j (row i: the power of x); or a table
    { x = [...], y = [...], g = [[...], ...] }, one row of g per y and one column per x,
    bilinear between them (a vertex outside the grid is refused where it is used)."""
    if not isinstance(value, dict):
        return value
    if set(value) in ({"poly"}, {"poly", "about"}):
        c = [[float(v) for v in row] for row in value["poly"]]
        about = value.get("about", (0.0, 0.0))
        if not c or not all(c) or len(about) != 2 \
                or not np.isfinite(np.concatenate([np.ravel(r) for r in c] + [about])).all():
            raise InputError(f"{where} = {{poly, about}}: poly is rows of finite numbers (row "
                             "i: the power of x) and about a point [x0, y0] (m)")
        x0, y0 = (float(v) for v in about)

        def poly(x, y):
            dx, dy = np.asarray(x, dtype=float) - x0, np.asarray(y, dtype=float) - y0
            return sum(cij * dx**i * dy**j for i, row in enumerate(c)
                       for j, cij in enumerate(row)) + 0.0 * dx
        return poly
    if set(value) == {"x", "y", "g"}:
        return _grid(value, where)
    raise InputError(f"{where} must be a number, {{ poly = [[c00, c01, ...], [c10, ...]], "
                     f"about = [x0, y0] }} or {{ x = [...], y = [...], g = [[...], ...] }} "
                     f"(got keys {', '.join(value)})")


def _grid(value, where: str):
    """The table g(x, y) = { x, y, g }, bilinear (scipy's RegularGridInterpolator)."""
    from scipy.interpolate import RegularGridInterpolator
    xs, ys = (np.asarray(value[k], dtype=float) for k in ("x", "y"))
    g = value["g"]
    if (xs.ndim != 1 or ys.ndim != 1 or min(xs.size, ys.size) < 2
            or np.any(np.diff(xs) <= 0) or np.any(np.diff(ys) <= 0)):
        raise InputError(f"{where} = {{x, y, g}}: x and y must increase, two values each "
                         "at least")
    if len(g) != ys.size or any(len(row) != xs.size for row in g):
        raise InputError(f"{where} = {{x, y, g}}: g needs one row per y ({ys.size}) of one "
                         f"value per x ({xs.size})")
    if not (np.isfinite(xs).all() and np.isfinite(ys).all() and np.isfinite(g).all()):
        raise InputError(f"{where} = {{x, y, g}}: x, y and g must be finite numbers (m)")
    table = RegularGridInterpolator((ys, xs), np.asarray(g, dtype=float))
    tol = 1e-9 * max(np.ptp(xs), np.ptp(ys))

    def grid(x, y):
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        off = (x < xs[0] - tol) | (x > xs[-1] + tol) | (y < ys[0] - tol) | (y > ys[-1] + tol)
        if np.any(off):
            k = np.flatnonzero(off)[0]
            raise InputError(f"{where}: the vertex ({x.flat[k]:g}, {y.flat[k]:g}) lies outside "
                             f"its table's x [{xs[0]:g}, {xs[-1]:g}], y [{ys[0]:g}, "
                             f"{ys[-1]:g}]")
        return table(np.column_stack([np.clip(y, ys[0], ys[-1]).ravel(),
                                      np.clip(x, xs[0], xs[-1]).ravel()])).reshape(x.shape)
    return grid


def _vertex(space, x: float, y: float, where: str, vertex_index) -> int:
    try:
        return vertex_index(space, x, y)
    except InputError as e:
        raise InputError(f"{where} = [{x:g}, {y:g}]: {e}") from None


def loads_of(data: dict, space, tables: Tables) -> list:
    """[[loads]] pressure (Pa) × a(t) (a time function of the beam's; none: a = 1),
    over region (none: the whole plate)."""
    from ..plate.system import Pressure, one
    out = []
    for i, d in enumerate(data.get("loads", [])):
        where = f"loads.{i}"
        time = {k: d[k] for k in TIME_FORMS if k in d}
        if "omega" in time and "amplitude" not in time:
            time["amplitude"] = 1.0          # the pressure (or force) is the amplitude
        a = _time_function(time, where, tables)
        a = one if a is None else a
        if "point" in d:
            out.append(_point_force(d, where, space, a))
            continue
        p = need(d, ("pressure",), where)["pressure"]
        region = _region(d["region"], space, f"{where}.region", area=True) \
            if "region" in d else None
        out.append(Pressure(check_finite(f"{where}.pressure", p), a, region))
    return out


def _point_force(d: dict, where: str, space, a):
    """[[loads]] point = [x, y], force = P (N) × a(t): a PointForce at that vertex."""
    from ..plate.system import PointForce
    if "pressure" in d or "region" in d:
        raise InputError(f"[{where}] a point force (point, force) takes no pressure or region")
    x, y = _point(d["point"], space.plate, f"{where}.point")
    P = check_finite(f"{where}.force", need(d, ("force",), where)["force"])
    force = PointForce(x, y, P, a)
    try:
        force.dof(space)
    except InputError as e:
        raise InputError(f"[{where}] point: {e}") from None
    return force


def initial_of(data: dict):
    """[initial] static_pressure (Pa: w⁰ the static deflection under it), velocity
    (m/s, uniform)."""
    from ..plate.system import PlateInitial, Pressure
    d = data.get("initial", {})
    static = Pressure(check_finite("[initial] static_pressure", d["static_pressure"])) \
        if "static_pressure" in d else None
    if "mode" in d and ("amplitude" not in d or static is not None):
        raise InputError("[initial] mode = k starts from the k-th mode shape: give its "
                         "amplitude (m, the largest |w|) and no static_pressure")
    if "amplitude" in d and "mode" not in d:
        raise InputError(f"[initial] amplitude = {d['amplitude']!r} scales a mode shape: "
                         "give the mode too (mode = k, k ≥ 1)")
    mode = check_count("[initial] mode", d["mode"]) if "mode" in d else 0
    return PlateInitial(static, check_finite("[initial] velocity", d.get("velocity", 0.0)),
                        mode, check_finite("[initial] amplitude", d.get("amplitude", 0.0)))


def probes_of(data: dict, space) -> tuple:
    """[output] probes = [[x, y], ...]: vertices of the mesh (none: the nearest the
    centre)."""
    from ..plate.system import vertex_index
    given = data.get("output", {}).get("probes")
    if given is None:
        x, y = space.vertices
        c = int(np.argmin(np.hypot(x - space.plate.centre[0], y - space.plate.centre[1])))
        return ((float(x[c]), float(y[c])),)
    points = tuple(_point(p, space.plate, f"output.probes[{k}]") for k, p in enumerate(given))
    seen = {}
    for k, (x, y) in enumerate(points):
        _vertex(space, x, y, f"output.probes[{k}]", vertex_index)
        first = seen.setdefault(vertex_index(space, x, y), k)
        if first != k:         # one column per vertex: a second one crashed the run
            raise InputError(f"output.probes[{k}] = [{x:g}, {y:g}] is the vertex of "
                             f"output.probes[{first}]: give each vertex once")
    return points


def method_of(data: dict) -> methods.Method:
    """[contact] law (position | moreau-jean | penalty, or a position-level solver's
    name as a beam scene's), solver, stiffness (N/m: the penalty law), restitution,
    theta (Moreau–Jean), and [time] beta (the β-scheme's)."""
    c = data.get("contact", {})
    law = c.get("law", "penalty" if "stiffness" in c else "position")
    solver = c.get("solver", "auto")
    if law in SOLVERS and law not in methods.LAWS:
        if "solver" in c:
            raise InputError(f"[contact] law = {law!r} names a solver: give it as law or "
                             "as solver, not both")
        law, solver = methods.split_law(law)
    check_choice("[contact] law", law, (*methods.LAWS, *SOLVERS))
    if law == "penalty" and "stiffness" not in c:
        raise InputError("[contact] law = 'penalty' needs stiffness (N/m)")
    if "stiffness" in c and law != "penalty":
        raise InputError(f"[contact] stiffness is the penalty spring: law = {law!r} does not "
                         "take it")
    if solver != "auto":
        check_choice("[contact] solver", solver, SOLVERS)
    try:
        return methods.make(law, solver, c.get("restitution", 0.0), c.get("stiffness"),
                            words=PLATE_WORDS,
                            params={**PLATE_KEYS["contact"].method_params(c),
                                    "beta": data.get("time", {}).get("beta")})
    except InputError as e:
        raise named_section(e) from None


def plate_scene(parsed: Parsed, tables: Tables, dynamic: bool = True) -> PlateScene:
    """The plate scene ``parsed`` (``dynamic=False``: the plate's space alone, for
    ``modes``)."""
    from ..plate.space import plate_space
    from ..plate.system import plate_system
    data = parsed.data
    space = plate_space(plate_of(data, tables))
    if not dynamic:
        return PlateScene("plate", PlateSetup(space), None, text=parsed.text,
                          files=tables.read, data=data, meshes=tables.meshes)
    t = data.get("time", {})
    if "dt" not in t or "T" not in t:
        raise InputError("[time] needs dt and T (s)")
    method = method_of(data)
    probes = probes_of(data, space)
    initial = initial_of(data)
    if initial.mode:        # the mode the plate has, named as the file writes it
        from ..plate.modes import check_mode_count
        check_mode_count(space, initial.mode, "[initial] mode")
    system = plate_system(space, obstacles_of(data, space), loads_of(data, space, tables),
                          initial, probes, damping_of(data))
    out = {**OUTPUT_DEFAULTS, **data.get("output", {})}
    stepping = stepping_of(t, out, load_window=t.get("load_window", "forward"))
    warn_aliased(parsed.data, stepping.dt)
    warn_tables(tables, stepping.T)
    return PlateScene("plate", PlateSetup(space, system, probes), stepping, method, out,
                      parsed.text, tables.read, data, tables.meshes)
