"""pyvista renders of a run: the deformed beam as a tube over its obstacles.

- :func:`render_beam`: an off-screen PNG of the beam at chosen times;
- :func:`animate`: a GIF (or MP4 with ``imageio-ffmpeg``) of the saved frames.

The beam is drawn through the same sub-points as the field files
(:func:`skfem_beam.output.fields.sample_line`), so a Hermite or B-spline beam is the cubic,
not its chords; the displacement is the physical ũ (support motion included).
Obstacles are drawn as walls whose face sits one tube radius beyond g (so the tube
touches the wall when the centre line touches g); point stops as blocks.
Transverse values are scaled when they are small next to L (the title says by what).

Headless (no ``DISPLAY``), measured with VTK 9.7.2 / pyvista 0.49 on Debian 12:
VTK's pip wheel (≥ 9.4) picks its render window at run time.  It falls back from X to
EGL by itself, but first logs "bad X server connection"; setting
``VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow`` (done below when no DISPLAY is set)
goes straight to EGL.  EGL needs Mesa's ``libegl1`` + ``libegl-mesa0`` and the software
rasteriser ``libgl1-mesa-dri``, which this machine image has, so CI needs no Xvfb.
Two alternatives also work here: ``xvfb-run -a python …`` (Debian's ``xvfb``; pyvista
0.49 no longer has ``start_xvfb``), and ``VTK_DEFAULT_OPENGL_WINDOW=vtkOSOpenGLRenderWindow``
with Debian's ``libosmesa6``.
"""
from __future__ import annotations

import math
import os
import sys
from pathlib import Path

import numpy as np

from ..errors import InputError
from .fields import sample_line

BEAM_COLORS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf")
OBSTACLE_COLOR = "#d62728"
SUPPORT_COLOR = "#7f7f7f"


def _pyvista():
    """Import pyvista set up for off-screen rendering (see the module docstring)."""
    if sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    try:
        import pyvista as pv
    except ImportError:
        raise InputError("rendering needs PyVista and VTK, which a run does not: "
                         "pip install \"skfem_beam[render]\"") from None
    pv.OFF_SCREEN = True
    return pv


def _nice(value: float) -> float:
    """The largest of 1, 2, 5 × 10^k not above value (at least 1)."""
    if value <= 1.0:
        return 1.0
    k = 10.0 ** math.floor(math.log10(value))
    return max(m * k for m in (1.0, 2.0, 5.0) if m * k <= value)


def _frames(result, times) -> list[int]:
    """Indices of the saved frames nearest to ``times`` (all frames when None)."""
    ft = np.asarray(result.frames_t)
    if times is None:
        return list(range(ft.size))
    return [int(np.argmin(np.abs(ft - float(t)))) for t in np.atleast_1d(times)]


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """[start, stop) of every run of True in mask."""
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


class _Scene:
    """What every picture of one run shares: sub-points, scale, sizes, obstacles."""

    def __init__(self, result, frames, scale, samples_per_element):
        self.result = result
        self.line = sample_line(result.system, samples_per_element)
        self.x = self.line.x
        self.L = float(self.x[-1] - self.x[0])
        self.disp = {k: self.displacement(k) for k in frames}
        g = np.concatenate([self.line.g1, self.line.g2])
        g = g[np.isfinite(g)]
        reach = max([np.nanmax(np.abs(d)) for d in self.disp.values()]
                    + [np.abs(g).max() if g.size else 0.0, 1e-300])
        if scale is None:
            scale = _nice(0.15 * self.L / reach)
        self.scale = float(scale)
        if not (math.isfinite(self.scale) and self.scale > 0):
            raise InputError(f"scale={scale!r} must be a positive number")
        self.radius = 0.006 * self.L
        self.half_height = max(self.scale * reach, 0.05 * self.L) * 1.25

    def displacement(self, k: int) -> np.ndarray:
        r = self.result
        return self.line.fields(float(r.frames_t[k]), r.frames_u[k], r.frames_v[k],
                                r.frames_force[k])["displacement"]

    def beam(self, pv, k: int):
        y = np.nan_to_num(self.scale * self.disp[k])
        pts = np.column_stack([self.x, y, np.zeros_like(y)])
        return pv.lines_from_points(pts).tube(radius=self.radius, n_sides=24)

    def add_static(self, pv, plotter):
        """Obstacles, the clamped support and the rest line."""
        s, r, L = self.scale, self.radius, self.L
        thick = 0.025 * L
        for g, side in ((self.line.g1, -1.0), (self.line.g2, 1.0)):
            for a, b in _runs(np.isfinite(g)):
                if b - a == 1:     # a point stop: a block beyond g
                    y0 = s * g[a] + side * r
                    w, d = 0.025 * L, 1.6 * thick
                    box = pv.Box(bounds=(self.x[a] - w, self.x[a] + w,
                                         min(y0, y0 + side * d), max(y0, y0 + side * d),
                                         -3 * r, 3 * r))
                    plotter.add_mesh(box, color=OBSTACLE_COLOR, render=False)
                else:              # a wall along [x_a, x_b): its face at g
                    pts = np.column_stack([self.x[a:b], s * g[a:b] + side * r,
                                           np.zeros(b - a)])
                    wall = pv.lines_from_points(pts).extrude((0.0, side * thick, 0.0),
                                                             capping=False)
                    plotter.add_mesh(wall, color=OBSTACLE_COLOR, render=False)
        h = self.half_height
        plotter.add_mesh(pv.Box(bounds=(-0.03 * L, 0.0, -h, h, -3 * r, 3 * r)),
                         color=SUPPORT_COLOR, render=False)
        plotter.add_mesh(pv.Line((0.0, 0.0, 0.0), (L, 0.0, 0.0)), color="#bbbbbb",
                         line_width=1, render=False)

    def frame_camera(self, plotter):
        plotter.enable_parallel_projection()
        plotter.view_xy()
        # frame the whole scene, whatever the beam does at this time
        plotter.add_mesh(self._corners(), opacity=0.0, render=False)
        plotter.camera.tight(padding=0.04)

    def _corners(self):
        import pyvista as pv
        h = self.half_height
        # room on the right for the legend and the time, on top for the title
        return pv.PolyData(np.array([[-0.03 * self.L, -h, 0.0],
                                     [1.30 * self.L, h + 0.06 * self.L, 0.0]]))

    def title(self, case: str | None) -> str:
        r = self.result
        head = f"{case}: " if case else ""
        sc = f", displacement ×{self.scale:g}" if self.scale != 1 else ""
        # plain ASCII: VTK's default font has no Greek letters
        scheme = f"theta = {r.theta:g}" if r.theta is not None else f"beta = {r.beta:g}"
        return f"{head}L = {self.L:g} m, {scheme}, dt = {r.dt:g} s{sc}"


