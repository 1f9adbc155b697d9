"""A plate run's own output (the beam's assumes a line along x): the timeseries columns,
the field frames on the plate's cells, and its charts.

- ``timeseries.csv``: ``t`` (s), ``w_x<X>_y<Y>`` (m, the deflection at each probe
  vertex), ``energy_J`` (½E_β, J), ``work_damping_J``, ``work_input_J``,
  ``work_contact_J`` (J, cumulative since t = 0: energy − energy[0] + work_damping =
  work_input + work_contact), ``contact_force_N`` (N, the sum of the nodal contact
  forces, positive along w) and ``contact_area_fraction`` (vertices whose contact force
  is not 0 / constrained vertices).
- fields (``fields.xdmf`` + ``.h5`` and/or ``fields.pvd`` + ``fields_vtu/``): point data
  on the mesh's vertices (quads for BFS, triangles for Morley and Argyris): ``w`` (m),
  ``displacement_vector`` (0, 0, w) for ParaView's Warp By Vector, ``velocity`` (m/s),
  ``contact_force`` (N, 0 at a vertex without obstacle), ``g1``, ``g2`` (m, NaN where
  there is none), ``bending_moment_xx``, ``bending_moment_yy``, ``bending_moment_xy``
  (N·m/m: M_xx = −D(w,xx + ν w,yy), M_yy = −D(w,yy + ν w,xx), M_xy = −D(1 − ν) w,xy,
  the element's second derivatives at the vertex averaged over the cells sharing it:
  :func:`curvature_operators`).
- ``impacts.csv``: one row per contact episode of a constrained vertex (the beam's per
  node, :mod:`.events`), in the order of t_start (then the vertex's row of C):
  ``t_start``, ``t_end`` (s), ``x``, ``y`` (m, the vertex), ``bound`` (1: g1, 2: g2),
  ``velocity`` (m/s, its approach velocity), ``peak_force`` (N, max |λ|), ``impulse``
  (N·s, Σ λΔt, signed like ``contact_force_N``), ``max_violation`` (m), ``open``; the
  impulses add up to Σ contact_force_N·Δt of the run to round-off (:func:`plate_impacts`).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from .events import COLUMNS, EPISODES, IMPACTS, MAGNITUDE, RIGID_PEAK, VELOCITY, impact_table
from .fields import FieldWriter, check_format
from .folder import atomic_write, csv_rows
from .supports import union_length

UNITS = {"t": "s", "w_x<X>_y<Y>": "m, the deflection at the probe vertex (X, Y)",
         "energy_J": "J, the scheme's discrete energy ½E_β",
         "work_damping_J": "J, work lost in damping (≥ 0), cumulative since t = 0",
         "work_input_J": "J, work of the pressures, cumulative since t = 0",
         "work_contact_J": "J, work of the contact forces (≤ 0 for exact contact with restitution "
                           "e = 0; a gain, with e > 0 or springs, is warned of), "
                           "cumulative since t = 0",
         "energy_balance": "energy_J − energy_J[0] + work_damping_J = work_input_J + "
                           "work_contact_J (to round-off)",
         "contact_force_N": "N, the sum of the nodal contact forces, positive along w",
         "contact_area_fraction": "vertices whose contact force is not 0 / constrained "
                                  "vertices"}


def probe_name(x: float, y: float) -> str:
    return f"w_x{x:g}_y{y:g}"


def plate_columns(probes):
    """timeseries.csv's columns of saved rows k0..k1 of a plate run."""
    def columns(run, k0, k1):
        t = np.arange(k0, k1) * run.save_every * run.dt
        cols = {"t": t}
        for i, (x, y) in enumerate(probes):
            cols[probe_name(x, y)] = run.obs[k0:k1, i]
        cols["energy_J"] = run.energy[k0:k1]
        work = run.work[k0:k1]
        cols.update({f"work_{name}_J": work[:, i] for i, name in enumerate(run.work_terms)})
        lam = run.lam[k0:k1]
        cols["contact_force_N"] = lam.sum(axis=1)
        m = lam.shape[1]
        cols["contact_area_fraction"] = (lam != 0).sum(axis=1) / m if m else 0.0 * t
        return cols
    return columns


MOMENTS = ("bending_moment_xx", "bending_moment_yy", "bending_moment_xy")


