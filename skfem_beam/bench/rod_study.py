"""The periodic rod against its exact solution: the accuracy study of issue 40 (the
default), every class and option, and convergence at a fixed Courant number.

    python -m skfem_beam.bench.rod_study --convergence [--N 20,40,80,160] [--courant 0.4,0.04]
        [--T 12] [--mass consistent,lumped,average] [--beta 0.25,0.5]

For each (mass, β, Courant number Δt/h, N): the L²(0, T) error of u(0, ·), the
L²(0, T; L²(0, L)) and max-in-time L²(0, L) errors of u (Gauss points inside every
element), the largest nodal penetration max(−u(0, tₙ)), the relative energy drift
(E(T) − E(0))/E(0) of the scheme's ½E_β, and the rates log₂(e_h/e_{h/2}).  The scene is
:func:`skfem_beam.scenes.periodic_rod` (L = c = 1, u0 = ½ − x/2, exact energy 1/8).

    python -m skfem_beam.bench.rod_study --classes [--N 80] [--out docs]

Every class and option at one N (default 80), Δt/h = 0.04 and 0.4, T = 12, one row of
:data:`SETTINGS` each (a new option is one more row): the errors, penetration, drift and
time loop of :func:`skfem_beam.bench.work_precision.rung` (and max|Δ²u(0)|, the
contact node's step-to-step oscillation), printed as a table and written
to ``rod_study.csv`` in --out, then the best setting at each Courant number against the
issue's targets (:func:`verdict`).  About 20 s once the kernels are compiled.

    python -m skfem_beam.bench.rod_study [--accuracy] [--N 80] [--out docs]

The accuracy study of issue 40: every named setting of :data:`ACCURACY` (scene-file keys,
usable as ``--set`` on the bar scene) at Δt/h = 0.4 and 0.04, with ONE error measure,
:func:`relative_error` of u(0, ·) over every step, the energy drift, the energy change
through each impact and the penetration; the best zero-penetration setting at each
Courant number, GetFEM's figures beside them, written to ``rod_study.json`` in --out.
"""
from __future__ import annotations

import csv
import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from .. import scenes
from ..bar import bar_system, l2_time, run_bar
from ..methods import MOREAU_JEAN
from ..parser import Parser, counts, made_folder, positives
from ..reference import exact_of
from .work_precision import COURANTS, run_method, rung

KEYS = ("l2_u0", "l2_u", "linf_l2_u")


def space_errors(run, exact, points: int = 5, chunk: int = 2000) -> np.ndarray:
    """‖u_h(tₙ) − u(tₙ)‖_{L²(0, L)} at every kept state (Gauss–Legendre in each element)."""
    result = run.result
    space = result.system.space
    xi, w = np.polynomial.legendre.leggauss(points)
    smp = space.sampler(0.5 * (xi + 1.0))
    weights = np.tile(0.5 * w, space.J) * np.repeat(space.h, points)
    t = result.frames_t
    keep = t <= run.t[-1] + 1e-9 * result.dt
    out = []
    for k in range(0, int(keep.sum()), chunk):
        U = result.frames_u[k:k + chunk]
        tk = t[k:k + chunk]
        e = (smp.E0 @ U.T).T - exact.u(smp.x[None, :], tk[:, None])
        out.append(np.sqrt((e * e) @ weights))
    return np.concatenate(out) if out else np.zeros(0)


def rod_row(N: int, courant: float, T: float = 12.0, beta: float = 0.25,
            mass: str = "average") -> dict:
    """One run of the periodic rod with Δt = courant·h/c, against :class:`RodExact`."""
    bar = scenes.periodic_rod(N, mass=mass)
    dt = courant * bar.h / bar.c
    run = run_bar(bar, dt, T, beta=beta, all_states_limit=10**8)
    exact = exact_of(bar, T)
    eu = space_errors(run, exact)
    E = run.energy
    return {"N": N, "courant": courant, "dt": dt, "beta": beta, "mass": mass,
            "l2_u0": l2_time(run.u0 - exact.u(0.0, run.t), dt), "l2_u": l2_time(eu, dt),
            "linf_l2_u": float(eu.max()), "penetration": run.penetration,
            "energy_drift": float((E[-1] - E[0]) / E[0]),
            "energy_max_change": float(np.abs(E - E[0]).max() / E[0]),
            "wall_time_s": run.wall_time_s}


