"""Holes in a support, in the beam's cross-section plane: where a two-plane beam's
displacement (v, w) at a node may be.

A hole is a convex set around the beam's rest position (0, 0):

- ``Hole.round(radius, centre)``: a drilled hole, |(v, w) − centre| ≤ radius (a
  second-order cone: the exact round-hole law, contact.round_hole);
- ``Hole.faces(rows, centre)``: flat faces (anti-vibration bars, broached lands), each row
  (ny, nz, gap) saying n·((v, w) − centre) ≤ gap with n = (ny, nz) normalised;
- ``Hole.regular(sides, radius, angle, centre)``: a regular polygon, ``radius`` to its
  faces (the inscribed circle), the first face's normal at ``angle`` (rad);
- ``Hole.polygon(vertices)``: any convex polygon, vertices counter-clockwise;
- ``Hole.broached(lands, land_width, radius, angle, centre)``: a broached hole, ``lands``
  arcs of the drilled circle (``land_width`` rad each, centred at angle + 2πk/lands) with
  lobes cut between them.  To first order in clearance/radius the tube centre's set is
  K = {p : p·e(φ) ≤ radius for every φ on a land}: arcs of the circle over the lands and,
  in each lobe, the two tangent lines at the lands' ends meeting in a corner (convex;
  full lands: the disk, lands of no width: the regular polygon).  Solved exactly by
  contact.round_hole, as a disk pair whose block knows its lands.

Faces are linear constraints: :meth:`Hole.rows` gives them as rows lo ≤ n·(v, w) ≤ hi,
two antiparallel faces merged into one row with both bounds (a square hole is then the
one-plane stops g1 ≤ v ≤ g2 and g1 ≤ w ≤ g2, decoupled: the projection law).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .checks import check_count, check_finite, check_positive
from .errors import InputError
from .polygons import clip


def _pair(name: str, value) -> tuple[float, float]:
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 2:
        raise InputError(f"{name}={value!r} must be a pair [y, z] (m)")
    return check_finite(f"{name}[0]", value[0]), check_finite(f"{name}[1]", value[1])


@dataclass(frozen=True)
class Hole:
    """A convex hole: ``radius`` (round) or ``faces`` ((k, 3) rows ny, nz, gap with n a unit
    vector), about ``centre`` (y, z) in m; ``shape`` names it in reports."""
    centre: tuple[float, float] = (0.0, 0.0)
    radius: float | None = None
    faces_: tuple[tuple[float, float, float], ...] = ()
    shape: str = "round"
    lands: int = 0            # broached: the lands (0: a round or flat-faced hole)
    land_width: float = 0.0   # broached: each land's angular width (rad)
    angle: float = 0.0        # broached: the first land's centre (rad)

    @classmethod
    def round(cls, radius: float, centre=(0.0, 0.0)) -> "Hole":
        hole = cls(_pair("centre", centre), check_positive("radius", radius), (), "round")
        hole._check_rest()
        return hole

    @classmethod
    def faces(cls, rows, centre=(0.0, 0.0), shape: str = "faces") -> "Hole":
        """Faces n·((v, w) − centre) ≤ gap, rows (ny, nz, gap), as written: a row whose
        normal is not of length 1 is normalised with its gap (2v ≤ 0.0004 is v ≤ 0.0002;
        the gap was kept, a hole twice as wide as written).  ``rows`` is not changed."""
        try:    # a ragged list (a face of two numbers) is no array
            rows = np.array(rows, dtype=float) if _is_table(rows) else None      # a copy
        except ValueError:
            rows = None
        if rows is None or rows.ndim != 2 or rows.shape[1] != 3 or rows.shape[0] < 1:
            raise InputError("hole faces must be [[ny, nz, gap], ...] (at least one face)")
        if not np.isfinite(rows).all():
            raise InputError("hole faces must be finite numbers")
        norm = np.hypot(rows[:, 0], rows[:, 1])
        if np.any(norm == 0):
            raise InputError(f"hole face {int(np.argmin(norm))} has the normal (0, 0)")
        n = rows[:, :2] / norm[:, None]
        unit = np.abs(norm - 1.0) <= 1e-12        # (cos a, sin a): the gap kept to the bit
        rows[~unit, 2] /= norm[~unit]
        n[np.abs(n) < 1e-14] = 0.0         # cos(π/2) is 6e-17: a square's faces are exact
        rows = np.column_stack([n / np.hypot(n[:, 0], n[:, 1])[:, None], rows[:, 2]])
        hole = cls(_pair("centre", centre), None, tuple(map(tuple, rows.tolist())), shape)
        hole._check_rest()
        return hole

    @classmethod
    def regular(cls, sides: int, radius: float, angle: float = 0.0, centre=(0.0, 0.0)) \
            -> "Hole":
        """A regular polygon of ``sides`` faces at ``radius`` from the centre (inscribed
        radius), the first face's outward normal at ``angle`` rad."""
        sides = check_count("sides", sides, 3)
        radius, angle = check_positive("radius", radius), check_finite("angle", angle)
        a = angle + 2 * math.pi * np.arange(sides) / sides
        return cls.faces(np.column_stack([np.cos(a), np.sin(a), np.full(sides, radius)]),
                         centre, f"{sides}-gon")

    @classmethod
    def polygon(cls, vertices) -> "Hole":
        """A convex polygon through ``vertices`` [[y, z], ...], counter-clockwise (m)."""
        try:    # a ragged list (a vertex of three numbers) is no array
            p = np.asarray(vertices, dtype=float) if _is_table(vertices) else None
        except ValueError:
            p = None
        if p is None or p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 3 \
                or not np.isfinite(p).all():
            raise InputError("hole polygon must be [[y1, z1], [y2, z2], ...] (at least three "
                             "vertices, m)")
        p, number = _plain_corners(p)
        e = np.roll(p, -1, axis=0) - p
        cross = e[:, 0] * np.roll(e, -1, axis=0)[:, 1] - e[:, 1] * np.roll(e, -1, axis=0)[:, 0]
        if np.any(cross <= 0):
            i = int(np.argmax(cross <= 0))
            raise InputError(f"hole polygon is not convex and counter-clockwise at vertex "
                             f"{number[(i + 1) % len(p)]} ({p[(i + 1) % len(p)].tolist()})")
        turning = np.sum(np.arctan2(cross, np.einsum("ij,ij->i", e, np.roll(e, -1, axis=0))))
        if turning > 2 * np.pi * (1 + 1e-9):    # left turns all, but round more than once
            raise InputError(f"hole polygon crosses itself (its edges turn {turning / np.pi:g}π, "
                             "a convex polygon's 2π): give its vertices once round, in order")
        n = np.column_stack([e[:, 1], -e[:, 0]])      # outward: the edge turned clockwise
        n /= np.hypot(n[:, 0], n[:, 1])[:, None]
        return cls.faces(np.column_stack([n, np.einsum("ij,ij->i", n, p)]), (0.0, 0.0),
                         "polygon")

    @classmethod
    def broached(cls, lands: int, land_width: float, radius: float, angle: float = 0.0,
                 centre=(0.0, 0.0)) -> "Hole":
        """``lands`` arcs of ``land_width`` rad on the circle of ``radius`` about ``centre``,
        the first centred at ``angle`` rad; open lobes between them (module docstring)."""
        lands = check_count("lands", lands, 2)
        width = check_finite("land_width", land_width)
        if width == 0.0:    # the limit the lands' pieces degenerate in: the polygon is that
            raise InputError(f"land_width=0°: lands of no width are the regular polygon "
                             f"of {lands} sides, {{ sides = {lands}, radius = r, angle = "
                             f"{angle:g} }} in a scene file (its angle in rad; "
                             f"Hole.regular)")
        if not 0.0 < width <= 2 * math.pi / lands * (1 + 1e-12):
            raise InputError(f"land_width={math.degrees(width):g}° must be in (0, "
                             f"{360 / lands:g}]° (360/lands: the lands may not overlap)")
        width = min(width, 2 * math.pi / lands)
        hole = cls(_pair("centre", centre), check_positive("radius", radius), (),
                   f"{lands}-land", lands, width, check_finite("angle", angle))
        hole._check_rest()
        return hole

    @property
    def is_round(self) -> bool:
        """A drilled round hole (a broached hole has its radius too, and lands)."""
        return self.radius is not None and self.lands == 0

    @property
    def is_broached(self) -> bool:
        return self.lands > 0

    @property
    def is_disk_pair(self) -> bool:
        """Solved as a pair of rows (v, w) with the box [c − r, c + r]: round or broached."""
        return self.radius is not None

    def land_row(self) -> tuple[float, float, float]:
        """(lands, half width, first land's angle), the contact law's constants of the
        hole's block ((0, 0, 0): a round hole)."""
        return (float(self.lands), 0.5 * self.land_width, self.angle)

    def _check_rest(self) -> None:
        """The beam's rest position (0, 0) must lie strictly inside."""
        gap = self.clearance(np.zeros(2))
        if gap <= 0:
            raise InputError(f"the {self.shape} hole about centre={list(self.centre)} does not "
                             "contain the beam's rest position (0, 0) strictly inside")

    def clearance(self, p) -> float:
        """Distance from p = (v, w) to the wall, inward (< 0: outside the hole)."""
        d = np.asarray(p, dtype=float) - np.asarray(self.centre)
        if self.is_round:
            return float(self.radius - np.hypot(d[0], d[1]))
        if self.is_broached:
            return -float(land_excess(d[0], d[1], self.radius, *self.land_row()))
        f = np.asarray(self.faces_)
        return float(np.min(f[:, 2] - f[:, :2] @ d))

    def rows(self) -> list[tuple[float, float, float, float]]:
        """The faces as rows (ny, nz, lo, hi): lo ≤ n·(v, w) ≤ hi, antiparallel faces
        merged (the row of the first; lo = −∞ when a face has no opposite)."""
        c = np.asarray(self.centre)
        out, used = [], set()
        f = list(self.faces_)
        for i, (ny, nz, gap) in enumerate(f):
            if i in used:
                continue
            hi = gap + ny * c[0] + nz * c[1]
            lo = -math.inf
            for k in range(i + 1, len(f)):
                if k not in used and abs(f[k][0] + ny) < 1e-12 and abs(f[k][1] + nz) < 1e-12:
                    lo = -(f[k][2] + f[k][0] * c[0] + f[k][1] * c[1])
                    used.add(k)
                    break
            out.append((ny, nz, lo, hi))
        return out

    def outline(self, points: int = 361) -> np.ndarray:
        """(points, 2) on the wall, for charts (a polygon: its vertices, closed)."""
        c = np.asarray(self.centre)
        if self.is_round:
            a = np.linspace(0.0, 2 * math.pi, points)
            return c + self.radius * np.column_stack([np.cos(a), np.sin(a)])
        if self.is_broached:
            return c + self._broached_outline(points)
        return c + faces_outline(np.asarray(self.faces_))


    def _broached_outline(self, points: int) -> np.ndarray:
        """∂K about the centre, closed: per land an arc (its share of ``points``), then
        the lobe's corner (the two edge lines are straight: their ends suffice)."""
        n, h, a0 = self.lands, 0.5 * self.land_width, self.angle
        delta = math.pi / n - h              # half the lobe's angle
        per = max(2, points // n)
        out = []
        for k in range(n):
            mid = a0 + 2 * math.pi * k / n
            a = np.linspace(mid - h, mid + h, per)
            out.append(self.radius * np.column_stack([np.cos(a), np.sin(a)]))
            if delta > 0.0:
                m = mid + math.pi / n
                out.append(self.radius / math.cos(delta) * np.array([[math.cos(m),
                                                                       math.sin(m)]]))
        out = np.concatenate(out)
        return np.vstack([out, out[:1]])


def land_excess(pa: float, pb: float, r: float, lands: float, half: float,
                angle: float) -> float:
    """max over the lands' φ of p·e(φ) − r: how far p = (pa, pb) lies beyond a broached
    hole's set K (≤ 0: inside; on a land's direction it is |p| − r).  The same arithmetic
    as contact.lands.land_excess (plain Python here, for the checks and charts)."""
    rho = math.hypot(pa, pb)
    step = 2 * math.pi / lands
    off = math.atan2(pb, pa) - angle
    off -= step * math.floor(off / step + 0.5)     # from the nearest land's centre
    return rho * math.cos(max(abs(off) - half, 0.0)) - r


def faces_outline(f: np.ndarray) -> np.ndarray:
    """The walls of the faces n·p ≤ gap (rows of ``f``), for a chart: the region's edges
    that lie on a face, in order, closed when the region is bounded; an open one's (flat
    bars, faces open on one side) up to three times the largest gap, NaN rows between its
    pieces.  (Each pair of neighbouring faces' corner had been drawn, closing an open
    hole with a wall the orbit crossed.)"""
    gap = max(float(np.abs(f[:, 2]).max()), 1e-300)
    for reach in (1e3 * gap, 3 * gap):      # bounded: well inside the first box
        poly = reach * np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])
        for face in f:
            poly = clip(poly, face[:2], face[2])
        if not len(poly):
            return np.zeros((0, 2))
        mid = 0.5 * (poly + np.roll(poly, -1, axis=0))        # edge i: poly[i] → poly[i+1]
        on = (np.abs(mid @ f[:, :2].T - f[:, 2]) <= 1e-9 * reach).any(axis=1)
        if on.all():
            return np.vstack([poly, poly[:1]])
    start = int(np.argmin(on)) + 1          # just after an edge on the box
    rows = []
    for k in range(start, start + len(poly)):
        i = k % len(poly)
        if on[i]:
            if not rows or np.isnan(rows[-1][0]):
                rows.append(poly[i])
            rows.append(poly[(i + 1) % len(poly)])
        elif rows and not np.isnan(rows[-1][0]):
            rows.append(np.full(2, np.nan))
    return np.array(rows).reshape(-1, 2)


