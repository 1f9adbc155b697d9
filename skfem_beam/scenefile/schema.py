"""The scene file's schema: its key tables (:data:`BEAM_KEYS`, :data:`BAR_KEYS`,
:data:`PLATE_KEYS`) and the
check of a parsed file against them.

Every value is checked by the object it builds; this module checks only the file's shape:
an unknown section or key is refused in one line naming it and the allowed ones, and a
value the schema marks as a number (N), or an array of numbers (ListOf), that is not one
(``"0.5m"``) in one line naming its key path (with the index inside an array:
``output.probes[0]``).  docs/scene_files.md is generated from the tables
(:mod:`skfem_beam.scenedocs`).
"""
from __future__ import annotations

from ..errors import InputError


V = None          # a value (checked by the object it builds)


class Number:
    """In a schema: a number (TOML integer or float, inf included; not nan, not a string
    such as "0.25mm", not a boolean), checked where the file is read."""


N = Number()


class Word:
    """In a schema: a word (a TOML string; the object checks which): a list or a number
    there ended in a TypeError from inside ("unhashable type: 'list'")."""


W = Word()


class Flag:
    """In a schema: true or false (TOML's booleans; "false" or 0 read as true, silently)."""


B = Flag()


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


class Names(dict):
    """In a schema: a table whose keys are names the objects check (a plate's edges:
    the rectangle's left, right, bottom, top, its keys here, or a mesh file's boundary
    names), each value checked by the object it builds."""

    def __init__(self, *usual):
        super().__init__(dict.fromkeys(usual, V))


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
        "table": W, "random": {"rms": N, "f_low": N, "f_high": N, "seed": N, "count": N},
        "psd": Either({"table": W, "seed": N, "df": N})}
SECTION = {"I": N, "A": N, "I_y": N, "I_z": N, "tube": {"outer_diameter": N, "wall": N},
           "rod": {"diameter": N}, "rect": {"b": N, "h": N}}
MATERIAL = {"E": N, "rho": N}
U0, V0 = {"x": NUMBERS, "u": NUMBERS}, {"x": NUMBERS, "v": NUMBERS}
TIME_KEYS = {"dt": N, "T": N, "beta": N, "load_window": W}
DAMPING_KEYS = {"zeta": N, "f1": N, "f2": N, "alpha": N, "alpha_K": N, "modal": N}
OUTPUT = {"format": W, "save_every": N, "frames": N, "flush_every": N, "checkpoint_every": N,
          "probes": NUMBERS}
OUTPUT_DEFAULTS = {"format": "both", "save_every": 1, "frames": 200, "flush_every": 20000,
                   "checkpoint_every": None}      # [output] when the file leaves them out
class ContactKeys(dict):
    """[contact]'s keys: its own, and the parameters of every registered law (numbers;
    the law's table checks their range, scenefile.build that the law named has them), so
    that a law of the user's with a parameter needs no edit here."""

    def method_params(self, contact: dict) -> dict:
        """The method's parameters among a [contact] table's values: θ, and the keys that
        are not this table's own (a step solver's, checked by its table)."""
        own = dict(self.items())
        return {k: v for k, v in contact.items() if k == "theta" or k not in own}

    def _all(self) -> dict:
        from ..contact.registry import all_parameters
        own = dict(self.items())
        return {**own, **{k: N for k in all_parameters() if k not in own}}

    def __contains__(self, key) -> bool:
        return key in self._all()

    def __getitem__(self, key):
        return self._all()[key]

    def __iter__(self):
        return iter(self._all())


CONTACT = ContactKeys(law=W, stiffness=N, restitution=N, friction=N, theta=N)
G = NumberOr({"poly": NUMBERS, "about": N, "x": NUMBERS, "g": NUMBERS},   # the rest: obstacles._g
             "{ poly = [...] } or { x = [...], g = [...] }")
# a plate's obstacle: a number, Σ c_ij (x − x0)^i (y − y0)^j or a table on an x, y grid
# (the rest: plate._g)
G_PLATE = NumberOr({"poly": ListOf(NUMBERS), "about": NUMBERS, "x": NUMBERS, "y": NUMBERS,
                    "g": ListOf(NUMBERS)},
                   "{ poly = [[...], ...], about = [x0, y0] } or { x = [...], y = [...], "
                   "g = [[...], ...] }")
HOLE = {"radius": N, "sides": N, "angle": N, "centre": NUMBERS,     # the rest: holes.py
        "polygon": ListOf(NUMBERS), "faces": ListOf(NUMBERS), "lands": N, "land_width": N}

