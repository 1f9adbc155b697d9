"""Field time series for ParaView: XDMF (``.xdmf`` + ``.h5``) and VTU (``.vtu`` + ``.pvd``).

One frame is written per :meth:`FieldWriter.write` call (coefficient vectors u, v and
the nodal contact forces λ), so a run can stream its output; :func:`write_fields`
writes all frames of a :class:`~skfem_beam.scheme.Result`.

The fields live as point data on a line mesh along the x axis (points padded to 3-D,
as VTK needs).  Its points are ``samples_per_element`` sub-points of every element
(ξ = 0, 1/s, …, (s−1)/s, and the end x = L), so the polyline ParaView draws follows
the cubic of a Hermite or B-spline field instead of its chord.  Arrays, per point:

- ``displacement``: the physical displacement ũ = u + h(x)φ(t) (m), in the fixed
  (ground) frame, for any lifting h of a moving support (``SceneView.lift``: the first
  paper's h or the static one); for the bar, the longitudinal u;
- ``displacement_vector``: (0, ũ, 0), for ParaView's *Warp By Vector*;
- ``velocity``: ũ_t = v + h(x)φ'(t) (m/s; v is the run's backward-difference velocity,
  φ' the support's own derivative);
- ``g1``, ``g2``: the obstacles in the same fixed frame as ũ (m), **NaN where there is
  none (±∞)**: an obstacle fixed to the ground stays at g, one carried by the moving
  support is drawn at g + φ(t), where it is at the frame's time; always present, so
  every time step of every scene has the same arrays;
- ``contact_force``: the nodal contact force at the constrained nodes, 0 elsewhere, in N
  for a beam whose ρS is known (ρS·λ: the ``contact_force_N`` of timeseries.csv; λ in
  m²/s², force per unit mass per length, when it is not); positive upwards; for the bar
  the obstacle's push R ≥ 0 at either end (Pa, or N with a cross-section A), as in
  timeseries.csv;
- ``bending_moment``: EI(x)ũ'' = ρS·k²(EI(x)/EI_ref)(u'' + h''φ) in N·m when ρS is known
  (per unit mass per length, m³/s², when not), beams only (spaces whose ``sampler``
  gives no second derivatives, e.g. P1, omit it).  Hermite u'' jumps at the nodes (and EI at a step): a
  node shared by two elements gets the mean of both sides.
"""
from __future__ import annotations

import errno
import os
import sys
import xml.etree.ElementTree as ET
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ..errors import InputError
from ..semidiscrete import SceneView
from .folder import atomic_write

FORMATS = ("xdmf", "vtu", "both", "none")


def physical_at(view, x: float, t, u, v=None, share: float = 1.0):
    """(ũ(x, t), ũ_t(x, t)) from the lifted values u(x), v(x) at times t: u + h(x)φ(t) and
    v + h(x)φ'(t) for any lifting (``view.lift``); ``share``: the plane's part of the
    support's direction (two planes); v None: (ũ, None).  h(x) within 1e-9 of 0 is 0 (the
    paper's h(L) is −5.6e-17 in floating point), and then u, v are returned as they are:
    the papers' columns stay bit for bit."""
    lift = None if view is None else view.lift
    h = 0.0 if lift is None else float(lift.h(np.array([x]))[0])
    if abs(h) <= 1e-9 or share == 0.0:
        return u, v
    h *= share
    t = np.asarray(t, dtype=float)
    return (np.asarray(u) + h * np.asarray(lift.motion.phi(t), dtype=float),
            None if v is None else np.asarray(v) + h * np.asarray(lift.motion.phi_d(t),
                                                                    dtype=float))


def physical_tip(view, t, u_tip, v_tip, share: float = 1.0):
    """:func:`physical_at` the tip L, or ``view.observed_x`` where the end at L is held."""
    X = view.L if view.observed_x is None else view.observed_x
    return physical_at(view, X, t, u_tip, v_tip, share)


