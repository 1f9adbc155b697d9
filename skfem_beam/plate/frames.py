"""Edge conditions that mix an Argyris vertex's dofs: an oblique (or curved) supported edge.

Along an edge of unit tangent t, normal n = (−t_y, t_x) and curvature κ (t' = κn along
its arc length), w = 0 holds w and its derivatives along the edge at 0, ∂w/∂n = 0 those
of ∂w/∂n.  At a vertex, on its gradient ∇w and Hessian H (the dofs u_x, u_y, u_xx, u_xy,
u_yy), the first two of each:

- simply supported (w = 0):         t·∇w = 0, tᵀHt + κ n·∇w = 0;
- clamped (w = 0 and ∂w/∂n = 0):    ∇w = 0, tᵀHt = 0, nᵀHt = 0 (∂²w/∂n² free);
- sliding (∂w/∂n = 0, w free):      n·∇w = 0, nᵀHt − κ t·∇w = 0.

On a straight edge along x or y each row is one dof (space.is_fixed); on an oblique
one a row mixes dofs.  So at each vertex of an oblique supported edge the five dofs are
replaced by an orthonormal basis of their own (an SVD of the vertex's rows from every
edge that meets there: a corner gets both edges' conditions): its leading vectors span
the rows (held at 0, by index, as any fixed dof), the others their null space (free).
u = Q ũ, Q orthogonal and the identity away from such vertices; K and M are taken in ũ
(Qᵀ K Q, Qᵀ M Q), a load is Qᵀ f.  w and the edges' midpoint u_n are never turned:
w = 0 is one dof, u_n the normal derivative already.

A curved edge given as a polygon turns a little at each vertex.  Each facet's own
(straight, κ = 0) conditions there would hold all of H at 0, the polygon's corner: a
clamped disk's λ² +1.55e-2 at 8 rings, converging as h (docs/plate.md).  Two facets of
one support that turn by less than BEND_DEGREES are one curved edge instead: their mean
tangent, and κ of the circle through the vertex and its two neighbours (a clamped one
keeps its Hessian free: :func:`clamped_curve`).
"""
import numpy as np
from scipy import sparse

# an Argyris vertex's dofs, in skfem's order
VERTEX_DOFS = ("u", "u_x", "u_y", "u_xx", "u_xy", "u_yy")
# a smaller turn at a vertex between facets of one support is a curved edge's polygon (a
# disk of r rings turns 60°/r: 30° at 2 rings), a larger one a corner (an octagon's 45°)
BEND_DEGREES = 35.0
STRAIGHT_DEGREES = 1e-6  # a smaller turn is a straight edge's round-off: κ = 0
RANK_TOL = 1e-8         # a singular value below this (relative) is a repeated row


def edge_rows(support: str, t, kappa: float = 0.0) -> list:
    """The rows the support of an edge (unit tangent t, curvature κ) puts on a vertex's
    (u_x, u_y, u_xx, u_xy, u_yy)."""
    tx, ty = t
    nx, ny = -ty, tx
    tt = (tx * tx, 2.0 * tx * ty, ty * ty)               # tᵀHt
    nt = (nx * tx, nx * ty + ny * tx, ny * ty)           # nᵀHt
    along, across = (tx, ty, 0.0, 0.0, 0.0), (nx, ny, 0.0, 0.0, 0.0)
    return {"simply_supported": [along, (kappa * nx, kappa * ny, *tt)],
            "clamped": [along, across, (0.0, 0.0, *tt), (0.0, 0.0, *nt)],
            "sliding": [across, (-kappa * tx, -kappa * ty, *nt)]}.get(support, [])


def facet_ends(mesh, groups) -> tuple[dict, set]:
    """({vertex: [(support, the facet's other end − the vertex), ...]} over every
    supported facet, the vertices an oblique one touches) (``groups``:
    space.support_groups' tuples)."""
    ends, oblique = {}, set()
    for facets, support, axis in groups:
        if support == "free":
            continue
        for a, b in zip(mesh.facets[0, facets], mesh.facets[1, facets]):
            a, b = int(a), int(b)
            ends.setdefault(a, []).append((support, mesh.p[:, b] - mesh.p[:, a]))
            ends.setdefault(b, []).append((support, mesh.p[:, a] - mesh.p[:, b]))
            if axis is None:
                oblique.update((a, b))
    return ends, oblique


