"""A plate scene's run (``python -m skfem_beam run`` on a ``kind = "plate"`` file): the
beams' streaming pipeline (:func:`~skfem_beam.output.stream.execute`: rows and frames as
they come, checkpoints, ``--resume``) with the plate's own columns, field writer and
charts (:mod:`skfem_beam.output.plate`)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import cli
from ..chart_process import draw
from ..errors import EXIT_UNSTABLE
from ..output.charts import deflection_chart, energy_chart, trajectory_chart
from ..output.plate import (UNITS, PlateFieldWriter, plate_cells,
                            plate_columns, plate_impacts, probe_name, vertex_w)
from ..output.stream import Series, execute, prepare
from ..spec import RunSpec
from ._beam import stability_warning, warn_contact_gain, warn_no_contact, warn_rough_start


def smallest_gap(system) -> float | None:
    """The smallest |g1|, |g2| at the constrained vertices (m; None: no finite one)."""
    g = np.abs(np.concatenate([system.lo, system.hi]))
    g = g[np.isfinite(g)]
    return float(g.min()) if g.size else None


def geometry(plate) -> dict:
    """The summary's geometry: the rectangle's nx, ny, a, b; a mesh file's name, its
    vertices and triangles, its bounding box [x0, x1, y0, y1] (m)."""
    if hasattr(plate, "nx"):
        return {"nx": plate.nx, "ny": plate.ny, "a": plate.a, "b": plate.b}
    return {"mesh": plate.mesh.source, "vertices": int(plate.mesh.points.shape[1]),
            "triangles": int(plate.mesh.triangles.shape[1]), "box": list(plate.box)}


def grid(plate) -> str:
    """The mesh, as the charts' titles name it."""
    if hasattr(plate, "nx"):
        return f"{plate.nx}×{plate.ny}"
    return f"{plate.mesh.triangles.shape[1]} triangles"


def run_plate_case(case: str, setup, spec: RunSpec) -> int:
    """Run the plate ``setup`` (scenefile.plate.PlateSetup) as ``spec`` says, write its
    folder, return the exit code."""
    prepare(spec.options)                         # fail before the run, not after it
    system = setup.system
    run = spec.method.build(system, spec.stepping)
    if run.beta is not None and run.beta < 0.25:     # β ≥ 1/4: no limit to warn of
        stability_warning(system, run.dt, run.beta)
    plate = system.meta["plate"]
    warn_thick(plate)
    summary = {
        "case": case, "kind": "plate", "element": plate.element, **geometry(plate),
        "thickness": plate.h, "edges": {e: plate.support(e) for e in plate.boundary_names},
        "dt": run.dt, "T": run.n_steps * run.dt, "beta": run.beta, "theta": run.theta,
        "method": spec.method.name, "unknowns": system.n,
        "constrained_vertices": int(system.C.shape[0]),
        "smallest_gap_m": smallest_gap(system),
        "probes": [list(p) for p in setup.probes],
        "units": {**UNITS, "max_penetration": "m, at the constrained vertices",
                  "smallest_gap_m": "m, the smallest |g1|, |g2| at the constrained "
                                    "vertices"},
        "config": spec.config,
    }
    series = Series(plate_columns(setup.probes), writer=PlateFieldWriter,
                    events=plate_impacts)
    code = execute(run, spec.options, summary, series, plate_charts(case, system, setup))
    if code == 0:
        warn_no_contact(run, system)
        warn_rough_start(run)
    if code in (0, EXIT_UNSTABLE):
        warn_contact_gain(run, "plate")
    return code


def warn_thick(plate) -> None:
    """One warning line for a plate thicker than a tenth of its shorter side: Kirchhoff–Love
    is a thin-plate model (no shear deformation), which such a plate leaves behind (a 5 m
    thickness on a 1 m plate ran without a word); or thinner than 1/10,000 of it, which a
    mesh file in mm makes of a plate in m."""
    x0, x1, y0, y1 = plate.box
    side = min(x1 - x0, y1 - y0)
    if plate.h > 0.1 * side:
        cli.warn(f"[section] thickness={plate.h:g} m is {plate.h / side:.2g} of the plate's "
                 f"shorter side {side:g} m: Kirchhoff–Love plates are thin (up to about 1/10); "
                 "shear deformation, which it leaves out, matters at this thickness")
    elif plate.h < 1e-4 * side:     # a mesh file in mm: a 1 km plate, w = 5e8 m, no word
        cli.warn(f"[section] thickness={plate.h:g} m is {plate.h / side:.2g} of the plate's "
                 f"shorter side {side:g} m: is the plate (its mesh file) in mm? Every length "
                 "is in m")


def plate_charts(case: str, system, setup):
    """The charts of a plate run: w at the probes, the energy and its balance, the total
    contact force, and the deflection over the plate at the frame of the largest contact
    force (the last frame when there is none); summary entries of the contact."""
    def finish(folder: Path, data: dict, run) -> dict:
        t, plate = data["t"], system.meta["plate"]
        about = (f"{run.label}, Δt={run.dt:g} s, {plate.element} {grid(plate)}")
        draw(trajectory_chart, folder / "probes.png", t,
             {f"w({x:g}, {y:g})": data[probe_name(x, y)] for x, y in setup.probes},
             title=f"{case}: deflection at the probes ({about})")
        draw(energy_chart, folder / "energy.png", t, data["energy_J"],
             title=f"{case}: discrete energy ½E_β ({about})",
             work={k: data[f"work_{k}_J"] for k in run.work_terms}, joules=True,
             support=False)         # a plate has no moving support
        if np.any(data["contact_force_N"]):
            draw(trajectory_chart, folder / "contact_force.png", t,
                 {"total contact force": data["contact_force_N"]},
                 title=f"{case}: total contact force on the plate ({about})",
                 ylabel="force (N)")
        r = run.result()
        force = np.abs(r.frames_force).sum(axis=1) if r.frames_force.size else np.zeros(1)
        k = int(np.argmax(force)) if np.any(force) else r.frames_t.size - 1
        w = vertex_w(system, r.frames_u[k])     # not vertex_fields: no moments needed here
        points, ((_, cells),) = plate_cells(system)
        held = (system.x_contact, system.meta["y_contact"], r.frames_force[k] != 0) \
            if r.frames_force.size else None
        draw(deflection_chart, folder / "deflection.png", points, cells, w,
             title=f"{case}: w at t = {r.frames_t[k]:.4g} s\n({about})", held=held)
        # the largest magnitude of the total force (g2 pushes down: a signed max read 0 N)
        return {"max_contact_force_N": float(np.max(np.abs(data["contact_force_N"]),
                                                    initial=0.0)),
                "max_contact_area_fraction":
                    float(np.max(data["contact_area_fraction"], initial=0.0))}
    return finish
