"""What drives a beam: the support's [motion] and the [[loads]], each with its time
function (a sine, a constant, a sum of sines, a table, band-limited noise or a PSD)."""
from __future__ import annotations

import math

import numpy as np

from ..checks import check_choice, check_finite
from ..errors import InputError
from ..problem import LIFTINGS, Load, Support
from ..timefunctions import Constant, Sine, SumOfSines, Table, band_limited, psd_from_csv
from .parts import need, plane_count
from .read import Tables


def _time_function(d: dict, where: str, reader: Tables):
    """A time function from the keys of TIME (one form), or None when none is given; its
    object's refusals name the table (``[loads.1] f_high=10 must exceed f_low=100``)."""
    try:
        return _time_form(d, where, reader)
    except InputError as e:
        raise e if str(e).startswith("[") else InputError(f"[{where}] {e}") from None


def _time_form(d: dict, where: str, reader: Tables):
    forms = [k for k in ("amplitude", "value", "sines", "table", "random", "psd") if k in d]
    if "omega" in d and "amplitude" not in d:
        forms.append("omega")
    if len(forms) > 1:
        raise InputError(f"[{where}] give one of amplitude/omega, value, sines, table, "
                         f"random, psd (got {', '.join(forms)})")
    if "phase" in d and (not forms or forms[0] != "amplitude"):   # it was ignored
        other = f"not to {forms[0]}" if forms else "give amplitude and omega with it"
        raise InputError(f"[{where}] phase belongs to amplitude · sin(omega t + phase): "
                         f"{other}")
    if not forms:
        return None
    form = forms[0]
    if form in ("amplitude", "omega"):
        if "amplitude" not in d or "omega" not in d:    # either alone was a zero, silently
            raise InputError(f"[{where}] amplitude and omega go together (amplitude · "
                             "sin(omega t + phase)); a constant is value = ...")
        return Sine(d["amplitude"], d["omega"], d.get("phase", 0.0))
    if form == "value":
        return Constant(d["value"])
    if form == "sines":
        rows = d["sines"]
        if not isinstance(rows, list) or not all(isinstance(r, list) and len(r) in (2, 3)
                                                 for r in rows):
            raise InputError(f"[{where}] sines must be [[amplitude, omega, phase], ...]")
        return SumOfSines(tuple(r[0] for r in rows), tuple(r[1] for r in rows),
                          tuple(r[2] if len(r) == 3 else 0.0 for r in rows))
    if form == "table":
        table = Table.from_csv(reader.path(d["table"]))
        reader.time_tables.append((where, d["table"], table))
        return table
    if form == "psd":   # a one-sided PSD table f (Hz), S (unit²/Hz), synthesised with a seed
        psd = d["psd"] if isinstance(d["psd"], dict) else {"table": d["psd"]}
        if "table" not in psd:
            raise InputError(f"[{where}] psd = {{ table = \"file.csv\", seed, df }} needs table")
        return psd_from_csv(reader.path(psd["table"]), psd.get("seed", 0), psd.get("df"))
    random = d["random"]
    if not isinstance(random, dict):
        raise InputError(f"[{where}] random = {{ rms, f_low, f_high, seed, count }} (got "
                         f"{random!r})")
    return band_limited(**need(random, ("rms", "f_low", "f_high"), f"{where}.random"), **{
        k: random[k] for k in ("seed", "count") if k in random})


def highest_frequency(d: dict) -> float:
    """The highest frequency (Hz) a [motion] or [[loads]] table's time function holds: its
    omega, its sines' omegas, its random band's f_high (0: none, or a table or PSD file,
    not read here)."""
    omegas = [d.get("omega", 0.0)] + [r[1] for r in d.get("sines", []) if len(r) > 1]
    band = d.get("random", {}).get("f_high", 0.0) if isinstance(d.get("random"), dict) \
        else 0.0
    return max([abs(w) / (2 * math.pi) for w in omegas] + [band])


