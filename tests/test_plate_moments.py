"""The plate's bending moments in its field frames and its impacts.csv (docs/plate.md,
"Scene files"): the moments of the simply supported rectangle under the sin·sin load
against Navier's exact field, converging at the measured rate; the arrays in the written
XDMF and VTU (meshio, and ParaView's pvpython when installed); impacts.csv of a short
plate_on_stops, whose impulses add up to the time integral of the timeseries' contact
force."""
import csv
import json
import os
import shutil
import subprocess
import textwrap

import meshio
import numpy as np
import pytest

from conftest import exit_code
from skfem_beam.output.plate import MOMENTS, bending_moments, curvature_operators, \
    vertex_fields
from skfem_beam.plate import Plate, load_vector, plate_space, static_deflection
from skfem_beam.scenefile import example, load, run_main

A, B, NU = 1.0, 0.6, 0.3


def navier(space):
    """(computed, exact) moments at every vertex of the simply supported A × B plate under
    p = sin(πx/A) sin(πy/B) (Pa): w = w0 sin sin, w0 = 1 / (D π⁴ (1/A² + 1/B²)²),
    M_xx = D w0 π² (1/A² + ν/B²) sin sin, M_yy = D w0 π² (1/B² + ν/A²) sin sin,
    M_xy = −D (1 − ν) w0 π²/(AB) cos cos."""
    D = space.plate.D
    f = load_vector(space, lambda x, y: np.sin(np.pi * x / A) * np.sin(np.pi * y / B))
    got = bending_moments(space, static_deflection(space, f), curvature_operators(space))
    w0 = 1.0 / (D * np.pi ** 4 * (1 / A ** 2 + 1 / B ** 2) ** 2)
    x, y = space.vertices
    ss = np.sin(np.pi * x / A) * np.sin(np.pi * y / B)
    cc = np.cos(np.pi * x / A) * np.cos(np.pi * y / B)
    exact = dict(zip(MOMENTS, (D * w0 * np.pi ** 2 * (1 / A ** 2 + NU / B ** 2) * ss,
                               D * w0 * np.pi ** 2 * (1 / B ** 2 + NU / A ** 2) * ss,
                               -D * (1 - NU) * w0 * np.pi ** 2 / (A * B) * cc)))
    return got, exact


def errors(element: str, n: int) -> np.ndarray:
    """Relative errors of M_xx and M_yy at the centre vertex, and the largest error of
    M_xy over the vertices over max |M_xy| (the corners'), on n × n cells."""
    space = plate_space(Plate(a=A, b=B, h=0.01, nu=NU, element=element, nx=n, ny=n))
    got, exact = navier(space)
    x, y = space.vertices
    c = int(np.argmin(np.hypot(x - A / 2, y - B / 2)))
    assert x[c] == pytest.approx(A / 2) and y[c] == pytest.approx(B / 2)
    xy = "bending_moment_xy"
    return np.array([abs(got[k][c] / exact[k][c] - 1) for k in MOMENTS[:2]]
                    + [np.abs(got[xy] - exact[xy]).max() / np.abs(exact[xy]).max()])


# element, coarse mesh n (then 2n), the bound of the centre errors on 2n, the smallest
# rate log2(e(n)/e(2n)) of M_xx, M_yy; measured (M_xx, M_yy at the centre; M_xy's worst):
# BFS 8 → 16: 1.27e-2 → 3.20e-3 (both), rates 1.99, 1.99; M_xy 4.8e-5 → 3.0e-6, 4.02
# Morley 8 → 16: 3.23e-2 → 8.35e-3, 4.86e-2 → 1.24e-2, rates 1.95, 1.97; M_xy 7.1e-2 →
#   3.6e-2, 0.98 (its worst is at the corners: a constant per triangle)
# Argyris 8 → 16: 5.22e-5 → 3.70e-6, 5.90e-5 → 3.80e-6, rates 3.82, 3.96; M_xy 2.6e-4 →
#   1.6e-5, 3.98
@pytest.mark.parametrize("element, n, bound, rate", [
    ("bfs", 8, 3.5e-3, 1.9),
    ("morley", 8, 1.4e-2, 1.9),
    ("argyris", 8, 5e-6, 3.7),
])
def test_moments_converge_to_navier(element, n, bound, rate):
    coarse, fine = errors(element, n), errors(element, 2 * n)
    rates = np.log2(coarse / fine)
    print(element, n, 2 * n, coarse, fine, rates)
    assert fine[:2].max() <= bound, fine
    assert rates[:2].min() >= rate, rates
    assert fine[2] < coarse[2], (coarse, fine)


def test_moments_of_a_uniform_curvature_are_exact():
    """w = x² + 3y² − 2xy is in every element's space (BFS: bicubic; Morley: quadratic):
    M_xx = −D(2 + 6ν), M_yy = −D(6 + 2ν), M_xy = 2D(1 − ν) at every vertex."""
    for element in ("bfs", "morley", "argyris"):
        space = plate_space(Plate(a=A, b=B, nu=NU, element=element, nx=3, ny=2,
                                  edges={}))
        basis = space.basis
        # the quadratic itself: skfem's L² projection on the space, exact to round-off
        u = basis.project(lambda x: x[0] ** 2 + 3 * x[1] ** 2 - 2 * x[0] * x[1])
        got = bending_moments(space, u)
        D = space.plate.D
        want = (-D * (2 + 6 * NU), -D * (6 + 2 * NU), 2 * D * (1 - NU))
        worst = max(np.abs(got[k] / v - 1).max() for k, v in zip(MOMENTS, want))
        print(element, worst)
        assert worst <= 1e-8, element       # the L² projection's round-off (Argyris 2e-9)


