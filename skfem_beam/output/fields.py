"""Field time series for ParaView: XDMF (``.xdmf`` + ``.h5``) and VTU (``.vtu`` + ``.pvd``).

One frame is written per :meth:`FieldWriter.write` call (coefficient vectors u, v and
the nodal contact forces λ), so a run can stream its output; :func:`write_fields`
writes all frames of a :class:`~skfem_beam.scheme.Result`.

The fields live as point data on a line mesh along the x axis (points padded to 3-D,
as VTK needs).  Its points are ``samples_per_element`` sub-points of every element
(ξ = 0, 1/s, …, (s−1)/s, and the end x = L), so the polyline ParaView draws follows
the cubic of a Hermite or B-spline field instead of its chord.  Arrays, per point:

- ``displacement``: the physical displacement ũ = u + h(x)φ(t) (m); the support motion
  φ is added only when the scene's support moves; for the bar, the longitudinal u;
- ``displacement_vector``: (0, ũ, 0), for ParaView's *Warp By Vector*;
- ``velocity``: ũ_t = v + h(x)φ'(t) (m/s; v is the run's backward-difference velocity);
- ``g1``, ``g2``: the obstacles (m), **NaN where there is none (±∞)** — always present,
  so every time step of every scene has the same arrays;
- ``contact_force``: the nodal contact force λ at the constrained nodes, 0 elsewhere
  (m²/s² for the beam: force per unit mass per length; N/m² for the bar);
- ``bending_moment``: k²ũ'' = k²(u'' + h''φ) (m³/s², per unit mass per length), beams
  only (spaces whose ``sampler`` gives no second derivatives, e.g. P1, omit it).  Hermite
  u'' jumps at the nodes; a node shared by two elements gets the mean of both sides.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import h5py
import meshio
import numpy as np
import scipy.sparse as sp
from meshio._common import write_xml

from ..errors import InputError
from ..problem import lifting
from ..semidiscrete import SceneView

FORMATS = ("xdmf", "vtu", "both", "none")


def lifting_dd(x, L):
    """h''(x) of :func:`~skfem_beam.problem.lifting`: −4(1 − s)²/L², s = x/L."""
    s = np.asarray(x, dtype=float) / L
    return -4.0 * (1.0 - s) ** 2 / L**2


def _phi_dot(support, t: float) -> float:
    """φ'(t) of a support: its own ``phi_d`` if it has one, else a 4th-order difference."""
    if hasattr(support, "phi_d"):
        return float(support.phi_d(t))
    d = 1e-5 / max(1.0, abs(getattr(support, "omega", 1.0)))
    f = support.phi
    return float((f(t - 2 * d) - 8 * f(t - d) + 8 * f(t + d) - f(t + 2 * d)) / (12 * d))


@dataclass
class LineSamples:
    """The output line mesh of a system and the maps from coefficients to point values."""
    x: np.ndarray                 # (P,) abscissae, increasing, x[0] = 0, x[-1] = L
    cells: np.ndarray             # (P−1, 2) line cells
    E0: sp.csr_matrix             # values at the points = E0 @ u
    E2: sp.csr_matrix | None      # second derivatives = E2 @ u (None: not a beam space)
    g1: np.ndarray                # obstacles at the points, NaN where infinite
    g2: np.ndarray
    contact: np.ndarray           # (m,) point index of every constrained value
    k2: float | None = None       # bending stiffness per unit mass (beam) or None
    support: object = None        # a moving Support, or None
    L: float = 1.0

    @property
    def points(self) -> np.ndarray:
        """(P, 3): the abscissae padded to 3-D (VTK and ParaView need 3-D points)."""
        return np.column_stack([self.x, np.zeros_like(self.x), np.zeros_like(self.x)])

    def fields(self, t: float, u, v, force) -> dict[str, np.ndarray]:
        """The point arrays of one frame (see the module docstring)."""
        u, v = np.asarray(u, dtype=float), np.asarray(v, dtype=float)
        disp, vel = self.E0 @ u, self.E0 @ v
        moment = self.E2 @ u if self.E2 is not None else None
        if self.support is not None:
            h = lifting(self.x, self.L)
            phi = float(self.support.phi(t))
            disp = disp + h * phi
            vel = vel + h * _phi_dot(self.support, t)
            if moment is not None:
                moment = moment + lifting_dd(self.x, self.L) * phi
        lam = np.zeros(self.x.size)
        lam[self.contact] = np.asarray(force, dtype=float)
        out = {"displacement": disp,
               "displacement_vector": np.column_stack([np.zeros_like(disp), disp,
                                                       np.zeros_like(disp)]),
               "velocity": vel, "g1": self.g1, "g2": self.g2, "contact_force": lam}
        if moment is not None:
            out["bending_moment"] = self.k2 * moment
        return out


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
    J = space.nodes.size - 1
    # keep ξ = 0..(s−1)/s of every element and the last end; a node shared by two
    # elements averages its two one-sided rows (equal for values; u'' may jump)
    e, j = np.divmod(np.arange(J * (s + 1)), s + 1)
    point = e * s + j
    shared = ((j == 0) & (e > 0)) | ((j == s) & (e < J - 1))
    R = sp.csr_matrix((np.where(shared, 0.5, 1.0), (point, np.arange(point.size))),
                      shape=(J * s + 1, point.size))
    x = np.empty(J * s + 1)
    x[point] = smp.x
    x[0], x[-1] = space.nodes[0], space.nodes[-1]
    E0 = (R @ smp.E0).tocsr()
    E2 = (R @ smp.E2).tocsr() if smp.E2 is not None and smp.E2.nnz else None

    view = system.view or SceneView(kind="beam" if system.meta.get("kind", "beam") == "beam"
                                    else "bar")
    L = float(view.L if view.L is not None else x[-1])
    g1 = np.full(x.size, -np.inf)
    g2 = np.full(x.size, np.inf)
    contact = np.abs(x[:, None] - np.asarray(system.x_contact)[None, :]).argmin(axis=0)
    near = np.abs(x[contact] - system.x_contact) <= 1e-9 * max(1.0, L)
    if not near.all():
        raise InputError(f"constrained value at x={system.x_contact[~near][0]:g} is not a node")
    if view.obstacles is not None:
        g1, g2 = view.obstacles.bounds(x)
    else:
        g1[contact], g2[contact] = system.lo, system.hi
    g1 = np.where(np.isfinite(g1), g1, np.nan)
    g2 = np.where(np.isfinite(g2), g2, np.nan)
    k2 = view.k2 if view.kind == "beam" else None
    cells = np.column_stack([np.arange(x.size - 1), np.arange(1, x.size)])
    return LineSamples(x=x, cells=cells, E0=E0, E2=E2 if k2 is not None else None,
                       g1=g1, g2=g2, contact=contact, k2=k2, support=view.support, L=L)


