"""The timeseries.csv columns of the probes :func:`skfem_beam.semidiscrete.add_probes` added.

At each probe x, four columns: ``probe_<x>_displacement`` (the physical ũ = u + h(x)φ(t), m),
``probe_<x>_velocity`` (the backward difference (uⁿ − uⁿ⁻¹)/Δt + h(x)φ'(t), m/s),
``probe_<x>_moment`` (bending moment k²ũ'' times EI(x)/EI_ref) and ``probe_<x>_shear``
(shear force σ̃ = −k²ũ''' likewise, docs/design.md §1), in N·m and N when the beam's mass
per length ρS is known (the mass-normalised values times ρS), else in m³/s² and m²/s².
A two-plane beam has each column twice, ending ``_v`` and ``_w`` (its plane).
"""
from __future__ import annotations

import numpy as np

QUANTITIES = ("displacement", "velocity", "moment", "shear")


def probe_units(system) -> dict:
    """The units of the probe columns of ``system`` (for summary.json)."""
    known = system.view is not None and system.view.rho_S
    return {"displacement": "m", "velocity": "m/s",
            "moment": "N·m (k²ũ''·ρS)" if known else "m³/s² (k²ũ'', per unit mass per length)",
            "shear": "N (−k²ũ'''·ρS)" if known else "m²/s² (−k²ũ''', per unit mass per length)"}


def third_derivative(h_dd, x: float, a: float, b: float) -> float:
    """h'''(x) from h'' sampled at ξ = 1/4, 1/2, 3/4 of the element [a, b]: exact when
    h'' is a polynomial of degree ≤ 2 there (the paper's quartic h, a cubic static h)."""
    z = a + (b - a) * np.array([0.25, 0.5, 0.75])
    f = np.asarray(h_dd(z), dtype=float)
    # derivative at x of the quadratic through (z_i, f_i), Lagrange form
    d = 0.0
    for i in range(3):
        j, k = [m for m in range(3) if m != i]
        d += f[i] * ((x - z[j]) + (x - z[k])) / ((z[i] - z[j]) * (z[i] - z[k]))
    return float(d)


def probe_columns(run, k0: int, k1: int) -> dict:
    """The probe columns for the run's saved rows k0..k1−1 (empty without probes)."""
    system = run.system
    probes = system.meta.get("probes") or []
    if not probes:
        return {}
    names = list(system.observe)
    view = system.view
    scale = view.rho_S or 1.0
    t = np.arange(k0, k1) * run.save_every * run.dt
    lift = view.lift
    phi = dphi = None
    if lift is not None:
        phi = np.asarray(lift.motion.phi(t), dtype=float)
        dphi = np.asarray(lift.motion.phi_d(t), dtype=float)
    cols = {}
    planes = [("", view.k2, 1.0)] if view.planes == 1 else \
        [("_v", view.k2, view.direction[0]), ("_w", view.k2_w, view.direction[1])]
    for p in probes:
        x, name = p["x"], p["name"]
        for suffix, k2_plane, share in planes:
            i = names.index(f"{name}_displacement{suffix}")
            u, v = run.obs[k0:k1, i], run.obsv[k0:k1, i]
            m = run.obs[k0:k1, names.index(f"{name}_moment{suffix}")]
            s = run.obs[k0:k1, names.index(f"{name}_shear{suffix}")]
            if lift is not None and share != 0.0:
                h = float(lift.h(np.array([x]))[0])
                h = share * (0.0 if abs(h) <= 1e-9 else h)   # h(L) = -5.6e-17 is 0
                k2 = k2_plane * p["EI_factor"]
                u, v = u + h * phi, v + h * dphi
                m = m + share * k2 * float(lift.h_dd(np.array([x]))[0]) * phi
                s = s - share * k2 * third_derivative(lift.h_dd, x, *p["element"]) * phi
            cols.update({f"{name}_displacement{suffix}": u, f"{name}_velocity{suffix}": v,
                         f"{name}_moment{suffix}": scale * m,
                         f"{name}_shear{suffix}": scale * s})
    return cols