@dataclass
class LineSamples:
    """The output line mesh of a system and the maps from coefficients to point values."""
    x: np.ndarray                 # (P,) abscissae, increasing, x[0] = 0, x[-1] = L
    cells: np.ndarray             # (P−1, 2) line cells
    E0: sp.csr_matrix             # values at the points = E0 @ u
    E2: sp.csr_matrix | None      # EI(x)/EI_ref · second derivatives = E2 @ u (None: not a beam)
    g1: np.ndarray                # obstacles at the points with the support at rest, NaN
    g2: np.ndarray                # where infinite (fixed ones where they are at every t)
    contact: np.ndarray           # (m,) point index of every constrained value
    k2: float | None = None       # bending stiffness per unit mass (beam) or None
    L: float = 1.0
    motion: object = None         # the moving support (phi, phi_d of t), or None
    h: np.ndarray | None = None   # the lifting h at the points (None: the support is at rest)
    h_dd: np.ndarray | None = None   # EI(x)/EI_ref · h'' at the points (beams)
    carried: tuple | None = None  # (g1, g2) of the obstacles carried by the support at
    fixed: tuple | None = None    # rest and of those fixed to the ground (±inf: none);
    #                               None when nothing is carried
    push: np.ndarray | None = None   # (m,) sign: the field's contact force is push·λ
    rho_S: float = 1.0            # forces and moments × this: N and N·m for a beam with ρS
    planes: int = 1               # 2: coefficients [v; w] (two_plane_fields)
    direction: tuple = (1.0, 0.0)  # two planes: the support's direction
    k2_w: float | None = None     # two planes: the second plane's k2
    row_planes: np.ndarray | None = None   # two planes: (m, 2) each row's force direction

    @property
    def points(self) -> np.ndarray:
        """(P, 3): the abscissae padded to 3-D (VTK and ParaView need 3-D points)."""
        return np.column_stack([self.x, np.zeros_like(self.x), np.zeros_like(self.x)])

    def obstacles_at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(g1, g2) at time t in the fixed frame of ũ, NaN where there is none: fixed
        obstacles where they are, carried ones moved by the support's φ(t)."""
        if self.carried is None:
            return self.g1, self.g2
        phi = float(self.motion.phi(t))
        lo = np.maximum(self.fixed[0], self.carried[0] + phi)
        hi = np.minimum(self.fixed[1], self.carried[1] + phi)
        return _nan_outside(lo), _nan_outside(hi)

    def fields(self, t: float, u, v, force) -> dict[str, np.ndarray]:
        """The point arrays of one frame (see the module docstring)."""
        if self.planes == 2:
            return self.two_plane_fields(t, u, v, force)
        u, v = np.asarray(u, dtype=float), np.asarray(v, dtype=float)
        disp, vel = self.E0 @ u, self.E0 @ v
        moment = self.E2 @ u if self.E2 is not None else None
        if self.h is not None:
            phi = float(self.motion.phi(t))
            disp = disp + self.h * phi
            vel = vel + self.h * float(self.motion.phi_d(t))
            if moment is not None:
                moment = moment + self.h_dd * phi
        lam = np.zeros(self.x.size)
        lam[self.contact] = self.rho_S * np.asarray(force, dtype=float) * \
            (1.0 if self.push is None else self.push)
        g1, g2 = self.obstacles_at(t)
        out = {"displacement": disp,
               "displacement_vector": np.column_stack([np.zeros_like(disp), disp,
                                                       np.zeros_like(disp)]),
               "velocity": vel, "g1": g1, "g2": g2, "contact_force": lam}
        if moment is not None:
            out["bending_moment"] = self.rho_S * self.k2 * moment
        return out

    def two_plane_fields(self, t: float, u, v, force) -> dict[str, np.ndarray]:
        """Two planes: each plane's ũ as a one-plane field (``displacement_v``, ``_w``,
        likewise velocity and bending moment) and the vectors (0, ũ_v, ũ_w) of the
        displacement, the velocity and the nodal contact force (Warp By Vector shows the
        whirl)."""
        u, v = np.asarray(u, dtype=float), np.asarray(v, dtype=float)
        n = u.size // 2
        out, vec = {}, {}
        for c, (suffix, share, k2) in enumerate(zip(("_v", "_w"), self.direction,
                                                     (self.k2, self.k2_w))):
            one = LineSamples(**{**self.__dict__, "planes": 1, "k2": k2, "push": None,
                                 "h": None if self.h is None or share == 0.0
                                 else share * self.h,
                                 "h_dd": None if self.h_dd is None or share == 0.0
                                 else share * self.h_dd,
                                 "carried": None})
            f = one.fields(t, u[c * n:(c + 1) * n], v[c * n:(c + 1) * n],
                           np.zeros(self.contact.size))
            for key in ("displacement", "velocity", "bending_moment"):
                if key in f:
                    out[f"{key}{suffix}"] = f[key]
            vec[c] = (f["displacement"], f["velocity"])
        lam = np.zeros((self.x.size, 2))
        np.add.at(lam, self.contact, self.rho_S * np.asarray(force, dtype=float)[:, None]
                  * self.row_planes)
        zero = np.zeros(self.x.size)
        out.update({"displacement_vector": np.column_stack([zero, vec[0][0], vec[1][0]]),
                    "velocity_vector": np.column_stack([zero, vec[0][1], vec[1][1]]),
                    "contact_force_vector": np.column_stack([zero, lam[:, 0], lam[:, 1]]),
                    "g1": self.g1, "g2": self.g2})
        return out