def curvature_operators(space):
    """(H_xx, H_yy, H_xy): sparse (vertices × skfem's dofs) matrices whose product with
    a coefficient vector is w,xx, w,yy, w,xy at each vertex of the mesh: each cell's own
    second derivatives (scikit-fem's ``hess`` of its basis functions, a basis whose
    quadrature points are the reference cell's vertices) at the vertex, averaged over
    the cells that share it (w,ij jumps between cells: BFS is C¹, not C²)."""
    from scipy import sparse
    from skfem import Basis
    mesh = space.basis.mesh
    ref = mesh.init_refdom().p                      # in the order of mesh.t's rows
    basis = Basis(mesh, space.basis.elem, quadrature=(ref, np.ones(ref.shape[1])))
    nv = mesh.p.shape[1]
    share = np.bincount(mesh.t.ravel(), minlength=nv).astype(float)
    rows = np.broadcast_to(mesh.t.T, (len(basis.basis),) + mesh.t.T.shape)  # (i, e, q)
    cols = np.broadcast_to(basis.element_dofs[:, :, None], rows.shape)
    hess = np.stack([phi[0].hess for phi in basis.basis])   # (i, 2, 2, e, q)
    shape = (nv, space.basis.N)

    def op(a, b):
        vals = hess[:, a, b] / share[rows]
        return sparse.csr_matrix((vals.ravel(), (rows.ravel(), cols.ravel())), shape=shape)
    return op(0, 0), op(1, 1), op(0, 1)


def bending_moments(space, full: np.ndarray, ops=None) -> dict[str, np.ndarray]:
    """M_xx, M_yy, M_xy (N·m/m) at each vertex from all of skfem's dofs ``full``
    (``ops``: :func:`curvature_operators`' matrices, made when None)."""
    hxx, hyy, hxy = (op @ full for op in (ops or curvature_operators(space)))
    D, nu = space.plate.D, space.plate.nu
    return dict(zip(MOMENTS, (-D * (hxx + nu * hyy), -D * (hyy + nu * hxx),
                              -D * (1.0 - nu) * hxy)))


def vertex_fields(system, u, v, force, ops=None) -> dict[str, np.ndarray]:
    """The point data of one frame (module docstring) from the system's coefficients
    u, v and its nodal contact forces (one per constrained vertex); ``ops``: the
    :func:`curvature_operators` of the system's space (made when None)."""
    from ..plate.system import full_dofs
    space = system.meta["space"]
    nv = space.vertices.shape[1]
    full = full_dofs(system, u)
    w = full[space.w_dofs]
    vel = vertex_w(system, v)
    where = system.meta["contact_vertices"]
    f = np.zeros(nv)
    f[where] = force
    g1, g2 = np.full(nv, np.nan), np.full(nv, np.nan)
    g1[where] = np.where(np.isfinite(system.lo), system.lo, np.nan)
    g2[where] = np.where(np.isfinite(system.hi), system.hi, np.nan)
    return {"w": w, "displacement_vector": np.column_stack([0 * w, 0 * w, w]),
            "velocity": vel, "contact_force": f, "g1": g1, "g2": g2,
            **bending_moments(space, full, ops)}


def vertex_w(system, u) -> np.ndarray:
    """w at each vertex of the mesh from the system's coefficients u."""
    from ..plate.system import full_dofs
    return full_dofs(system, u)[system.meta["space"].w_dofs]


def plate_cells(system) -> tuple[np.ndarray, list]:
    """(the vertices padded to 3-D, [(cell type, cells)]) of the plate's mesh, each cell
    counter-clockwise seen from +z, so that ParaView's normals point along +w (a BFS mesh's
    quads were all clockwise, a mesh file's triangles as the file had them)."""
    mesh = system.meta["space"].basis.mesh
    points = np.column_stack([mesh.p[0], mesh.p[1], np.zeros(mesh.p.shape[1])])
    kind = "quad" if mesh.t.shape[0] == 4 else "triangle"
    cells = np.ascontiguousarray(mesh.t.T)
    x, y = mesh.p[0][cells], mesh.p[1][cells]       # twice each cell's signed area
    area = np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)
    cells[area < 0] = cells[area < 0, ::-1]
    return points, [(kind, cells)]


