"""Convex polygons in the plane (k × 2 vertex arrays, in order): cut by a half-plane,
and their area.  One clipping rule (Sutherland–Hodgman) serves a hole's chart wall
(holes.faces_outline) and a plate pressure's cut cells (plate.region)."""
from __future__ import annotations

import numpy as np


def clip(polygon: np.ndarray, normal, gap: float) -> np.ndarray:
    """The convex ``polygon`` ∩ {p : normal·p ≤ gap}: its vertices in order (none: no
    overlap).  A vertex on the line is kept, and only a side whose ends lie strictly on
    either side of it adds its crossing: no vertex twice."""
    d = polygon @ np.asarray(normal, dtype=float) - gap
    kept = []
    for i in range(len(polygon)):
        j = (i + 1) % len(polygon)
        if d[i] <= 0:
            kept.append(polygon[i])
        if d[i] < 0 < d[j] or d[j] < 0 < d[i]:  # the side crosses the line: where it does
            kept.append(polygon[i] + d[i] / (d[i] - d[j]) * (polygon[j] - polygon[i]))
    return np.array(kept).reshape(-1, 2)


def area(polygon: np.ndarray) -> float:
    """The shoelace area of a polygon."""
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * abs(float(x @ np.roll(y, -1) - y @ np.roll(x, -1)))