def _check_result(result, what: str) -> None:
    """One line when ``result`` is not a line's run in memory (a folder read back, a
    plate's)."""
    if not hasattr(result, "frames_t") or getattr(result.system, "view", None) is None:
        raise InputError(f"{what} needs the Result of a beam's solve(...) with its frames "
                         f"in memory, not {type(result).__name__} (a saved folder's fields "
                         "open in ParaView: docs/getting_started.md)")
    if getattr(result.system.view, "planes", 1) != 1:   # it raised KeyError('displacement')
        raise InputError(f"{what} draws a beam in one plane; this one bends in two (its "
                         "fields displacement_v, _w open in ParaView: "
                         "docs/getting_started.md)")


def render_beam(path, result, times=None, scale=None, samples_per_element: int = 8,
                window_size=(1600, 640), case: str | None = None) -> np.ndarray:
    """Write an off-screen PNG of the beam at the saved frames nearest to ``times``
    (default: first, middle and last frame); return the image (H × W × 3, uint8).

    ``scale`` multiplies the transverse values (displacement and obstacles alike);
    None picks 1, 2 or 5 × 10^k so that the picture is about 1/4 as tall as long.
    """
    _check_result(result, "render_beam")
    pv = _pyvista()
    if times is None:
        n = result.frames_t.size
        frames = sorted({0, n // 2, n - 1})
    else:
        frames = _frames(result, times)
    if not frames:
        raise InputError("times is empty: give at least one time to render")
    sc = _Scene(result, frames, scale, samples_per_element)
    plotter = pv.Plotter(off_screen=True, window_size=list(window_size))
    try:
        plotter.set_background("white")
        sc.add_static(pv, plotter)
        labels = []
        for i, k in enumerate(frames):
            color = BEAM_COLORS[i % len(BEAM_COLORS)]
            plotter.add_mesh(sc.beam(pv, k), color=color, render=False)
            labels.append([f"t = {result.frames_t[k]:.4g} s", color])
        legend = plotter.add_legend(labels, bcolor="white", face="line")
        height = min(0.9, 0.07 * len(labels) + 0.04)
        legend.SetPosition(0.85, 0.5 - height / 2)    # in the margin right of the tip
        legend.SetPosition2(0.14, height)
        plotter.add_text(sc.title(case), font_size=11, color="black", position="upper_edge",
                         render=False)
        sc.frame_camera(plotter)
        path = Path(path)
        img = plotter.screenshot(str(path), return_img=True)
    finally:
        plotter.close()
    return np.asarray(img)[..., :3]


def animate(path, result, fps: float = 20, every: int = 1, scale=None,
            samples_per_element: int = 8, window_size=(1280, 512),
            case: str | None = None) -> Path:
    """Write an animation of every ``every``-th saved frame: ``.gif`` (pyvista + imageio)
    or ``.mp4`` (needs ``imageio-ffmpeg``).  The scale and the camera stay fixed."""
    _check_result(result, "animate")
    pv = _pyvista()
    path = Path(path)
    if isinstance(every, bool) or int(every) != every or every < 1:
        raise InputError(f"every={every!r} must be a whole number ≥ 1")
    suffix = path.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise InputError(f"animation {path}: use a .gif or .mp4 file name")
    if suffix == ".mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise InputError("MP4 needs imageio-ffmpeg (pip install \"skfem_beam[video]\"); "
                             "or write a .gif") from None
    frames = list(range(0, result.frames_t.size, int(every)))
    sc = _Scene(result, frames, scale, samples_per_element)
    plotter = pv.Plotter(off_screen=True, window_size=list(window_size))
    try:
        plotter.set_background("white")
        sc.add_static(pv, plotter)
        plotter.add_text(sc.title(case), font_size=10, color="black", position="upper_edge",
                         render=False)
        beam = sc.beam(pv, frames[0])      # updated in place: one render per frame
        plotter.add_mesh(beam, color=BEAM_COLORS[0], render=False)
        clock = plotter.add_text("", font_size=10, color="black", position="right_edge",
                                 render=False)
        sc.frame_camera(plotter)
        if suffix == ".gif":
            plotter.open_gif(str(path), fps=fps)
        else:
            # yuv420p needs even sizes only: no resizing to 16's multiples (and its warning)
            plotter.open_movie(str(path), framerate=fps, macro_block_size=2)
        for k in frames:
            beam.copy_from(sc.beam(pv, k))
            clock.SetText(clock.RightEdge, f"t = {result.frames_t[k]:.4f} s")
            plotter.write_frame()
    finally:
        plotter.close()
    return path