class PlateFieldWriter(FieldWriter):
    """:class:`~.fields.FieldWriter` on the plate's cells: the same files, flushing and
    closing; the frames are :func:`vertex_fields`."""

    def __init__(self, folder, system, fmt: str = "both", name: str = "fields"):
        check_format(fmt, "format=")
        self.folder = Path(folder)
        if not self.folder.is_dir():
            raise InputError(f"field output folder {self.folder} does not exist")
        self.fmt, self.name, self.system = fmt, name, system
        self.points, self.cells = plate_cells(system)
        self.m, self.n = system.C.shape[0], system.n
        self.ops = curvature_operators(system.meta["space"])
        self.times, self._vtu_files, self._xdmf, self.closed = [], [], None, False
        if fmt in ("xdmf", "both"):
            from .xdmf import XdmfSeries
            self._room_for_hdf5()
            self._xdmf = XdmfSeries(self.folder / f"{name}.xdmf").__enter__()
            self._xdmf.write_points_cells(self.points, self.cells)
        if fmt in ("vtu", "both"):
            (self.folder / f"{name}_vtu").mkdir(exist_ok=True)

    def _write(self, t: float, u, v, force) -> None:
        if self.closed:
            raise ValueError("write() on a closed FieldWriter")
        force = np.zeros(self.m) if force is None else np.asarray(force, dtype=float)
        data = vertex_fields(self.system, np.asarray(u, float), np.asarray(v, float), force,
                             self.ops)
        t = float(t)
        if self._xdmf is not None:
            self._room_for_hdf5()
            self._xdmf.write_data(t, point_data=data)
        if self.fmt in ("vtu", "both"):
            import meshio
            rel = f"{self.name}_vtu/{self.name}_{len(self.times):06d}.vtu"
            meshio.write(self.folder / rel, meshio.Mesh(self.points, self.cells,
                                                        point_data=data),
                         file_format="vtu", compression=None)
            self._vtu_files.append(rel)
        self.times.append(t)


PLATE_COLUMNS = COLUMNS[:3] + ("y",) + COLUMNS[3:]      # the beam's, and the vertex's y
IMPACT_UNITS = {"t_start": "s", "t_end": "s", "x": "m", "y": "m",
                "bound": "1 = g1 (lower), 2 = g2 (upper)", "velocity": VELOCITY,
                "peak_force": "N" + MAGNITUDE, "impulse": "N·s", "max_violation": "m",
                "open": "1 = not over at the last state",
                "contact_fraction": EPISODES}


def _impact_rows(run, last: int) -> dict:
    """impacts.csv's columns (module docstring) of ``run``'s events up to state ``last``."""
    s = run.system
    events = run.impact_events(last)
    # an unstable run ends at its last good saved state: impacts after it are not kept
    keep = np.asarray(events["t_start"]) <= (last + 0.5) * run.dt
    events = {k: np.asarray(v)[keep] for k, v in events.items()}
    table = impact_table(events, np.asarray(s.lo), np.asarray(s.hi))   # N, N·s: SI system
    table["y"] = np.asarray(s.meta["y_contact"], dtype=float)[events["value"]]
    table["value"] = events["value"]
    return table


def _vertex_stats(table: dict, rows: np.ndarray, duration: float) -> dict:
    return {"impacts": int(rows.size),
            "contact_fraction": union_length(table["t_start"][rows], table["t_end"][rows])
            / duration if duration > 0 else 0.0,
            "max_impulse": float(np.abs(table["impulse"][rows]).max()),
            "max_peak_force": float(table["peak_force"][rows].max()),
            "max_violation": float(table["max_violation"][rows].max())}


def plate_impacts(folder: Path, run, last: int | None = None) -> dict:
    """Write ``folder/impacts.csv`` of a plate run (module docstring) and return the
    summary entry ``impact_statistics``: the rows (``impacts``), the vertices touched, the
    total impulse (N·s), the time any vertex is in contact (``contact_fraction``), the
    largest peak force, impulse and violation, and per vertex touched
    (``vertices``: x, y, impacts, contact_fraction, max_impulse, max_peak_force,
    max_violation; the beam's ``nodes``).  ``last``: the last state the loop computed."""
    last = run.n if last is None else int(last)
    table = _impact_rows(run, last)
    text = csv_rows(table, list(PLATE_COLUMNS), ("bound", "open")) if table["x"].size else ""
    atomic_write(Path(folder) / IMPACTS,
                 lambda fh: fh.write(",".join(PLATE_COLUMNS) + "\n" + text))
    duration = max(0, last - 1) * run.dt       # states 1..n, as the run's contact_fraction
    touched = np.unique(table["value"])
    units = dict(IMPACT_UNITS)
    if not run.springs:
        units["peak_force"] += RIGID_PEAK
    everything = np.arange(table["x"].size)
    stats = {"impacts": int(table["x"].size), "vertices_touched": int(touched.size),
             "total_impulse": float(np.sum(table["impulse"])),
             **(_vertex_stats(table, everything, duration) if everything.size else {}),
             "vertices": [{"x": float(table["x"][rows[0]]), "y": float(table["y"][rows[0]]),
                           **_vertex_stats(table, rows, duration)}
                          for rows in (np.flatnonzero(table["value"] == j) for j in touched)],
             "units": units}
    return {"impact_statistics": stats}