def _nan_outside(g: np.ndarray) -> np.ndarray:
    """±inf (no obstacle) as NaN, which ParaView leaves undrawn."""
    return np.where(np.isfinite(g), g, np.nan)


def _split_obstacles(obstacles, x: np.ndarray):
    """((g1, g2) of the carried parts, (g1, g2) of the fixed ones) at x, ±inf where none."""
    parts = obstacles.parts or (obstacles,)
    out = []
    for carried in (True, False):
        b = [o.bounds(x) for o in parts if bool(o.carried) == carried]
        out.append((np.max([lo for lo, _ in b], axis=0) if b else np.full(x.shape, -np.inf),
                    np.min([hi for _, hi in b], axis=0) if b else np.full(x.shape, np.inf)))
    return out[0], out[1]


def _side_values(f, space, x_elem: np.ndarray, s: int) -> np.ndarray:
    """f at the sub-points of every element, taken from inside the element: an element's
    last sub-point is evaluated 1e-12 of its length before its end node, so a shared node
    gets both one-sided values (h'' of a static lifting jumps where EI does)."""
    j = np.arange(x_elem.size) % (s + 1)
    e = np.arange(x_elem.size) // (s + 1)
    h = np.diff(space.nodes)[e]
    return np.asarray(f(np.where(j == s, x_elem - 1e-12 * h, x_elem)), dtype=float)


def sample_line(system, samples_per_element: int = 8) -> LineSamples:
    """The output line of ``system`` (a :class:`~skfem_beam.semidiscrete.SemiDiscrete`)."""
    s = samples_per_element
    if isinstance(s, bool) or int(s) != s or s < 1:
        raise InputError(f"samples_per_element={s!r} must be a whole number ≥ 1")
    s = int(s)
    space = system.space
    if space is None or not hasattr(space, "sampler"):
        raise InputError("field output needs a space with a sampler (Hermite, B-spline, P1)")
    smp = space.sampler(np.linspace(0.0, 1.0, s + 1))
    x, R, e = _line_points(space, smp, s)
    E0 = (R @ smp.E0).tocsr()

    view = system.view or SceneView(kind="beam" if system.meta.get("kind", "beam") == "beam"
                                    else "bar")
    beam = view.kind == "beam" and smp.E2 is not None and smp.E2.nnz > 0
    EIf = _element_EI(system, space, e) if beam else None
    E2 = (R @ (smp.E2 if EIf is None else sp.diags(EIf) @ smp.E2)).tocsr() if beam else None

    L = float(view.L if view.L is not None else x[-1])
    lift = view.lift
    h, h_dd = (None, None) if lift is None else \
        _lift_values(lift, x, (space, smp, s, R), beam, EIf)
    g1, g2, contact, carried, fixed = _obstacle_lines(system, view, x, L)
    cells = np.column_stack([np.arange(x.size - 1), np.arange(1, x.size)])
    return LineSamples(x=x, cells=cells, E0=E0, E2=E2, g1=_nan_outside(g1),
                       g2=_nan_outside(g2), contact=contact,
                       k2=view.k2 if beam else None, L=L,
                       motion=None if lift is None else lift.motion, h=h, h_dd=h_dd,
                       carried=carried, fixed=fixed, push=_push(system, view),
                       rho_S=float(view.rho_S or 1.0) if beam else 1.0,
                       **_two_plane_entries(system, view))