BEAM_KEYS = {
    "kind": W, "planes": N, "material": MATERIAL, "section": SECTION,
    "mass_normalised": {"k2": N, "rho_S": N},
    "mass": {"added": N},
    "geometry": {"L": N},
    "segments": [{"length": N, "material": MATERIAL, "section": SECTION}],
    "ends": {"left": W, "right": W},
    "supports": [{"x": N}],
    "motion": {"end": W, "at": N, "lifting": W, "direction": NUMBERS, **TIME},
    "obstacles": [{"x": N, "x_from": N, "x_to": N, "g1": G, "g2": G, "hole": HOLE,
                   "carried": B, "stiffness": N, "damping": N, "friction": N}],
    "wear": {"coefficient": N, "service_years": N, "land": N, "radius": N},
    "damping": DAMPING_KEYS,
    "loads": [{"x": N, "distributed": B, "per_mass": B, "gravity": N, "x_from": N, "x_to": N,
               "direction": NUMBERS, "rotating": {"amplitude": N, "omega": N,
                                                  "phase": N},
               **TIME}],
    "initial": {"mode": N, "amplitude": N, "u0": U0, "v0": V0, "fixed_frame": B,
                "u0_w": U0, "v0_w": V0},
    "mesh": {"J": N, "element": W, "nodes": NUMBERS, "mass": W, "massless": W},
    "time": TIME_KEYS, "contact": CONTACT, "output": OUTPUT,
}
BAR_KEYS = {
    "kind": W, "material": MATERIAL, "section": SECTION, "geometry": {"L": N},
    "ends": {"left": W, "right": W},
    "obstacles": [{"x": NumberOrWord("left", "right"), "stiffness": N}],
    "damping": {"viscosity": N},
    "loads": [{"value": N}],
    "initial": {"u0": NumberOr(U0, "{ x = [...], u = [...] }"),
                "v0": NumberOr(V0, "{ x = [...], v = [...] }")},
    "mesh": {"J": N, "mass": W, "massless": W, "element": W},
    # no friction (no cross-section to slide in) and no probes (it writes u(0), u(L)):
    # they were read and ignored
    "time": TIME_KEYS, "contact": ContactKeys(law=W, stiffness=N, restitution=N, theta=N),
    "output": {k: v for k, v in OUTPUT.items() if k != "probes"},
}
PLATE_KEYS = {
    "kind": W, "geometry": {"a": N, "b": N, "mesh": W}, "section": {"thickness": N},
    "material": {"E": N, "rho": N, "nu": N},
    "edges": Names("left", "right", "bottom", "top"),
    "mesh": {"nx": N, "ny": N, "element": W},
    "obstacles": [{"g1": G_PLATE, "g2": G_PLATE, "region": NUMBERS, "disk": NUMBERS,
                   "points": ListOf(NUMBERS)}],
    "loads": [{"pressure": N, "region": NUMBERS, "point": NUMBERS, "force": N, **TIME}],
    "initial": {"static_pressure": N, "velocity": N, "mode": N, "amplitude": N},
    "damping": DAMPING_KEYS,
    "time": TIME_KEYS,
    "contact": ContactKeys(law=W, solver=W, stiffness=N, restitution=N, theta=N),
    "output": {**OUTPUT, "probes": ListOf(NUMBERS)},
}
KINDS = {"beam": BEAM_KEYS, "bar": BAR_KEYS, "plate": PLATE_KEYS}


def key_path(path: tuple) -> str:
    """A key path as written in error lines: tables and arrays of tables dotted, as
    ``--set`` names them (``obstacles.0.g1``), items of a value's array by index
    (``output.probes[0]``)."""
    out = ""
    for part in path:
        out += part if str(part).startswith("[") else f".{part}" if out else str(part)
    return out


def _is_number(value) -> bool:
    """An int or float, inf included; not a boolean and not nan (which no key means:
    ``amplitude = nan`` had run to "the initial state u0, v0 is not finite")."""
    return isinstance(value, (int, float)) and not isinstance(value, bool) and value == value


SI = "in SI units (m, s, kg, N, Pa; e.g. 0.25 mm is 0.00025)"


def _written(path: tuple, value, sets) -> str:
    """The bad value as the user wrote it: ``key = value`` in the file, or the ``--set``
    that gave it (``sets``: dotted key → text), then the item inside it if the --set
    gave a whole array."""
    name = key_path(path)
    key = key_path(tuple(p for p in path if not str(p).startswith("[")))
    if not sets or key not in sets:
        return f"{name} = {value!r}"
    given = f"--set {key}={sets[key]}"
    return given if key == name else f"{given}: {name} = {value!r}"


def _bad_value(path: tuple, value, sets, allowed: str) -> InputError:
    return InputError(f"{_written(path, value, sets)}: must be {allowed}")


def check_keys(data, schema, path=(), sets=None) -> None:
    """Refuse a key ``schema`` does not allow, naming it and the allowed ones, and check
    each value by its schema entry (``sets``: the keys ``--set`` gave, dotted, as written
    there)."""
    for key, value in data.items():
        if key not in schema:
            where = f"[{key_path(path)}]" if path else "the top level"
            raise InputError(f"unknown key {key_path(path + (key,))!r}; {where} allows: "
                             f"{', '.join(schema)}")
        _check_value(value, schema[key], path + (key,), sets)


def _check_value(value, sub, path: tuple, sets) -> None:
    """Refuse ``value`` if it is not what its schema entry ``sub`` says (a number, an
    array of them, a table, an array of tables), naming its key path, the value as
    written and what is allowed; V (a value the objects check) passes."""
    if sub is N:
        if not _is_number(value):
            raise _bad_value(path, value, sets, f"a number, {SI}")
    elif sub is W:
        if not isinstance(value, str):
            raise _bad_value(path, value, sets, "a word in quotes")
    elif sub is B:
        if not isinstance(value, bool):
            raise _bad_value(path, value, sets, "true or false (no quotes)")
    elif isinstance(sub, Names):
        if not isinstance(value, dict):
            raise InputError(f"{key_path(path)} must be a table of names = values "
                             f"(got {value!r})")
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
            raise InputError(f"{key_path(path)} must be a table of {', '.join(sub)} "
                             f"(got {value!r})")
        check_keys(value, sub, path, sets)
    elif isinstance(sub, list):
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise InputError(f"{key_path(path)} must be an array of tables "
                             f"[[{key_path(path)}]] of {', '.join(sub[0])}")
        for i, item in enumerate(value):
            check_keys(item, sub[0], path + (i,), sets)
