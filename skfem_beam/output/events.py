"""impacts.csv and the per-node, per-obstacle contact statistics of summary.json.

One row per impact of a constrained value (``Run.impact_events``, which a checkpoint
carries, so a resumed run writes the same table as an uninterrupted one):

    t_start, t_end   s: the first state on the obstacle and the first one off it (a contact
                     still under way at the last state ends there)
    x                m: the node
    bound            1: the lower bound (g1; the bar's obstacle at x = 0),
                     2: the upper bound (g2; the bar's obstacle at x = L)
    velocity         m/s: the node's approach velocity (yⁿ − yⁿ⁻¹)/Δt before contact
    peak_force       max |force| over the contact
    impulse          Σ force·Δt over the event, signed like the timeseries column
                     ``contact_force`` (beam: λ, > 0 pushed up by g1; bar: R ≥ 0)
    max_violation    m: the largest nodal violation of the bound during the contact
    angle, normal_velocity, tangential_velocity
                     two planes only (before ``open``): where on the hole (rad) and the
                     node's velocity before the impact, normal and along the wall (m/s);
                     output.supports says how
    open             1: the event was not over at the run's last state (in contact, or
                     within the two states after t_end that a penalty spring's trailing
                     force reaches); its peak_force and impulse are those so far.  Only
                     the last rows of a run can be open: an interrupted or failed run's,
                     and a finished run's contacts under way at T.  0 otherwise.

An event owns the whole contact force of its value (a law's explicit part included) from
its first state to the second state after t_end, or to the value's next impact (see
scheme.kernels.track_impacts), so the impulses add up to Σ λΔt of the run to round-off.

Forces are in N and impulses in N·s when the mass per length (beam: ``rho_S``) or the
bar's cross-section is known, else in the system's units (beam: per unit mass per length,
m²/s² and m²/s; bar: per unit cross-section, Pa and Pa·s); summary.json says which.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .folder import atomic_write, csv_rows
from .supports import support_statistics, union_length, work_rate_units

IMPACTS = "impacts.csv"
COLUMNS = ("t_start", "t_end", "x", "bound", "velocity", "peak_force", "impulse",
           "max_violation", "open")
HOLE_COLUMNS = ("angle", "normal_velocity", "tangential_velocity")   # two planes
FRICTION_COLUMNS = ("slip", "friction_impulse")                      # ... with friction
TWO_PLANE_COLUMNS = COLUMNS[:-1] + HOLE_COLUMNS + COLUMNS[-1:]


def impact_table(events: dict, lo: np.ndarray, hi: np.ndarray, scale: float = 1.0,
                 sign: float = 1.0, planes: int = 1, friction: bool = False) \
        -> dict[str, np.ndarray]:
    """The impacts.csv columns of ``events`` (``Run.impact_events()``): forces and impulses
    times ``scale`` (ρS for a beam in N), impulses times ``sign`` (the bar's R = sign·λ);
    ``lo``, ``hi``: the bounds of the constrained values (which side each contact is on)."""
    j = np.asarray(events["value"], dtype=int)
    impulse = np.asarray(events["impulse"], dtype=float)
    lower = np.isfinite(lo[j]) & (~np.isfinite(hi[j]) | (impulse > 0)
                                  | ((impulse == 0) & (events["velocity"] < 0)))
    table = {"t_start": events["t_start"], "t_end": events["t_end"], "x": events["x"],
             "bound": np.where(lower, 1, 2), "velocity": events["velocity"],
             "peak_force": scale * np.asarray(events["peak_force"], dtype=float),
             "impulse": sign * scale * impulse, "max_violation": events["max_violation"]}
    if planes == 2:
        table.update({k: np.asarray(events[k], dtype=float) for k in HOLE_COLUMNS})
    if friction:
        table.update({"slip": np.asarray(events["slip"], dtype=float),
                      "friction_impulse": scale * np.asarray(events["friction_impulse"],
                                                             dtype=float)})
    return {**table, "open": np.asarray(events["open"], dtype=int)}


def _stats(table: dict, rows: np.ndarray, duration: float) -> dict:
    start, end = table["t_start"][rows], table["t_end"][rows]
    return {"impacts": int(rows.size),
            "contact_fraction": union_length(start, end) / duration if duration > 0 else 0.0,
            "max_impulse": float(np.abs(table["impulse"][rows]).max()),
            "max_peak_force": float(table["peak_force"][rows].max()),
            "max_violation": float(table["max_violation"][rows].max())}


def _acting(obstacles, x: float, bound: int) -> int | None:
    """The index of the part of ``obstacles`` whose g1 (bound 1) or g2 (2) is the bound at
    x (the highest g1, the lowest g2 of all parts), or None."""
    parts = getattr(obstacles, "parts", ())
    if len(parts) < 2:
        return None
    g = [p.bounds(np.array([x]))[bound - 1][0] for p in parts]
    best = max(g) if bound == 1 else min(g)
    return next((i for i, v in enumerate(g) if np.isfinite(v) and v == best), None)


def _describe(part) -> str:
    br = tuple(getattr(part, "breakpoints", ()))
    if len(br) == 1:     # point stops, or a profile with one kink (flat obstacles' x = L/2)
        near = br[0] + np.array([-1e-6, 1e-6]) * max(1.0, abs(br[0]))
        lo, hi = part.bounds(near)
        if np.isfinite(lo).any() or np.isfinite(hi).any():
            return f"profile, kink at x={br[0]:g}"
        return f"point stops at x={br[0]:g}"
    if len(br) == 2:
        return f"span [{br[0]:g}, {br[1]:g}]"
    return "profile"


def impact_statistics(table: dict, duration: float, obstacles=None) -> dict:
    """Per constrained node with contact (``nodes``) and, when ``obstacles`` has several
    parts (``Obstacles.combine``, several point stops or spans), per part (``obstacles``):
    impacts, contact_fraction (the time in contact, intervals united, over ``duration``),
    max_impulse (largest |impulse|), max_peak_force, max_violation."""
    x, bound = table["x"], table["bound"].astype(int)
    nodes = [{"x": float(xi), **_stats(table, np.flatnonzero(x == xi), duration)}
             for xi in np.unique(x)]
    out = {"nodes": nodes, "obstacles": None}
    if len(getattr(obstacles, "parts", ())) > 1:
        owner = np.array([_acting(obstacles, xi, b) for xi, b in zip(x, bound)], dtype=object)
        out["obstacles"] = [
            {"obstacle": i, "where": _describe(part),
             "x": sorted({float(v) for v in x[owner == i]}),
             **_stats(table, np.flatnonzero(owner == i), duration)}
            for i, part in enumerate(obstacles.parts) if np.any(owner == i)]
    return out


def spring_supports(table: dict, obstacles, stiffness, damping) -> list[dict]:
    """Spring supports (the penalty law): per obstacle (``obstacles.parts`` in order, a
    scene file's [[obstacles]]; one obstacle: itself) its ``stiffness`` and ``damping``
    (one number, or one per obstacle, as given: N/m, N·s/m), its impacts, its largest
    deflection (m: the largest compression of its spring at a node, impacts.csv's
    max_violation) and its largest force (impacts.csv's peak_force, in its units), 0 for
    an obstacle never touched.  An impact is the obstacle's whose g1 (bound 1) or g2 (2)
    is the node's bound (Obstacles.owners: the law's own choice of spring)."""
    parts = getattr(obstacles, "parts", ()) or (obstacles,)
    k = np.broadcast_to(np.asarray(stiffness, dtype=float), (len(parts),))
    c = np.broadcast_to(np.asarray(damping, dtype=float), (len(parts),))
    x, bound = np.asarray(table["x"], dtype=float), np.asarray(table["bound"], dtype=int)
    owner = obstacles.owners(x)[np.arange(x.size), bound - 1] if x.size else \
        np.zeros(0, int)
    return [_spring(table, np.flatnonzero(owner == i), i, _describe(part), k[i], c[i])
            for i, part in enumerate(parts)]


def hole_springs(table: dict, supports, stiffness: float, damping: float) -> list[dict]:
    """:func:`spring_supports` of a two-plane run: one stiffness and damping on every
    support, one entry per support (a hole or faces at x, ``supports`` in order)."""
    x = np.asarray(table["x"], dtype=float)
    return [_spring(table, np.flatnonzero(x == xi), i, f"support at x={xi:g}", stiffness,
                    damping) for i, xi in enumerate(supports)]


def _spring(table: dict, rows, i: int, where: str, stiffness, damping) -> dict:
    """One entry of ``spring_supports``: the impacts ``rows`` of ``table`` its spring took."""
    return {"obstacle": i, "where": where, "stiffness": float(stiffness),
            "damping": float(damping), "impacts": int(rows.size),
            "max_deflection": float(table["max_violation"][rows].max(initial=0.0)),
            "max_force": float(table["peak_force"][rows].max(initial=0.0))}


# impact_statistics' contact_fraction, as summary.json's units say it
EPISODES = ("of the run's time: each episode from its first state in contact to its first "
            "state off, one still open at the end to its last state (so one step less than "
            "the run's contact_fraction, which counts every step that ends in contact)")
# impacts.csv's velocity, as summary.json's units say it
VELOCITY = ("m/s: (yⁿ − yⁿ⁻¹)/Δt at the state before the first in contact, relative to the "
            "obstacle where a support moves it (a free flight's approach; after a one-step "
            "separation, that separation's, away from the obstacle)")
# peak_force is unsigned, unlike the impulse and the contact_force column
MAGNITUDE = " (the largest |force|: the impulse carries the sign)"
# peak_force's unit under exact contact
RIGID_PEAK = ("; rigid (exact) contact: the largest one-step force, which grows as dt "
              "shrinks: quote the impulse")


def write_impacts(folder: Path, run, units: dict, scale: float = 1.0, sign: float = 1.0,
                  obstacles=None, last: int | None = None, wear=None) -> dict:
    """Write ``folder/impacts.csv`` from ``run`` (a :class:`~skfem_beam.scheme.Run`) and
    return the summary entry ``{"impact_statistics": ...}``; ``units``: the force and
    impulse units (``{"force": "N", "impulse": "N·s"}``), see :func:`impact_table`.
    ``last``: the last state the loop computed when it is not ``run.n`` (a failed step
    stops the loop inside a chunk)."""
    return _write_impacts(folder, run, units, scale, sign, obstacles, last, wear)[0]


def _add_spring_supports(out: dict, table: dict, obstacles, springs: tuple,
                         force_unit: str, supports=()) -> None:
    """Add to ``out`` (of :func:`_write_impacts`, with its impacts ``table``) the entry
    ``spring_supports`` of the supports' springs ``springs`` = (stiffness, damping), N/m
    and N·s/m: a penalty run on ``obstacles`` (:func:`spring_supports`), or, two planes,
    on the ``supports`` at those x (:func:`hole_springs`)."""
    out["spring_supports"] = spring_supports(table, obstacles, *springs) \
        if obstacles is not None else hole_springs(table, supports, *springs)
    out["impact_statistics"]["units"]["spring_supports"] = (
        "per obstacle: stiffness N/m, damping N·s/m (as given), max_deflection m (the "
        f"largest compression of its spring), max_force {force_unit} (its largest "
        "peak_force)")


# rows of impacts.csv formatted at a time: its text for 669,000 impacts in one piece took
# about 500 MB at the end of a run (measured); a few MB a piece, the same characters
ROWS_AT_A_TIME = 50_000


def write_rows(fh, table: dict, columns: list) -> None:
    """impacts.csv's header and rows, ROWS_AT_A_TIME at a time (a table holding ±inf in
    one piece: csv_rows formats such a table otherwise, and the file is the same then)."""
    fh.write(",".join(columns) + "\n")
    n = table["x"].size
    step = ROWS_AT_A_TIME if all(np.isfinite(np.asarray(table[k], dtype=float)).all()
                                 for k in columns) else max(n, 1)
    for a in range(0, n, step):
        fh.write(csv_rows({k: np.asarray(table[k])[a:a + step] for k in columns}, columns,
                          ("bound", "open")))


def _write_impacts(folder, run, units, scale, sign, obstacles, last, wear) -> tuple:
    """(:func:`write_impacts`' summary entry, the impacts table it wrote)."""
    s = run.system
    last = run.n if last is None else int(last)
    events = run.impact_events(last)
    # an unstable run ends at its last good saved state: impacts after it are not kept
    keep = np.asarray(events["t_start"]) <= (last + 0.5) * run.dt
    events = {k: np.asarray(v)[keep] for k, v in events.items()}
    planes = getattr(s, "planes", 1)
    friction = "friction" in run.work_terms
    table = impact_table(events, np.asarray(s.lo), np.asarray(s.hi), scale, sign, planes,
                         friction)
    columns = list(COLUMNS if planes == 1 else TWO_PLANE_COLUMNS)
    if friction:
        columns[-1:-1] = FRICTION_COLUMNS
    atomic_write(Path(folder) / IMPACTS, lambda fh: write_rows(fh, table, columns))
    # the share of the states 1..n, as the run's own contact_fraction counts it
    duration = max(0, last - 1) * run.dt
    stats = impact_statistics(table, duration, obstacles)
    f, i = units["force"] + MAGNITUDE, units["impulse"]
    if not run.springs:     # exact contact: the force of one step, impulse/Δt
        f += RIGID_PEAK + ", or give the supports a stiffness"
    stats["units"] = {"t_start": "s", "t_end": "s", "x": "m", "bound": "1 = g1 (lower), "
                      "2 = g2 (upper); a round or broached hole's contacts: 1 (its wall; "
                      "where on it: angle)", "velocity": VELOCITY, "peak_force": f,
                      "impulse": i,
                      "max_violation": "m", "open": "1 = not over at the last state",
                      "contact_fraction": EPISODES}
    if planes == 2:
        from ..scheme.beta import disk_rows
        stats["supports"] = support_statistics(table, run, scale, duration, last * run.dt,
                                               wear)
        stats["units"].update(work_rate_units(units["force"] == "N", wear))
        if disk_rows(s).size:       # a round hole's event is its pair's (Run.impact_events)
            stats["units"]["impulse"] += "; a round hole's: Σ|force|Δt"
            stats["units"]["velocity"] += ("; a round or broached hole's: its node's v only "
                                           "(the approach is normal_velocity)")
    if friction:
        stats["units"].update({"slip": "m, Σ|u_t|Δt over the contact",
                               "friction_impulse": i + ", Σ|p_t| over the contact"})
        from ..scheme.moreau_jean import NSGS_TOL
        coefficients = sorted({float(m) for m in run.system.friction if m > 0})
        residual = run.record.friction_residual
        if residual is None:               # position level: each block exact, no NSGS
            return {"impact_statistics": stats, "friction": {"coefficients": coefficients,
                                                             "law": run.solver}}, table
        return {"impact_statistics": stats, "friction": {
            "coefficients": coefficients,
            "nsgs_tolerance": NSGS_TOL, "nsgs_max_residual": residual}}, table
    return {"impact_statistics": stats}, table


def beam_impacts(folder: Path, run, problem, last: int | None = None, wear=None,
                 springs: tuple | None = None) -> dict:
    """:func:`write_impacts` for a beam scene, in N and N·s when ρS is known (``wear``:
    output.supports.Wear, two planes; ``springs``: the supports' (stiffness, damping),
    N/m and N·s/m, of a penalty run)."""
    rho_S = problem.beam.rho_S
    units = {"force": "N", "impulse": "N·s"} if rho_S else \
        {"force": "m²/s² (N per kg/m)", "impulse": "m²/s (N·s per kg/m)"}
    out, table = _write_impacts(folder, run, units, rho_S or 1.0, 1.0, problem.obstacles,
                                last, wear)
    if springs is not None and getattr(run.system, "planes", 1) == 2:   # (no friction)
        supports = np.unique(np.asarray(run.system.x_contact, dtype=float))
        _add_spring_supports(out, table, None, springs, units["force"], supports)
    elif springs is not None and problem.obstacles is not None:
        _add_spring_supports(out, table, problem.obstacles, springs, units["force"])
    return out


def bar_impacts(folder: Path, run, bar, last: int | None = None) -> dict:
    """:func:`write_impacts` for the bar: R ≥ 0 (impulse = ∫R dt; R(tₙ) is the force of
    state n + 1, bar.BarSeries), in N and N·s with a cross-section A, else per unit
    cross-section."""
    units = {"force": "Pa (per unit cross-section)", "impulse": "Pa·s"} if bar.A is None \
        else {"force": "N", "impulse": "N·s"}
    return write_impacts(folder, run, units, 1.0, bar.gap_sign, None, last)