def _line_points(space, smp, s: int):
    """(x, R, e): the line's points, the matrix R averaging the sampler's rows onto them
    and the element of every sampler row.  Keeps ξ = 0..(s−1)/s of every element and the
    last end; a node shared by two elements averages its two one-sided rows (equal for
    values; u'' may jump)."""
    J = space.nodes.size - 1
    e, j = np.divmod(np.arange(J * (s + 1)), s + 1)
    point = e * s + j
    shared = ((j == 0) & (e > 0)) | ((j == s) & (e < J - 1))
    R = sp.csr_matrix((np.where(shared, 0.5, 1.0), (point, np.arange(point.size))),
                      shape=(J * s + 1, point.size))
    x = np.empty(J * s + 1)
    x[point] = smp.x
    x[0], x[-1] = space.nodes[0], space.nodes[-1]
    return x, R, e


def _element_EI(system, space, e):
    """EI/EI_ref of the element of every sampler row (a stepped beam's moment is
    EI(x)u''), or None for a uniform beam."""
    problem = system.meta.get("problem")
    if problem is None or not problem.beam.segments:
        return None
    return problem.beam.factors(0.5 * (space.nodes[:-1] + space.nodes[1:]))[1][e]


def _lift_values(lift, x, sampling, beam: bool, EIf):
    """(h, h_dd) of the lifting at the points x: h'' only for a beam, evaluated at the
    points when smooth (the paper's h), else per side and averaged like u''.
    ``sampling``: (space, sampler, s, R) of :func:`_line_points`."""
    space, smp, s, R = sampling
    h, h_dd = np.asarray(lift.h(x), dtype=float), None
    if beam and lift.kind == "paper":          # smooth: evaluated at the points
        h_dd = np.asarray(lift.h_dd(x), dtype=float)
    elif beam:                                 # per side, averaged like u''
        side = _side_values(lift.h_dd, space, smp.x, s)
        h_dd = R @ (side if EIf is None else EIf * side)
    return h, h_dd


def _two_plane_entries(system, view) -> dict:
    """The LineSamples entries of a two-plane system (none for one plane)."""
    if view.planes != 2:
        return {}
    from ..scheme.beta import hole_arrays, row_planes
    pair, *_, Nc = hole_arrays(system)
    return {"planes": 2, "direction": view.direction, "k2_w": view.k2_w,
            "row_planes": row_planes(pair, Nc)}


def _push(system, view):
    """The bar's field force is the obstacle's push R ≥ 0, as in timeseries.csv: λ at a
    lower bound (x = 0), −λ at an upper one (x = L, where U = −u(L)); None for a beam."""
    if view.kind != "bar":
        return None
    return np.where(np.isfinite(np.asarray(system.lo, dtype=float)), 1.0, -1.0)


def _obstacle_lines(system, view, x, L):
    """g1, g2 at the points x (−∞/+∞ where there is none), the points of the constrained
    values, and the carried/fixed parts of the obstacles when a support moves them."""
    g1 = np.full(x.size, -np.inf)
    g2 = np.full(x.size, np.inf)
    contact = np.abs(x[:, None] - np.asarray(system.x_contact)[None, :]).argmin(axis=0)
    near = np.abs(x[contact] - system.x_contact) <= 1e-9 * max(1.0, L)
    if not near.all():
        raise InputError(f"constrained value at x={system.x_contact[~near][0]:g} is not a node")
    carried = fixed = None
    if view.obstacles is not None:
        g1, g2 = view.obstacles.bounds(x)
        if view.lift is not None and view.obstacles.carried:   # combine: any part carried
            carried, fixed = _split_obstacles(view.obstacles, x)
    else:
        g1[contact], g2[contact] = system.lo, system.hi
    return g1, g2, contact, carried, fixed


