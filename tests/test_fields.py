"""Field files (XDMF + h5, VTU + pvd) read back by meshio, VTK and ParaView; renders; meshes."""
import json
import os
import shutil
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

from skfem_beam import beam_system, scenes, solve
from skfem_beam.bar import Bar, bar_system
from skfem_beam.errors import InputError
from skfem_beam.output.fields import FieldWriter, sample_line, write_fields
from skfem_beam.meshes import PAPER_MESHES, load_mesh, write_mesh
from skfem_beam.problem import Beam, BeamProblem, Load, Obstacles, lifting, lifting_dd

ARRAYS = {"displacement", "displacement_vector", "velocity", "g1", "g2", "contact_force",
          "bending_moment"}
S = 8   # sub-points per element (the default)


@pytest.fixture(scope="module")
def run():
    """The first paper's scene up to the first impacts (frames 0.09 and 0.11 s hold contact)."""
    return solve(beam_system(scenes.point_stops()), dt=5e-5, T=0.15, beta=0.5, frames=30)


@pytest.fixture(scope="module")
def written(run, tmp_path_factory):
    folder = tmp_path_factory.mktemp("fields")
    paths = write_fields(folder, run, fmt="both")
    return folder, paths


def _observed_at(run, t):
    """The tip displacement the integrator saved at time t (saved every step) and the
    contact force there in N (the fields' unit: ρS λ, the series' contact_force_N)."""
    k = int(round(t / run.dt))
    assert abs(run.t[k] - t) < 1e-12
    rho_S = run.system.meta["problem"].beam.rho_S
    return run.observed["tip_displacement"][k], rho_S * run.contact_force[k, 0]


def _contact_frame(run):
    k = int(np.flatnonzero(run.frames_force[:, 0] != 0)[0])
    assert run.frames_force[k, 0] != 0
    return k


def test_files_and_layout(run, written):
    folder, paths = written
    names = sorted(p.name for p in paths)
    assert names == ["fields.h5", "fields.pvd", "fields.xdmf"]
    assert all(p.parent == folder and p.is_file() for p in paths)
    assert len(list((folder / "fields_vtu").glob("*.vtu"))) == run.frames_t.size
    root = ET.parse(folder / "fields.xdmf").getroot()
    topo = root.find(".//Topology")
    assert topo.get("TopologyType") == "Polyline" and topo.get("NodesPerElement") == "2"
    assert len(root.find("Domain")) == 1   # no separate mesh grid (stale block in Xdmf2)


def test_the_same_frames_write_the_same_h5_bytes(run, written, tmp_path):
    """fields.h5 holds no times: its datasets' headers kept their creation and
    modification times, so that two runs of one scene differed byte for byte (a second
    apart), their arrays equal."""
    import h5py
    folder, _ = written
    with h5py.File(folder / "fields.h5", "r") as f:
        info = [h5py.h5o.get_info(f[name].id) for name in f]
    assert len(info) > 7 and not any(i.ctime or i.mtime for i in info)
    write_fields(tmp_path, run, fmt="xdmf")
    assert (tmp_path / "fields.h5").read_bytes() == (folder / "fields.h5").read_bytes()


def test_meshio_reads_xdmf(run, written):
    folder, _ = written
    k = _contact_frame(run)
    J = run.system.space.J
    with meshio.xdmf.TimeSeriesReader(folder / "fields.xdmf") as rd:
        points, cells = rd.read_points_cells()
        assert rd.num_steps == run.frames_t.size
        assert points.shape == (J * S + 1, 3) and not points[:, 1:].any()
        assert cells[0].type == "line" and len(cells[0].data) == J * S
        times = [rd.read_data(i)[0] for i in range(rd.num_steps)]
        t, pd, _ = rd.read_data(k)
    np.testing.assert_allclose(times, run.frames_t, rtol=1e-15)
    assert set(pd) == ARRAYS
    tip, force = _observed_at(run, t)
    assert pd["displacement"][-1] == pytest.approx(tip, rel=1e-12)
    assert pd["contact_force"][-1] == pytest.approx(force, rel=1e-12)
    assert pd["g1"][-1] == -0.1 and pd["g2"][-1] == 0.1
    assert np.isnan(pd["g1"][:-1]).all()          # no obstacle: NaN (documented)


