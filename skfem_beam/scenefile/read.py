"""A scene file read once: its text, parsed as TOML, its kind, the ``--set`` overrides
applied and its shape checked against the schema (:class:`Parsed`, a plain object the
builders read; nothing after :func:`read` opens the file again); the tables it names
(:class:`Tables`); the shipped scene files (:func:`example`)."""
from __future__ import annotations

import base64
import hashlib
import tomllib
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError
from ..parser import set_pair
from .schema import BEAM_KEYS, KINDS, ListOf, Names, check_keys, key_path


@dataclass(frozen=True)
class Parsed:
    """A scene file as read: ``path`` (relative tables are relative to its folder),
    ``text`` (the file as read), ``data`` (the parsed TOML with the overrides), ``kind``
    ("beam" or "bar") and ``files`` (the stored texts of its tables, path as written →
    text: a resumed run's, else empty); ``meshes`` a resumed run's stored mesh files
    (path as written → {"sha256", "base64"}: :meth:`Tables.mesh`), None when not
    resuming."""
    path: Path
    text: str
    data: dict
    kind: str
    files: dict
    meshes: dict | None = None


def read(path, overrides=(), files: dict | None = None, text: str | None = None,
         meshes: dict | None = None) -> Parsed:
    """Read the scene file ``path`` once (or take its stored ``text``), parse it, apply
    ``overrides`` (``KEY=VALUE`` strings as ``--set``) and check its keys and the values
    the schema marks (every such error line names the file).  ``meshes``: a resumed
    run's stored mesh files (None: not a resume)."""
    path = scene_path(path)
    if text is None:
        try:
            text = path.read_text(encoding="utf-8-sig")     # a byte-order mark is no TOML
        except OSError as e:
            raise InputError(f"cannot read the scene file {path}: {e.strerror}") from None
        except UnicodeDecodeError:
            raise InputError(f"{path}: not a UTF-8 text file") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"{path}: not valid TOML: {e}") from None
    kind = data.get("kind", "beam")
    if not isinstance(kind, str) or kind not in KINDS:     # a list: unhashable, a traceback
        raise InputError(f"{path}: kind={kind!r} must be one of: {', '.join(KINDS)}")
    try:
        sets = dict(apply_set(data, assignment) for assignment in overrides)
    except InputError as e:
        raise InputError(f"{path.name}: {e}") from None
    if data.get("kind", "beam") != kind:
        raise InputError(f"{path}: --set kind={data.get('kind')!r}: a scene's kind is its "
                         f"file's ({kind!r}); write another file for another kind")
    try:
        check_keys(data, KINDS[kind], sets=sets)
    except InputError as e:
        raise InputError(f"{path.name}: {e}{_kind_hint(data, kind)}") from None
    return Parsed(path, text, data, kind, dict(files or {}),
                  None if meshes is None else dict(meshes))


def _kind_hint(data: dict, kind: str) -> str:
    """Where no ``kind`` is written (a beam) and another kind's keys fit the file: say so
    (a plate file without it was told "[geometry] allows: L")."""
    if "kind" in data:
        return ""
    for other, schema in KINDS.items():
        if other != kind:
            try:
                check_keys({k: v for k, v in data.items() if k != "kind"}, schema)
            except InputError:
                continue
            return f" (no kind is written, so it is read as a {kind}; a {other}'s file says " \
                f"kind = \"{other}\")"
    return ""


def scene_path(path) -> Path:
    """The scene file ``path``, or the shipped one of its name (``run point_stops.toml``
    from any folder; a resumed run's too, whose relative files are beside it)."""
    path = Path(path)
    if not path.exists() and path.parent == Path("."):
        return _shipped(path.name) or path
    return path


def apply_set(data: dict, assignment: str) -> tuple[str, str]:
    """``KEY=VALUE`` (KEY dotted, array items by index: ``obstacles.0.g1``, or
    ``obstacles[0].g1`` as refusal lines write list items; an item of an array of values
    too, ``output.probes.0``) into ``data``; a key the scene's kind does not allow is
    refused by name.  Returns (KEY, VALUE), KEY dotted."""
    key, eq, text = assignment.partition("=")
    if not eq or not key.strip():
        raise InputError(f"--set {assignment!r}: expected KEY=VALUE, e.g. time.dt=1e-5")
    dotted, parsed = set_pair(assignment)
    parts, value = dotted.split("."), text.strip()
    schema = KINDS.get(data.get("kind", "beam"), BEAM_KEYS)
    node, sub = data, schema
    for i, part in enumerate(parts):
        last = i == len(parts) - 1
        if isinstance(sub, (list, ListOf)):
            k = _item_index(key, parts, i, node)
            if isinstance(sub, ListOf) and last:    # an item of an array of values
                node[k:k + 1] = [parsed]
                return ".".join(parts), value
            if k == len(node):
                node.append({} if isinstance(sub, list) else [])
            node, sub = node[k], sub[0] if isinstance(sub, list) else sub.item
            if last:
                raise InputError(f"--set {key}: name a key of the item, e.g. "
                                 f"{key}.{next(iter(sub))}")
            continue
        if isinstance(sub, Names) and last:
            node[part] = parsed      # a name the objects check
            return ".".join(parts), value
        if not isinstance(sub, dict):
            raise InputError(f"--set {key}: {key_path(parts[:i])} is a value, not a table: "
                             f"set it whole, --set {key_path(parts[:i])}=...")
        if part not in sub:
            raise InputError(f"--set {key}: unknown key {part!r}; "
                             f"{'[' + key_path(parts[:i]) + ']' if i else 'the top level'} "
                             f"allows: {', '.join(sub)}")
        if last:
            node[part] = parsed
            return ".".join(parts), value
        node = node.setdefault(part, [] if isinstance(sub[part], (list, ListOf)) else {})
        sub = sub[part]


