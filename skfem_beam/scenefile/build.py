"""A parsed scene → :class:`Scene`, the Python API's objects: the problem (a beam's or a
bar's), and what the file leaves to inference: the contact law (from [contact], the
obstacles' own stiffness and the holes' friction), the time grid, the method's β, the
output options and [wear]."""
from __future__ import annotations

import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from .. import methods
from ..checks import check_choice, check_nonnegative, check_positive
from ..contact import SOLVERS
from ..errors import InputError
from ..scheme import Stepping
from .bar import bar_problem
from .beam import beam_problem
from .forcing import warn_aliased, warn_tables
from .parts import named_section, need, outer_radius, plane_count, stepping_of
from .read import Parsed, Tables, read
from .schema import CONTACT, OUTPUT_DEFAULTS


BEAM_MASSES = ("consistent", "redistributed")        # [mesh] mass of a beam
SCENE_WORDS = methods.Words(solver="[contact] law = ", massless="[mesh] massless = ",
                            law="[contact] law = ", restitution="[contact] restitution = ",
                            theta="[contact] theta = ", param="[contact] ",
                            stiffness="[contact] stiffness = ")


@dataclass(frozen=True)
class Scene:
    """A scene file read into the Python API's objects.

    ``problem``: a BeamProblem or a Bar; ``stepping``: the time grid; ``law``,
    ``stiffness`` (N/m), ``restitution``: the [contact] keys, ``damping`` (N·s/m): the
    supports' dashpots ([[obstacles]] damping) (``method`` builds the run's method from
    them and [time] beta, the β-scheme's β; ``beta`` is the β summary.json records);
    ``stiffness`` and ``damping`` are tuples (one per obstacle) when the
    [[obstacles]] stiffness or damping differ;
    ``output``: format, save_every, frames, flush_every, checkpoint_every; ``text``: the
    file as read and ``files`` the tables it read (path as written → text), so that a run
    can be rebuilt from its summary.json; ``data``: the parsed TOML with the overrides.
    """
    kind: str
    problem: object
    stepping: Stepping
    law: str = "auto"
    stiffness: float | tuple[float, ...] | None = None
    restitution: float = 0.0
    output: dict = field(default_factory=dict)
    text: str = ""
    files: dict = field(default_factory=dict)
    data: dict = field(default_factory=dict)
    damping: float | tuple[float, ...] = 0.0

    @property
    def method(self) -> methods.Method:
        """The run's method (:mod:`skfem_beam.methods`): ``law`` names a class
        (methods.LAWS) or a position-level solver."""
        law, solver = methods.split_law(self.law)
        if law == "penalty" and self.stiffness is None:
            raise InputError("[contact] law='penalty' needs stiffness (N/m)")
        massless = self.data.get("mesh", {}).get("massless")    # as written: None if not
        contact = self.data.get("contact", {})
        params = CONTACT.method_params(contact)
        params["beta"] = self._beta_given()
        return methods.make(law, solver, self.restitution or 0.0, self.stiffness, massless,
                            words=SCENE_WORDS, damping=self.damping, params=params)

    def _beta_given(self) -> float | None:
        """[time] beta; a bar's default, 1/4 whatever the law (None: the method's own)."""
        given = self.data.get("time", {}).get("beta")
        return methods.BAR_BETA if given is None and self.kind == "bar" else given

    @property
    def beta(self) -> float:
        """The run's β as summary.json records it (methods.recorded_beta): the β-scheme
        method's; for Moreau–Jean, which has none, [time] beta or its default."""
        return methods.recorded_beta(self.method, self._beta_given(), self.kind)


def load(path, overrides=(), files: dict | None = None, text: str | None = None,
         dynamic: bool = True, meshes: dict | None = None) -> Scene:
    """Read the scene file ``path`` (``overrides``: ``KEY=VALUE`` strings as ``--set``).
    ``text``/``files``/``meshes``: the file's and its tables' stored texts and its mesh
    files' stored bytes (a resumed run) instead of the file system.  ``dynamic=False``:
    the structure alone (natural frequencies need no [time], [contact] or [output]: they
    are not read, and ``stepping`` is None)."""
    return build(read(path, overrides, files, text, meshes), dynamic)


def build(parsed: Parsed, dynamic: bool = True) -> Scene:
    """The scene :func:`~skfem_beam.scenefile.read.read` parsed as the API's objects
    (``dynamic``: as :func:`load`); every error line names the file."""
    path = parsed.path
    tables = Tables(path.parent, parsed.files, parsed.meshes)
    try:    # every error line names the file
        with tempfile.TemporaryDirectory() as tmp:
            tables.tmp = Path(tmp)
            if parsed.kind == "plate":
                from .plate import plate_scene
                return plate_scene(parsed, tables, dynamic)
            problem = (beam_problem if parsed.kind == "beam" else bar_problem)(parsed.data,
                                                                              tables)
        if not dynamic:
            return Scene(parsed.kind, problem, None, text=parsed.text, files=tables.read,
                         data=parsed.data)
        return _scene(parsed.kind, problem, parsed.data, parsed.text, tables)
    except InputError as e:
        raise InputError(f"{path.name}: {e}") from None


