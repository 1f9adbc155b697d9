"""Scene files: a beam or a bar, its time grid, contact law and output, in one TOML file.

    python -m skfem_beam run SCENE.toml [--out DIR] [--set time.dt=1e-5 ...] [--T 4]
        [--format F] [--frames N] [--save-every N] [--flush-every N]
        [--checkpoint-every S] [--resume DIR] [--overwrite]
    python -m skfem_beam modes SCENE.toml [--n 6] [--out DIR] [--set ...]

:func:`load` reads a file into the objects of the Python API, one to one (:class:`Scene`:
``problem`` a BeamProblem or a Bar, ``stepping`` a scheme.Stepping, the contact law, the
output options).  Every value is checked by the object it builds; this module checks only
the file's shape: an unknown section or key is refused in one line naming it and the
allowed ones, and a value the schema marks as a number (N), or an array of numbers
(ListOf), that is not one (``"0.5m"``) in one line naming its key path (with the index
inside an array: ``output.probes[0]``).  Relative paths (tables) are relative to the
scene file.  The keys are :data:`BEAM_KEYS` and :data:`BAR_KEYS` (docs/scene_files.md,
generated from them).

Choices a TOML file forces:

- obstacles are numbers, polynomials ``{ poly = [c0, c1, c2, ...], about = x0 }``
  (Σ c_k (x − x0)^k, the second paper's convex obstacles) or tables ``{ x = [...],
  g = [...] }`` (linear between the points; its corners need not be mesh nodes), over a
  point (``x``), a span (``x_from``, ``x_to``) or, with neither, the whole beam;
- a beam's u0/v0 tables ``{ x = [...], u = [...] }`` are interpolated by a not-a-knot
  cubic spline (C², its slope gives the Hermite slopes); a bar's linearly (P1);
- ``[initial]`` of a beam is read in the fixed frame (ũ, ũ_t) unless ``fixed_frame =
  false``: a scene with no ``[initial]`` starts at rest, as the papers' pipe does.
"""
from __future__ import annotations

import argparse
import csv
import math
import sys
import tempfile
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..bar import Bar
from ..errors import InputError
from ..problem import (Beam, BeamProblem, Damping, InitialState, Load, Material, Obstacles,
                      Section, Support)
from ..checks import check_choice
from .. import methods
from ..contact import SOLVERS
from ..output.options import OutputOptions
from ..scheme import Stepping
from ..spec import RunSpec
from ..timefunctions import Constant, Sine, SumOfSines, Table, band_limited, psd_from_csv

BEAM_MASSES = ("consistent", "redistributed")        # [mesh] mass of a beam
SCENE_WORDS = methods.Words(solver="[contact] law = ", massless="[mesh] massless = ",
                            law="[contact] law = ", restitution="[contact] restitution = ",
                            theta="[contact] theta = ")

V = None          # a value (checked by the object it builds)


class Number:
    """In a schema: a number (TOML integer or float, inf included; not a string such as
    "0.25mm", not a boolean), checked where the file is read."""


N = Number()


class ListOf:
    """In a schema: an array whose every item is ``item`` (N, or a ListOf: an array of
    arrays), checked where the file is read, so that a unit string inside a list is one
    line naming its index (``output.probes[0]``) as a single number is.  The lengths are
    the objects' to check (a direction is a pair, a face a triple)."""

    def __init__(self, item):
        self.item = item

    def describe(self) -> str:
        inner = "numbers" if self.item is N else self.item.describe()
        return f"an array of {inner}"


class NumberOrWord:
    """In a schema: a number, or one of ``words`` (a bar's obstacle x: 0, L, "left",
    "right")."""

    def __init__(self, *words):
        self.words = words


class Either(dict):
    """In a schema: a value, or a table of these keys."""


class NumberOr(dict):
    """In a schema: a number, or a table of these keys (``form``: the table as written,
    for the error line)."""

    def __init__(self, keys: dict, form: str):
        super().__init__(keys)
        self.form = form


NUMBERS = ListOf(N)
TIME = {"amplitude": N, "omega": N, "phase": N, "value": N, "sines": ListOf(NUMBERS),
        "table": V, "random": {"rms": N, "f_low": N, "f_high": N, "seed": N, "count": N},
        "psd": Either({"table": V, "seed": N, "df": N})}
SECTION = {"I": N, "A": N, "I_y": N, "I_z": N, "tube": {"outer_diameter": N, "wall": N},
           "rod": {"diameter": N}, "rect": {"b": N, "h": N}}
MATERIAL = {"E": N, "rho": N}
U0, V0 = {"x": NUMBERS, "u": NUMBERS}, {"x": NUMBERS, "v": NUMBERS}
TIME_KEYS = {"dt": N, "T": N, "beta": N, "load_window": V}
OUTPUT = {"format": V, "save_every": N, "frames": N, "flush_every": N, "checkpoint_every": N,
          "probes": NUMBERS}
CONTACT = {"law": V, "stiffness": N, "restitution": N, "friction": N, "theta": N}
G = NumberOr({"poly": NUMBERS, "about": N, "x": NUMBERS, "g": NUMBERS},   # the rest: _g
             "{ poly = [...] } or { x = [...], g = [...] }")
HOLE = {"radius": N, "sides": N, "angle": N, "centre": NUMBERS,     # the rest: holes.py
        "polygon": ListOf(NUMBERS), "faces": ListOf(NUMBERS), "lands": N, "land_width": N}

