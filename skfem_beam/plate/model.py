"""The plate's data: a rectangle, its material, the support of each edge and the mesh."""
from dataclasses import dataclass, field

from ..errors import InputError

EDGES = ("left", "right", "bottom", "top")
SUPPORTS = ("clamped", "simply_supported", "free", "sliding")
ELEMENTS = ("bfs", "morley", "argyris")


def all_simply_supported() -> dict[str, str]:
    return {edge: "simply_supported" for edge in EDGES}


@dataclass
class Plate:
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
        if not -1.0 < self.nu < 0.5:
            raise InputError(f"plate nu={self.nu!r} must lie in (-1, 0.5)")
        if not self.h > 0:
            raise InputError(f"plate thickness h={self.h!r} must be > 0")
        if not (self.a > 0 and self.b > 0):
            raise InputError(f"plate sides a={self.a!r}, b={self.b!r} must be > 0")
        for edge, support in self.edges.items():
            if edge not in EDGES:
                raise InputError(f"plate edge {edge!r} is not one of: {', '.join(EDGES)}")
            if support not in SUPPORTS:
                raise InputError(f"plate edge {edge}: support {support!r} is not one of: "
                                 f"{', '.join(SUPPORTS)}")
        if self.element not in ELEMENTS:
            raise InputError(f"plate element {self.element!r} is not one of: "
                             f"{', '.join(ELEMENTS)}")
        if not (int(self.nx) == self.nx >= 1 and int(self.ny) == self.ny >= 1):
            raise InputError(f"plate nx={self.nx!r}, ny={self.ny!r} must be whole numbers ≥ 1")

    @property
    def D(self) -> float:
        """The bending stiffness E h³ / (12 (1 − ν²)), N·m."""
        return self.E * self.h ** 3 / (12.0 * (1.0 - self.nu ** 2))

    def support(self, edge: str) -> str:
        return self.edges.get(edge, "free")