def study(Ns=(20, 40, 80, 160), courant: float = 0.4, T: float = 12.0, beta: float = 0.25,
          mass: str = "average") -> list[dict]:
    """One row per N at a fixed Courant number; rates against the previous row."""
    rows = []
    for N in Ns:
        row = rod_row(N, courant, T, beta, mass)
        if rows:
            for key in KEYS:
                row[f"rate_{key}"] = math.log2(rows[-1][key] / row[key])
        rows.append(row)
    return rows


def table(rows: list[dict]) -> str:
    lines = [f"{'mass':>10} {'β':>5} {'Δt/h':>5} {'N':>4} {'L2 u(0)':>9} {'rate':>5} "
             f"{'L2L2 u':>9} {'rate':>5} {'maxL2 u':>9} {'rate':>5} {'penetr.':>8} "
             f"{'ΔE/E(T)':>9}"]
    for r in rows:
        rate = lambda k: f"{r[f'rate_{k}']:5.2f}" if f"rate_{k}" in r else "    -"  # noqa: E731
        lines.append(f"{r['mass']:>10} {r['beta']:5.2f} {r['courant']:5.2f} {r['N']:4d} "
                     f"{r['l2_u0']:9.2e} {rate('l2_u0')} {r['l2_u']:9.2e} {rate('l2_u')} "
                     f"{r['linf_l2_u']:9.2e} {rate('linf_l2_u')} {r['penetration']:8.1e} "
                     f"{r['energy_drift']:9.2e}")
    return "\n".join(lines)


# (label, class, mass, how to run), as work_precision.METHODS: every class and option
SETTINGS = [
    *[(f"position, {mass}, β={b}, e={e:g}", "position", mass, dict(beta=beta, restitution=e))
      for mass in ("average", "consistent", "lumped")
      for b, beta in (("1/4", 0.25), ("1/2", 0.5)) for e in (0.0, 0.5, 1.0)],
    *[(f"Moreau–Jean, average, θ={th}, e={e:g}", MOREAU_JEAN, "average",
       dict(theta=theta, restitution=e))
      for th, theta in (("1/2", 0.5), ("1", 1.0)) for e in (0.0, 1.0)],
    ("penalty k=1e3, average, β=1/4", "penalty", "average", dict(beta=0.25, stiffness=1e3)),
    ("penalty k=1e5, average, β=1/4", "penalty", "average", dict(beta=0.25, stiffness=1e5)),
    # massless rows "beta" (β-weighted K row) or "quasi-static" (equilibrium at t_{n+1})
    *[(f"modified mass, β={b}" + (", quasi-static" if rows == "quasi-static" else ""),
       "modified mass", "redistributed", dict(beta=beta, massless=rows))
      for b, beta, rows in (("1/2", 0.5, "beta"), ("1/4", 0.25, "beta"),
                            ("1/4", 0.25, "quasi-static"), ("1/2", 0.5, "quasi-static"),
                            ("1/100", 0.01, "quasi-static"))],
]
# the targets: no penetration (round-off), |drift| ≤ 0.5 % over T = 12
PENETRATION_TOL, DRIFT_TOL = 1e-12, 0.005
COLUMNS = (("penetr.", "penetration", "8.1e"), ("drift %", "energy_drift", "+8.3f"),
           ("L∞L² u", "linf_l2_u", "9.2e"), ("L²H¹ u", "l2_h1_u", "9.2e"),
           ("L²L² u_t", "l2_l2_ut", "9.2e"), ("L² σ(0)", "l2_stress", "9.2e"),
           ("L² u(0)", "error", "9.2e"), ("max|Δ²u0|", "max_d2_u0", "9.2e"),
           ("loop s", "wall_time_s", "7.4f"))


def class_rows(N: int = 80, settings=SETTINGS, courants=COURANTS):
    """One row of :func:`work_precision.rung` per setting and Courant number."""
    for setting in settings:
        for courant in courants:
            yield rung("rod", setting, N, courant)