BEAM_KEYS = {
    "kind": V, "planes": N, "material": MATERIAL, "section": SECTION,
    "mass_normalised": {"k2": N, "rho_S": N},
    "mass": {"added": N},
    "geometry": {"L": N},
    "segments": [{"length": N, "material": MATERIAL, "section": SECTION}],
    "ends": {"left": V, "right": V},
    "supports": [{"x": N}],
    "motion": {"end": V, "at": N, "lifting": V, "direction": NUMBERS, **TIME},
    "obstacles": [{"x": N, "x_from": N, "x_to": N, "g1": G, "g2": G, "hole": HOLE,
                   "carried": V, "stiffness": N, "damping": N, "friction": N}],
    "wear": {"coefficient": N, "service_years": N, "land": N, "radius": N},
    "damping": {"zeta": N, "f1": N, "f2": N, "alpha": N, "alpha_K": N, "modal": N},
    "loads": [{"x": N, "distributed": V, "per_mass": V, "gravity": N, "x_from": N, "x_to": N,
               "direction": NUMBERS, "rotating": {"amplitude": N, "omega": N,
                                                  "phase": N},
               **TIME}],
    "initial": {"mode": N, "amplitude": N, "u0": U0, "v0": V0, "fixed_frame": V},
    "mesh": {"J": N, "element": V, "nodes": NUMBERS, "mass": V, "massless": V},
    "time": TIME_KEYS, "contact": CONTACT, "output": OUTPUT,
}
BAR_KEYS = {
    "kind": V, "material": MATERIAL, "section": SECTION, "geometry": {"L": N},
    "ends": {"left": V, "right": V},
    "obstacles": [{"x": NumberOrWord("left", "right"), "stiffness": N}],
    "damping": {"viscosity": N},
    "loads": [{"value": N}],
    "initial": {"u0": NumberOr(U0, "{ x = [...], u = [...] }"),
                "v0": NumberOr(V0, "{ x = [...], v = [...] }")},
    "mesh": {"J": N, "mass": V, "massless": V},
    "time": TIME_KEYS, "contact": CONTACT, "output": OUTPUT,
}
KINDS = {"beam": BEAM_KEYS, "bar": BAR_KEYS}
OUTPUT_DEFAULTS = {"format": "both", "save_every": 1, "frames": 200, "flush_every": 20000,
                   "checkpoint_every": None}


@dataclass(frozen=True)
class Scene:
    """A scene file read into the Python API's objects.

    ``problem``: a BeamProblem or a Bar; ``stepping``: the time grid; ``law``,
    ``stiffness`` (N/m), ``restitution``: the [contact] keys, ``damping`` (N·s/m): the
    supports' dashpots ([[obstacles]] damping) (``method`` builds the run's method from
    them);
    ``output``: format, save_every, frames, flush_every, checkpoint_every; ``text``: the
    file as read and ``files`` the tables it read (path as written → text), so that a run
    can be rebuilt from its summary.json; ``data``: the parsed TOML with the overrides.
    """
    kind: str
    problem: object
    stepping: Stepping
    law: str = "auto"
    stiffness: float | None = None
    restitution: float = 0.0
    output: dict = field(default_factory=dict)
    text: str = ""
    files: dict = field(default_factory=dict)
    data: dict = field(default_factory=dict)
    damping: float = 0.0

    @property
    def method(self) -> methods.Method:
        """The run's method (:mod:`skfem_beam.methods`): ``law`` names a class
        (methods.LAWS) or a position-level solver."""
        law, solver = (self.law, "auto") if self.law in methods.LAWS else ("position", self.law)
        if law == "penalty" and self.stiffness is None:
            raise InputError("[contact] law='penalty' needs stiffness (N/m)")
        massless = self.data.get("mesh", {}).get("massless")    # as written: None if not
        theta = self.data.get("contact", {}).get("theta")
        return methods.make(law, solver, self.restitution or 0.0, self.stiffness, massless,
                            words=SCENE_WORDS, damping=self.damping, theta=theta)


# ---------------------------------------------------------------- the file's shape

def _where(path: tuple) -> str:
    """A key path as written in error lines: tables and arrays of tables dotted, as
    ``--set`` names them (``obstacles.0.g1``), items of a value's array by index
    (``output.probes[0]``)."""
    out = ""
    for part in path:
        out += part if str(part).startswith("[") else f".{part}" if out else str(part)
    return out


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


SI = "in SI units (m, s, kg, N, Pa; e.g. 0.25 mm is 0.00025)"


def _written(path: tuple, value, sets) -> str:
    """The bad value as the user wrote it: ``key = value`` in the file, or the ``--set``
    that gave it (``sets``: dotted key → text), then the item inside it if the --set
    gave a whole array."""
    name = _where(path)
    key = _where(tuple(p for p in path if not str(p).startswith("[")))
    if not sets or key not in sets:
        return f"{name} = {value!r}"
    given = f"--set {key}={sets[key]}"
    return given if key == name else f"{given}: {name} = {value!r}"


def _bad_value(path: tuple, value, sets, allowed: str) -> InputError:
    return InputError(f"{_written(path, value, sets)}: must be {allowed}")


def _check_keys(data, schema, path=(), sets=None) -> None:
    """Refuse a key ``schema`` does not allow, naming it and the allowed ones, and check
    each value by its schema entry (``sets``: the keys ``--set`` gave, dotted, as written
    there)."""
    for key, value in data.items():
        if key not in schema:
            where = f"[{_where(path)}]" if path else "the top level"
            raise InputError(f"unknown key {_where(path + (key,))!r}; {where} allows: "
                             f"{', '.join(schema)}")
        _check_value(value, schema[key], path + (key,), sets)


def _check_value(value, sub, path: tuple, sets) -> None:
    """Refuse ``value`` if it is not what its schema entry ``sub`` says (a number, an
    array of them, a table, an array of tables), naming its key path, the value as
    written and what is allowed; V (a value the objects check) passes."""
    if sub is N:
        if not _is_number(value):
            raise _bad_value(path, value, sets, f"a number, {SI}")
    elif isinstance(sub, NumberOrWord):
        if not _is_number(value) and value not in sub.words:
            words = ", ".join(repr(w) for w in sub.words)
            raise _bad_value(path, value, sets, f"a number or one of {words}, {SI}")
    elif isinstance(sub, ListOf):
        if not isinstance(value, list):
            raise _bad_value(path, value, sets, f"{sub.describe()}, {SI}")
        for i, item in enumerate(value):
            _check_value(item, sub.item, path + (f"[{i}]",), sets)
    elif isinstance(sub, NumberOr) and not isinstance(value, dict):
        if not _is_number(value):
            raise _bad_value(path, value, sets, f"a number or a table ({sub.form}), {SI}")
    elif isinstance(sub, Either) and not isinstance(value, dict):
        return          # the value form: checked by the object it builds
    elif isinstance(sub, dict):
        if not isinstance(value, dict):
            raise InputError(f"{_where(path)} must be a table of {', '.join(sub)} "
                             f"(got {value!r})")
        _check_keys(value, sub, path, sets)
    elif isinstance(sub, list):
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise InputError(f"{_where(path)} must be an array of tables "
                             f"[[{_where(path)}]] of {', '.join(sub[0])}")
        for i, item in enumerate(value):
            _check_keys(item, sub[0], path + (i,), sets)