def _unit(d):
    return d / np.hypot(d[0], d[1])


def curve_through(back, ahead) -> tuple[np.ndarray, float, float]:
    """(tangent, κ, turn in degrees) at a vertex from its neighbours on the curve, at
    ``back`` and ``ahead`` relative to it: the mean of the facets' directions, and the
    curvature of the circle through the three points (2 sin(turn) / chord)."""
    t1, t2 = _unit(-back), _unit(ahead)
    turn = np.arctan2(t1[0] * t2[1] - t1[1] * t2[0], np.dot(t1, t2))
    return _unit(t1 + t2), 2.0 * np.sin(turn) / np.hypot(*(ahead - back)), np.degrees(turn)


def vertex_edges(ends: list) -> list:
    """A vertex's (support, tangent, κ): each pair of facets of one support that turns
    by less than BEND_DEGREES there one curved edge (:func:`curve_through`), every other
    facet a straight edge of its own."""
    out, used = [], set()
    for i, (support, back) in enumerate(ends):
        if i in used:
            continue
        for j in range(i + 1, len(ends)):
            if j not in used and ends[j][0] == support:
                t, kappa, turn = curve_through(back, ends[j][1])
                if abs(turn) < BEND_DEGREES:
                    out.append((support, t, kappa if abs(turn) > STRAIGHT_DEGREES else 0.0))
                    used.add(j)
                    break
        else:
            out.append((support, _unit(back), 0.0))
    return out


def clamped_curve(edges: list) -> bool:
    """A vertex on a clamped curved edge only: it keeps w = 0, ∇w = 0 by name (is_fixed)
    and its Hessian free.  Measured on the clamped disk (λ² against exact, 8 and 16
    rings): +1.56e-3, +4.13e-4 so; the curve's own conditions (mean tangent, κ) +1.96e-3,
    +4.64e-4: the polygon's error and the Hessian left free partly cancel, and either
    converges as h² (the polygon's)."""
    return all(support == "clamped" and kappa != 0.0 for support, _, kappa in edges)


def vertex_frame(rows: list) -> tuple[np.ndarray, int]:
    """(V, r): an orthonormal basis V (columns) of a vertex's five derivative dofs whose
    first r columns span ``rows`` (held at 0) and the rest their null space."""
    if not rows:
        return np.eye(5), 0
    _, s, vt = np.linalg.svd(np.asarray(rows, dtype=float))
    return vt.T, int(np.sum(s > RANK_TOL * s[0]))


def oblique_frames(basis, groups, fixed: np.ndarray):
    """(fixed, Q): the dofs held at 0 and u = Q ũ (sparse, orthogonal) with the vertices
    of oblique supported edges in their own frames (module docstring); Q is None where
    there are none (the rectangle, any edges along x and y, Morley: fixed unchanged)."""
    if tuple(basis.elem.dofnames[:6]) != VERTEX_DOFS:
        return fixed, None
    ends, oblique = facet_ends(basis.mesh, groups)
    frames = {v: vertex_edges(ends[v]) for v in sorted(oblique)}
    frames = {v: edges for v, edges in frames.items() if not clamped_curve(edges)}
    if not frames:
        return fixed, None
    vertices = np.array(list(frames))
    mixed = basis.nodal_dofs[1:6, vertices].ravel()
    fixed = np.setdiff1d(fixed, mixed)          # by name before: now by the frames
    rows, cols, vals, held = [], [], [], []
    for v in vertices:
        V, r = vertex_frame([row for edge in frames[v] for row in edge_rows(*edge)])
        dofs = basis.nodal_dofs[1:6, v]
        held += list(dofs[:r])
        rows.append(np.repeat(dofs, 5))
        cols.append(np.tile(dofs, 5))
        vals.append(V.ravel())
    rest = np.setdiff1d(np.arange(basis.N), mixed)
    Q = sparse.csr_matrix((np.concatenate(vals + [np.ones(rest.size)]),
                           (np.concatenate(rows + [rest]), np.concatenate(cols + [rest]))),
                          shape=(basis.N, basis.N))
    return np.union1d(fixed, np.asarray(held, dtype=int)), Q