def class_line(r: dict) -> str:
    cells = [f"{100 * r[key] if key == 'energy_drift' else r[key]:{fmt}}"
             for _, key, fmt in COLUMNS]
    status = "" if r["status"] == "success" else f"  {r['status']}: no error measured"
    return f"{r['method']:34s} {r['courant']:5g} " + " ".join(cells) + status


def class_header() -> str:
    return f"{'setting':34s} {'Δt/h':>5} " + " ".join(
        f"{name:>{int(fmt.split('.')[0].lstrip('+'))}}" for name, _, fmt in COLUMNS)


def meets(r: dict) -> bool:
    """Both targets: no penetration and |drift| ≤ 0.5 %."""
    return r["penetration"] <= PENETRATION_TOL and abs(r["energy_drift"]) <= DRIFT_TOL


def verdict(rows: list[dict], courant: float) -> dict:
    """At one Courant number, the row with the smallest u(0) error: of all rows ("any"),
    of those that do not penetrate ("exact"), of those that meet both targets
    ("targets"; None when no row does)."""
    sel = [r for r in rows if r["courant"] == courant and r["status"] == "success"]
    best = lambda rs: min(rs, key=lambda r: r["error"]) if rs else None  # noqa: E731
    return {"courant": courant, "any": best(sel),
            "exact": best([r for r in sel if r["penetration"] <= PENETRATION_TOL]),
            "targets": best([r for r in sel if meets(r)])}


def verdict_text(v: dict) -> str:
    lines = [f"Δt/h = {v['courant']:g}:"]
    for key, what in (("any", "smallest u(0) error"),
                      ("exact", "smallest u(0) error without penetration"),
                      ("targets", "smallest u(0) error, no penetration, |drift| ≤ 0.5 %")):
        r = v[key]
        lines.append(f"  {what}: " + ("none" if r is None else
                                     f"{r['method']} ({r['error']:.3g}, drift "
                                     f"{100 * r['energy_drift']:+.2f} %, penetration "
                                     f"{r['penetration']:.1e})"))
    return "\n".join(lines)


def classes(N: int, out: Path) -> list[dict]:
    """The study of every class: print it, write ``out``/rod_study.csv, say the verdict."""
    print(class_header(), flush=True)
    rows = []
    for row in class_rows(N):
        rows.append(row)
        print(class_line(row), flush=True)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "rod_study.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    for courant in COURANTS:
        print(verdict_text(verdict(rows, courant)))
    print(f"written {out}/rod_study.csv")
    return rows


# --- the accuracy study (issue 40): one error measure, named settings --------------------

# GetFEM's dynamic-contact demo on the same rod (issue 40): its best error at each
# Courant number (Signorini–Newmark, β = 1/2) and its energy over T = 12
GETFEM = {"error": {"0.04": 0.0319, "0.4": 0.0124}, "energy_drift": 0.0002,
          "scheme": "Signorini–Newmark, β = 1/2"}

