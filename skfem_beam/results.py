"""A run's folder read back into Python, and exported for MATLAB (``.mat``) or numpy (``.npz``).

    from skfem_beam import read_run
    run = read_run("out/point_stops")
    run.summary["impacts"], run.series["t"], run.series["tip_displacement"]
    run.fields.t, run.fields.x, run.fields["displacement"]      # (frames, points)

    python -m skfem_beam export out/point_stops --to mat [--out pipe.mat]

What a command writes (docs/design.md §5) comes back as plain numpy arrays:

- ``summary``: summary.json as a dict (the strings "inf", "-inf", "nan" the writer made of
  non-finite floats are floats again);
- ``series``: every column of timeseries.csv by its header name, whatever the command
  wrote (probe columns included); exact (shortest round-trip) digits were written, so the values are
  the run's own, bit for bit;
- ``fields``: the field frames (:class:`SavedFields`) from ``fields.xdmf`` + ``fields.h5``,
  or from ``fields.pvd`` + ``fields_vtu/`` when there is no XDMF; None with ``--format
  none``;
- ``impacts``: the columns of ``impacts.csv`` when the run wrote one, else None;
- ``tables``: every other CSV of the folder (e.g. energy_decay's ``energy.csv``), by file
  stem, as columns.

A killed run reads back up to its last flush (its summary says "running").
"""
from __future__ import annotations

import csv
import io
import json
import os
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import InputError
from .lock import check_not_busy
from .parser import Parser

SERIES, SUMMARY, IMPACTS = "timeseries.csv", "summary.json", "impacts.csv"
CHECKPOINT = "checkpoint.npz"       # what --resume reads (output.checkpoint)
FORMATS = ("npz", "mat")


@dataclass
class SavedFields:
    """Field frames as saved: ``t`` (frames,), ``points`` (points, 3), and ``arrays``:
    name → (frames, points) or (frames, points, 3) for vectors; ``source``: "xdmf" or "vtu"."""
    t: np.ndarray
    points: np.ndarray
    arrays: dict[str, np.ndarray]
    source: str

    @property
    def x(self) -> np.ndarray:
        """The abscissae of the points (the line lies along x)."""
        return self.points[:, 0]

    def __getitem__(self, name: str) -> np.ndarray:
        if name not in self.arrays:     # e.g. displacement in a two-plane run's folder
            raise KeyError(f"{name!r} is not a field of this run; it holds: "
                           f"{', '.join(self.arrays)}")
        return self.arrays[name]


@dataclass
class SavedRun:
    """One run folder read back (see the module docstring)."""
    folder: Path
    summary: dict
    series: dict[str, np.ndarray]
    fields: SavedFields | None = None
    impacts: dict[str, np.ndarray] | None = None
    tables: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)

    @property
    def t(self) -> np.ndarray:
        return self.series["t"]

    @property
    def status(self) -> str:
        return self.summary.get("status", "")

    def __getitem__(self, name: str) -> np.ndarray:
        return self.series[name]


# ---------------------------------------------------------------- reading

def _unplain(value):
    """Undo output.folder._plain: the non-finite floats it wrote as strings."""
    if isinstance(value, dict):
        return {k: _unplain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_unplain(v) for v in value]
    if value in ("inf", "-inf", "nan"):
        return float(value)
    return value


def read_csv(path: Path) -> dict[str, np.ndarray]:
    """A CSV with a header row as columns: floats where every value parses as one (parsed
    exactly: the digits written come back bit for bit), strings otherwise.  A last line
    without its newline is a part of a row (a run killed within a write: output.series)
    and is left out."""
    path = Path(path)
    with open(path, newline="") as fh:
        header = next(csv.reader([fh.readline()]), [])
        if not header:
            raise InputError(f"{path} has no header row")
        body = fh.read()
    body = body[:body.rfind("\n") + 1]
    if not body.strip():          # a header alone: e.g. impacts.csv of a run without impact
        return {name: np.zeros(0) for name in header}
    try:    # the fast path: every value a number (numpy's parser rounds correctly)
        values = np.loadtxt(io.StringIO(body), delimiter=",", ndmin=2, dtype=float)
    except ValueError:
        values = None
    if values is not None:
        if values.size == 0:
            values = np.zeros((0, len(header)))
        if values.shape[1] != len(header):
            raise InputError(f"{path}: {values.shape[1]} values per row under "
                             f"{len(header)} column names")
        return {name: values[:, i].copy() for i, name in enumerate(header)}
    rows = list(csv.reader(io.StringIO(body)))   # mixed columns (e.g. a label per impact)
    return {name: _column(path, name, [r[i] if i < len(r) else "" for r in rows])
            for i, name in enumerate(header)}