def warn_aliased(data: dict, dt: float) -> None:
    """One warning line for each driver whose highest frequency lies above the steps'
    Nyquist frequency 1/(2 dt): the scheme samples it at the steps, so it acts as another,
    lower frequency (a band at 6–9 kHz with dt = 1e-4 s moved the tube 14 times more than
    with dt = 1e-5 s, without a word)."""
    from ..cli import warn
    drivers = [("[motion]", data.get("motion"))] + \
        [(f"loads.{i}", d) for i, d in enumerate(data.get("loads", []))]
    for where, d in drivers:
        f = highest_frequency(d) if isinstance(d, dict) else 0.0
        if f > 0.5 / dt:
            warn(f"{where}: its highest frequency, {f:g} Hz, lies above the steps' Nyquist "
                 f"frequency 1/(2 dt) = {0.5 / dt:g} Hz: the steps alias it to a lower one; "
                 f"dt ≤ {0.5 / f:.3g} s resolves it (about 10 steps a period: "
                 f"{0.1 / f:.3g} s)")


def warn_tables(tables: Tables, T: float) -> None:
    """One warning line for each time table that ends before T (past its last row it is
    held at its last value: the motion stops there, a load stays constant), and for each
    whose spline leaves its rows (a ramp then a hold: the spline overshoots where a
    measured history would not)."""
    from ..cli import warn
    for where, name, table in tables.time_tables:
        if table.t[-1] < T:
            warn(f"[{where}] table = {name!r} ends at t={table.t[-1]:g} s, before T={T:g} s: "
                 "from there on it is held at its last value")
        over = overshoot(table)
        if over is not None:
            t0, t1, value = over
            warn(f"[{where}] table = {name!r}: the cubic spline through its rows reaches "
                 f"{value:.3g} between t={t0:g} and {t1:g} s, outside the rows' values "
                 "there: give rows closer together where it bends (a spline gives the "
                 "acceleration a support's motion needs)")


def overshoot(table: Table, share: float = 0.05):
    """(t_i, t_i+1, the spline's farthest value) of the first interval where the spline
    leaves [min, max] of its two rows by more than ``share`` of the table's range, or
    None."""
    t, phi = np.array(table.t), np.array(table.phi)
    span = float(phi.max() - phi.min())
    s = np.linspace(0.0, 1.0, 17)[1:-1]
    tt = t[:-1, None] + s * np.diff(t)[:, None]
    v = table(tt.ravel()).reshape(tt.shape)
    lo, hi = np.minimum(phi[:-1], phi[1:])[:, None], np.maximum(phi[:-1], phi[1:])[:, None]
    out = np.maximum(lo - v, v - hi)
    bad = np.flatnonzero(out.max(axis=1) > share * span) if span > 0 else []
    if not len(bad):
        return None
    i = int(bad[0])
    return float(t[i]), float(t[i + 1]), float(v[i, np.argmax(out[i])])


def support_of(data: dict, L: float, reader: Tables) -> Support:
    m = data.get("motion")
    if m is None:
        return Support()
    if "end" in m and "at" in m:
        raise InputError("[motion] give end (left | right) or at (x of a support), not both")
    at = m.get("at", 0.0)
    if "end" in m:
        ends = {"left": 0.0, "right": L}
        if m["end"] not in ends:
            raise InputError(f"[motion] end={m['end']!r} must be one of: left, right")
        at = ends[m["end"]]
    lifting = check_choice("[motion] lifting", m.get("lifting", "auto"), LIFTINGS)
    direction = _direction(m, data, "motion")
    time = {k: v for k, v in m.items() if k != "direction"}
    # either alone: _time_function refuses it (it was a support at rest)
    if {"amplitude", "omega"} <= set(time) and not set(time) & {"phase", "value", "sines",
                                                                 "table", "random", "psd"}:
        return Support(m["amplitude"], m["omega"], at=at, lifting=lifting,
                       direction=direction)
    return Support(motion=_time_function(time, "motion", reader), at=at, lifting=lifting,
                   direction=direction)


def _direction(d: dict, data: dict, where: str) -> tuple[float, float]:
    """A table's direction = [dy, dz] (two planes only; default the first plane)."""
    from ..problem import check_direction
    if "direction" not in d:
        return (1.0, 0.0)
    if plane_count(data) != 2:
        raise InputError(f"[{where}] direction acts in the cross-section: it needs planes = 2")
    return check_direction(f"[{where}] direction", d["direction"])