def _item_index(key: str, parts: list, i: int, items) -> int:
    """``parts[i]`` as the index of an item of the array ``items`` (its length: a new
    item), or one line saying what is allowed."""
    if not isinstance(items, list):
        raise InputError(f"--set {key}: {key_path(parts[:i])} is not an array in the file")
    n, part = len(items), parts[i]
    if not part.isdigit() or int(part) > n:
        raise InputError(f"--set {key}: {key_path(parts[:i])} has {n} item(s); "
                         f"index {part!r} must be "
                         + (f"0..{n - 1} (an item) or " if n else "") + f"{n} (a new one)")
    return int(part)


class Tables:
    """Files named in the scene, relative to it; their texts are kept (``read``) so that a
    run stores them, and a resumed run reads the stored texts (``stored``).  A mesh file
    (:meth:`mesh`, binary or text) is kept as its bytes: ``meshes``, path as written →
    {"sha256", "base64"}; ``resumed``: a resumed run's stored ones (None: not a resume)."""

    def __init__(self, base: Path, stored: dict, resumed: dict | None = None):
        self.base, self.stored, self.read, self.tmp = base, stored, {}, None
        self.resumed, self.meshes = resumed, {}
        self.time_tables = []       # (key path, file, Table) of each time table read

    def mesh(self, name: str) -> Path:
        """The path of the mesh file ``name`` to read, its bytes kept in ``meshes``.  A
        resumed run builds from its stored copy (written to ``tmp`` under its own name,
        for the extension), never from the scene's folder; a run that stored none (a
        folder written before mesh files were stored) reads the scene's folder's file
        (the run command says so), refused in one line if the run recorded another
        sha256."""
        given = (self.resumed or {}).get(name) or {}
        if "base64" in given:
            data = base64.b64decode(given["base64"])
            digest = hashlib.sha256(data).hexdigest()
            if given.get("sha256", digest) != digest:
                raise InputError(f"the stored copy of the mesh file {name} does not match "
                                 "its sha256 in the run's summary.json; cannot resume, "
                                 "nothing was changed")
            p = self.tmp / "meshes" / str(len(self.meshes)) / Path(name).name
            p.parent.mkdir(parents=True)
            p.write_bytes(data)
        else:
            p = Path(name) if Path(name).is_absolute() else self.base / name
            try:
                data = p.read_bytes()
            except OSError:
                return p    # the reader names the file and why (read_plate_mesh)
            digest = hashlib.sha256(data).hexdigest()
            if given.get("sha256", digest) != digest:
                raise InputError(f"the mesh file {p} differs from the one the run used "
                                 f"(sha256 {digest[:12]}…, recorded "
                                 f"{given['sha256'][:12]}…); cannot resume, nothing was "
                                 "changed")
        self.meshes[name] = {"sha256": digest,
                             "base64": base64.b64encode(data).decode("ascii")}
        return p

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
            self.read[name] = p.read_text(encoding="utf-8-sig")
        except (OSError, UnicodeDecodeError):
            pass    # the reader names the file and why (Table.from_csv)
        return p


def _shipped(name: str) -> Path | None:
    """The shipped scene file of that name, if there is one."""
    try:
        return example(name)
    except InputError:
        return None


def example(name: str) -> Path:
    """The path of a shipped scene file (``skfem_beam/scene_files/NAME.toml``, a plate's
    in ``skfem_beam/scene_files/plates/NAME.toml``, beside its mesh file if it has one)."""
    folder = Path(__file__).resolve().parents[1] / "scene_files"
    places = (".", "plates")
    for place in places:
        p = folder / place / f"{Path(name).stem}.toml"
        if p.is_file():
            return p
    shipped = sorted(q.stem for place in places for q in folder.glob(f"{place}/*.toml"))
    raise InputError(f"no scene file {name!r}; shipped: {', '.join(shipped)}")
