"""A pyvista render of a plate's run: its deflected surface at one saved frame.

:func:`render_plate` draws the plate's cells (BFS quads, Morley or Argyris triangles) at
z = scale·w, coloured by w (mm), the constrained vertices in contact at that frame as red
points (their contact force ≠ 0), off-screen (the beam's renders: output.render, whose
headless set-up it shares).  The transverse scale is 1, 2 or 5 × 10^k, chosen so that
the largest absolute w drawn is about a tenth of the plate's larger side unless given.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from .render import _frames, _nice, _pyvista


def render_plate(path, result, time=None, scale=None, window_size=(1200, 800)) -> np.ndarray:
    """Write an off-screen PNG of the plate at the saved frame nearest to ``time`` (default:
    the frame of the largest absolute w); return the image (H × W × 3, uint8)."""
    system = getattr(result, "system", None)
    if not hasattr(result, "frames_t") or system is None \
            or system.meta.get("kind") != "plate":
        raise InputError("render_plate needs the Result of a plate's solve(plate_system(...)) "
                         f"with its frames in memory, not {type(result).__name__}")
    from ..plate.system import full_dofs
    space = system.meta["space"]
    w = full_dofs(system, np.asarray(result.frames_u))[:, space.w_dofs]     # frames × vertices
    k = int(np.argmax(np.abs(w).max(axis=1))) if time is None else _frames(result, time)[0]
    size = max(space.plate.box[1] - space.plate.box[0], space.plate.box[3] - space.plate.box[2])
    peak = float(np.abs(w[k]).max())
    if scale is None:
        scale = _nice(0.1 * size / peak) if peak > 0 else 1.0
    pv = _pyvista()
    mesh = space.basis.mesh
    cells = np.asarray(mesh.t).T            # quads (BFS) or triangles
    faces = np.hstack([np.full((cells.shape[0], 1), cells.shape[1]), cells]).ravel()
    points = np.column_stack([mesh.p[0], mesh.p[1], scale * w[k]])
    surface = pv.PolyData(points, faces)
    surface["w (mm)"] = 1e3 * w[k]
    plotter = pv.Plotter(off_screen=True, window_size=list(window_size))
    try:
        plotter.set_background("white")
        plotter.add_mesh(surface, scalars="w (mm)", show_edges=True, cmap="viridis")
        touching = np.flatnonzero(np.asarray(result.frames_force[k]) != 0.0)
        if touching.size:
            vertices = system.meta["contact_vertices"][touching]
            plotter.add_points(points[vertices], color="#d62728", point_size=12,
                               render_points_as_spheres=True)
        plotter.add_text(f"t = {result.frames_t[k]:.4g} s, w × {scale:g}, "
                         f"{touching.size} vertices in contact", font_size=11, color="black",
                         position="upper_edge")
        plotter.view_isometric()
        img = plotter.screenshot(str(Path(path)), return_img=True)
    finally:
        plotter.close()
    return np.asarray(img)[..., :3]