def _toml_value(text: str):
    """``text`` as a TOML value (number, boolean, array, inline table, quoted string);
    a bare word is a string (``--set ends.right=free``)."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def apply_set(data: dict, assignment: str) -> tuple[str, str]:
    """``KEY=VALUE`` (KEY dotted, array items by index: ``obstacles.0.g1``) into
    ``data``; a key the scene's kind does not allow is refused by name.  Returns (KEY,
    VALUE) as written."""
    key, eq, text = assignment.partition("=")
    if not eq or not key.strip():
        raise InputError(f"--set {assignment!r}: expected KEY=VALUE, e.g. time.dt=1e-5")
    parts = key.strip().split(".")
    schema = KINDS.get(data.get("kind", "beam"), BEAM_KEYS)
    node, sub = data, schema
    for i, part in enumerate(parts):
        last = i == len(parts) - 1
        if isinstance(sub, list):
            items = node
            if not part.isdigit() or int(part) > len(items):
                raise InputError(f"--set {key}: {_where(parts[:i])} has {len(items)} "
                                 f"item(s); index {part!r} must be 0..{len(items)}")
            if int(part) == len(items):
                items.append({})
            node, sub = items[int(part)], sub[0]
            if last:
                raise InputError(f"--set {key}: name a key of the item, e.g. "
                                 f"{key}.{next(iter(sub))}")
            continue
        if not isinstance(sub, dict) or part not in sub:
            allowed = ", ".join(sub) if isinstance(sub, dict) else "none"
            raise InputError(f"--set {key}: unknown key {part!r}; "
                             f"{'[' + _where(parts[:i]) + ']' if i else 'the top level'} "
                             f"allows: {allowed}")
        if last:
            node[part] = _toml_value(text.strip())
            return ".".join(parts), text.strip()
        child = sub[part]
        if isinstance(child, list):
            node = node.setdefault(part, [])
        else:
            node = node.setdefault(part, {})
        sub = child


# ---------------------------------------------------------------- reading

def load(path, overrides=(), files: dict | None = None, text: str | None = None,
         dynamic: bool = True) -> Scene:
    """Read the scene file ``path`` (``overrides``: ``KEY=VALUE`` strings as ``--set``).
    ``text``/``files``: the file's and its tables' stored texts (a resumed run) instead of
    the file system.  ``dynamic=False``: the structure alone (natural frequencies need
    no [time], [contact] or [output]: they are not read, and ``stepping`` is None)."""
    path = Path(path)
    if text is None:
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as e:
            raise InputError(f"cannot read the scene file {path}: {e.strerror}") from None
        except UnicodeDecodeError:
            raise InputError(f"{path}: not a UTF-8 text file") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"{path}: not valid TOML: {e}") from None
    kind = data.get("kind", "beam")
    if kind not in KINDS:
        raise InputError(f"{path}: kind={kind!r} must be one of: {', '.join(KINDS)}")
    sets = dict(apply_set(data, assignment) for assignment in overrides)
    kind = data.get("kind", "beam")
    reader = _Reader(path.parent, dict(files or {}))
    try:    # every error line names the file
        _check_keys(data, KINDS[kind], sets=sets)
        with tempfile.TemporaryDirectory() as tmp:
            reader.tmp = Path(tmp)
            problem = (_beam_problem if kind == "beam" else _bar)(data, reader)
        if not dynamic:
            return Scene(kind, problem, None, text=text, files=reader.read, data=data)
        return _scene(kind, problem, data, text, reader.read)
    except InputError as e:
        raise InputError(f"{path.name}: {e}") from None


def _supports(data: dict) -> tuple[float, float] | None:
    """A beam's [[obstacles]] stiffness (N/m) and damping (N·s/m, default 0): the supports'
    own compliance, one pair for all of them (the penalty law's springs and dashpots;
    their deflection is the support's).  None: rigid supports."""
    if data.get("kind", "beam") != "beam":
        return None
    obstacles = data.get("obstacles", [])
    pairs = {(o.get("stiffness"), o.get("damping")) for o in obstacles}
    if pairs <= {(None, None)}:
        return None
    if len(pairs) > 1 or None in {k for k, _ in pairs}:
        raise InputError("[[obstacles]] stiffness, damping: give every obstacle the same "
                         f"(got {', '.join(f'{k}, {c}' for k, c in sorted(pairs, key=str))})")
    if "stiffness" in data.get("contact", {}) or \
            data.get("contact", {}).get("law", "penalty") not in ("penalty", "auto"):
        raise InputError("[[obstacles]] stiffness makes the supports springs (the penalty "
                         "law): leave out [contact] law and stiffness")
    (k, c), = pairs
    return k, 0.0 if c is None else c


def _scene(kind, problem, data, text, files) -> Scene:
    contact = data.get("contact", {})
    law, k, c = contact.get("law", "auto"), contact.get("stiffness"), 0.0
    if any(h.friction > 0 for h in getattr(problem, "holes", ())) and "law" not in contact:
        law = methods.MoreauJean.name    # Coulomb friction is a velocity-level law
    supports = _supports(data)
    if supports is not None:
        law, (k, c) = "penalty", supports
    if k is not None and law == "auto":
        law = "penalty"
    check_choice("[contact] law", law, (*methods.LAWS, *SOLVERS))
    if k is not None and law in methods.LAWS and law != methods.Penalty.name:
        raise InputError(f"[contact] stiffness is the penalty spring: law = {law!r} does not "
                         "take it")
    t, mesh = data.get("time", {}), data.get("mesh", {})
    if "dt" not in t or "T" not in t:
        raise InputError("[time] needs dt and T (s)")
    out = {**OUTPUT_DEFAULTS, **data.get("output", {})}
    if kind == "beam":
        check_choice("[mesh] mass", mesh.get("mass", "consistent"), BEAM_MASSES)
        if mesh.get("mass") == "redistributed" and _planes(data) == 2:
            raise InputError("[mesh] mass = \"redistributed\" is for one plane; planes = 2 "
                             "takes the consistent mass")
    rows = mesh.get("massless")
    methods.check_massless(rows, mesh.get("mass", "consistent"), "[mesh] massless")
    scene = Scene(kind, problem, Stepping(t["dt"], t["T"], 0.5, massless=rows or "beta"), law, k,
                  contact.get("restitution", 0.0), out, text, files, data, c)
    method = scene.method          # the method's own checks (law, stiffness, restitution)
    beta = t.get("beta", methods.default_beta(method, kind))
    stepping = Stepping(t["dt"], t["T"], beta, out["save_every"], out["frames"],
                        t.get("load_window", "forward"), massless=rows or "beta")
    return replace(scene, stepping=stepping)


class _Reader:
    """Files named in the scene, relative to it; their texts are kept (``read``) so that a
    run stores them, and a resumed run reads the stored texts (``stored``)."""

    def __init__(self, base: Path, stored: dict):
        self.base, self.stored, self.read, self.tmp = base, stored, {}, None

    def path(self, name) -> Path:
        if not isinstance(name, str):
            raise InputError(f"table={name!r} must be a file name (a string)")
        if name in self.stored:
            p = self.tmp / f"{len(self.read)}_{Path(name).name}"
            p.write_text(self.stored[name], encoding="utf-8")
            self.read[name] = self.stored[name]
            return p
        p = Path(name) if Path(name).is_absolute() else self.base / name
        try:
            self.read[name] = p.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError):
            pass    # the reader names the file and why (Table.from_csv)
        return p