def _supports(data: dict) -> tuple | None:
    """A beam's [[obstacles]] stiffness (N/m) and damping (N·s/m, default 0): the supports'
    own compliance (the penalty law's springs and dashpots; their deflection is the
    support's), one number each when every obstacle has the same, else a tuple of one per
    obstacle (one plane only: its rows know their obstacle).  Every obstacle has a
    stiffness or none does (rigid supports: None); a damping needs a stiffness."""
    if data.get("kind", "beam") != "beam":
        return None
    obstacles = data.get("obstacles", [])
    given = [(o.get("stiffness"), o.get("damping")) for o in obstacles]
    if all(k is None and c is None for k, c in given):
        return None
    springs = [i for i, (k, _) in enumerate(given) if k is not None]
    for i, (k, c) in enumerate(given):
        where = f"[obstacles.{i}]"
        if k is None and c is not None:
            raise InputError(f"{where} damping is a dashpot beside the support's spring: "
                             "give its stiffness (N/m) too")
        if k is None:
            raise InputError(f"{where} has no stiffness while [obstacles.{springs[0]}] has "
                             "one: give every obstacle a stiffness (springs, N/m) or none "
                             "(rigid); rigid and spring supports together are not modelled")
        check_positive(f"{where} stiffness", k)
        if c is not None:
            check_nonnegative(f"{where} damping", c)
    if "stiffness" in data.get("contact", {}) or \
            data.get("contact", {}).get("law", "penalty") not in ("penalty", "auto"):
        raise InputError("[[obstacles]] stiffness makes the supports springs (the penalty "
                         "law): leave out [contact] law and stiffness")
    ks = tuple(float(k) for k, _ in given)
    cs = tuple(0.0 if c is None else float(c) for _, c in given)
    if len(set(ks)) == 1 and len(set(cs)) == 1:
        return ks[0], cs[0]
    if plane_count(data) == 2:
        raise InputError("[[obstacles]] stiffness, damping may differ per obstacle in one "
                         f"plane only; with planes = 2 give every obstacle the same (got "
                         f"{', '.join(f'{k:g}, {c:g}' for k, c in zip(ks, cs))})")
    return ks, cs


def _scene(kind, problem, data, text, tables: Tables) -> Scene:
    contact = data.get("contact", {})
    law, k, c = contact.get("law", "auto"), contact.get("stiffness"), 0.0
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
        if mesh.get("mass") == "redistributed" and plane_count(data) == 2:
            raise InputError("[mesh] mass = \"redistributed\" is for one plane; planes = 2 "
                             "takes the consistent mass")
    rows = mesh.get("massless")
    methods.check_massless(rows, mesh.get("mass", "consistent"), "[mesh] massless")
    stepping = stepping_of(t, out, load_window=t.get("load_window", "forward"),
                           massless=rows or "beta")
    warn_aliased(data, stepping.dt)
    warn_tables(tables, stepping.T)
    scene = Scene(kind, problem, stepping, law, k, contact.get("restitution", 0.0), out, text,
                  tables.read, data, c)
    try:
        scene.beta      # the method's own checks (law, stiffness, restitution, β)
    except InputError as e:
        raise named_section(e) from None
    return scene


def wear(scene: Scene):
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
    if not scene.problem.beam.rho_S:    # K × W per kg/m was printed as mm³ and mm
        raise InputError("[wear] needs forces in newtons, so the beam's mass per length: "
                         "give [material] and [section], or rho_S in [mass_normalised]")
    sections = [s.get("section", {}) for s in scene.data.get("segments", [])] or \
        [scene.data.get("section", {})]
    radii = {outer_radius(section) for section in sections}     # a stepped tube's: one?
    outer = radii.pop() if len(radii) == 1 else None
    radius = d.get("radius", outer)
    if radius is None and "land" in d:
        raise InputError("[wear] radius (m, the tube's outer radius) is needed for the depth "
                         "(land) when the section is not a tube or a rod, or its segments' "
                         "outer diameters differ")
    walls = {section.get("tube", {}).get("wall") for section in sections}
    given = need(d, ("coefficient", "service_years"), "wear")
    worn = Wear(given["coefficient"], given["service_years"], d.get("land"), radius,
                walls.pop() if len(walls) == 1 else None)
    _warn_wear_sizes(worn, scene.problem.beam.L, outer)
    return worn


def _warn_wear_sizes(worn, L: float, section: float | None) -> None:
    """One warning line for a [wear] land longer than the beam, or a radius ten times
    the section's outer radius or more (none: longer than the beam): a size in mm written
    as m (19 for 0.019) made the depth 1000 times too small and dropped the wear-through
    warning."""
    from ..cli import warn
    if worn.land is not None and worn.land > L:
        warn(f"[wear] land = {worn.land:g} m is longer than the beam (L = {L:g} m): it is "
             "the baffle's thickness in m (0.019 for 19 mm)")
    r = worn.radius
    if r is not None and (r >= 10 * section if section else r > L):
        warn(f"[wear] radius = {r:g} m is " + (f"{r / section:.4g}× the section's outer "
             f"radius {section:g} m" if section is not None else f"longer than the beam "
             f"(L = {L:g} m)") + ": it is the tube's outer radius in m (0.009525 for 9.525 mm)")


