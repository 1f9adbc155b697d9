"""The plate's data: a rectangle (:class:`Plate`) or a triangle mesh read from a file
(:class:`MeshPlate`), its material, the support of each edge and the element."""
from dataclasses import dataclass, field

from ..checks import check_count, check_finite, check_positive
from ..errors import InputError

MAX_PLATE_SIDE = 2000     # elements a side: 16M unknowns (BFS), past a machine's memory

EDGES = ("left", "right", "bottom", "top")
SUPPORTS = ("clamped", "simply_supported", "free", "sliding")
ELEMENTS = ("bfs", "morley", "argyris")


def all_simply_supported() -> dict[str, str]:
    return {edge: "simply_supported" for edge in EDGES}


class _Plate:
    """What every plate derives from its material, its edges and its bounding ``box``."""

    def _check_section(self) -> None:
        """h, E, rho positive numbers, nu in (−1, ½) (each refused in one line naming it)."""
        self.h = check_positive("plate thickness h", self.h)
        self.E = check_positive("plate E", self.E)
        self.rho = check_positive("plate rho", self.rho)
        nu = check_finite("plate nu", self.nu)
        if not -1.0 < nu < 0.5:
            raise InputError(f"plate nu={self.nu!r} must lie in (-1, 0.5)")
        self.nu = nu

    @property
    def size(self) -> float:
        """The longer side of the bounding box (m): the scale of geometric tolerances."""
        x0, x1, y0, y1 = self.box
        return max(x1 - x0, y1 - y0)

    @property
    def centre(self) -> tuple[float, float]:
        x0, x1, y0, y1 = self.box
        return ((x0 + x1) / 2, (y0 + y1) / 2)

    @property
    def D(self) -> float:
        """The bending stiffness E h³ / (12 (1 − ν²)), N·m."""
        return self.E * self.h ** 3 / (12.0 * (1.0 - self.nu ** 2))

    def support(self, edge: str) -> str:
        return self.edges.get(edge, "free")


def _check_supports(edges: dict, names, whose: str = "") -> None:
    """Each edge a name of ``names`` (``whose``: " the boundaries of ..." in the error
    line) with a support of SUPPORTS."""
    if not isinstance(edges, dict):
        raise InputError(f"plate edges={edges!r} must map edges to supports, e.g. "
                         f"{{'left': 'clamped'}} (supports: {', '.join(SUPPORTS)})")
    for edge, support in edges.items():
        if edge not in names:
            raise InputError(f"plate edge {edge!r} is not one of{whose}: "
                             f"{', '.join(names) or '(none)'}")
        if support not in SUPPORTS:
            raise InputError(f"plate edge {edge}: support {support!r} is not one of: "
                             f"{', '.join(SUPPORTS)}")


@dataclass
class Plate(_Plate):
    """A rectangular Kirchhoff–Love plate [0, a] × [0, b] (SI units).

    ``edges`` maps an edge (left x=0, right x=a, bottom y=0, top y=b) to its support;
    an edge not named is free; "sliding" holds ∂w/∂n = 0 and leaves w free (a line of
    symmetry).  ``element`` is "bfs" (Bogner–Fox–Schmit on an nx × ny
    grid of rectangles), "morley" or "argyris" (the grid's rectangles cut in two
    triangles)."""
    a: float = 1.0
    b: float = 1.0
    h: float = 0.01                 # thickness
    E: float = 210e9
    rho: float = 7850.0
    nu: float = 0.3
    edges: dict[str, str] = field(default_factory=all_simply_supported)
    element: str = "bfs"
    nx: int = 8
    ny: int = 8

    def __post_init__(self):
        self._check_section()
        self.a = check_positive("plate side a", self.a)
        self.b = check_positive("plate side b", self.b)
        _check_supports(self.edges, EDGES)
        if self.element not in ELEMENTS:
            raise InputError(f"plate element {self.element!r} is not one of: "
                             f"{', '.join(ELEMENTS)}")
        self.nx = check_count("plate nx", self.nx, most=MAX_PLATE_SIDE)
        self.ny = check_count("plate ny", self.ny, most=MAX_PLATE_SIDE)

    @property
    def boundary_names(self) -> tuple[str, ...]:
        return EDGES

    @property
    def box(self) -> tuple[float, float, float, float]:
        """(x0, x1, y0, y1): the rectangle."""
        return (0.0, self.a, 0.0, self.b)

    def outline(self) -> str:
        """The plate, as the error lines name it."""
        return f"the plate [0, {self.a:g}] × [0, {self.b:g}]"


@dataclass(eq=False)
class MeshPlate(_Plate):
    """A Kirchhoff–Love plate on a triangle mesh (any outline) read from a file
    (:func:`skfem_beam.plate.meshfile.read_plate_mesh`), SI units.

    ``mesh`` a :class:`~skfem_beam.plate.meshfile.PlateMesh`; ``edges`` maps a boundary
    name of the mesh to its support (a boundary not named, and any boundary line the
    file does not name, is free); ``element`` "morley" or "argyris" (BFS needs the
    rectangle's grid).  Regions are checked against the mesh's bounding box ``box``."""
    mesh: object
    h: float = 0.01
    E: float = 210e9
    rho: float = 7850.0
    nu: float = 0.3
    edges: dict[str, str] = field(default_factory=dict)
    element: str = "argyris"

    def __post_init__(self):
        from .meshfile import PlateMesh
        if not isinstance(self.mesh, PlateMesh):
            raise InputError(f"MeshPlate mesh={self.mesh!r} must be a PlateMesh: "
                             "read_plate_mesh(path) reads one from a file")
        self._check_section()
        if self.element == "bfs":
            raise InputError("plate element 'bfs' needs the rectangle's grid ([geometry] a, "
                             "b); a mesh file's plate takes morley or argyris")
        if self.element not in ELEMENTS:
            raise InputError(f"plate element {self.element!r} is not one of: morley, argyris")
        _check_supports(self.edges, self.boundary_names,
                        f" the boundaries of the mesh {self.mesh.source}")

    @property
    def boundary_names(self) -> tuple[str, ...]:
        return tuple(self.mesh.boundaries)

    @property
    def box(self) -> tuple[float, float, float, float]:
        """(x0, x1, y0, y1): the mesh's bounding box."""
        (x0, y0), (x1, y1) = self.mesh.points.min(axis=1), self.mesh.points.max(axis=1)
        return (float(x0), float(x1), float(y0), float(y1))

    @property
    def a(self) -> float:
        """The bounding box's width along x (m)."""
        x0, x1, _, _ = self.box
        return x1 - x0

    @property
    def b(self) -> float:
        """The bounding box's height along y (m)."""
        _, _, y0, y1 = self.box
        return y1 - y0

    def outline(self) -> str:
        x0, x1, y0, y1 = self.box
        return f"the plate (its mesh's bounding box [{x0:g}, {x1:g}] × [{y0:g}, {y1:g}])"