def _plain_corners(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A polygon's vertices without a repeated one (a closed outline's last, as CAD writes
    it) or one in the middle of an edge: the same hole, which the convexity check refused
    ("not convex ... at vertex N"); with each kept vertex's number as given."""
    scale = float(np.abs(p).max()) or 1.0
    number = np.arange(len(p))
    keep = np.linalg.norm(p - np.roll(p, -1, axis=0), axis=1) > 1e-12 * scale
    p, number = (p[keep], number[keep]) if keep.any() else (p[:1], number[:1])
    while len(p) > 3:
        a, b = p - np.roll(p, 1, axis=0), np.roll(p, -1, axis=0) - p
        straight = (np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]) <= 1e-12 * scale * scale) \
            & (np.einsum("ij,ij->i", a, b) > 0)
        if not straight.any():
            break
        k = int(np.argmax(straight))
        p, number = np.delete(p, k, axis=0), np.delete(number, k)
    return p, number


def _is_table(value) -> bool:
    return isinstance(value, (list, tuple, np.ndarray)) and not isinstance(value, (str, bytes))


def hole_from_table(d: dict, where: str) -> Hole:
    """A hole from a scene file's ``hole = { ... }``: ``radius`` alone (round; with
    ``sides`` a regular polygon, ``angle`` its first face's normal in rad; with ``lands`` a
    broached hole, ``land_width`` and ``angle`` in degrees), ``polygon``, or ``faces``;
    ``centre`` optional."""
    if not isinstance(d, dict):
        raise InputError(f"{where} must be a table: {{ radius = r }}, {{ sides = n, radius = r }}, "
                         "{ lands = n, land_width = deg, radius = r }, "
                         "{ polygon = [[y, z], ...] } or { faces = [[ny, nz, gap], ...] }")
    allowed = {"radius", "sides", "angle", "centre", "polygon", "faces", "lands", "land_width"}
    unknown = set(d) - allowed
    if unknown:
        raise InputError(f"unknown key {where}.{sorted(unknown)[0]}; a hole allows: "
                         f"{', '.join(sorted(allowed))}")
    centre = d.get("centre", (0.0, 0.0))
    if ("lands" in d or "land_width" in d) and not {"polygon", "faces", "sides"} & set(d):
        return _broached_from_table(d, where, centre)
    if {"lands", "land_width"} & set(d):
        raise InputError(f"{where} lands and land_width make a broached hole: not with "
                         "sides, polygon or faces")
    if "polygon" in d:
        if set(d) - {"polygon"}:
            raise InputError(f"{where} polygon stands alone (its vertices are absolute)")
        return Hole.polygon(d["polygon"])
    if "faces" in d:
        if set(d) - {"faces", "centre"}:
            raise InputError(f"{where} faces take only centre beside them")
        return Hole.faces(d["faces"], centre)
    if "sides" in d:
        if "radius" not in d:
            raise InputError(f"{where} sides = n needs radius (to the faces, m)")
        return Hole.regular(d["sides"], d["radius"], d.get("angle", 0.0), centre)
    if "radius" not in d:
        raise InputError(f"{where} needs radius, sides with radius, lands with radius, "
                         "polygon or faces")
    if "angle" in d:
        raise InputError(f"{where} angle applies to a regular polygon (sides) or lands")
    return Hole.round(d["radius"], centre)