# named settings: the bar scene file's keys (``--set KEY=VALUE``), nothing else
ACCURACY = {
    "explicit lumped": {"mesh.mass": "lumped", "time.beta": 0.0},
    "average, β=0": {"mesh.mass": "average", "time.beta": 0.0},
    "average, β=1/4": {"mesh.mass": "average", "time.beta": 0.25},
    "consistent, β=1/2": {"mesh.mass": "consistent", "time.beta": 0.5},
    "modified mass, β=1/2": {"mesh.mass": "redistributed", "time.beta": 0.5},
    "modified mass, quasi-static, β=1/4": {"mesh.mass": "redistributed", "time.beta": 0.25,
                                           "mesh.massless": "quasi-static"},
    "modified mass, quasi-static, β=1/2": {"mesh.mass": "redistributed", "time.beta": 0.5,
                                           "mesh.massless": "quasi-static"},
    # β → 0: central differences on the dofs with mass, the contact node quasi-static
    # (the semi-explicit modified-mass scheme); β = 1/100 is that limit to 3 digits
    "modified mass, quasi-static, β=1/100": {"mesh.mass": "redistributed", "time.beta": 0.01,
                                             "mesh.massless": "quasi-static"},
    # P2 elements (twice P1's unknowns, the same Δt): β = 0.09, near Fox–Goodwin's
    # fourth-order 1/12, where the time stepping's dispersion cancels most of the
    # space's at Δt/h = 0.4 (measured: 0.0065 at β = 0.088, 0.0064 at 0.092)
    "P2, average, β=0.09": {"mesh.element": "p2", "mesh.mass": "average", "time.beta": 0.09},
    "P2, modified mass, quasi-static, β=1/10": {"mesh.element": "p2",
                                               "mesh.mass": "redistributed",
                                               "time.beta": 0.1,
                                               "mesh.massless": "quasi-static"},
    "average, β=1/4, e=1": {"mesh.mass": "average", "time.beta": 0.25,
                            "contact.restitution": 1.0},
    "Moreau–Jean, average, θ=1/2, e=1": {"mesh.mass": "average", "contact.law": MOREAU_JEAN,
                                         "contact.theta": 0.5, "contact.restitution": 1.0},
}
# the winners (measured, docs/rod_study.json): the smallest error without penetration at
# each Courant number, and the one setting whose energy stays within 0.5 % at both
ENERGY = "modified mass, quasi-static, β=1/100"
BEST = {0.4: "P2, average, β=0.09", 0.04: "P2, modified mass, quasi-static, β=1/10"}
ACCURACY_COURANTS = (0.4, 0.04)


def relative_error(u_h: np.ndarray, u: np.ndarray) -> float:
    """The study's one error measure, over every saved step tₙ (n = 0 … to T):

        e = √( Σₙ (u_h(0, tₙ) − u(0, tₙ))² / Σₙ u(0, tₙ)² ),

    ``u_h`` the computed and ``u`` the exact values of u(0, tₙ)."""
    u_h, u = np.asarray(u_h, dtype=float), np.asarray(u, dtype=float)
    return float(np.sqrt(np.sum((u_h - u) ** 2) / np.sum(u * u)))


def run_keywords(keys: dict) -> dict:
    """The keywords of :func:`work_precision.run_method` for a setting's scene-file keys."""
    kw = {"beta": keys.get("time.beta", 0.25),
          "restitution": keys.get("contact.restitution", 0.0),
          "massless": keys.get("mesh.massless", "beta")}
    if keys.get("contact.law") == MOREAU_JEAN:
        kw["theta"] = keys.get("contact.theta", 0.5)
    return kw


def impact_changes(t: np.ndarray, E: np.ndarray, period: float, E_exact: float) -> list:
    """(E after − E before)/E_exact through each contact (one per period: before at
    period/6, after at 5·period/6, a sixth of a period from the contact's ends)."""
    starts = np.arange(0.0, t[-1] - 5 * period / 6 + 1e-12, period)
    return [float((np.interp(s + 5 * period / 6, t, E) - np.interp(s + period / 6, t, E))
                  / E_exact) for s in starts]


def accuracy_row(name: str, courant: float, N: int = 80, T: float = 12.0) -> dict:
    """One named setting on the periodic rod (exact energy E = 1/8): the relative error of
    u(0, ·), the drift E(T)/E(0) − 1 of the scheme's energy (½E_β from its first two
    states; ½|v|²_M + ½|u|²_K for Moreau–Jean), the drift against the exact energy, the
    mean change through an impact, the largest penetration."""
    keys = ACCURACY[name]
    bar = replace(scenes.periodic_rod(N, mass=keys["mesh.mass"]),
                  element=keys.get("mesh.element", "p1"))
    dt = courant * bar.h / bar.c
    r = run_method(bar_system(bar), dt, T, run_keywords(keys), frames=10)
    exact = exact_of(scenes.periodic_rod(N), T)
    E, E_exact = r.energy, 0.125
    changes = impact_changes(r.t, E, exact.period, E_exact)
    return {"name": name, "dt_over_h": courant, "N": N, "set": dict(keys),
            "error": relative_error(r.observed["u0"], exact.u(0.0, r.t)),
            "drift": float(E[-1] / E[0] - 1.0), "drift_exact": float(E[-1] / E_exact - 1.0),
            "impact_change": float(np.mean(changes)) if changes else float("nan"),
            "penetration": r.max_penetration,
            "status": r.status}