def test_meshio_reads_vtu_series(run, written):
    folder, _ = written
    k = _contact_frame(run)
    sets = ET.parse(folder / "fields.pvd").getroot().findall(".//DataSet")
    np.testing.assert_allclose([float(d.get("timestep")) for d in sets], run.frames_t)
    mesh = meshio.read(folder / sets[k].get("file"))
    assert set(mesh.point_data) == ARRAYS
    tip, _ = _observed_at(run, run.frames_t[k])
    assert mesh.point_data["displacement"][-1] == pytest.approx(tip, rel=1e-12)


def test_vtk_xdmf_reader(run, written):
    vtk = pytest.importorskip("vtk")
    from vtk.util.numpy_support import vtk_to_numpy
    folder, _ = written
    k = _contact_frame(run)
    rd = vtk.vtkXdmfReader()
    rd.SetFileName(str(folder / "fields.xdmf"))
    rd.UpdateInformation()
    times = rd.GetOutputInformation(0).Get(vtk.vtkStreamingDemandDrivenPipeline.TIME_STEPS())
    np.testing.assert_allclose(times, run.frames_t, rtol=1e-12)
    rd.UpdateTimeStep(times[k])
    grid = rd.GetOutputDataObject(0)
    assert grid.GetClassName() == "vtkUnstructuredGrid"
    pd = grid.GetPointData()
    assert {pd.GetArrayName(i) for i in range(pd.GetNumberOfArrays())} == ARRAYS
    tip, _ = _observed_at(run, times[k])
    assert vtk_to_numpy(pd.GetArray("displacement"))[-1] == pytest.approx(tip, rel=1e-12)


def test_vtk_xml_reader_through_pvd(run, written):
    pv = pytest.importorskip("pyvista")
    folder, _ = written
    k = _contact_frame(run)
    rd = pv.PVDReader(str(folder / "fields.pvd"))   # pvd parsed, VTU read by VTK's XML reader
    np.testing.assert_allclose(rd.time_values, run.frames_t)
    rd.set_active_time_value(rd.time_values[k])
    grid = rd.read()[0]
    assert set(grid.point_data.keys()) == ARRAYS
    tip, force = _observed_at(run, rd.time_values[k])
    assert grid.point_data["displacement"][-1] == pytest.approx(tip, rel=1e-12)
    assert grid.point_data["contact_force"][-1] == pytest.approx(force, rel=1e-12)


PVPYTHON = textwrap.dedent("""
    import json, sys
    from paraview import servermanager
    from paraview.simple import OpenDataFile, XDMFReader, Xdmf3ReaderS, PVDReader
    from vtk.util.numpy_support import vtk_to_numpy
    xdmf, pvd, k = sys.argv[1], sys.argv[2], int(sys.argv[3])
    out = {}
    for name, make in [("default_xdmf", lambda: OpenDataFile(xdmf)),
                       ("xdmf3", lambda: Xdmf3ReaderS(FileName=[xdmf])),
                       ("xdmf2", lambda: XDMFReader(FileNames=[xdmf])),
                       ("pvd", lambda: PVDReader(FileName=pvd))]:
        r = make()
        times = list(r.TimestepValues)
        r.UpdatePipeline(times[k])
        d = servermanager.Fetch(r)
        blocks = d.GetNumberOfBlocks() if d.IsA("vtkMultiBlockDataSet") else 0
        g = d.GetBlock(0) if blocks else d
        pd = g.GetPointData()
        out[name] = {"reader": r.GetXMLName(), "times": times, "blocks": blocks,
                     "arrays": sorted(pd.GetArrayName(i) for i in range(pd.GetNumberOfArrays())),
                     "tip": float(vtk_to_numpy(pd.GetArray("displacement"))[-1]),
                     "force": float(vtk_to_numpy(pd.GetArray("contact_force"))[-1])}
    print("RESULT" + json.dumps(out))
""")


@pytest.mark.skipif(shutil.which("pvpython") is None,
                    reason="ParaView's pvpython is not installed "
                           "(apt-get install paraview python3-paraview)")