def _broached_from_table(d: dict, where: str, centre) -> Hole:
    """``{ lands = n, land_width = deg, radius = r, angle = deg }`` (degrees: a drawing's)."""
    for key in ("lands", "land_width", "radius"):
        if key not in d:
            raise InputError(f"{where} a broached hole needs lands, land_width (degrees) "
                             f"and radius (m): {key} is missing")
    try:
        return Hole.broached(d["lands"], math.radians(check_finite("land_width",
                                                                    d["land_width"])),
                             d["radius"], math.radians(check_finite("angle",
                                                                    d.get("angle", 0.0))),
                             centre)
    except InputError as e:
        raise InputError(f"{where}: {e}") from None


@dataclass(frozen=True)
class HoleAt:
    """A hole acting at the node x (``x_to`` None) or at every node of [x, x_to];
    ``carried``: it moves with the moving support (else fixed to the ground);
    ``friction``: Coulomb's μ at its wall (round holes: round-hole-friction or
    Moreau–Jean; flat faces and broached holes: round-hole-friction)."""
    hole: Hole
    x: float
    x_to: float | None = None
    carried: bool = False
    friction: float = 0.0
    name: str = ""          # how error lines name it (a scene file's obstacles.<i>)

    def __post_init__(self):
        object.__setattr__(self, "x", check_finite("x", self.x))
        if self.x_to is not None:
            object.__setattr__(self, "x_to", check_finite("x_to", self.x_to))
            if self.x_to <= self.x:
                raise InputError(f"hole span [x_from={self.x:g}, x_to={self.x_to:g}] needs "
                                 "x_from < x_to")
        if not isinstance(self.carried, (bool, np.bool_)):
            raise InputError(f"carried={self.carried!r} must be True or False")
        mu = check_finite("friction", self.friction)
        if mu < 0:
            raise InputError(f"friction={mu:g} must be ≥ 0 (Coulomb's μ)")
        object.__setattr__(self, "friction", mu)

    @property
    def breakpoints(self) -> tuple[float, ...]:
        return (self.x,) if self.x_to is None else (self.x, self.x_to)

    def acts_at(self, x: np.ndarray, L: float) -> np.ndarray:
        tol = 1e-9 * max(1.0, L)
        if self.x_to is None:
            return np.abs(x - self.x) <= tol
        return (x >= self.x - tol) & (x <= self.x_to + tol)