def _time_function(d: dict, where: str, reader: _Reader):
    """A time function from the keys of TIME (one form), or None when none is given."""
    forms = [k for k in ("amplitude", "value", "sines", "table", "random", "psd") if k in d]
    if "omega" in d and "amplitude" not in d:
        forms.append("omega")
    if len(forms) > 1:
        raise InputError(f"[{where}] give one of amplitude/omega, value, sines, table, "
                         f"random, psd (got {', '.join(forms)})")
    if not forms:
        return None
    form = forms[0]
    if form in ("amplitude", "omega"):
        return Sine(d.get("amplitude", 0.0), d.get("omega", 0.0), d.get("phase", 0.0))
    if form == "value":
        return Constant(d["value"])
    if form == "sines":
        rows = d["sines"]
        if not isinstance(rows, list) or not all(isinstance(r, list) and len(r) in (2, 3)
                                                 for r in rows):
            raise InputError(f"[{where}] sines must be [[amplitude, omega, phase], ...]")
        return SumOfSines(tuple(r[0] for r in rows), tuple(r[1] for r in rows),
                          tuple(r[2] if len(r) == 3 else 0.0 for r in rows))
    if form == "table":
        return Table.from_csv(reader.path(d["table"]))
    if form == "psd":   # a one-sided PSD table f (Hz), S (unit²/Hz), synthesised with a seed
        psd = d["psd"] if isinstance(d["psd"], dict) else {"table": d["psd"]}
        if "table" not in psd:
            raise InputError(f"[{where}] psd = {{ table = \"file.csv\", seed, df }} needs table")
        return psd_from_csv(reader.path(psd["table"]), psd.get("seed", 0), psd.get("df"))
    return band_limited(**d["random"])


def _section(d: dict, where: str) -> Section:
    """A [section]: I and A, I_y, I_z and A (two planes: v along y bends with I_z, w
    along z with I_y), tube, rod or rect."""
    forms = [k for k in ("tube", "rod", "rect") if k in d] + (["I/A"] if set(d) & {
        "I", "A", "I_y", "I_z"} else [])
    if len(forms) != 1:
        raise InputError(f"[{where}] needs one of I and A, I_y, I_z and A, tube, rod, rect "
                         f"(got {', '.join(forms) or 'none'})")
    if "I_y" in d or "I_z" in d:
        if "I" in d:
            raise InputError(f"[{where}] give I (one plane) or I_y and I_z, not both")
        axes = _need(d, ("I_y", "I_z", "A"), where)
        return Section(axes["I_z"], axes["A"], axes["I_y"])
    if "tube" in d:
        return Section.tube(**_need(d["tube"], ("outer_diameter", "wall"), f"{where}.tube"))
    if "rod" in d:
        return Section.rod(**_need(d["rod"], ("diameter",), f"{where}.rod"))
    if "rect" in d:
        return Section.rect(**_need(d["rect"], ("b", "h"), f"{where}.rect"))
    return Section(**_need(d, ("I", "A"), where))


def _bar_area(d: dict) -> float:
    """A bar's [section]: its area A (m²), given as A or by a tube, rod or rect (a bar
    has no bending, so no I)."""
    from ..checks import check_positive
    forms = [k for k in ("tube", "rod", "rect", "A") if k in d]
    if len(forms) != 1 or "I" in d:
        raise InputError(f"a bar's [section] needs one of A, tube, rod, rect (got "
                         f"{', '.join(forms + (['I'] if 'I' in d else [])) or 'none'}; a bar "
                         "has no I)")
    if "A" in d:
        return check_positive("section.A", d["A"])
    return _section(d, "section").A


def _need(d: dict, keys, where: str) -> dict:
    missing = [k for k in keys if k not in d]
    if missing:
        raise InputError(f"[{where}] needs {', '.join(keys)} (missing {', '.join(missing)})")
    return {k: d[k] for k in keys}


# beyond these a value is more likely in the wrong unit than a material (rubber to
# diamond; aerogel-free foams to osmium): one warning line, the run goes on
PLAUSIBLE = {"E": (1e6, 1.2e12, "Pa"), "rho": (10.0, 23000.0, "kg/m³")}


def _material(d: dict, where: str, plausible: bool = True) -> Material:
    """[material] E, rho; a beam's outside PLAUSIBLE warns (a bar's may be the papers'
    dimensionless a = ρ = 1)."""
    from ..cli import warn
    material = Material(**_need(d, ("E", "rho"), where))
    for key, (low, high, unit) in PLAUSIBLE.items():
        value = d[key]
        if plausible and not low <= value <= high:
            warn(f"[{where}] {key} = {value:g} {unit} is outside engineering materials "
                 f"({low:g}–{high:g} {unit}): is it in {unit}?")
    return material


def _beam(data: dict) -> Beam:
    """The beam of [material] + [section], [mass_normalised] or [[segments]], with its
    [mass] added (kg/m, e.g. the fluid's hydrodynamic mass)."""
    beam = _structure(data)
    added = data.get("mass", {}).get("added")
    return beam if added is None else beam.with_added_mass(added)