def test_paraview_reads_both(run, written, tmp_path):
    folder, _ = written
    k = _contact_frame(run)
    script = tmp_path / "read.py"
    script.write_text(PVPYTHON)
    # pvpython runs Debian's own Python: keep a venv's settings out of its way
    env = {key: v for key, v in os.environ.items()
           if key not in ("VIRTUAL_ENV", "PYTHONPATH", "PYTHONHOME")}
    proc = subprocess.run(["pvpython", "--force-offscreen-rendering", str(script),
                           str(folder / "fields.xdmf"), str(folder / "fields.pvd"), str(k)],
                          capture_output=True, text=True, timeout=180, env=env)
    assert proc.returncode == 0, proc.stderr[-2000:]
    line = [s for s in proc.stdout.splitlines() if s.startswith("RESULT")][-1]
    out = json.loads(line[len("RESULT"):])
    assert out["default_xdmf"]["reader"] == "Xdmf3ReaderS"   # the reader that aborted
    tip, force = _observed_at(run, run.frames_t[k])      # force: ρS λ, in N
    assert force != 0
    for name, got in out.items():
        np.testing.assert_allclose(got["times"], run.frames_t, rtol=1e-12, err_msg=name)
        assert set(got["arrays"]) == ARRAYS, name
        assert got["blocks"] <= 1, f"{name}: {got['blocks']} blocks (a stale mesh block?)"
        assert got["tip"] == pytest.approx(tip, rel=1e-12), name
        assert got["force"] == pytest.approx(force, rel=1e-12), name


