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
  there is none).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from .fields import FieldWriter, check_format

UNITS = {"t": "s", "w_x<X>_y<Y>": "m, the deflection at the probe vertex (X, Y)",
         "energy_J": "J, the scheme's discrete energy ½E_β",
         "work_damping_J": "J, work lost in damping (≥ 0), cumulative since t = 0",
         "work_input_J": "J, work of the pressures, cumulative since t = 0",
         "work_contact_J": "J, work of the contact forces (≤ 0 for exact contact), "
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


def vertex_fields(system, u, v, force) -> dict[str, np.ndarray]:
    """The point data of one frame (module docstring) from the system's coefficients
    u, v and its nodal contact forces (one per constrained vertex)."""
    from ..plate.system import full_dofs
    space = system.meta["space"]
    nv = space.vertices.shape[1]
    w = full_dofs(system, u)[space.w_dofs]
    vel = full_dofs(system, v)[space.w_dofs]
    where = system.meta["contact_vertices"]
    f = np.zeros(nv)
    f[where] = force
    g1, g2 = np.full(nv, np.nan), np.full(nv, np.nan)
    g1[where] = np.where(np.isfinite(system.lo), system.lo, np.nan)
    g2[where] = np.where(np.isfinite(system.hi), system.hi, np.nan)
    return {"w": w, "displacement_vector": np.column_stack([0 * w, 0 * w, w]),
            "velocity": vel, "contact_force": f, "g1": g1, "g2": g2}


def plate_cells(system) -> tuple[np.ndarray, list]:
    """(the vertices padded to 3-D, [(cell type, cells)]) of the plate's mesh."""
    mesh = system.meta["space"].basis.mesh
    points = np.column_stack([mesh.p[0], mesh.p[1], np.zeros(mesh.p.shape[1])])
    kind = "quad" if mesh.t.shape[0] == 4 else "triangle"
    return points, [(kind, np.ascontiguousarray(mesh.t.T))]


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
        data = vertex_fields(self.system, np.asarray(u, float), np.asarray(v, float), force)
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


def deflection_chart(path, points, cells, w, title="") -> None:
    """w over the plate (mm, colour) at one frame, with the mesh's cells drawn."""
    from matplotlib.collections import PolyCollection
    from .charts import figure
    tall = np.ptp(points[:, 1]) > 1.5 * np.ptp(points[:, 0])
    with figure(path, figsize=(5, 6.5) if tall else (7, 5)) as (fig, ax):
        polys = points[cells][:, :, :2]
        coll = PolyCollection(polys, array=1e3 * w[cells].mean(axis=1), cmap="viridis",
                              edgecolors="0.6", linewidths=0.3)
        ax.add_collection(coll)
        ax.set_xlim(points[:, 0].min(), points[:, 0].max())
        ax.set_ylim(points[:, 1].min(), points[:, 1].max())
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_title(title, fontsize=9)
        fig.colorbar(coll, ax=ax, label="w (mm), cell mean")