def _structure(data: dict) -> Beam:
    mn, segs = data.get("mass_normalised"), data.get("segments")
    forms = [k for k in ("mass_normalised", "segments") if k in data] + \
        (["material/section"] if "material" in data or "section" in data else [])
    if len(forms) != 1:
        raise InputError("a beam needs one of [material] with [section], [mass_normalised] "
                         f"(k2, rho_S) or [[segments]] (got {', '.join(forms) or 'none'})")
    if segs is not None:
        if "geometry" in data:
            raise InputError("[[segments]] give the length: leave out [geometry]")
        return Beam.stepped([(s.get("length", math.nan), _material(s.get("material", {}),
                                                                    f"segments.{i}.material"),
                              _section(s.get("section", {}), f"segments.{i}.section"))
                             for i, s in enumerate(segs)])
    L = _need(data.get("geometry", {}), ("L",), "geometry")["L"]
    if mn is not None:
        return Beam(L, _need(mn, ("k2",), "mass_normalised")["k2"], mn.get("rho_S"))
    return Beam.physical(L, _material(data.get("material", {}), "material"),
                         _section(data.get("section", {}), "section"))


def _g(value, where: str):
    """An obstacle g: a number, {poly, about} or {x, g} (a table, linear between points)."""
    if not isinstance(value, dict):
        return value
    if set(value) == {"poly", "about"} or set(value) == {"poly"}:
        c = [float(v) for v in value["poly"]]
        x0 = float(value.get("about", 0.0))

        def poly(x):
            d = np.asarray(x, dtype=float) - x0
            out = c[0] + c[1] * d if len(c) > 1 else np.full(d.shape, c[0])
            for k in range(2, len(c)):
                out = out + c[k] * d**k
            return out
        return poly
    if set(value) == {"x", "g"}:
        xs, gs = np.asarray(value["x"], dtype=float), np.asarray(value["g"], dtype=float)
        if xs.ndim != 1 or xs.shape != gs.shape or xs.size < 2 or np.any(np.diff(xs) <= 0):
            raise InputError(f"{where} = {{x, g}}: x must increase, with one g per x (at "
                             "least two)")
        return lambda x: np.interp(np.asarray(x, dtype=float), xs, gs)
    raise InputError(f"{where} must be a number, {{ poly = [c0, c1, ...], about = x0 }} or "
                     f"{{ x = [...], g = [...] }} (got keys {', '.join(value)})")


def _hole(o: dict, i: int, friction: float = 0.0):
    """A [[obstacles]] hole = {...} at x or over [x_from, x_to] (holes.HoleAt); its
    ``friction`` μ, else the scene's [contact] friction."""
    from ..holes import HoleAt, hole_from_table
    where = f"obstacles.{i}"
    if "g1" in o or "g2" in o:
        raise InputError(f"[{where}] a hole bounds (v, w) itself: leave out g1, g2")
    hole = hole_from_table(o["hole"], f"{where}.hole")
    mu = o.get("friction", friction)
    if "x" in o:
        if "x_from" in o or "x_to" in o:
            raise InputError(f"[{where}] give x or x_from, x_to, not both")
        return HoleAt(hole, o["x"], carried=o.get("carried", False), friction=mu)
    a, b = _need(o, ("x_from", "x_to"), where).values()
    return HoleAt(hole, a, b, carried=o.get("carried", False), friction=mu)


def _obstacle(o: dict, i: int) -> Obstacles:
    where = f"obstacles.{i}"
    g1, g2 = _g(o.get("g1", -np.inf), f"{where}.g1"), _g(o.get("g2", np.inf), f"{where}.g2")
    carried = o.get("carried", False)
    if "x" in o:
        if "x_from" in o or "x_to" in o or callable(g1) or callable(g2):
            raise InputError(f"[{where}] a point stop (x) takes numbers g1, g2 and no "
                             "x_from/x_to")
        return Obstacles.stops([o["x"]], g1, g2, carried=carried)
    if "x_from" in o or "x_to" in o:
        a, b = _need(o, ("x_from", "x_to"), where).values()
        return Obstacles.span(a, b, g1, g2, carried=carried)
    return Obstacles(g1, g2, carried=carried)


def _obstacles(data: dict) -> tuple[Obstacles, tuple]:
    """The flat obstacles (the first plane's, g1 ≤ v ≤ g2) and the holes."""
    items = list(enumerate(data.get("obstacles", [])))
    mu = data.get("contact", {}).get("friction", 0.0)
    holes = tuple(_hole(o, i, mu) for i, o in items if "hole" in o)
    if (mu or any("friction" in o for _, o in items)) and _planes(data) != 2:
        raise InputError("friction acts along the wall of a hole, in the cross-section: the "
                         "one-plane beam has no tangential direction (planes = 2 and a hole)")
    for i, o in items:
        if "friction" in o and "hole" not in o:
            raise InputError(f"[obstacles.{i}] friction acts at a hole's wall: this obstacle "
                             "has no hole")
    if holes and _planes(data) != 2:
        raise InputError("[[obstacles]] hole bounds (v, w) in the cross-section: it needs "
                         "planes = 2 at the top of the file")
    parts = [_obstacle(o, i) for i, o in items if "hole" not in o]
    if not parts:
        return Obstacles(), holes
    return (parts[0] if len(parts) == 1 else Obstacles.combine(*parts)), holes


def _planes(data: dict) -> int:
    planes = data.get("planes", 1)
    if planes not in (1, 2) or isinstance(planes, bool):
        raise InputError(f"planes = {planes!r} must be 1 or 2 (bending planes)")
    return int(planes)


def _support(data: dict, L: float, reader: _Reader) -> Support:
    m = data.get("motion")
    if m is None:
        return Support()
    if "end" in m and "at" in m:
        raise InputError("[motion] give end (left | right) or at (x of a support), not both")
    at = m.get("at", 0.0)
    if "end" in m:
        ends = {"left": 0.0, "right": L}
        if m["end"] not in ends:
            raise InputError(f"[motion] end={m['end']!r} must be one of: left, right")
        at = ends[m["end"]]
    lifting = m.get("lifting", "auto")
    direction = _direction(m, data, "motion")
    time = {k: v for k, v in m.items() if k != "direction"}
    if set(time) & {"amplitude", "omega"} and not set(time) & {"phase", "value", "sines",
                                                                "table", "random", "psd"}:
        return Support(m.get("amplitude", 0.0), m.get("omega", 0.0), at=at, lifting=lifting,
                       direction=direction)
    return Support(motion=_time_function(time, "motion", reader), at=at, lifting=lifting,
                   direction=direction)


