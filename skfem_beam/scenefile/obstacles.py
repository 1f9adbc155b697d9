"""A beam's [[obstacles]]: the flat ones (numbers, polynomials or tables g1 ≤ v ≤ g2 at a
point, over a span or along the whole beam) and the holes (two planes)."""
from __future__ import annotations

import math

import numpy as np

from ..checks import check_finite
from ..errors import InputError
from ..problem import Obstacles
from .parts import need, outer_radius, plane_count


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
        tol = 1e-9 * max(1.0, float(np.abs(xs).max()))

        def table(x):       # not extended flat beyond its points, as a plate's table
            x = np.asarray(x, dtype=float)
            off = x[(x < xs[0] - tol) | (x > xs[-1] + tol)]
            if off.size:
                raise InputError(f"{where} = {{x, g}}: the obstacle acts at x={off[0]:g}, "
                                 f"outside its table's x [{xs[0]:g}, {xs[-1]:g}]: extend "
                                 "the table, or give x_from, x_to")
            return np.interp(x, xs, gs)
        return table
    raise InputError(f"{where} must be a number, {{ poly = [c0, c1, ...], about = x0 }} or "
                     f"{{ x = [...], g = [...] }} (got keys {', '.join(value)})")


def _hole(o: dict, i: int, friction: float = 0.0):
    """A [[obstacles]] hole = {...} at x or over [x_from, x_to] (holes.HoleAt); its
    ``friction`` μ, else the scene's [contact] friction."""
    from ..holes import HoleAt, hole_from_table
    where = f"obstacles.{i}"
    if "g1" in o or "g2" in o:
        raise InputError(f"[{where}] a hole bounds (v, w) itself: leave out g1, g2")
    hole = _named(f"{where}.hole", lambda: hole_from_table(o["hole"], f"{where}.hole"))
    mu = o.get("friction", friction)
    if "x" in o:
        if "x_from" in o or "x_to" in o:
            raise InputError(f"[{where}] give x or x_from, x_to, not both")
        at = (o["x"],)
    else:
        at = tuple(need(o, ("x_from", "x_to"), where).values())
    return _named(where, lambda: HoleAt(hole, *at, carried=o.get("carried", False),
                                        friction=mu, name=where))


def _named(where: str, make):
    """make(), its refusal prefixed with the key path ``where`` (a hole's own checks name
    only the value: with two baffles the user could not tell which was wrong)."""
    try:
        return make()
    except InputError as e:
        text = str(e)
        if text.startswith((where, f"[{where}]")):
            raise
        raise InputError(f"{where}: {text}") from None


def _obstacle(o: dict, i: int) -> Obstacles:
    where = f"obstacles.{i}"
    if "g1" not in o and "g2" not in o:     # else it would bound nothing, and run silently
        raise InputError(f"[{where}] needs g1 and/or g2 (m), or a hole: without them it "
                         "bounds nothing")
    g1, g2 = _g(o.get("g1", -np.inf), f"{where}.g1"), _g(o.get("g2", np.inf), f"{where}.g2")
    carried = o.get("carried", False)
    if "x" in o:
        if "x_from" in o or "x_to" in o or callable(g1) or callable(g2):
            raise InputError(f"[{where}] a point stop (x) takes numbers g1, g2 and no "
                             "x_from/x_to")
        return Obstacles.stops([o["x"]], g1, g2, carried=carried, name=where)
    if "x_from" in o or "x_to" in o:
        a, b = need(o, ("x_from", "x_to"), where).values()
        return Obstacles.span(a, b, g1, g2, carried=carried, name=where)
    return Obstacles(g1, g2, carried=carried, name=where)


def _warn_hole_size(items, tube: float | None) -> None:
    """One warning line for a hole whose radius is half the tube's outer radius or more: a
    hole's sizes are clearances round the tube's axis, and the hole's own radius written
    there runs (with a tube rattling over centimetres)."""
    from ..cli import warn
    for i, o in items:
        r = o.get("hole", {}).get("radius") if isinstance(o.get("hole"), dict) else None
        if tube and isinstance(r, (int, float)) and r >= 0.5 * tube:
            warn(f"[obstacles.{i}] hole radius = {r:g} m is {r / tube:.2g}× the tube's outer "
                 f"radius {tube:g} m: it is the radial clearance round the tube's axis "
                 "(0.0004 for 0.4 mm), not the hole's own radius")


def _warn_polygon_degrees(items) -> None:
    """One warning line for a regular polygon's angle beyond a turn: it is in rad (a
    broached hole's lands are in degrees, a drawing's), and 30 meant as degrees ran as
    30 rad, another polygon, silently."""
    from ..cli import warn
    for i, o in items:
        hole = o.get("hole") if isinstance(o.get("hole"), dict) else {}
        a = hole.get("angle")
        if "sides" in hole and isinstance(a, (int, float)) and abs(a) > 2 * math.pi:
            warn(f"[obstacles.{i}] hole angle = {a:g} is in rad for sides = n (a turn is "
                 f"6.283): {a:g}° would be angle = {math.radians(a):.6g}")


def obstacles_and_holes(data: dict, L: float) -> tuple[Obstacles, tuple]:
    """The flat obstacles (the first plane's, g1 ≤ v ≤ g2) and the holes, each on the beam
    [0, L] (BeamProblem checks it too, without the key path)."""
    items = list(enumerate(data.get("obstacles", [])))
    mu = data.get("contact", {}).get("friction", 0.0)
    if check_finite("[contact] friction", mu) < 0:     # also where every hole sets its own
        raise InputError(f"[contact] friction={mu:g} must be ≥ 0 (Coulomb's μ)")
    if any("hole" in o for _, o in items) and plane_count(data) != 2:   # first: the other
        raise InputError("[[obstacles]] hole bounds (v, w) in the cross-section: it needs "
                         "planes = 2 at the top of the file")       # lines assume it
    holes = tuple(_hole(o, i, mu) for i, o in items if "hole" in o)
    for i, h in zip([i for i, o in items if "hole" in o], holes):
        for b in h.breakpoints:
            if not 0.0 <= b <= L:
                raise InputError(f"obstacles.{i}: hole at x={b:g} lies outside the beam "
                                 f"[0, L={L:g}]")
    _warn_hole_size(items, outer_radius(data.get("section", {})))
    _warn_polygon_degrees(items)
    if (mu or any("friction" in o for _, o in items)) and plane_count(data) != 2:
        raise InputError("friction acts along the wall of a hole, in the cross-section: the "
                         "one-plane beam has no tangential direction (planes = 2 and a hole)")
    for i, o in items:
        if o.get("carried", False) and "motion" not in data:   # it ran as a fixed obstacle
            raise InputError(f"[obstacles.{i}] carried = true moves the obstacle with the "
                             "support's [motion]: this scene has none")
        if "friction" in o and "hole" not in o:
            raise InputError(f"[obstacles.{i}] friction acts at a hole's wall: this obstacle "
                             "has no hole")
    if mu and not holes:        # it ran frictionless without a word
        raise InputError(f"[contact] friction={mu:g} acts at a hole's wall: this scene has "
                         "no hole ([[obstacles]] hole = ...)")
    parts = [_obstacle(o, i) for i, o in items if "hole" not in o]
    if not parts:
        return Obstacles(), holes
    return (parts[0] if len(parts) == 1 else Obstacles.combine(*parts)), holes
