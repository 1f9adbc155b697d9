"""Two planes: what a pipe engineer reads per support (a hole or flat obstacles at a
node): impacts, the time in contact, where on the hole the impacts land, and the work
rates that wear it, in summary.json's ``impact_statistics.supports`` (the orbit chart,
the node's w against v with the hole drawn, is ``charts.orbit_chart``).

Work rates (W, when the beam's mass per length ρS is known; else per unit mass per
length, m³/s³), over the run's time T:

- ``impact_work_rate``: −(1/T)·Σ ½λ·(y^{n+1} − y^{n−1}), the support's share of the
  scheme's contact work (the energy lost at its impacts per second; ≥ 0 for exact
  contact, whose contact work is ≤ 0);
- ``normal_work_rate``: (1/T)∫|F_n||v_t| dt, |F_n| the contact force's normal part, v_t
  the node's velocity along the wall ((y^{n+1} − y^{n−1})/(2Δt), its component along the
  tangent of the face, or of the circle at the node); the wear work rate of Archard's law
  per unit wear coefficient.  Where friction acts (μ > 0) it is the friction work over μ,
  the share of the force that slid: the same number for the β-scheme, whose friction law
  slips by y^{n+1} − y^{n−1}, except in a broached hole's lobe corner, where this tally
  takes the whole force along the nearest land edge's normal and the friction splits it
  between the corner's two faces (a trefoil with 40° and 10° lands: 0.83 % and 0.60 %
  below the friction work over μ, at most 1.4 % in a sector; the split in the compiled
  loop cost 0.3-0.6 s more of a broached tube's first run, measured, not kept); for
  Moreau–Jean, whose impacts are instantaneous, the
  central difference counted at an impact that sticks the velocity before it (a rate that
  did not fall with μ);
- ``friction_work_rate`` (with friction): −(1/T) × the support's share of the friction
  work (the energy its friction takes per second, ≥ 0).

**Wear** (:class:`Wear`, ``[wear]`` of a scene file): Archard's law, the worn volume
V = K·∫|F_n||v_t| dt, so a wear volume rate K × the normal work rate (m³/s), the volume
after the service life, and a depth from the stated assumptions: the wear spreads over
the tube's surface in contact, the land's width b (axial) times the arc the contact
covers: uniformly round the tube, d = V/(2πRb); per 30° sector k of the hole (the
direction of the wall's normal where the work is done: in a round hole the node's angle,
as Code_Aster's POST_USURE sums it per sector; on a face, or on a broached hole's land
edge while the node sits in a lobe's corner, the face's or the edge's normal: wear only
where there is metal), d_k = V_k/(R·(π/6)·b).  The tube does not turn about its axis, so
a sector of the hole wears the same sector of the tube.  Without a land the volumes and
volume rates alone (per support and per sector): they need only K and the service years.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..checks import check_positive
from ..errors import InputError
from ..scheme.kernels import SECTORS

YEAR = 365.25 * 86400.0     # s


@dataclass(frozen=True)
class Wear:
    """Archard's law at the supports: ``coefficient`` K (m³/(N·m)), ``service_years`` Y,
    ``land`` b (m, the support's axial contact width), ``radius`` R (m, the tube's outer
    radius); the module docstring says what each number assumes.  The volumes need only
    K and Y; the depths spread them over the land and the radius, so with ``land`` None
    there are no depths (and the radius may be None).  ``wall`` (m, a tube's wall, None:
    not a tube): a deepest sector deeper than it is said (`worn_through`)."""
    coefficient: float
    service_years: float
    land: float | None = None
    radius: float | None = None
    wall: float | None = None

    def __post_init__(self):
        if self.land is not None and self.radius is None:
            raise InputError("[wear] land: a depth spreads the volume over the land and the "
                             "tube's radius: give radius (m) too")
        for name in ("coefficient", "service_years", "land", "radius", "wall"):
            if getattr(self, name) is None:
                continue        # land, radius: only the depths need them
            object.__setattr__(self, name, check_positive(f"[wear] {name}",
                                                          getattr(self, name)))

    def of(self, normal_work_rate: float, sectors: np.ndarray, T: float) -> dict:
        """The support's wear from its normal work rate (W) and its normal work per
        sector over the run's time T (J): volume rates and volumes, per support and per
        sector, and the depths only with a land (a depth spreads a volume over it)."""
        life = self.service_years * YEAR
        rate = self.coefficient * normal_work_rate
        arc = 2 * math.pi / SECTORS
        rates = self.coefficient * np.asarray(sectors) / T     # m³/s per sector
        out = {"volume_rate": rate, "volume": rate * life}
        if self.land is not None:
            out["depth_uniform"] = rate * life / (2 * math.pi * self.radius * self.land)
        out["sectors"] = [self._sector(k, arc, float(r), float(r * life))
                          for k, r in enumerate(rates)]
        return out

    def _sector(self, k: int, arc: float, rate: float, volume: float) -> dict:
        """Sector k (from +v towards +w): its volume rate, volume and, with a land, depth."""
        out = {"from_rad": -math.pi + k * arc, "to_rad": -math.pi + (k + 1) * arc,
               "volume_rate": rate, "volume": volume}
        if self.land is not None:
            out["depth"] = volume / (self.radius * arc * self.land)
        return out


ANGLE_BINS = SECTORS   # the impact-angle histogram: the wear's 30° sectors, −180° to 180°


def worn_through(supports: list[dict], wear: Wear | None) -> list[str]:
    """One line per support whose deepest sector wears deeper than the tube's wall within
    the service years: Archard's law is then extrapolated past the wall (the table's
    depth is not a remaining wall)."""
    if wear is None or wear.wall is None:
        return []
    lines = []
    for s in supports:
        depth = deepest(s)
        if depth is not None and depth > wear.wall:
            years = wear.service_years * wear.wall / depth      # depth ∝ time
            lines.append(f"the support at x={s['x']:g} wears {depth * 1e3:.4g} mm deep "
                         f"in {wear.service_years:g} years, more than the tube's wall "
                         f"({wear.wall * 1e3:g} mm): it wears through in about {years:.3g} "
                         "years (the depth past the wall is Archard's law extrapolated)")
    return lines


def deepest(support: dict) -> float | None:
    """A support's deepest sector's depth (m; None without [wear] land)."""
    depths = [k["depth"] for k in (support.get("wear") or {}).get("sectors", [])
              if "depth" in k]
    return max(depths) if depths else None


def union_length(start: np.ndarray, end: np.ndarray) -> float:
    """Total length of the union of the intervals [start, end) (a contact fraction's
    time: per support here, per node and obstacle in output.events)."""
    total, reach = 0.0, -np.inf
    for a, b in sorted(zip(start.tolist(), end.tolist())):
        a = max(a, reach)
        if b > a:
            total += b - a
            reach = b
    return total


def support_statistics(table: dict, run, scale: float, duration: float, T: float,
                       wear: Wear | None = None) -> list[dict]:
    """Per node with a hole or flat obstacles: impacts, contact fraction (of ``duration``,
    as the run's own), the histogram of the impact angles (ANGLE_BINS bins over [−π, π])
    and the work rates over the run's time ``T`` (module docstring), forces times
    ``scale`` (ρS: W); with friction its work rate, with ``wear`` the support's wear."""
    x_rows = np.asarray(run.system.x_contact, dtype=float)
    record = run.record
    work = record.row_work
    T = T if T > 0 else math.nan
    edges = np.linspace(-math.pi, math.pi, ANGLE_BINS + 1)
    out = []
    for x in np.unique(x_rows):
        rows = support_rows(run, x)
        ev = np.flatnonzero(table["x"] == x)
        angles = np.asarray(table["angle"], dtype=float)[ev]
        counts, _ = np.histogram(angles[np.isfinite(angles)], edges)
        entry = {
            "x": float(x), "impacts": int(ev.size),
            "contact_fraction": union_length(table["t_start"][ev], table["t_end"][ev])
            / duration if ev.size and duration > 0 else 0.0,
            "impact_angle_histogram": {"edges_rad": edges.tolist(), "counts": counts.tolist()},
            "impact_work_rate": -scale * float(work[rows, 0].sum()) / T + 0.0,  # not -0.0
            "normal_work_rate": _normal_work_rate(run, rows, scale, T)}
        if record.friction_tallied:
            entry["friction_work_rate"] = -scale * float(work[rows, 2].sum()) / T + 0.0
        if wear is not None:
            entry["wear"] = support_wear(run, x, scale, T, wear)
        out.append(entry)
    return out


def support_rows(run, x: float) -> np.ndarray:
    """The constrained rows of the support at x (a hole's two, or its faces)."""
    return np.flatnonzero(np.asarray(run.system.x_contact, dtype=float) == x)


def _normal_work_rate(run, rows, scale: float, T: float) -> float:
    return scale * float(run.record.row_work[rows, 1].sum()) / T


def support_wear(run, x: float, scale: float, T: float, wear: Wear) -> dict:
    """The wear entry of the support at x, as summary.json has it (the same code): the
    wear chart draws it in the charts' phase, before summary.json is written."""
    T = T if T > 0 else math.nan
    rows = support_rows(run, x)
    return wear.of(_normal_work_rate(run, rows, scale, T),
                   scale * run.record.sector_work[rows].sum(axis=0), T)


def _wear_units(wear: Wear) -> str:
    """What the wear entry's numbers are; without a land it says why there is no depth."""
    volumes = ("volume_rate m³/s = K × normal_work_rate, volume m³ after service_years, "
               "sectors: per 30° of the hole (rad from +v towards +w) the volume_rate and "
               "volume")
    if wear.land is None:
        return (f"{volumes}; K = coefficient m³/(N·m), as given in [wear]; no depth: a "
                "depth needs [wear] land (the support's axial width b, m)")
    return (f"{volumes}, and depth volume/(R·(π/6)·b); depth_uniform m = volume/(2πRb) "
            "(worn evenly round the tube over the land b); K = coefficient m³/(N·m), "
            "R = radius, b = land (m), as given in [wear]")


def work_rate_units(newtons: bool, wear: Wear | None = None) -> dict:
    unit = "W" if newtons else "m³/s³ (W per kg/m)"
    out = {} if wear is None else {"wear": _wear_units(wear)}
    return {**out,
            "friction_work_rate": f"{unit}: −(1/T) × the support's friction work",
            "impact_work_rate": f"{unit}: −(1/T)Σ ½λ·(y^(n+1) − y^(n−1)) over the support's "
                                "rows, the energy its impacts take out of the beam per second",
            "normal_work_rate": f"{unit}: (1/T)∫|F_n||v_t| dt, the contact force times the "
                                "node's velocity along the wall (the wear work rate)",
            "impact_angle_histogram": "counts of impacts per angle bin, the angle of the "
                                      "node's offset from the hole's centre (rad, from +v "
                                      "towards +w)",
            "angle": "rad, where on the hole (atan2(w − cz, v − cy) at the first state in "
                     "contact)",
            "normal_velocity": "m/s, the node's velocity before the impact along the wall's "
                               "outward normal (> 0: towards the wall)",
            "tangential_velocity": "m/s, its component along the wall, counter-clockwise"}


DASH = "—"      # a number the run has not got: no friction, no [wear], no land


def _cell(value: float | None) -> str:
    return DASH if value is None else f"{value + 0.0:.4g}"    # + 0.0: no "-0" on screen


def _row(s: dict) -> list[str]:
    """One support's cells: x, impacts, contact fraction, the three work rates, the worn
    volume (mm³) and the deepest sector's depth (mm), as summary.json has them."""
    wear, depth = s.get("wear"), deepest(s)
    return [f"{s['x']:g}", str(s["impacts"]), _cell(s["contact_fraction"]),
            _cell(s["impact_work_rate"]), _cell(s["normal_work_rate"]),
            _cell(s.get("friction_work_rate")),
            _cell(wear["volume"] * 1e9 if wear else None),
            _cell(depth * 1e3 if depth is not None else None)]


def support_table(supports: list[dict], newtons: bool = True,
                  wear: Wear | None = None) -> str:
    """summary.json's ``impact_statistics.supports`` as a plain-text table for the
    terminal, one row per support (about 80 columns): the answer a pipe engineer reads
    first, without opening the file.  ``newtons``: the work rates are in W (ρS known);
    ``wear``: the run's [wear], whose service years the heading names.  "" without
    supports."""
    if not supports:
        return ""
    unit = "W" if newtons else "W/(kg/m)"
    head = ["x (m)", "impacts", "contact", f"impact {unit}", f"normal {unit}",
            f"friction {unit}", "volume mm³", "depth mm"]
    rows = [_row(s) for s in supports]
    widths = [max(len(r[i]) for r in [head] + rows) for i in range(len(head))]
    about = "contact: fraction of the time"
    if wear is not None:
        about += (f"; wear after {wear.service_years:g} years; "
                  + ("depth: deepest 30° sector" if wear.land is not None
                     else "no depth without [wear] land"))
    lines = [f"supports ({about}):"]
    lines += ["  ".join(c.rjust(w) for c, w in zip(r, widths)) for r in [head] + rows]
    return "\n".join(lines)