def best_rows(rows: list[dict]) -> list[dict]:
    """At each Courant number, the row with the smallest error that does not penetrate."""
    out = []
    for courant in ACCURACY_COURANTS:
        sel = [r for r in rows if r["dt_over_h"] == courant and r["status"] == "success"
               and r["penetration"] <= PENETRATION_TOL]
        if sel:
            out.append(min(sel, key=lambda r: r["error"]))
    return out


def energy_settings(rows: list[dict]) -> list[str]:
    """The settings that do not penetrate and keep |drift| ≤ 0.5 % at every Courant number."""
    names = []
    for name in ACCURACY:
        mine = [r for r in rows if r["name"] == name]
        if mine and all(r["penetration"] <= PENETRATION_TOL
                        and abs(r["drift"]) <= DRIFT_TOL for r in mine):
            names.append(name)
    return names


def accuracy_line(r: dict) -> str:
    return (f"{r['name']:40s} {r['dt_over_h']:5g} {r['error']:8.4f} {100 * r['drift']:+8.3f} "
            f"{100 * r['drift_exact']:+8.3f} {100 * r['impact_change']:+9.4f} "
            f"{r['penetration']:9.1e}")


def accuracy(N: int, out: Path) -> dict:
    """Run every setting of :data:`ACCURACY`, print the table, write rod_study.json."""
    print(f"{'setting':40s} {'Δt/h':>5} {'error':>8} {'drift %':>8} {'vs 1/8 %':>8} "
          f"{'impact %':>9} {'penetr.':>9}", flush=True)
    rows = []
    for name in ACCURACY:
        for courant in ACCURACY_COURANTS:
            rows.append(accuracy_row(name, courant, N))
            print(accuracy_line(rows[-1]), flush=True)
    study = {"N": N, "T": 12.0, "best": best_rows(rows), "energy": energy_settings(rows),
             "getfem": GETFEM, "rows": rows}
    out.mkdir(parents=True, exist_ok=True)
    (out / "rod_study.json").write_text(json.dumps(study, indent=1, ensure_ascii=False) + "\n",
                                        encoding="utf-8")
    for r in study["best"]:
        print(f"best at Δt/h = {r['dt_over_h']:g}: {r['name']} ({r['error']:.4f})")
    print(f"energy within 0.5 % at both: {', '.join(study['energy']) or 'none'}")
    print(f"written {out}/rod_study.json")
    return study


def main(argv=None) -> None:
    p = Parser(prog="skfem_beam.bench.rod_study", description=__doc__)
    p.add_argument("--classes", action="store_true",
                   help="every class and option at one N (the first of --N; default 80)")
    p.add_argument("--accuracy", action="store_true",
                   help="the named settings at Δt/h = 0.4, 0.04 (N default 80): rod_study.json "
                        "(the default)")
    p.add_argument("--convergence", action="store_true",
                   help="the convergence table over --N, --courant, --mass, --beta (printed)")
    p.add_argument("--out", type=made_folder, default="docs",
                   help="folder for rod_study.csv (--classes) or rod_study.json (--accuracy)")
    p.add_argument("--N", type=counts, default=None,
                   help="default 20,40,80,160 (80 with --classes)")
    p.add_argument("--courant", type=positives, default="0.4,0.04")
    p.add_argument("--T", type=float, default=12.0)
    p.add_argument("--mass", default="consistent,lumped,average")
    p.add_argument("--beta", type=lambda s: [float(b) for b in s.split(",")],
                   default="0.25,0.5")
    args = p.parse_args(argv)
    if args.classes:
        classes(args.N[0] if args.N else 80, Path(args.out))
        return
    if not args.convergence:        # the command: the accuracy study
        accuracy(args.N[0] if args.N else 80, Path(args.out))
        return
    Ns = args.N or [20, 40, 80, 160]
    rows = []
    for mass in args.mass.split(","):
        for beta in args.beta:
            for courant in args.courant:
                rows += study(Ns, courant, args.T, beta, mass)
    print(table(rows))


if __name__ == "__main__":
    from ..cli import main_guard
    main_guard(main)
