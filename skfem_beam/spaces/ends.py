"""End conditions and rigid intermediate supports shared by the beam spaces.

Each end of the beam is one of

==========  ==================  =====================================
name        fixed (essential)   natural (left to the weak form)
==========  ==================  =====================================
clamped     u = 0, u' = 0       —
pinned      u = 0               u'' = 0 (no moment)
sliding     u' = 0              u''' = 0 (no shear)
free        —                   u'' = 0, u''' = 0
==========  ==================  =====================================

A rigid intermediate support fixes u(x_s) = 0 at a mesh node x_s (0 < x_s < L).
The spaces drop (Hermite) or eliminate (B-spline) what is fixed; the natural
conditions need nothing.  Today's beam is ``("clamped", "free")``.
"""
from __future__ import annotations

import numpy as np

from ..errors import InputError

#: name -> (displacement fixed, slope fixed)
END_CONDITIONS = {
    "clamped": (True, True),
    "pinned": (True, False),
    "sliding": (False, True),
    "free": (False, False),
}
DEFAULT_ENDS = ("clamped", "free")


def check_ends(ends) -> tuple[str, str]:
    """``ends`` as a pair of known end-condition names (InputError otherwise)."""
    allowed = ", ".join(END_CONDITIONS)
    if isinstance(ends, str) or not hasattr(ends, "__len__") or len(ends) != 2:
        raise InputError(f"ends={ends!r} must be a pair (condition at x=0, condition at x=L), "
                         f"each one of: {allowed}")
    for i, e in enumerate(ends):
        if not isinstance(e, str) or e not in END_CONDITIONS:
            raise InputError(f"ends.{('left', 'right')[i]}={e!r} is not one of: {allowed}")
    return (ends[0], ends[1])


def support_nodes(nodes: np.ndarray, supports) -> np.ndarray:
    """Indices (sorted, unique) of the interior mesh nodes at the abscissae ``supports``."""
    nodes = np.asarray(nodes, dtype=float)
    L = nodes[-1] - nodes[0]
    out = []
    for k, xs in enumerate(supports):
        i = int(np.abs(nodes - xs).argmin())
        if abs(nodes[i] - xs) > 1e-9 * L:
            raise InputError(f"supports[{k}] x={xs:g}: the mesh has no node there (the "
                             f"nearest, x={nodes[i]:g}, is {abs(nodes[i] - xs):.3g} m away); "
                             "choose J, or the nodes, so that it is one")
        if i == 0 or i == nodes.size - 1:
            raise InputError(f"supports[{k}] x={xs:g} is at an end of the beam: use "
                             "ends=(...) ('pinned' there) instead")
        out.append(i)
    if len(set(out)) != len(out):
        raise InputError(f"two supports at one node: supports={tuple(supports)!r}")
    return np.array(sorted(out), dtype=int)


def fixed_dofs(J: int, ends, supports: np.ndarray):
    """(value fixed, slope fixed) as boolean arrays over the nodes x_0..x_J."""
    value = np.zeros(J + 1, dtype=bool)
    slope = np.zeros(J + 1, dtype=bool)
    value[0], slope[0] = END_CONDITIONS[ends[0]]
    value[J], slope[J] = END_CONDITIONS[ends[1]]
    value[np.asarray(supports, dtype=int)] = True
    return value, slope