def check_format(fmt: str, flag: str = "--format ") -> str:
    """``fmt`` if it is one of FORMATS; else one clear error line."""
    if fmt not in FORMATS:
        raise InputError(f"{flag}{fmt!r} is not one of: {', '.join(FORMATS)}")
    return fmt


H5_MARGIN = 1 << 20   # bytes a disk keeps free below which no HDF5 frame is written


def _h5py_dealloc(tb) -> bool:
    """Whether a traceback ends in h5py freeing an object id (``ObjectID._dealloc``)."""
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    return tb is not None and "h5py" in tb.tb_frame.f_code.co_filename


@contextmanager
def _quiet_h5py_dealloc():
    """After a failed write (a full disk) h5py reports every object it can no longer
    flush as it frees it: a traceback and "Exception ignored in ObjectID.__dealloc__"
    each, through sys.excepthook and sys.unraisablehook, before the write's own OSError
    reaches the run, whose one line says what failed.  Those reports are dropped here;
    anything else goes to the hooks as usual."""
    excepthook, unraisablehook = sys.excepthook, sys.unraisablehook

    def on_except(kind, value, tb):
        if not _h5py_dealloc(tb):
            excepthook(kind, value, tb)

    def on_unraisable(u):
        if "h5py" not in f"{u.err_msg} {u.object!r}":
            unraisablehook(u)
    sys.excepthook, sys.unraisablehook = on_except, on_unraisable
    try:
        yield
    finally:
        sys.excepthook, sys.unraisablehook = excepthook, unraisablehook