def _direction(d: dict, data: dict, where: str) -> tuple[float, float]:
    """A table's direction = [dy, dz] (two planes only; default the first plane)."""
    from ..problem import check_direction
    if "direction" not in d:
        return (1.0, 0.0)
    if _planes(data) != 2:
        raise InputError(f"[{where}] direction acts in the cross-section: it needs planes = 2")
    return check_direction(f"[{where}] direction", d["direction"])


def _loads(data: dict, reader: _Reader) -> tuple[Load, Load]:
    """The loads of the first and the second plane: a load along ``direction`` = [dy, dz]
    acts dy× in v and dz× in w; ``rotating`` = {amplitude, omega, phase} is
    amplitude·cos(ωt + phase) in v and amplitude·sin(ωt + phase) in w (two planes)."""
    total_v, total_w = Load(), Load()
    for i, d in enumerate(data.get("loads", [])):
        where = f"loads.{i}"
        dy, dz = _direction(d, data, where)
        d = {k: v for k, v in d.items() if k != "direction"}
        if "rotating" in d:
            if _planes(data) != 2:
                raise InputError(f"[{where}] rotating acts in the cross-section: it needs "
                                 "planes = 2")
            if "gravity" in d or (dy, dz) != (1.0, 0.0) or \
                    set(d) & {"amplitude", "omega", "phase", "value", "sines", "table",
                              "random", "psd"}:
                raise InputError(f"[{where}] rotating is the load's time function and "
                                 "direction: give it alone with x, distributed or per_mass")
            rot = _need(d["rotating"], ("amplitude", "omega"), f"{where}.rotating")
            phase = d["rotating"].get("phase", 0.0)
            rest = {k: v for k, v in d.items() if k != "rotating"}
            total_v = total_v + _load(rest, where, Sine(rot["amplitude"], rot["omega"],
                                                        phase + math.pi / 2))
            total_w = total_w + _load(rest, where, Sine(rot["amplitude"], rot["omega"], phase))
            continue
        if "gravity" in d:
            if len(d) > 1:
                raise InputError(f"[{where}] gravity = g stands alone, with a direction in "
                                 f"two planes (got {', '.join(d)})")
            part = Load.gravity(d["gravity"])
        else:
            time = _time_function(d, where, reader)
            if time is None:
                raise InputError(f"[{where}] needs a time function: amplitude/omega, value, "
                                 "sines, table, random or (two planes) rotating")
            part = _load(d, where, time)
        total_v, total_w = total_v + part.scaled(dy), total_w + part.scaled(dz)
    return total_v, total_w


def _load(d: dict, where: str, time) -> Load:
    """One [[loads]] item's load with the time function ``time``."""
    kinds = [k for k in ("x", "distributed", "per_mass") if d.get(k, False) is not False]
    span = [k for k in ("x_from", "x_to") if k in d]
    if span and kinds != ["distributed"]:
        raise InputError(f"[{where}] x_from, x_to bound a distributed load (distributed = "
                         "true)")
    if len(kinds) != 1:
        raise InputError(f"[{where}] needs one of x (a point force, N), distributed = "
                         "true (N/m) or per_mass = true (m/s²)")
    if kinds[0] == "x":
        return Load(points=((d["x"], time),))
    if kinds[0] == "distributed" and span:
        a, b = _need(d, ("x_from", "x_to"), where).values()
        if not a < b:
            raise InputError(f"[{where}] x_from={a:g} must be below x_to={b:g}")
        return Load.distributed(_span(a, b), time)
    if kinds[0] == "distributed":
        return Load.distributed(1.0, time)
    return Load.uniform(time)


def _span(a: float, b: float):
    """1 N/m on [a, b], 0 elsewhere (exact when a and b are mesh nodes; else the load
    quadrature cuts the element there)."""
    return lambda x: ((np.asarray(x) >= a) & (np.asarray(x) <= b)).astype(float)


def _damping(data: dict) -> Damping:
    d = data.get("damping")
    if d is None:
        return Damping()
    if "modal" in d:
        if len(d) > 1:
            raise InputError("[damping] modal = ζ (every mode) stands alone: not with "
                             f"{', '.join(k for k in d if k != 'modal')}")
        return Damping(modal=d["modal"])
    if set(d) & {"zeta", "f1", "f2"}:
        if set(d) & {"alpha", "alpha_K"}:
            raise InputError("[damping] give zeta, f1, f2 or alpha, alpha_K, not both")
        return Damping.ratio(**_need(d, ("zeta", "f1", "f2"), "damping"))
    return Damping(d.get("alpha", 0.0), d.get("alpha_K", 0.0))


def _spline(d: dict, name: str, value: str):
    """(f, f') of a {x, u} table: a not-a-knot cubic spline."""
    pairs = _need(d, ("x", value), f"initial.{name}")
    try:
        from scipy.interpolate import CubicSpline
        s = CubicSpline(np.asarray(pairs["x"], dtype=float),
                        np.asarray(pairs[value], dtype=float), bc_type="not-a-knot")
    except ValueError as e:
        raise InputError(f"[initial.{name}] table x = [...], {value} = [...]: {e}") from None
    return s, s.derivative()


def _initial(data: dict, problem: BeamProblem) -> BeamProblem:
    ini = data.get("initial", {})
    fixed = ini.get("fixed_frame", True)
    if "mode" in ini:
        if "u0" in ini:
            raise InputError("[initial] give mode or u0, not both")
        u0, du0 = _mode_shape(problem, ini["mode"], ini.get("amplitude", 1.0))
    elif "u0" in ini:
        u0, du0 = _spline(ini["u0"], "u0", "u")
    else:
        u0 = du0 = None
    v0 = _spline(ini["v0"], "v0", "v")[0] if "v0" in ini else None
    return replace(problem, initial=InitialState(u0, v0, du0, fixed_frame=fixed))