def _column(path: Path, name: str, col: list[str]) -> np.ndarray:
    """Floats, or strings for a column of text; a column of numbers with a word in it is
    a damaged file (it came back as text, and an export wrote it so)."""
    numbers = []
    for row, v in enumerate(col):
        try:
            numbers.append(float(v))
        except ValueError:
            if v.strip() and any(_number(w) for w in col):
                raise InputError(f"{path}: row {row + 2}, column {name}: {v!r} is not a "
                                 "number, as the column's other values are (a damaged "
                                 "file)") from None
            return np.array(col)
    return np.array(numbers)


def _number(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


def _h5_item(folder: Path, item: ET.Element, h5files: dict):
    """The array a <DataItem Format="HDF">file.h5:/name</DataItem> points at."""
    import h5py
    fname, _, dataset = item.text.strip().partition(":")
    if fname not in h5files:
        h5files[fname] = h5py.File(folder / fname, "r")
    return h5files[fname][dataset][()]


def read_xdmf(path: Path) -> SavedFields:
    """The frames of an XDMF temporal collection whose data live in an .h5 beside it
    (the layout :class:`~skfem_beam.output.fields.FieldWriter` writes: the mesh in the
    first step, included by the others)."""
    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        raise InputError(f"{path} is not readable XML ({e})") from None
    steps = root.findall("./Domain/Grid/Grid")
    h5files: dict = {}
    try:
        if not steps:
            raise InputError(f"{path} holds no time steps")
        points = _h5_item(path.parent, steps[0].find("Geometry/DataItem"), h5files)
        times, arrays = [], {}
        for grid in steps:
            times.append(float(grid.find("Time").get("Value")))
            for att in grid.findall("Attribute"):
                arrays.setdefault(att.get("Name"), []).append(
                    _h5_item(path.parent, att.find("DataItem"), h5files))
    except (OSError, KeyError) as e:
        raise InputError(f"{path}: its .h5 data cannot be read ({e})") from None
    finally:
        for f in h5files.values():
            f.close()
    return SavedFields(np.array(times), np.asarray(points, dtype=float),
                       {k: np.array(v) for k, v in arrays.items()}, "xdmf")


def read_pvd(path: Path) -> SavedFields:
    """The frames of a ``.pvd`` collection of ``.vtu`` files (read with meshio)."""
    import meshio
    path = Path(path)
    try:
        sets = ET.parse(path).getroot().findall("./Collection/DataSet")
    except ET.ParseError as e:
        raise InputError(f"{path} is not readable XML ({e})") from None
    if not sets:
        raise InputError(f"{path} holds no time steps")
    times, arrays, points = [], {}, None
    for ds in sets:
        try:
            mesh = meshio.read(path.parent / ds.get("file"), file_format="vtu")
        except OSError as e:
            raise InputError(f"{path}: frame {ds.get('file')} cannot be read ({e})") from None
        points = mesh.points if points is None else points
        times.append(float(ds.get("timestep")))
        for k, v in mesh.point_data.items():
            arrays.setdefault(k, []).append(v)
    return SavedFields(np.array(times), np.asarray(points, dtype=float),
                       {k: np.array(v) for k, v in arrays.items()}, "vtu")


def read_run(folder, fields: str = "auto") -> SavedRun:
    """Read the run folder ``folder`` (see the module docstring).

    ``fields``: "auto" (XDMF when it is there, else VTU), "xdmf", "vtu", or "none"
    (skip the field frames, the largest part of a folder).
    """
    if fields not in ("auto", "xdmf", "vtu", "none"):
        raise InputError(f"fields={fields!r} is not one of: auto, xdmf, vtu, none")
    if not isinstance(folder, (str, Path)):
        raise InputError(f"read_run needs a run folder's path, not {folder!r}")
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"{folder} is not a run folder: no such folder")
    missing = [name for name in (SUMMARY, SERIES) if not (folder / name).is_file()]
    if missing:
        raise InputError(f"{folder} is not a run folder: no {' and no '.join(missing)}")
    try:
        summary = _unplain(json.loads((folder / SUMMARY).read_text()))
    except json.JSONDecodeError as e:
        raise InputError(f"{folder / SUMMARY} is not valid JSON ({e})") from None
    series = read_csv(folder / SERIES)
    xdmf, pvd = folder / "fields.xdmf", folder / "fields.pvd"
    frames = None
    try:
        if fields in ("auto", "xdmf") and xdmf.is_file():
            frames = read_xdmf(xdmf)
        elif fields in ("auto", "vtu") and pvd.is_file():
            frames = read_pvd(pvd)
    except InputError as e:     # a run writing them now: not damaged, read in mid-flush
        if summary.get("status") != "running":
            raise
        raise InputError(f"{folder}: a run is writing its fields now ({e}): read it again, "
                         "or read_run(folder, fields='none') for the rows") from None
    if frames is None and fields in ("xdmf", "vtu"):      # the file asked for is not there
        raise InputError(f"{folder} has no {fields} field files "
                         f"({'fields.xdmf' if fields == 'xdmf' else 'fields.pvd'})")
    impacts = read_csv(folder / IMPACTS) if (folder / IMPACTS).is_file() else None
    tables = {p.stem: read_csv(p) for p in sorted(folder.glob("*.csv"))
              if p.name not in (SERIES, IMPACTS)}
    return SavedRun(folder, summary, series, frames, impacts, tables)