SHORT = "0.004"      # s: plate_on_stops' first contacts (42 episodes at 19 vertices)


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("pos") / "run"
    assert exit_code(run_main, [str(example("plate_on_stops")), "--T", SHORT,
                                "--out", str(out)]) == 0
    return out


def columns(path) -> dict:
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return {name: np.array([float(r[i]) for r in rows[1:]]) for i, name in enumerate(rows[0])}


def test_fields_hold_the_moments(short_run):
    """fields.xdmf and the VTU frames hold bending_moment_xx, _yy, _xy at every vertex;
    the first frame's are those of the start (the API's), bit for bit."""
    system = load(example("plate_on_stops")).problem.system
    with meshio.xdmf.TimeSeriesReader(str(short_run / "fields.xdmf")) as reader:
        reader.read_points_cells()
        t, data, _ = reader.read_data(0)
        frames = reader.num_steps
    first = vertex_fields(system, system.u0, system.v0, np.zeros(system.C.shape[0]))
    for k in MOMENTS:
        assert data[k].shape == (system.meta["space"].vertices.shape[1],)
        np.testing.assert_array_equal(data[k], first[k])
    # the static start under 100 kPa, clamped: the edges' M_nn is the largest, hogging
    assert data["bending_moment_xx"].min() < 0 < data["bending_moment_xx"].max()
    last = meshio.read(short_run / "fields_vtu" / f"fields_{frames - 1:06d}.vtu")
    for k in MOMENTS:
        assert np.all(np.isfinite(last.point_data[k]))


def test_impacts_add_up_to_the_contact_force(short_run):
    """One row per contact episode of a vertex, in time order; Σ impulse = Σ
    contact_force_N Δt of timeseries.csv (measured: equal to the last bit)."""
    header = (short_run / "impacts.csv").read_text().splitlines()[0]
    assert header == "t_start,t_end,x,y,bound,velocity,peak_force,impulse," \
                     "max_violation,open"
    imp, ts = columns(short_run / "impacts.csv"), columns(short_run / "timeseries.csv")
    summary = json.loads((short_run / "summary.json").read_text())
    dt = summary["dt"]
    assert imp["t_start"].size == summary["impacts"] > 0
    assert np.all(np.diff(imp["t_start"]) >= 0)
    assert np.all(imp["t_end"] > imp["t_start"])
    integral = ts["contact_force_N"].sum() * dt
    total = imp["impulse"].sum()
    print("impulses", total, "∫ contact force dt", integral)
    assert abs(total - integral) <= 1e-12 * abs(integral)
    assert np.all(imp["impulse"] > 0) and np.all(imp["bound"] == 1)   # pushed up by g1
    assert np.all(imp["peak_force"] * dt <= imp["impulse"] * (1 + 1e-12))
    stats = summary["impact_statistics"]
    assert stats["impacts"] == imp["t_start"].size
    assert stats["total_impulse"] == pytest.approx(total, rel=1e-12)
    assert stats["vertices_touched"] == len(stats["vertices"]) == \
        len({(x, y) for x, y in zip(imp["x"], imp["y"])})
    assert stats["units"]["impulse"] == "N·s"


PVPYTHON = textwrap.dedent("""
    import json, sys
    from paraview import servermanager
    from paraview.simple import OpenDataFile, PVDReader
    from vtk.util.numpy_support import vtk_to_numpy
    xdmf, pvd = sys.argv[1], sys.argv[2]
    out = {}
    for name, make in [("xdmf", lambda: OpenDataFile(xdmf)),
                       ("pvd", lambda: PVDReader(FileName=pvd))]:
        r = make()
        r.UpdatePipeline(list(r.TimestepValues)[0])
        d = servermanager.Fetch(r)
        g = d.GetBlock(0) if d.IsA("vtkMultiBlockDataSet") else d
        pd = g.GetPointData()
        out[name] = {"arrays": sorted(pd.GetArrayName(i) for i in range(pd.GetNumberOfArrays())),
                     "mxx": vtk_to_numpy(pd.GetArray("bending_moment_xx")).tolist()}
    print("RESULT" + json.dumps(out))
""")


@pytest.mark.skipif(shutil.which("pvpython") is None,
                    reason="ParaView's pvpython is not installed")
def test_paraview_reads_the_moments(short_run, tmp_path):
    script = tmp_path / "read.py"
    script.write_text(PVPYTHON)
    env = {key: v for key, v in os.environ.items()
           if key not in ("VIRTUAL_ENV", "PYTHONPATH", "PYTHONHOME")}
    proc = subprocess.run(["pvpython", "--force-offscreen-rendering", str(script),
                           str(short_run / "fields.xdmf"), str(short_run / "fields.pvd")],
                          capture_output=True, text=True, timeout=180, env=env)
    assert proc.returncode == 0, proc.stderr[-2000:]
    line = [s for s in proc.stdout.splitlines() if s.startswith("RESULT")][-1]
    out = json.loads(line[len("RESULT"):])
    with meshio.xdmf.TimeSeriesReader(str(short_run / "fields.xdmf")) as reader:
        reader.read_points_cells()
        _, data, _ = reader.read_data(0)
    for name, got in out.items():
        assert set(MOMENTS) <= set(got["arrays"]), name
        np.testing.assert_array_equal(got["mxx"], data["bending_moment_xx"], err_msg=name)