def _mode_shape(problem: BeamProblem, k, amplitude):
    """amplitude × the k-th mode shape (its largest |u| 1, on 50 samples per element)."""
    from ..modes import modes
    if isinstance(k, bool) or not isinstance(k, int) or k < 1:
        raise InputError(f"[initial] mode={k!r} must be a whole number ≥ 1")
    m = modes(problem, k, samples_per_element=50)
    v = m.vectors[:, k - 1] * (float(amplitude) / np.abs(m.shapes[:, k - 1]).max())
    space = m.space

    def shape(derivative):
        return lambda x: np.asarray(space.point_rows(np.ravel(x), derivative) @ v).reshape(
            np.shape(x))
    return shape(0), shape(1)


def _beam_problem(data: dict, reader: _Reader) -> BeamProblem:
    beam = _beam(data)
    ends = data.get("ends", {})
    mesh = data.get("mesh", {})
    obstacles, holes = _obstacles(data)
    load, load_w = _loads(data, reader)
    problem = BeamProblem(
        beam, obstacles, _support(data, beam.L, reader), load,
        J=mesh.get("J", 19), element=mesh.get("element", "hermite"), nodes=mesh.get("nodes"),
        ends=(ends.get("left", "clamped"), ends.get("right", "free")),
        supports=tuple(s.get("x", math.nan) for s in data.get("supports", [])),
        damping=_damping(data), planes=_planes(data), holes=holes, load_w=load_w)
    return _initial(data, problem)


def _bar_profile(d, name: str, value: str):
    if isinstance(d, dict):
        pairs = _need(d, ("x", value), f"initial.{name}")
        if not isinstance(pairs["x"], list) or not isinstance(pairs[value], list) \
                or len(pairs["x"]) != len(pairs[value]):
            raise InputError(f"[initial.{name}] x and {value} must be arrays of one length")
        return list(zip(pairs["x"], pairs[value]))
    return d


def _bar(data: dict, reader: _Reader) -> Bar:
    L = _need(data.get("geometry", {}), ("L",), "geometry")["L"]
    mat = _material(data.get("material", {}), "material", plausible=False)
    A = _bar_area(data["section"]) if "section" in data else None
    obstacles = data.get("obstacles", [])
    if len(obstacles) != 1 or "x" not in obstacles[0]:
        raise InputError("a bar needs one [[obstacles]] with x = 0 or x = L (the end it "
                         f"hits; stiffness = k for an elastic obstacle), got {len(obstacles)}")
    o = obstacles[0]
    ends = {"left": "free", "right": "free", **data.get("ends", {})}
    side = "left" if o["x"] in (0, "left") else "right"
    if ends[side] != "free":
        raise InputError(f"[ends] {side}={ends[side]!r}: the bar's obstacle is at that end, "
                         "which must be free (the far end is free or clamped)")
    loads = data.get("loads", [])
    if len(loads) > 1:
        raise InputError("a bar takes one [[loads]] value = f (a uniform body force, N/m³)")
    ini, mesh = data.get("initial", {}), data.get("mesh", {})
    law = data.get("contact", {}).get("law", "auto")
    return Bar(a=mat.E, b=data.get("damping", {}).get("viscosity", 0.0), rho=mat.rho, L=L,
               f=loads[0].get("value", 0.0) if loads else 0.0,
               v0=_bar_profile(ini.get("v0", 0.0), "v0", "v"),
               u0=_bar_profile(ini.get("u0", 0.0), "u0", "u"),
               obstacle="elastic" if "stiffness" in o and law != "penalty" else "rigid",
               k=o.get("stiffness", 100.0), N=mesh.get("J", 100),
               mass=mesh.get("mass", "average"),
               far_end=ends["right" if side == "left" else "left"], obstacle_at=o["x"], A=A)


# ---------------------------------------------------------------- commands

def _run_parser() -> argparse.ArgumentParser:
    from ..parser import Parser
    p = Parser(prog="python -m skfem_beam run",
               description="Run the scene a TOML file describes (docs/scene_files.md).")
    p.add_argument("scene", nargs="?", default=None, help="the scene file (TOML)")
    p.add_argument("--set", action="append", default=None, metavar="KEY=VALUE",
                   help="override a key of the file, e.g. time.dt=1e-5 (repeatable)")
    p.add_argument("--T", type=float, default=None, help="final time (s): [time] T")
    p.add_argument("--out", default=None, help="output folder (default out/<scene name>)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out folder")
    for flag in ("format", "frames", "save-every", "flush-every", "checkpoint-every"):
        p.add_argument(f"--{flag}", default=None,
                       type=str if flag == "format" else float if flag == "checkpoint-every"
                       else int, help=f"[output] {flag.replace('-', '_')}")
    p.add_argument("--probe", action="append", type=float, default=None, metavar="X",
                   help="also record u, velocity, moment and shear at x = X (m), with "
                        "[output] probes (repeatable)")
    p.add_argument("--resume", metavar="DIR", default=None,
                   help="continue the stopped run in DIR from its last checkpoint (with "
                        "none: run it again from step 0)")
    return p


def run_main(argv) -> int:
    """``python -m skfem_beam run``: the scene through the scenes' own pipeline."""
    from ..cli import stored_args
    p = _run_parser()
    args = stored_args(p.parse_args(argv), p, argv)
    scene = _scene_of(args.scene, args.set, args.resume)
    spec = _spec(scene, {k: v for k, v in vars(args).items() if k != "resume"}, args.resume)
    name = f"scene {Path(args.scene).stem}" if args.scene else "scene"
    if scene.kind == "bar":
        from ..cases.impacting_bar import run_bar_case
        return run_bar_case(scene.problem, spec)
    from ..cases._beam import run_beam_case
    return run_beam_case(name, scene.problem, spec, stops=_chart_stops(scene.problem))


def _scene_of(path, sets, resume) -> Scene:
    """The scene file (or, resuming, the text the run stored) with the --set overrides."""
    from ..output.series import read_summary
    stored = {}
    if resume:
        config = read_summary(Path(resume))["config"]
        if "scene_text" not in config:
            raise InputError(f"--resume {resume}: not a run of python -m skfem_beam run")
        stored = {"text": config["scene_text"], "files": config.get("scene_files", {})}
    elif path is None:
        raise InputError("run needs a scene file: python -m skfem_beam run SCENE.toml")
    return load(path or "scene.toml", sets or (), **stored)