def test_sub_points_follow_the_cubic(run):
    """Values at the sub-points are the space's own sampler values (not chords), and
    ũ = u + hφ, ũ_t = v + hφ', k²ũ'' = k²(u'' + h''φ)."""
    system = run.system
    space, pb = system.space, system.meta["problem"]
    line = sample_line(system, S)
    smp = space.sampler(np.arange(S) / S)            # ξ = 0..(S−1)/S of every element
    k = run.frames_t.size // 2
    t, u, v = run.frames_t[k], run.frames_u[k], run.frames_v[k]
    f = line.fields(t, u, v, run.frames_force[k])
    phi = pb.support.phi(t)
    dphi = pb.support.amplitude * pb.support.omega * np.cos(pb.support.omega * t)
    x = line.x[:-1]
    A, w = pb.support.amplitude, pb.support.omega       # φ = 0.2 sin 10t: 0.2 m, 2 m/s
    np.testing.assert_allclose(x, smp.x, atol=6e-16 * pb.beam.L)
    np.testing.assert_allclose(f["displacement"][:-1], smp.E0 @ u + lifting(x, pb.beam.L) * phi,
                               rtol=1e-13, atol=5e-15 * A)
    np.testing.assert_allclose(f["velocity"][:-1], smp.E0 @ v + lifting(x, pb.beam.L) * dphi,
                               rtol=1e-8, atol=5e-13 * A * w)
    inner = np.arange(x.size) % S != 0               # u'' jumps at nodes: compare inside
    want = pb.beam.rho_S * pb.beam.k2 * (smp.E2 @ u + lifting_dd(x, pb.beam.L) * phi)  # N·m
    np.testing.assert_allclose(f["bending_moment"][:-1][inner], want[inner], rtol=1e-10)
    assert f["displacement"][0] == pytest.approx(phi, abs=5e-15 * A)   # the clamp moves with φ
    # a cubic, not its chord: mid-element values differ from the nodal average
    nodes = f["displacement"][::S]
    chord = 0.5 * (nodes[:-1] + nodes[1:])
    assert np.abs(f["displacement"][S // 2::S] - chord).max() > 1e-6


def test_lifting_second_derivative():
    L, x, d = 1.501, np.linspace(0, 1.501, 7), 1e-3
    fd = (lifting(x + d, L) - 2 * lifting(x, L) + lifting(x - d, L)) / d**2
    np.testing.assert_allclose(lifting_dd(x, L), fd, atol=1e-5)


def test_bspline_and_bar_spaces(tmp_path):
    """B-splines have a moment; the P1 bar has none and its obstacle comes from C."""
    pb = BeamProblem(Beam(10.0, 282.84), Obstacles(-0.01, 0.01), J=20, element="bspline",
                     load=Load.uniform(lambda t: np.sin(10 * t)))
    rb = solve(beam_system(pb), dt=1e-3, T=0.05, frames=5)
    (tmp_path / "b").mkdir()
    write_fields(tmp_path / "b", rb, fmt="xdmf")
    with meshio.xdmf.TimeSeriesReader(tmp_path / "b" / "fields.xdmf") as rd:
        rd.read_points_cells()
        t, pd, _ = rd.read_data(rd.num_steps - 1)
    assert set(pd) == ARRAYS
    smp = rb.system.space.sampler(np.arange(S) / S)
    np.testing.assert_allclose(pd["displacement"][:-1], smp.E0 @ rb.frames_u[-1],
                               atol=1e-13 * 0.01)                  # 1e-13 × the gap
    assert (pd["g1"] == -0.01).all() and (pd["g2"] == 0.01).all()

    rbar = solve(bar_system(Bar(N=10)), dt=0.01, T=0.2, beta=0.25, frames=4)
    (tmp_path / "bar").mkdir()
    write_fields(tmp_path / "bar", rbar, fmt="vtu", samples_per_element=1)
    mesh = meshio.read(tmp_path / "bar" / "fields_vtu" / "fields_000002.vtu")
    assert set(mesh.point_data) == ARRAYS - {"bending_moment"}
    np.testing.assert_allclose(mesh.point_data["displacement"], rbar.frames_u[2])
    assert mesh.point_data["g1"][0] == 0.0 and np.isnan(mesh.point_data["g1"][1:]).all()
    assert np.isnan(mesh.point_data["g2"]).all()


def test_streaming_writer(run, tmp_path, monkeypatch):
    """Frames go out one by one; flush() makes the files readable mid-run by another
    process (the .h5 is not locked: ParaView aborted on a run in progress); the .h5 is
    written beside the .xdmf whatever the working directory."""
    elsewhere = tmp_path / "cwd"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    out = tmp_path / "out"
    out.mkdir()
    with FieldWriter(out, run.system, fmt="both", samples_per_element=4, name="live") as w:
        for k in range(3):
            w.write(run.frames_t[k], run.frames_u[k], run.frames_v[k], run.frames_force[k])
        w.flush()
        read = ("import meshio, sys\nwith meshio.xdmf.TimeSeriesReader(sys.argv[1]) as rd:\n"
                "    rd.read_points_cells(); print(rd.num_steps)")
        p = subprocess.run([sys.executable, "-c", read, str(out / "live.xdmf")],
                           capture_output=True, text=True)
        assert p.returncode == 0 and p.stdout.strip() == "3", p.stderr
        assert len(ET.parse(out / "live.pvd").getroot().findall(".//DataSet")) == 3
        w.write(run.frames_t[3], run.frames_u[3], run.frames_v[3], run.frames_force[3])
        with pytest.raises(ValueError, match="shapes"):
            w.write(0.0, run.frames_u[0][:-1], run.frames_v[0], run.frames_force[0])
    assert list(elsewhere.iterdir()) == []
    with meshio.xdmf.TimeSeriesReader(out / "live.xdmf") as rd:
        rd.read_points_cells()
        assert rd.num_steps == 4
        assert rd.read_data(3)[0] == run.frames_t[3]


def test_closing_after_a_flush_does_not_write_the_indexes_again(run, tmp_path):
    """A run's last update flushes, then the run closes its writer: the .xdmf and .pvd
    (each replaced whole when written) are written once, and list every frame."""
    with FieldWriter(tmp_path, run.system, fmt="both", samples_per_element=4) as w:
        for k in range(3):
            w.write(run.frames_t[k], run.frames_u[k], run.frames_v[k], run.frames_force[k])
        w.flush()
        inodes = {s: os.stat(tmp_path / f"fields.{s}").st_ino for s in ("xdmf", "pvd")}
    assert {s: os.stat(tmp_path / f"fields.{s}").st_ino for s in ("xdmf", "pvd")} == inodes
    assert len(ET.parse(tmp_path / "fields.pvd").getroot().findall(".//DataSet")) == 3
    with meshio.xdmf.TimeSeriesReader(tmp_path / "fields.xdmf") as rd:
        rd.read_points_cells()
        assert rd.num_steps == 3 and rd.read_data(2)[0] == run.frames_t[2]


def test_bad_field_options(run, tmp_path):
    with pytest.raises(InputError, match="format='vtk' is not one of: xdmf, vtu, both, none"):
        FieldWriter(tmp_path, run.system, fmt="vtk")
    with pytest.raises(InputError, match="does not exist"):
        FieldWriter(tmp_path / "missing", run.system)
    with pytest.raises(InputError, match="samples_per_element"):
        FieldWriter(tmp_path, run.system, samples_per_element=0)
    assert write_fields(tmp_path, run, fmt="none") == [] and list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------- renders
def _colour_masks(img):
    """Boolean masks of beam-blue and obstacle-red pixels (shaded, so by dominance)."""
    r, g, b = (img[..., i].astype(int) for i in range(3))
    return (b > r + 60) & (b > g + 20), (r > g + 80) & (r > b + 80)


def test_render_png_shows_beam_between_stops(run, tmp_path):
    pytest.importorskip("pyvista")
    from skfem_beam.output.render import render_beam
    k = _contact_frame(run)
    path = tmp_path / "beam.png"
    img = render_beam(path, run, times=[run.frames_t[k]], case="point_stops")
    assert path.is_file() and path.stat().st_size > 5000
    import imageio.v3 as iio
    np.testing.assert_array_equal(iio.imread(path)[..., :3], img)
    gray = img.mean(axis=2)
    assert gray.std() > 15                                 # not blank
    ink = (gray < 240).mean()
    assert 0.02 < ink < 0.6, ink                           # a picture, not a fill
    blue, red = _colour_masks(img)
    assert blue.mean() > 0.003 and red.mean() > 0.001
    # the stops are the red blocks at the tip: one above, one below the beam's end
    cols = np.flatnonzero(red.any(axis=0) & blue.any(axis=0))
    assert cols.size > 3
    rows_red = np.flatnonzero(red[:, cols].any(axis=1))
    rows_blue = np.flatnonzero(blue[:, cols].any(axis=1))
    gap = np.flatnonzero(np.diff(rows_red) > 1)
    assert gap.size == 1, "expected two separate stop blocks"
    upper_end, lower_start = rows_red[gap[0]], rows_red[gap[0] + 1]
    assert upper_end <= rows_blue.min() and rows_blue.max() <= lower_start


def test_animation_gif(run, tmp_path):
    pytest.importorskip("pyvista")
    from skfem_beam.output.render import animate
    path = animate(tmp_path / "run.gif", run, every=10, window_size=(480, 200))
    import imageio.v3 as iio
    frames = iio.imread(path)
    assert frames.shape[0] == len(range(0, run.frames_t.size, 10))
    assert frames[0].std() > 10 and np.abs(frames[0].astype(int) - frames[-1]).max() > 0
    with pytest.raises(InputError, match=".gif or .mp4"):
        animate(tmp_path / "run.avi", run)


def test_a_folder_read_back_is_refused_by_the_renders_in_one_line(tmp_path):
    """render_beam and animate draw a Result's frames in memory: a SavedRun (read_run)
    was an AttributeError from inside; one line, with or without PyVista."""
    from skfem_beam import read_run
    from skfem_beam.cases import point_stops
    from skfem_beam.output.render import animate, render_beam
    assert point_stops.main(["--T", "0.01", "--out", str(tmp_path / "run")]) == 0
    saved = read_run(tmp_path / "run")
    for draw, name in ((render_beam, "x.png"), (animate, "x.gif")):
        with pytest.raises(InputError, match="needs the Result of a beam's solve.* not "
                                             "SavedRun"):
            draw(tmp_path / name, saved)


def test_a_two_plane_run_is_refused_by_the_renders_in_one_line():
    """The trefoil tube's Result: KeyError('displacement') from inside (its fields are
    displacement_v, _w)."""
    from skfem_beam import beam_system, solve
    from skfem_beam.output.render import animate, render_beam
    from skfem_beam.scenefile import example, load
    scene = load(example("tube_round_holes"))
    result = solve(beam_system(scene.problem), 1e-4, 2e-3, progress=False)
    for draw, name in ((render_beam, "x.png"), (animate, "x.gif")):
        with pytest.raises(InputError, match="draws a beam in one plane; this one bends in "
                                             "two"):
            draw(name, result)


# ----------------------------------------------------------------------------- meshes
MESH_DIR = os.path.join(os.path.dirname(__file__), "..", "meshes")


@pytest.mark.parametrize("name", sorted(PAPER_MESHES))
def test_shipped_meshes(name):
    L, J = PAPER_MESHES[name]
    x = load_mesh(os.path.join(MESH_DIR, f"{name}.msh"), L)
    # written to full precision: equal (0 measured), 1e-16 L is 1e-15 m on the 10 m pipe
    np.testing.assert_allclose(x, np.linspace(0, L, J + 1), rtol=0, atol=1e-16 * L)
    if L == 10.0:
        assert 5.0 in x
    pb = BeamProblem(Beam(L, 282.84), Obstacles.point_stops(L, -0.1, 0.1), nodes=x)
    assert pb.J == J


def _write(path, points, cells):
    fmt = {"file_format": "gmsh22"} if str(path).endswith(".msh") else {}   # not ANSYS
    meshio.write(path, meshio.Mesh(np.asarray(points, float), cells), **fmt)
    return path


def test_mesh_in_any_order_and_format(tmp_path):
    x = np.array([0.0, 1.0, 0.25, 0.5])        # gmsh-style: end points first
    pts = np.column_stack([x, 0 * x, 0 * x])
    cells = [("vertex", np.array([[0], [1]])), ("line", np.array([[0, 2], [2, 3], [3, 1]]))]
    for suffix in (".msh", ".vtu", ".xdmf"):
        # meshio cannot read back its own mixed vertex + line XDMF: lines only there
        path = _write(tmp_path / f"m{suffix}", pts, cells[1:] if suffix == ".xdmf" else cells)
        np.testing.assert_array_equal(load_mesh(path, 1.0), [0.0, 0.25, 0.5, 1.0])
    np.testing.assert_array_equal(load_mesh(write_mesh(tmp_path / "w.vtu", [0, 0.5, 1]), 1.0),
                                  [0.0, 0.5, 1.0])


@pytest.mark.parametrize("points, cells, message", [
    ([[0, 0, 0], [0.5, 0, 0], [0.5, 0, 0], [1, 0, 0]], [[0, 1], [1, 2], [2, 3]],
     "duplicate nodes at x=0.5"),
    ([[0, 0, 0], [0.5, 0, 0], [0.9, 0, 0]], [[0, 1], [1, 2]],
     "runs from 0 to 0.9, not from 0 to L=1"),
    ([[0.1, 0, 0], [1, 0, 0]], [[0, 1]], "runs from 0.1 to 1"),
    ([[0, 0, 0], [0.5, 0.2, 0], [1, 0, 0]], [[0, 1], [1, 2]], "does not lie on the x axis"),
    ([[0, 0, 0], [0.5, 0, 0], [1, 0, 0]], [[0, 2], [0, 1]], "not a chain of cells"),
    ([[0, 0, 0], [0.5, 0, 0], [0.7, 0, 0], [1, 0, 0]], [[0, 1], [2, 3]], "not a chain of cells"),
    ([[0, 0, 0], [np.nan, 0, 0], [1, 0, 0]], [[0, 1], [1, 2]], "non-finite"),
])
def test_bad_meshes(tmp_path, points, cells, message):
    path = _write(tmp_path / "bad.vtu", points, [("line", np.array(cells))])
    with pytest.raises(InputError, match=message) as e:
        load_mesh(path, 1.0)
    assert "\n" not in str(e.value)


def test_unreadable_meshes(tmp_path, capsys):
    (tmp_path / "junk.msh").write_text("not a mesh\n")
    with pytest.raises(InputError, match="cannot read mesh .*junk.msh"):
        load_mesh(tmp_path / "junk.msh", 1.0)
    assert capsys.readouterr().out == ""          # meshio's own chatter is captured
    with pytest.raises(InputError, match="does not exist"):
        load_mesh(tmp_path / "none.msh", 1.0)
    tri = _write(tmp_path / "tri.vtu", [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
                 [("triangle", np.array([[0, 1, 2]]))])
    with pytest.raises(InputError, match="not a line mesh: it has triangle cells"):
        load_mesh(tri, 1.0)
    with pytest.raises(InputError, match="L=-1 must be > 0"):
        load_mesh(tri, -1.0)


def test_field_forces_are_the_series_newtons(tmp_path):
    """A scene file's run (the heat-exchanger tube, two baffles): at every frame, the
    field contact_force summed over the tube equals timeseries.csv's contact_force_N
    (the net force, N) at that time."""
    from conftest import exit_code
    from skfem_beam.scenefile import example, run_main
    out = tmp_path / "hx"
    assert exit_code(run_main, [str(example("heat_exchanger_tube")), "--set", "time.T=0.1",
                                "--format", "xdmf", "--frames", "100", "--out", str(out)]) == 0
    series = np.genfromtxt(out / "timeseries.csv", delimiter=",", names=True)
    small = 6e-15 * np.abs(series["contact_force_N"]).max()   # N, for a force near 0
    hits = 0
    with meshio.xdmf.TimeSeriesReader(out / "fields.xdmf") as rd:
        rd.read_points_cells()
        for i in range(rd.num_steps):
            t, pd, _ = rd.read_data(i)
            k = int(np.argmin(np.abs(series["t"] - t)))
            assert abs(series["t"][k] - t) < 1e-12
            assert pd["contact_force"].sum() == pytest.approx(series["contact_force_N"][k],
                                                              rel=1e-12, abs=small)
            hits += series["contact_force_N"][k] != 0
    assert hits >= 2