def loads_of(data: dict, reader: Tables, L: float = math.inf) -> tuple[Load, Load]:
    """The loads of the first and the second plane: a load along ``direction`` = [dy, dz]
    acts dy× in v and dz× in w (gravity pulls along it; without one, down in v);
    ``rotating`` = {amplitude, omega, phase} is
    amplitude·cos(ωt + phase) in v and amplitude·sin(ωt + phase) in w (two planes)."""
    total_v, total_w = Load(), Load()
    for i, d in enumerate(data.get("loads", [])):
        where = f"loads.{i}"
        dy, dz = _direction(d, data, where)
        if "gravity" in d and "direction" in d:     # where it pulls: it pulled the other way
            dy, dz = -dy, -dz                       # (Load.gravity: −gρA on u)
        d = {k: v for k, v in d.items() if k != "direction"}
        if "rotating" in d:
            if plane_count(data) != 2:
                raise InputError(f"[{where}] rotating acts in the cross-section: it needs "
                                 "planes = 2")
            if "gravity" in d or (dy, dz) != (1.0, 0.0) or \
                    set(d) & {"amplitude", "omega", "phase", "value", "sines", "table",
                              "random", "psd"}:
                raise InputError(f"[{where}] rotating is the load's time function and "
                                 "direction: give it alone with x, distributed or per_mass")
            rot = need(d["rotating"], ("amplitude", "omega"), f"{where}.rotating")
            phase = d["rotating"].get("phase", 0.0)
            rest = {k: v for k, v in d.items() if k != "rotating"}
            total_v = total_v + _load(rest, where, Sine(rot["amplitude"], rot["omega"],
                                                        phase + math.pi / 2), L)
            total_w = total_w + _load(rest, where, Sine(rot["amplitude"], rot["omega"], phase),
                                      L)
            continue
        if "gravity" in d:
            if len(d) > 1:
                raise InputError(f"[{where}] gravity = g stands alone, with a direction in "
                                 f"two planes (got {', '.join(d)})")
            part = Load.gravity(d["gravity"])
        else:
            time = _time_function(d, where, reader)
            if time is None:
                raise InputError(f"[{where}] needs a time function: amplitude/omega, value, "
                                 "sines, table, random or (two planes) rotating")
            part = _load(d, where, time, L)
        total_v, total_w = total_v + part.scaled(dy), total_w + part.scaled(dz)
    return total_v, total_w


def _load(d: dict, where: str, time, L: float = math.inf) -> Load:
    """One [[loads]] item's load with the time function ``time`` (``L``: the beam's
    length, which a span must lie in)."""
    kinds = [k for k in ("x", "distributed", "per_mass") if d.get(k, False) is not False]
    span = [k for k in ("x_from", "x_to") if k in d]
    if span and kinds != ["distributed"]:
        raise InputError(f"[{where}] x_from, x_to bound a distributed load (distributed = "
                         "true)")
    if len(kinds) != 1:
        raise InputError(f"[{where}] needs one of x (a point force, N), distributed = "
                         "true (N/m) or per_mass = true (m/s²)")
    if kinds[0] == "x":
        x = check_finite(f"[{where}] x", d["x"])
        if not -1e-12 * L <= x <= L * (1 + 1e-12):
            raise InputError(f"[{where}] x={x:g} must lie on the beam [0, L={L:g}]")
        return Load(points=((x, time),))
    if kinds[0] == "distributed" and span:
        a, b = need(d, ("x_from", "x_to"), where).values()
        if not a < b:
            raise InputError(f"[{where}] x_from={a:g} must be below x_to={b:g}")
        if a < -1e-12 * L or b > L * (1 + 1e-12):     # off the beam it loaded nothing
            raise InputError(f"[{where}] x_from, x_to = [{a:g}, {b:g}] must lie on the beam "
                             f"[0, L={L:g}]")
        return Load.distributed(_span(a, b), time)
    if kinds[0] == "distributed":
        return Load.distributed(1.0, time)
    return Load.uniform(time)


def _span(a: float, b: float):
    """1 N/m on [a, b], 0 elsewhere (exact when a and b are mesh nodes; else the load
    quadrature cuts the element there)."""
    return lambda x: ((np.asarray(x) >= a) & (np.asarray(x) <= b)).astype(float)