class FieldWriter:
    """Write field frames of ``system`` into ``folder`` as ``name.xdmf`` (+ ``name.h5``)
    and/or ``name.pvd`` (+ ``name_vtu/name_NNNNNN.vtu``).

    Use as a context manager; the files are complete after :meth:`close` (or
    :meth:`flush`, which also makes them readable during a run).
    """

    _indexed = None     # how many frames the written indexes list (None: none written yet)

    def __init__(self, folder, system, fmt: str = "both", samples_per_element: int = 8,
                 name: str = "fields"):
        check_format(fmt, "format=")
        self.folder = Path(folder)
        if not self.folder.is_dir():
            raise InputError(f"field output folder {self.folder} does not exist")
        self.fmt, self.name = fmt, name
        self.line = sample_line(system, samples_per_element)
        self.m = system.C.shape[0]
        self.n = system.n
        self.times: list[float] = []
        self._vtu_files: list[str] = []
        self._xdmf = None
        self.closed = False
        if fmt in ("xdmf", "both"):
            from .xdmf import XdmfSeries    # meshio and h5py: loaded with a run's first frame
            self._room_for_hdf5()           # the mesh's datasets are written now
            self._xdmf = XdmfSeries(self.folder / f"{name}.xdmf").__enter__()
            self._xdmf.write_points_cells(self.line.points, [("line", self.line.cells)])
        if fmt in ("vtu", "both"):
            (self.folder / f"{name}_vtu").mkdir(exist_ok=True)

    @property
    def paths(self) -> list[Path]:
        """The files this writer makes (the VTU frames are listed in the ``.pvd``)."""
        out = []
        if self.fmt in ("xdmf", "both"):
            out += [self.folder / f"{self.name}.xdmf", self.folder / f"{self.name}.h5"]
        if self.fmt in ("vtu", "both"):
            out.append(self.folder / f"{self.name}.pvd")
        return out

    def write(self, t: float, u, v, force) -> None:
        """One frame: time t, coefficients u and v, nodal contact forces λ (one per C row)."""
        with _quiet_h5py_dealloc():
            self._write(t, u, v, force)

    def _write(self, t: float, u, v, force) -> None:
        if self.closed:
            raise ValueError("write() on a closed FieldWriter")
        u, v = np.asarray(u, dtype=float), np.asarray(v, dtype=float)
        force = np.zeros(self.m) if force is None else np.asarray(force, dtype=float)
        if u.shape != (self.n,) or v.shape != (self.n,) or force.shape != (self.m,):
            raise ValueError(f"frame shapes u{u.shape}, v{v.shape}, force{force.shape}; "
                             f"expected ({self.n},), ({self.n},), ({self.m},)")
        t = float(t)
        data = self.line.fields(t, u, v, force)
        if self._xdmf is not None:
            self._room_for_hdf5()
            self._xdmf.write_data(t, point_data=data)
        if self.fmt in ("vtu", "both"):
            rel = f"{self.name}_vtu/{self.name}_{len(self.times):06d}.vtu"
            import meshio
            mesh = meshio.Mesh(self.line.points, [("line", self.line.cells)], point_data=data)
            # uncompressed: zlib's set-up per array was 60% of a frame's time (docs/design.md)
            meshio.write(self.folder / rel, mesh, file_format="vtu", compression=None)
            self._vtu_files.append(rel)
        self.times.append(t)

    def _write_pvd(self) -> None:
        # meshio has no PVD (collection) writer: this small XML is the ParaView format
        root = ET.Element("VTKFile", type="Collection", version="0.1",
                          byte_order="LittleEndian")
        coll = ET.SubElement(root, "Collection")
        for t, rel in zip(self.times, self._vtu_files):
            ET.SubElement(coll, "DataSet", timestep=repr(t), group="", part="0", file=rel)
        ET.indent(root)
        atomic_write(self.folder / f"{self.name}.pvd", lambda fh: ET.ElementTree(root).write(
            fh, xml_declaration=True, encoding="utf-8"), binary=True)

    def flush(self) -> None:
        """Write the XML indexes now, so the files already read back as they are."""
        with _quiet_h5py_dealloc():
            self._flush()

    def _flush(self) -> None:
        if not self.closed:
            self._index()

    def _index(self) -> None:
        if self._indexed == len(self.times):
            return      # they list every frame already (a run's last update, then close)
        if self._xdmf is not None:
            self._xdmf.flush()
        if self.fmt in ("vtu", "both"):
            self._write_pvd()
        self._indexed = len(self.times)

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        with _quiet_h5py_dealloc():
            self._close()

    def _close(self) -> None:
        try:
            self._index()
        finally:
            self._close_h5()

    def _room_for_hdf5(self) -> None:
        """HDF5 does not survive a full disk: a write that fails half way leaves its
        metadata dirty, and the library then crashes (a segmentation fault, measured 1 run
        in 3 on a 3 MiB disk) instead of returning the error.  So a frame is written only
        while H5_MARGIN bytes are free; below that the disk counts as full (ENOSPC), as it
        will be in a moment, and the run stops on its one error line."""
        st = os.statvfs(self.folder)
        if st.f_bavail * st.f_frsize < H5_MARGIN:
            raise OSError(errno.ENOSPC, f"{os.strerror(errno.ENOSPC)} (less than "
                          f"{H5_MARGIN >> 20} MiB left for {self.name}.h5)")

    def _close_h5(self) -> None:
        """Close the .h5 whatever happened: a file left open after a failed write (a full
        disk) is flushed again when the interpreter exits, and HDF5 then fails with
        tracebacks or a segmentation fault instead of the run's one error line."""
        h5 = getattr(self._xdmf, "h5_file", None)
        if h5 is None:
            return
        for _ in range(2):            # a failed flush on close leaves the id open: again
            try:
                if h5.id.valid:
                    h5.close()
            except Exception:         # noqa: BLE001  (its error is the disk's, said already)
                continue
            return

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def write_fields(folder, result, fmt: str = "both", samples_per_element: int = 8,
                 name: str = "fields", every: int = 1) -> list[Path]:
    """Write every ``every``-th frame of ``result`` (frames are already decimated by
    ``solve(frames=…)``); return the files made (none for ``fmt="none"``).  Frames whose
    coefficients are not finite (never reached, or a blown-up run) are left out."""
    if isinstance(every, bool) or int(every) != every or every < 1:
        raise InputError(f"every={every!r} must be a whole number ≥ 1")
    if fmt == "none":
        return []
    with FieldWriter(folder, result.system, fmt, samples_per_element, name) as w:
        for k in range(0, result.frames_t.size, int(every)):
            if not np.isfinite(result.frames_u[k]).all():
                continue
            w.write(result.frames_t[k], result.frames_u[k], result.frames_v[k],
                    result.frames_force[k])
    return w.paths