# ---------------------------------------------------------------- export

_MATLAB_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,62}$")


def matlab_name(name: str, taken=()) -> str:
    """``name`` made a variable name MATLAB accepts (a letter first, then letters, digits,
    underscores, at most 63 characters), different from every name in ``taken``."""
    s = re.sub(r"[^A-Za-z0-9_]", "_", str(name))
    if not s or not s[0].isalpha():
        s = "x" + s
    s = s[:63]
    base, k = s, 2
    while s in taken:
        tail = f"_{k}"
        s, k = base[:63 - len(tail)] + tail, k + 1
    return s


def _numbers(v) -> bool:
    """A number, or a list of numbers (not strings that happen to parse as numbers)."""
    if isinstance(v, (list, tuple)):
        return all(isinstance(w, (int, float)) for w in v)
    return isinstance(v, (int, float))


def _matlab_value(value):
    """A summary entry as savemat stores it: dicts become structs, None an empty matrix,
    lists of numbers (or of equal-length number lists) matrices, other lists cells."""
    if isinstance(value, dict):
        out = {}
        for k, v in value.items():
            out[matlab_name(k, out)] = _matlab_value(v)
        return out
    if value is None:
        return np.zeros((0, 0))
    if isinstance(value, (list, tuple)):
        try:
            if all(_numbers(v) for v in value):
                return np.array(value, dtype=float)
        except ValueError:           # ragged: a cell of rows
            pass
        cell = np.empty(len(value), dtype=object)
        for i, v in enumerate(value):
            cell[i] = _matlab_value(v)
        return cell
    return value