def _wear(scene: Scene):
    """[wear] as output.supports.Wear (radius defaults to a tube's or rod's outer one).
    Without land: volumes only (a depth spreads the volume over the land), so no radius
    is needed either."""
    from ..output.supports import Wear
    d = scene.data.get("wear")
    if d is None:
        return None
    holes = getattr(scene.problem, "holes", ())
    if not holes:
        raise InputError("[wear] needs holes (planes = 2 and [[obstacles]] hole = ...): wear "
                         "comes from the normal force times the sliding along a wall")
    radius = d.get("radius", _outer_radius(scene.data.get("section", {})))
    if radius is None and "land" in d:
        raise InputError("[wear] radius (m, the tube's outer radius) is needed for the depth "
                         "(land) when [section] is not a tube or a rod")
    need = _need(d, ("coefficient", "service_years"), "wear")
    return Wear(need["coefficient"], need["service_years"], d.get("land"), radius)


def _outer_radius(section: dict) -> float | None:
    """A tube's or rod's outer radius (m) from [section], else None."""
    diameter = section.get("tube", {}).get("outer_diameter") or \
        section.get("rod", {}).get("diameter")
    return None if diameter is None else 0.5 * diameter


def _spec(scene: Scene, flags: dict, resume) -> RunSpec:
    """The scene and the command line's flags (which override its [output] and [time] T)
    as one RunSpec; summary.json's config records both, in the flags' names."""
    given = flags.pop("probe", None) or []
    for key, value in scene.output.items():
        if key != "probes" and flags[key] is None:
            flags[key] = value
    flags["T"] = scene.stepping.T if flags["T"] is None else flags["T"]
    flags["out"] = flags["out"] or f"out/{Path(flags['scene']).stem}"
    options = OutputOptions(flags["out"], flags["overwrite"], resume, flags["format"],
                            flags["frames"], flags["save_every"], flags["flush_every"],
                            flags["checkpoint_every"])
    stepping = replace(scene.stepping, T=flags["T"], save_every=options.save_every,
                       frames=options.frames)
    law, restitution = scene.law, scene.restitution
    mass = scene.data.get("mesh", {}).get("mass", "consistent") if scene.kind == "beam" \
        else scene.problem.mass
    probes = [float(x) for x in np.atleast_1d(scene.output.get("probes", []))] + \
        [x for x in given if x not in scene.output.get("probes", [])]
    config = {"command": "python -m skfem_beam run", "scene_text": scene.text,
              "scene_files": scene.files, **flags, "dt": stepping.dt, "beta": stepping.beta,
              "method": "penalty" if law == "penalty" else "contact",
              "law": law if law in methods.LAWS else "position",
              "solver": "auto" if law in methods.LAWS or restitution else law,
              "stiffness": scene.stiffness, "restitution": restitution, "mass": mass,
              "massless": stepping.massless, "probe": probes}
    return RunSpec(stepping, scene.method, options, config, mass, tuple(probes),
                   _wear(scene) if scene.kind == "beam" else None)


def _chart_stops(problem: BeamProblem) -> tuple:
    """The obstacle at the tip, for the tip chart (none when it has none)."""
    lo, hi = problem.obstacles.bounds([problem.beam.L])
    return tuple(float(g) for g in (lo[0], hi[0]) if np.isfinite(g))


def modes_main(argv) -> int:
    """``python -m skfem_beam modes``: natural frequencies of the scene's beam."""
    from ..parser import Parser
    from ..modes import modes
    from ..two_planes import plane_problems
    p = Parser(prog="python -m skfem_beam modes",
               description="Natural frequencies and mode shapes of a scene file's beam, with "
                           "its ends and supports (obstacles ignored).")
    p.add_argument("scene", help="the scene file (TOML)")
    p.add_argument("--n", type=int, default=6, help="number of modes")
    p.add_argument("--set", action="append", default=None, metavar="KEY=VALUE",
                   help="override a key of the file (repeatable)")
    p.add_argument("--out", default=None, help="write DIR/modes.csv")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out folder")
    args = p.parse_args(argv)
    scene = load(args.scene, args.set or (), dynamic=False)
    if scene.kind != "beam":
        raise InputError(f"modes: {args.scene} is a {scene.kind}; modes are computed for "
                         "beams")
    out = None
    if args.out is not None:
        from ..output.folder import check_output_dir
        out = check_output_dir(args.out, args.overwrite)
    problem = scene.problem
    # two planes: each plane's modes (its own EI), the lowest n of both, with their plane
    planes = [("", modes(problem, args.n))] if problem.planes == 1 else \
        [(p, modes(one, args.n)) for p, one in zip("vw", plane_problems(problem))]
    rows = sorted(((m.f[i], m.omega[i], p, m.shapes[:, i]) for p, m in planes
                   for i in range(m.f.size)), key=lambda r: r[0])[:args.n]
    two = problem.planes == 2
    print(f"{'mode':>4s}{' plane' if two else ''} {'f (Hz)':>14s} {'ω (rad/s)':>14s}")
    for i, (f, w, p, _) in enumerate(rows, 1):
        print(f"{i:4d}{p:>6s} {f:14.6g} {w:14.6g}" if two else f"{i:4d} {f:14.6g} {w:14.6g}")
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        with open(out / "modes.csv", "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["mode"] + (["plane"] if two else []) + ["f_Hz", "omega_rad_s"]
                       + [f"u({float(x):.12g})" for x in planes[0][1].x])
            for i, (f, om, p, shape) in enumerate(rows, 1):
                w.writerow([i] + ([p] if two else []) + [f"{f:.17g}", f"{om:.17g}"]
                           + [f"{u:.17g}" for u in shape])
        print(f"written: {out / 'modes.csv'}", file=sys.stderr)
    return 0


def example(name: str) -> Path:
    """The path of a shipped scene file (``skfem_beam/scene_files/NAME.toml``)."""
    p = Path(__file__).resolve().parents[1] / "scene_files" / f"{Path(name).stem}.toml"
    if not p.is_file():
        shipped = sorted(q.stem for q in p.parent.glob("*.toml"))
        raise InputError(f"no scene file {name!r}; shipped: {', '.join(shipped)}")
    return p


__all__ = ["Scene", "load", "apply_set", "run_main", "modes_main", "example", "BEAM_KEYS",
           "BAR_KEYS"]
