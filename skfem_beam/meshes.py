"""1-D line meshes from files: read any format meshio reads, check, return the nodes.

The papers' meshes are shipped in ``meshes/`` (Gmsh 4.1 ASCII); rebuild them with

    python -m skfem_beam.meshes --out meshes

and use one as ``BeamProblem(..., nodes=load_mesh("meshes/pipe10_J40.msh", 10.0))``.
"""
from __future__ import annotations

import io
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import meshio
import numpy as np

from .checks import check_positive
from .errors import InputError
from .parser import Parser

# name -> (L, J): uniform meshes of the papers (J even on [0, 10]: x = 5 is a node)
PAPER_MESHES = {
    "point_stops_J19": (1.501, 19),
    "pipe10_J40": (10.0, 40),
    "pipe10_J80": (10.0, 80),
    "pipe10_J160": (10.0, 160),
}
_POINT_CELLS = ("vertex",)   # Gmsh physical points may come along; they are ignored


def _read(path: Path):
    """meshio.read, with its failures as one InputError line."""
    said = io.StringIO()
    try:
        # meshio prints every failed attempt and then calls sys.exit(1) when no reader
        # for the extension accepts the file: capture the text, turn the exit into ours
        with redirect_stdout(said), redirect_stderr(said):
            return meshio.read(path)
    except (Exception, SystemExit) as e:   # ReadError, KeyError, ValueError, … too
        lines = [s.strip() for s in said.getvalue().splitlines() if s.strip()]
        msg = str(e).strip() if isinstance(e, Exception) else ""
        msg = msg.splitlines()[0] if msg else (lines[-1] if lines else "")
        if isinstance(e, Exception) and type(e).__name__ != "ReadError":
            msg = f"{type(e).__name__}: {msg}".rstrip(": ")
        raise InputError(f"cannot read mesh {path}: {msg.removeprefix('Error: ')}") from None


def load_mesh(path, L: float) -> np.ndarray:
    """Nodes 0 = x_0 < … < x_J = L of the line mesh in ``path``.

    The points may come in any order: they are sorted by x, and the line cells must
    then join each node to the next one (no gap, no overlap).  Refused with an
    :class:`~skfem_beam.errors.InputError` (one line): an unreadable file, cells that
    are not lines, points off the x axis, non-finite or duplicate coordinates, a mesh
    that does not run from 0 to L.
    """
    L = check_positive("L", L)
    path = Path(path)
    if not path.is_file():
        raise InputError(f"mesh file {path} does not exist")
    mesh = _read(path)
    other = sorted({c.type for c in mesh.cells} - {"line", *_POINT_CELLS})
    if other:
        raise InputError(f"mesh {path} is not a line mesh: it has {', '.join(other)} cells")
    lines = [c.data for c in mesh.cells if c.type == "line"]
    if not lines or sum(len(c) for c in lines) == 0:
        raise InputError(f"mesh {path} has no line cells")
    cells = np.concatenate(lines).astype(np.int64)
    used = np.unique(cells)
    pts = np.asarray(mesh.points, dtype=float)[used]
    if not np.isfinite(pts).all():
        raise InputError(f"mesh {path} has a non-finite coordinate")
    tol = 1e-9 * L
    if pts.shape[1] > 1 and np.abs(pts[:, 1:]).max() > tol:
        raise InputError(f"mesh {path} does not lie on the x axis "
                         f"(|y| or |z| up to {np.abs(pts[:, 1:]).max():.3g})")
    x = pts[:, 0]
    order = np.argsort(x, kind="stable")
    xs = x[order]
    dup = np.diff(xs) <= tol
    if dup.any():
        raise InputError(f"mesh {path} has duplicate nodes at x={xs[1:][dup][0]:.12g}")
    if abs(xs[0]) > tol or abs(xs[-1] - L) > tol:
        raise InputError(f"mesh {path} runs from {xs[0]:.12g} to {xs[-1]:.12g}, "
                         f"not from 0 to L={L:g}")
    rank = np.empty(used.size, dtype=np.int64)
    rank[order] = np.arange(used.size)
    a, b = np.sort(rank[np.searchsorted(used, cells)], axis=1).T
    if cells.shape[0] != xs.size - 1 or np.any(b - a != 1) or np.unique(a).size != a.size:
        bad = np.flatnonzero(b - a != 1)
        where = (f": a cell joins x={xs[a[bad[0]]]:.12g} and x={xs[b[bad[0]]]:.12g}"
                 if bad.size else f": {cells.shape[0]} cells for {xs.size} nodes")
        raise InputError(f"mesh {path} is not a chain of cells from node to next node{where}")
    xs = xs.copy()
    xs[0], xs[-1] = 0.0, L
    return xs


def write_mesh(path, nodes) -> Path:
    """Write the line mesh through ``nodes`` (points padded to 3-D) in a meshio format."""
    x = np.asarray(nodes, dtype=float)
    pts = np.column_stack([x, np.zeros_like(x), np.zeros_like(x)])
    cells = [("line", np.column_stack([np.arange(x.size - 1), np.arange(1, x.size)]))]
    path = Path(path)
    meshio.write(path, meshio.Mesh(pts, cells),
                 **({"file_format": "gmsh", "binary": False} if path.suffix == ".msh" else {}))
    return path


def main(argv=None) -> int:
    p = Parser(prog="python -m skfem_beam.meshes",
                                description="Write the papers' uniform line meshes (.msh).")
    p.add_argument("--out", default="meshes", help="folder (default: meshes)")
    args = p.parse_args(argv)
    out = Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:        # a file of that name, a read-only parent
        raise InputError(f"--out {out}: cannot make the folder ({e.strerror})") from None
    for name, (L, J) in PAPER_MESHES.items():
        print(write_mesh(out / f"{name}.msh", np.linspace(0.0, L, J + 1)))
    return 0


if __name__ == "__main__":
    import sys
    try:    # not cli.main_guard: cli imports this module
        raise SystemExit(main())
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        raise SystemExit(2) from None
