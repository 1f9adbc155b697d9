"""meshio's XDMF time series writer (``.xdmf`` + ``.h5``), as :class:`.fields.FieldWriter`
uses it: with the traps ParaView's readers fall into worked around, and the HDF5
datasets made at less cost.

A module of its own so that meshio and h5py (0.07 s of imports) load with a run's first
frame, not with the command: a short run writes its frames after its loop, while the
chart process draws on the other core (docs/design.md, "The whole command").
"""
from __future__ import annotations

import os
import xml.etree.ElementTree as ET

import h5py
import meshio
import numpy as np

from .folder import atomic_write


class XdmfSeries(meshio.xdmf.TimeSeriesWriter):
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
        # unlocked: ParaView opening a run in progress aborted on HDF5's lock
        self.h5_file = h5py.File(self.h5_filename, "w", locking=False)
        # no times in the datasets' headers: the same run writes the same bytes
        self._untimed = h5py.h5p.create(h5py.h5p.DATASET_CREATE)
        self._untimed.set_obj_track_times(False)
        return self

    def __exit__(self, *_):
        self.flush()
        self.h5_file.close()

    def write_points_cells(self, points, cells):
        super().write_points_cells(points, cells)
        self._mesh = self.domain.find(f"Grid[@Name='{self.mesh_name}']")
        self.domain.remove(self._mesh)
        for topo in self._mesh.iter("Topology"):
            if topo.get("TopologyType") == "Polyline" and "NodesPerElement" not in topo.attrib:
                topo.set("NodesPerElement", "2")

    def numpy_to_xml_string(self, data):
        """One HDF5 dataset, as meshio makes it (``dataN``, contiguous, the array's own
        type), made through h5py's low-level calls: a frame has seven, and h5py's
        ``create_dataset`` costs 2.4× as much per dataset (docs/design.md)."""
        data = np.ascontiguousarray(data)
        name = f"data{self.data_counter}"
        self.data_counter += 1
        space = h5py.h5s.create_simple(data.shape)
        dataset = h5py.h5d.create(self.h5_file.id, name.encode(), h5py.h5t.py_create(data.dtype),
                                  space, dcpl=self._untimed)
        dataset.write(h5py.h5s.ALL, h5py.h5s.ALL, data)
        return f"{os.path.basename(self.h5_filename)}:/{name}"

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
        """Make the files readable as they are now (meshio writes the XML only at exit): the
        data first, then the XML that points at it, replaced whole (a run killed while
        meshio wrote it in place left it empty or cut, and ParaView aborted on it)."""
        self.h5_file.flush()
        atomic_write(self.filename, lambda fh: ET.ElementTree(self.xdmf_file).write(fh),
                     binary=True)