class _XdmfSeries(meshio.xdmf.TimeSeriesWriter):
    """meshio's XDMF time series writer with the traps of docs/design.md §6 worked around.

    - meshio opens the ``.h5`` in the *working directory* (``filename.stem + ".h5"``);
      here it is opened beside the ``.xdmf`` (the XML refers to it by base name, so the
      reference stays relative to the ``.xdmf``, as XDMF readers resolve it).
    - meshio writes line cells as ``TopologyType="Polyline"`` without
      ``NodesPerElement``; ParaView 5.11's Xdmf3 reader aborts the process (SIGABRT,
      measured) on that, so the attribute (2: straight segments) is added.
    - meshio keeps the mesh in a separate ``<Grid Name="mesh">`` beside the temporal
      collection; ParaView's Xdmf2 reader shows it as a second, stale block.  Here the
      mesh lives in the first time step and the others include it from there (the
      layout FEniCS writes), which both ParaView readers, VTK's and meshio's read.
    Only the in-memory XML tree that meshio builds is edited; meshio writes the files.
    """

    _pointer = ('xpointer(//Grid[@Name="TimeSeries_meshio"]/Grid[1]'
                '/*[self::Topology or self::Geometry])')

    def __enter__(self):
        self.h5_filename = str(self.filename.with_suffix(".h5"))
        self.h5_file = h5py.File(self.h5_filename, "w")
        return self

    def write_points_cells(self, points, cells):
        super().write_points_cells(points, cells)
        self._mesh = self.domain.find(f"Grid[@Name='{self.mesh_name}']")
        self.domain.remove(self._mesh)
        for topo in self._mesh.iter("Topology"):
            if topo.get("TopologyType") == "Polyline" and "NodesPerElement" not in topo.attrib:
                topo.set("NodesPerElement", "2")

    def write_data(self, t, point_data=None, cell_data=None):
        super().write_data(t, point_data, cell_data)
        steps = list(self.collection)
        grid = steps[-1]
        grid.set("GridType", "Uniform")
        include = grid[0]             # meshio's xi:include of the mesh grid
        if len(steps) == 1:           # the first step holds the mesh itself
            grid.remove(include)
            for k, item in enumerate(self._mesh):
                grid.insert(k, item)
        else:
            include.set("xpointer", self._pointer)

    def flush(self):
        """Make the files readable as they are now (meshio writes the XML only at exit)."""
        write_xml(self.filename, self.xdmf_file)
        self.h5_file.flush()


def check_format(fmt: str, flag: str = "--format ") -> str:
    """``fmt`` if it is one of FORMATS; else one clear error line."""
    if fmt not in FORMATS:
        raise InputError(f"{flag}{fmt!r} is not one of: {', '.join(FORMATS)}")
    return fmt


class FieldWriter:
    """Write field frames of ``system`` into ``folder`` as ``name.xdmf`` (+ ``name.h5``)
    and/or ``name.pvd`` (+ ``name_vtu/name_NNNNNN.vtu``).

    Use as a context manager; the files are complete after :meth:`close` (or
    :meth:`flush`, which also makes them readable during a run).
    """

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
            self._xdmf = _XdmfSeries(self.folder / f"{name}.xdmf").__enter__()
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
            self._xdmf.write_data(t, point_data=data)
        if self.fmt in ("vtu", "both"):
            rel = f"{self.name}_vtu/{self.name}_{len(self.times):06d}.vtu"
            mesh = meshio.Mesh(self.line.points, [("line", self.line.cells)], point_data=data)
            meshio.write(self.folder / rel, mesh, file_format="vtu")
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
        ET.ElementTree(root).write(self.folder / f"{self.name}.pvd", xml_declaration=True,
                                   encoding="utf-8")

    def flush(self) -> None:
        """Write the XML indexes now, so the files already read back as they are."""
        if self.closed:
            return
        if self._xdmf is not None:
            self._xdmf.flush()
        if self.fmt in ("vtu", "both"):
            self._write_pvd()

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        if self._xdmf is not None:
            self._xdmf.__exit__(None, None, None)   # writes the XML, closes the .h5
        if self.fmt in ("vtu", "both"):
            self._write_pvd()

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
