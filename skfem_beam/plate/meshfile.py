"""A plate's triangle mesh from a file meshio reads (gmsh .msh, .vtu, .xdmf, ...): the
vertices, the linear triangles and the named boundaries (lines of the file).

A boundary's name comes from the file: a gmsh physical line's name ($PhysicalNames;
an unnamed physical tag is named by its number, "3"), a cell set of lines (meshio's
``cell_sets``: .xdmf, .vtu written by meshio), or, for a format that stores no names,
an integer cell data on the lines (each value a boundary named by its number).  Any
failure is one :class:`~skfem_beam.errors.InputError` line naming the file."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..checks import check_count, check_positive
from ..errors import InputError


@dataclass(frozen=True, eq=False)
class PlateMesh:
    """``points`` (2, vertices) in m, ``triangles`` (3, triangles) vertex indices,
    ``boundaries`` name → (2, lines) vertex index pairs, ``source`` the file as named."""
    points: np.ndarray
    triangles: np.ndarray
    boundaries: dict
    source: str = ""


def _line_names(m, block: int, cells: np.ndarray) -> dict[str, np.ndarray]:
    """name → the rows of ``cells`` (the line block ``block`` of meshio's mesh ``m``)."""
    out: dict[str, list] = {}
    tags = (m.cell_data.get("gmsh:physical") or [None] * len(m.cells))[block]
    if tags is not None:
        named = {int(v[0]): k for k, v in (m.field_data or {}).items()
                 if len(v) > 1 and int(v[1]) == 1}
        for tag in np.unique(tags):
            out.setdefault(named.get(int(tag), str(int(tag))), []).append(
                np.flatnonzero(tags == tag))
    for name, sets in (m.cell_sets or {}).items():
        if name.startswith("gmsh:") or block >= len(sets) or sets[block] is None:
            continue
        rows = np.asarray(sets[block], dtype=int)
        if rows.size:
            out.setdefault(name, []).append(rows)
    if not out:     # a format without names: an integer cell data on the lines
        for key, data in m.cell_data.items():
            values = np.asarray(data[block])
            if key.startswith("gmsh:") or values.ndim != 1 or not np.issubdtype(
                    values.dtype, np.integer):
                continue
            for tag in np.unique(values):
                out.setdefault(str(int(tag)), []).append(np.flatnonzero(values == tag))
    return {k: cells[np.concatenate(v)] for k, v in out.items()}


def _read(path: Path):
    """meshio's mesh in ``path``; what meshio prints on the way (it tries each format an
    extension may be: .msh is ansys, then gmsh) is kept off the terminal."""
    import contextlib
    import io

    import meshio
    if not path.is_file():
        raise InputError(f"cannot read the mesh file {path}: "
                         + ("a folder, not a file" if path.is_dir() else "no such file"))
    chatter = io.StringIO()
    try:
        with contextlib.redirect_stdout(chatter), contextlib.redirect_stderr(chatter):
            return meshio.read(path, file_format="gmsh" if path.suffix == ".msh" else None)
    except SystemExit:      # meshio's way of saying no format it tried could parse it
        raise InputError(f"cannot read the mesh file {path}: meshio cannot parse it as "
                         f"{path.suffix or 'a file without extension'}") from None
    except Exception as e:  # meshio raises many kinds on a file it cannot parse
        why = (str(e).strip().splitlines() or [type(e).__name__])[0]
        raise InputError(f"cannot read the mesh file {path}: {why}") from None


# 2-D cells other than linear triangles, which a plate's mesh does not read
SURFACES = {"quad", "quad8", "quad9", "triangle6", "triangle7", "polygon"}


def _check_coincident(points, path) -> None:
    """One line when two vertices coincide (within 1e-9 of the mesh's size): a seam that
    was not merged, which cut the plate there (a clamped square's ω₁ 13.5 % low)."""
    from scipy.spatial import cKDTree
    size = float(np.ptp(points, axis=0).max()) if len(points) else 0.0
    pairs = cKDTree(points).query_pairs(1e-9 * size, output_type="ndarray")
    if len(pairs):
        x, y = points[pairs[0, 0]]
        raise InputError(f"the mesh file {path} has {len(pairs)} pair(s) of coincident "
                         f"vertices (the first at ({x:g}, {y:g})): a seam that was not "
                         "merged cuts the plate there; merge them (gmsh: Coherence Mesh)")


def read_plate_mesh(path, source: str | None = None) -> PlateMesh:
    """The plate's mesh in the file ``path`` (``source``: the name as written, for the
    summary and the error lines)."""
    if not isinstance(path, (str, Path)):
        raise InputError(f"read_plate_mesh needs a file name, not {path!r}")
    path = Path(path)
    m = _read(path)
    tri = [b.data for b in m.cells if b.type == "triangle"]
    if not tri:
        kinds = ", ".join(sorted({b.type for b in m.cells})) or "none"
        raise InputError(f"the mesh file {path} has no linear triangles (cells: {kinds}); "
                         "a plate's mesh needs 'triangle' cells")
    others = {b.type for b in m.cells if b.type in SURFACES}
    if others:      # else they were left out: holes in the plate (ω₁ 564 → 1,024 rad/s)
        count = sum(len(b.data) for b in m.cells if b.type in others)
        raise InputError(f"the mesh file {path} holds {count} {', '.join(sorted(others))} "
                         "cell(s) beside its triangles: a plate is read from linear "
                         "triangles alone and would have holes there; mesh it in triangles")
    triangles = np.concatenate(tri).T.astype(np.int64)
    xyz = np.asarray(m.points, dtype=float)
    if xyz.shape[1] > 2 and np.any(xyz[:, 2:] != 0):
        raise InputError(f"the mesh file {path} is not flat: its points have z ≠ 0")
    used = np.unique(triangles)
    bad = used[~np.isfinite(xyz[used, :2]).all(axis=1)]
    if bad.size:        # else a NaN or inf surfaced as a tiny cell or a singular step
        k = int(bad[0])
        raise InputError(f"the mesh file {path}: point {k} has a non-finite coordinate "
                         f"({', '.join(repr(float(c)) for c in xyz[k, :2])}); a plate's "
                         "points need finite x, y")
    _check_coincident(xyz[used, :2], path)
    number = np.full(xyz.shape[0], -1)
    number[used] = np.arange(used.size)     # the order of the file, unused points dropped
    lines: dict[str, list] = {}
    for i, block in enumerate(m.cells):
        if block.type == "line":
            for name, cells in _line_names(m, i, block.data).items():
                lines.setdefault(name, []).append(cells)
    boundaries = {}
    for name, parts in lines.items():
        pairs = number[np.concatenate(parts).T]
        if np.any(pairs < 0):
            raise InputError(f"the mesh file {path}: boundary {name!r} has a point that is "
                             "not a vertex of a triangle")
        boundaries[name] = pairs
    return PlateMesh(np.ascontiguousarray(xyz[used, :2].T), number[triangles], boundaries,
                     str(path) if source is None else source)


def disk(radius: float, rings: int, boundary: str = "rim") -> PlateMesh:
    """A disk of ``radius`` (m) centred at the origin: the centre and ``rings`` rings of
    6k vertices (k = 1..rings, radius·k/rings), Delaunay triangles, the outer ring's lines
    named ``boundary``: the mesh of the shipped plate_disk.msh and of the tests."""
    from scipy.spatial import Delaunay
    radius, rings = check_positive("disk radius", radius), check_count("disk rings", rings)
    xy = [np.zeros((1, 2))]
    for k in range(1, rings + 1):
        angle = np.arange(6 * k) * 2 * np.pi / (6 * k)
        xy.append(radius * k / rings * np.column_stack([np.cos(angle), np.sin(angle)]))
    points = np.concatenate(xy)
    triangles = Delaunay(points).simplices.T
    n = 6 * rings
    rim = points.shape[0] - n + np.arange(n)
    return PlateMesh(points.T.copy(), triangles.astype(np.int64),
                     {boundary: np.vstack([rim, np.roll(rim, -1)])}, f"disk({radius:g}, {rings})")


def write_msh(mesh: PlateMesh, path) -> None:
    """``mesh`` as a gmsh 2.2 ASCII file: the triangles (physical surface "plate") and
    each boundary's lines as a named physical line, so that :func:`read_plate_mesh` reads
    back the same vertices, triangles and names."""
    import meshio
    if not isinstance(mesh, PlateMesh):
        raise InputError(f"write_msh needs a PlateMesh (disk(...), read_plate_mesh(...)), "
                         f"not {mesh!r}")
    if not Path(path).parent.is_dir():
        raise InputError(f"write_msh: the folder of {path} does not exist")
    names = list(mesh.boundaries)
    lines = [mesh.boundaries[k].T for k in names]
    tags = [np.full(len(c), i + 1) for i, c in enumerate(lines)]
    surface = np.full(mesh.triangles.shape[1], len(names) + 1)
    cells = [("triangle", mesh.triangles.T)] + [("line", c) for c in lines]
    physical = [surface] + tags
    field = {k: np.array([i + 1, 1]) for i, k in enumerate(names)}
    field["plate"] = np.array([len(names) + 1, 2])
    points = np.column_stack([mesh.points.T, np.zeros(mesh.points.shape[1])])
    meshio.write(path, meshio.Mesh(points, cells, cell_data={"gmsh:physical": physical,
                                                             "gmsh:geometrical": physical},
                                   field_data=field), file_format="gmsh22", binary=False)