def variables(run: SavedRun, matlab: bool = True) -> dict:
    """The run as flat named arrays: series columns under their own names, field arrays
    as ``fields_<name>`` (frames × points) with ``fields_t``, ``fields_x`` and (a plate's)
    ``fields_y``, impacts as
    ``impacts_<column>``, other tables as ``<stem>_<column>``; with ``matlab`` every name
    made MATLAB-valid (``probe_0.6_displacement`` → ``probe_0_6_displacement``)."""
    out: dict = {}

    def put(name, value):
        out[matlab_name(name, out) if matlab else name] = value

    for k, v in run.series.items():
        put(k, v)
    if run.fields is not None:
        put("fields_t", run.fields.t)
        put("fields_x", run.fields.x)
        if np.any(run.fields.points[:, 1]):         # a plate's vertices
            put("fields_y", run.fields.points[:, 1])
        for k, v in run.fields.arrays.items():
            put(f"fields_{k}", v)
    for prefix, table in [("impacts", run.impacts or {})] + list(run.tables.items()):
        for k, v in table.items():
            put(f"{prefix}_{k}", v)
    return out


def export(folder, to: str, out=None) -> Path:
    """Write the run in ``folder`` as ``to`` = "npz" (numpy) or "mat" (MATLAB, v5 via
    scipy.io.savemat: series as column vectors, fields as frames × points matrices, the
    summary as a struct); return the file (default: ``folder/<folder name>.<to>``).
    In the ``.npz`` the summary is the JSON text ``summary_json``."""
    if to not in FORMATS:
        raise InputError(f"--to {to!r} is not one of: {', '.join(FORMATS)}")
    folder = Path(folder)
    if not folder.is_dir():             # before --out, which defaults to a file inside it
        raise InputError(f"{folder} is not a run folder: no such folder")
    check_not_busy(folder)              # a run writing it: its files are half there
    out = Path(out) if out is not None else folder / f"{folder.resolve().name}.{to}"
    if out.suffix != f".{to}":
        raise InputError(f"--out {out} must end in .{to} for --to {to}")
    if out.name == CHECKPOINT and (out.resolve() == (folder / CHECKPOINT).resolve()
                                   or (out.parent / "summary.json").is_file()):
        raise InputError(f"--out {out} is a run's checkpoint (what --resume reads): "
                         "choose another file")
    if not out.parent.is_dir():
        raise InputError(f"--out {out}: folder {out.parent} does not exist")
    if out.exists() and not _an_export(out, to):     # it replaced a user's thesis.mat
        raise InputError(f"--out {out} exists and is not an export of a run: choose another "
                         "file (an earlier export there is replaced)")
    run = read_run(folder)
    data = variables(run, matlab=to == "mat")
    tmp = out.with_name(f".{out.stem}.{os.getpid()}.tmp{out.suffix}")
    try:
        if to == "npz":
            np.savez_compressed(tmp, summary_json=np.array(json.dumps(run.summary)), **data)
        else:
            from scipy.io import savemat
            data["summary"] = _matlab_value(run.summary)
            savemat(tmp, data, do_compression=True, long_field_names=True, oned_as="column")
        os.replace(tmp, out)
    finally:
        tmp.unlink(missing_ok=True)
    return out


def _an_export(path: Path, to: str) -> bool:
    """Whether ``path`` is a file ``export`` wrote: its summary is in it (``summary_json``
    in a .npz, ``summary`` in a .mat)."""
    try:
        if to == "npz":
            with np.load(path) as f:
                return "summary_json" in f.files
        from scipy.io import whosmat
        return any(name == "summary" for name, _, _ in whosmat(path))
    except Exception:       # noqa: BLE001  (not a file numpy or scipy can read: not ours)
        return False


def export_main(argv=None) -> int:
    """``python -m skfem_beam export DIR --to npz|mat [--out FILE]``."""
    p = Parser(prog="python -m skfem_beam export",
               description="write a run folder's results as one .npz (numpy) or .mat "
                           "(MATLAB) file")
    p.add_argument("folder", metavar="DIR", help="a run folder (summary.json, timeseries.csv)")
    p.add_argument("--to", required=True, help="npz | mat")
    p.add_argument("--out", metavar="FILE", default=None,
                   help="the file to write (default DIR/<DIR name>.npz or .mat)")
    args = p.parse_args(argv)
    path = export(args.folder, args.to, args.out)
    print(f"{args.folder} -> {path} ({path.stat().st_size / 1e6:.3g} MB)")
    return 0
