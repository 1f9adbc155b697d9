"""Plates on a triangle mesh read from a file ([geometry] mesh, docs/plate.md "A mesh
file"): the built-in rectangle written as a file gives the same plate to round-off; a
clamped disk (Argyris) against the exact frequency and centre deflection, the error
shrinking with the mesh; the shipped plate_disk scene; bad input one line, nothing
written; --resume builds the plate from the mesh file's bytes the run stored (the
scene's copy moved or changed), a changed file refused in one line."""
import meshio
import numpy as np
import pytest

from conftest import assert_scene_refused
from skfem_beam.errors import InputError
from skfem_beam.plate import (Plate, deflection_at_vertex, load_vector, natural_frequencies,
                              plate_space, static_deflection)
from skfem_beam.plate.meshfile import disk, read_plate_mesh, write_msh
from skfem_beam.plate.model import MeshPlate
from skfem_beam.plate.space import rectangle_mesh
from skfem_beam.scenefile import example, load, run_main

SIDES = ("left", "right", "bottom", "top")
MIXED = {"left": "clamped", "right": "simply_supported", "bottom": "sliding"}


def rectangle_file(plate: Plate, path, fmt: str = "gmsh22"):
    """The built-in rectangle's triangles and edges as a mesh file (gmsh: physical lines
    named left/right/bottom/top; vtu: the edges as integer line tags 1..4)."""
    mesh = rectangle_mesh(plate)
    lines = [mesh.facets[:, mesh.boundaries[k]].T for k in SIDES]
    tags = [np.full(len(c), i + 1) for i, c in enumerate(lines)]
    cells = [("triangle", mesh.t.T)] + [("line", c) for c in lines]
    data = [np.full(mesh.t.shape[1], 9)] + tags
    points = np.column_stack([mesh.p.T, np.zeros(mesh.p.shape[1])])
    if fmt == "gmsh22":
        meshio.write(path, meshio.Mesh(points, cells, cell_data={
            "gmsh:physical": data, "gmsh:geometrical": data},
            field_data={k: np.array([i + 1, 1]) for i, k in enumerate(SIDES)}),
            file_format="gmsh22", binary=False)
    else:
        meshio.write(path, meshio.Mesh(points, cells, cell_data={"edge": data}))
    return path


@pytest.mark.parametrize("element", ["morley", "argyris"])
@pytest.mark.parametrize("fmt", ["gmsh22", "vtu"])
def test_the_rectangle_as_a_mesh_file_is_the_same_plate(tmp_path, element, fmt):
    plate = Plate(a=1.3, b=0.7, element=element, nx=6, ny=4, edges=MIXED)
    path = rectangle_file(plate, tmp_path / f"rect.{'msh' if fmt == 'gmsh22' else fmt}", fmt)
    names = dict(zip(SIDES, SIDES)) if fmt == "gmsh22" else {k: str(i + 1) for i, k in
                                                              enumerate(SIDES)}
    mesh_plate = MeshPlate(read_plate_mesh(path), element=element,
                           edges={names[k]: v for k, v in MIXED.items()})
    built, read = plate_space(plate), plate_space(mesh_plate)
    np.testing.assert_array_equal(built.fixed_dofs, read.fixed_dofs)
    w_built = natural_frequencies(built, 4)[0]
    w_read = natural_frequencies(read, 4)[0]
    assert np.max(np.abs(w_read - w_built) / w_built) <= 1e-12
    u_built = static_deflection(built, load_vector(built, lambda x, y: 1e3 + 0 * x))
    u_read = static_deflection(read, load_vector(read, lambda x, y: 1e3 + 0 * x))
    centre = deflection_at_vertex(built, u_built, 0.65, 0.35)
    assert abs(deflection_at_vertex(read, u_read, 0.65, 0.35) - centre) <= 1e-12 * abs(centre)


CLAMPED_DISK = 10.2158      # ω a² √(ρh/D), the first mode of a clamped disk (Leissa)
# measured (rings: relative error of λ², of w(0)): 2: 1.35e-2, -2.25e-2; 4: 5.44e-3,
# -1.00e-2; 8: 1.56e-3, -3.01e-3; 16: 4.13e-4, -8.08e-4 (O(h²): the polygon's area)
DISK_ERRORS = {2: (1.4e-2, 2.3e-2), 4: (5.5e-3, 1.01e-2), 8: (1.6e-3, 3.1e-3)}


def test_clamped_disk_argyris_converges_to_the_exact_plate(tmp_path):
    radius, q = 0.5, 1e3
    errors = []
    for rings, (tol_frequency, tol_deflection) in DISK_ERRORS.items():
        write_msh(disk(radius, rings), tmp_path / "disk.msh")
        plate = MeshPlate(read_plate_mesh(tmp_path / "disk.msh"), edges={"rim": "clamped"},
                          element="argyris")
        space = plate_space(plate)
        omega = natural_frequencies(space, 1)[0][0]
        lam = omega * radius ** 2 * np.sqrt(plate.rho * plate.h / plate.D)
        u = static_deflection(space, load_vector(space, lambda x, y: q + 0 * x))
        w0 = deflection_at_vertex(space, u, 0.0, 0.0)
        exact = q * radius ** 4 / (64 * plate.D)
        errors.append((abs(lam / CLAMPED_DISK - 1), abs(w0 / exact - 1)))
        assert errors[-1][0] <= tol_frequency and errors[-1][1] <= tol_deflection, (rings,
                                                                                     errors)
    # each halving of h: ratios 2.5, 3.5 (λ²), 2.2, 3.3 (w0): towards 4
    assert all(a[0] > 2 * b[0] and a[1] > 2 * b[1] for a, b in zip(errors, errors[1:])), \
        errors


def test_shipped_disk_scene_loads_and_its_first_frequency_is_the_disk(tmp_path):
    scene = load(example("plate_disk"))
    space = scene.problem.space
    plate = space.plate
    assert isinstance(plate, MeshPlate) and plate.element == "argyris"
    assert plate.boundary_names == ("rim",) and plate.box == (-0.5, 0.5, -0.5, 0.5)
    lam = natural_frequencies(space, 1)[0][0] * 0.25 * np.sqrt(plate.rho * plate.h / plate.D)
    assert abs(lam / CLAMPED_DISK - 1) < 3e-3          # measured 2.66e-3 with 6 rings
    assert scene.problem.system.C.shape[0] > 0 and scene.problem.probes[0] == (0.0, 0.0)


DISK = example("plate_disk").read_text()


@pytest.mark.parametrize("old, new, word", [
    ('rim = "clamped"', 'edge = "clamped"', "rim"),         # the names the mesh has
    ('rim = "clamped"', 'rim = "glued"', "glued"),
    ('element = "argyris"', 'element = "bfs"', "bfs"),
    ('element = "argyris"', 'element = "argyris"\nnx = 4', "nx"),
    ('mesh = "plate_disk.msh"', 'mesh = "garbage.msh"', "garbage.msh"),
    ('mesh = "plate_disk.msh"', 'mesh = "missing.msh"', "missing.msh"),
    ('mesh = "plate_disk.msh"', 'mesh = "plate_disk.msh"\na = 1.0', "not both"),
    ("region = [-0.2, -0.2, 0.2, 0.2]", "region = [-0.2, -0.2, 0.6, 0.2]", "off the plate"),
    # in the mesh's bounding box, outside the disk (its corner): no vertex, no area
    ("region = [-0.2, -0.2, 0.2, 0.2]", "region = [0.4, 0.4, 0.5, 0.5]", "no vertex"),
    ("[time]", "[[loads]]\npressure = 1e3\nregion = [0.4, 0.4, 0.5, 0.5]\n[time]",
     "loads.0.region = [0.4, 0.4, 0.5, 0.5] holds none of the plate"),
    ('element = "argyris"', 'element = "argyrus"', "not one of: morley, argyris"),
    ("probes = [[0.0, 0.0], [0.25, 0.0]]", "probes = [[0.0, 0.7]]", "off the plate"),
    ("probes = [[0.0, 0.0], [0.25, 0.0]]", "probes = [[0.01, 0.0]]", "not a vertex"),
])
def test_bad_mesh_plate_scene_one_line_nothing_written(tmp_path, capsys, old, new, word):
    assert old in DISK
    files = {"plate_disk.msh": example("plate_disk").with_suffix(".msh").read_bytes(),
             "garbage.msh": "not a mesh\n", "disk.toml": DISK.replace(old, new)}
    assert_scene_refused(tmp_path, capsys, files, "disk.toml", word)


def test_an_unknown_boundary_lists_the_mesh_names(tmp_path):
    write_msh(disk(1.0, 2), tmp_path / "d.msh")
    with pytest.raises(InputError) as refused:
        MeshPlate(read_plate_mesh(tmp_path / "d.msh"), edges={"left": "clamped"})
    assert "'left'" in str(refused.value) and "rim" in str(refused.value)


def test_a_rectangle_edge_name_is_still_refused_by_name(tmp_path, capsys):
    text = example("plate_on_stops").read_text().replace('left = "clamped"', 'rim = "clamped"')
    assert_scene_refused(tmp_path, capsys, {"p.toml": text}, "p.toml",
                         "left, right, bottom, top")


# --resume and the mesh file: the run stores its bytes (summary.json config
# scene_meshes: path as written → sha256, base64) and a resume builds from them.
SHORT, LONG = "0.002", "0.004"


def _disk_scene(folder):
    """The shipped plate_disk scene and its mesh copied into ``folder``."""
    folder.mkdir()
    shipped = example("plate_disk")
    (folder / "plate_disk.toml").write_text(shipped.read_text())
    (folder / "plate_disk.msh").write_bytes(shipped.with_suffix(".msh").read_bytes())
    return folder / "plate_disk.toml"


@pytest.fixture(scope="module")
def disk_runs(tmp_path_factory):
    """The disk scene run to SHORT (to be resumed) and to LONG (never stopped)."""
    from conftest import exit_code
    base = tmp_path_factory.mktemp("disk_runs")
    scene = _disk_scene(base / "src")
    short, whole = base / "short", base / "whole"
    assert exit_code(run_main, [str(scene), "--set", f"time.T={SHORT}", "--out",
                                str(short)]) == 0
    assert exit_code(run_main, [str(scene), "--set", f"time.T={LONG}", "--out",
                                str(whole)]) == 0
    return short, whole


def _copy_run(short, tmp_path):
    """The short run's folder and its scene copied (the scene where the run names it)."""
    import shutil
    scene = _disk_scene(tmp_path / "src")
    run = tmp_path / "run"
    shutil.copytree(short, run)
    _edit_config(run, lambda c: c.update(scene=str(scene), out=str(run)))
    return scene, run


def _edit_config(run, edit):
    """``edit`` the stored config in summary.json and in the checkpoint (as a folder an
    older version wrote, or one whose stored copy was lost)."""
    import json
    from skfem_beam.output.checkpoint import read_checkpoint, write_checkpoint
    summary = json.loads((run / "summary.json").read_text())
    edit(summary["config"])
    (run / "summary.json").write_text(json.dumps(summary))
    ck = read_checkpoint(run)
    config = ck.pop("config")
    edit(config)
    write_checkpoint(run / "checkpoint.npz", {k: v for k, v in ck.items()
                                              if k not in ("sha256", "format")}, config)


def _same_as_whole(run, whole):
    for name in ("timeseries.csv", "impacts.csv"):
        assert (run / name).read_bytes() == (whole / name).read_bytes(), name


def test_resume_builds_the_plate_from_the_stored_mesh_not_the_scene_folder(
        disk_runs, tmp_path, capsys):
    import base64
    import hashlib
    import json
    from conftest import exit_code
    short, whole = disk_runs
    scene, run = _copy_run(short, tmp_path)
    shipped = example("plate_disk").with_suffix(".msh").read_bytes()
    stored = json.loads((run / "summary.json").read_text())["config"]["scene_meshes"]
    assert list(stored) == ["plate_disk.msh"]
    assert base64.b64decode(stored["plate_disk.msh"]["base64"]) == shipped
    assert stored["plate_disk.msh"]["sha256"] == hashlib.sha256(shipped).hexdigest()
    (scene.parent / "plate_disk.msh").rename(tmp_path / "moved.msh")    # moved away
    capsys.readouterr()
    assert exit_code(run_main, ["--resume", str(run), "--T", LONG]) == 0
    assert "notice" not in capsys.readouterr().err
    _same_as_whole(run, whole)
    # the extended run stores the copy again: it resumes without the scene's folder too
    config = json.loads((run / "summary.json").read_text())["config"]
    assert config["scene_meshes"] == stored and config["T"] == float(LONG)


def test_a_folder_without_the_stored_mesh_reads_the_scene_folder_with_a_notice(
        disk_runs, tmp_path, capsys):
    from conftest import exit_code
    short, whole = disk_runs
    scene, run = _copy_run(short, tmp_path)
    _edit_config(run, lambda c: c.pop("scene_meshes"))        # as written before
    capsys.readouterr()
    assert exit_code(run_main, ["--resume", str(run), "--T", LONG]) == 0
    notices = [line for line in capsys.readouterr().err.splitlines() if "notice" in line]
    assert len(notices) == 1 and "plate_disk.msh" in notices[0], notices
    _same_as_whole(run, whole)


def _one_line_refusal(run, capsys, words):
    from conftest import exit_code
    before = {p.name: p.read_bytes() for p in run.iterdir() if p.is_file()}
    capsys.readouterr()
    assert exit_code(run_main, ["--resume", str(run), "--T", LONG]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and all(w in err for w in words), err
    assert {p.name: p.read_bytes() for p in run.iterdir() if p.is_file()} == before


def test_a_changed_mesh_file_is_refused_in_one_line(disk_runs, tmp_path, capsys):
    """The stored copy lost (its sha256 kept) and the scene's mesh file changed: refused,
    naming the file; the run's folder unchanged."""
    short, _ = disk_runs
    scene, run = _copy_run(short, tmp_path)
    _edit_config(run, lambda c: c["scene_meshes"]["plate_disk.msh"].pop("base64"))
    mesh = scene.parent / "plate_disk.msh"
    mesh.write_text(mesh.read_text().replace("2 8.3333333333333329e-02", "2 8.4e-02", 1))
    _one_line_refusal(run, capsys, [str(mesh), "differs", "sha256"])


def test_an_older_folder_with_another_mesh_is_refused_in_one_line(disk_runs, tmp_path,
                                                                   capsys):
    """No sha256 recorded (a folder written before): the summary's vertices, triangles
    and box are what the mesh is checked against."""
    short, _ = disk_runs
    scene, run = _copy_run(short, tmp_path)
    _edit_config(run, lambda c: c.pop("scene_meshes"))
    write_msh(disk(0.5, 4), scene.parent / "plate_disk.msh")
    _one_line_refusal(run, capsys, ["plate_disk.msh", "vertices"])


def test_a_binary_mesh_file_is_stored_and_read_back_exactly(tmp_path):
    """A binary gmsh file's bytes round-trip through the stored copy (base64): the scene
    built from the copy, the file gone, is the same plate."""
    m = disk(0.5, 3)
    points = np.column_stack([m.points.T, np.zeros(m.points.shape[1])])
    tags = [np.full(m.triangles.shape[1], 2), np.full(m.boundaries["rim"].shape[1], 1)]
    meshio.write(tmp_path / "bin.msh", meshio.Mesh(
        points, [("triangle", m.triangles.T), ("line", m.boundaries["rim"].T)],
        cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags},
        field_data={"rim": np.array([1, 1]), "plate": np.array([2, 2])}),
        file_format="gmsh22", binary=True)
    raw = (tmp_path / "bin.msh").read_bytes()
    assert b"\0" in raw                                     # binary indeed
    (tmp_path / "s.toml").write_text(DISK.replace("plate_disk.msh", "bin.msh"))
    first = load(tmp_path / "s.toml", dynamic=False)
    (tmp_path / "bin.msh").unlink()
    again = load(tmp_path / "s.toml", dynamic=False, meshes=first.meshes)
    assert again.meshes == first.meshes
    a, b = first.problem.space.plate.mesh, again.problem.space.plate.mesh
    assert np.array_equal(a.points, b.points) and np.array_equal(a.triangles, b.triangles)
    assert a.source == b.source == "bin.msh"


def _disk_with(change: str):
    """The 6-ring disk with one fault: a triangle listed twice, a triangle on an interior
    edge (three at that edge), one folded onto a rim edge's inner side, a NaN point."""
    d = disk(0.5, 6)
    p, t = d.points, d.triangles
    rim = d.boundaries["rim"][:, 0]
    if change == "repeated":
        t = np.column_stack([t, t[:, 5]])
    elif change == "three":     # one more triangle on triangle 0's first edge, an inner one
        edge = t[:2, 0]
        p = np.column_stack([p, 3.0 * p[:, edge].mean(axis=1)])
        t = np.column_stack([t, [edge[0], edge[1], p.shape[1] - 1]])
    elif change == "folded":    # a rim edge's second triangle, inside the disk
        p = np.column_stack([p, 0.9 * p[:, rim].mean(axis=1)])
        t = np.column_stack([t, [rim[0], rim[1], p.shape[1] - 1]])
    else:
        p = p.copy()
        p[0, t[0, 0]] = np.nan
    return type(d)(p, t, d.boundaries)


@pytest.mark.parametrize("change, word", [
    ("repeated", "triangle 216 repeats triangle 5 (1 repeated)"),
    ("three", "share the edge"),
    ("folded", "overlap (both on one side of their edge"),
    ("nan", "has a non-finite coordinate (nan, "),
])
def test_overlapping_triangles_and_non_finite_points_are_refused(tmp_path, capsys, change,
                                                                 word):
    """They were accepted (overlaps assembled twice: another plate, silently) or refused
    for another reason (a NaN point: "dt ... outside floating-point range")."""
    d = _disk_with(change)
    name = "bad.vtu" if change == "nan" else "bad.msh"
    if change == "nan":     # written by meshio itself, NaN as it is
        meshio.write(tmp_path / name, meshio.Mesh(
            np.vstack([d.points, np.zeros(d.points.shape[1])]).T,
            [("triangle", d.triangles.T)]))
    else:
        write_msh(d, tmp_path / name)
    scene = DISK.replace("plate_disk.msh", name)
    assert_scene_refused(tmp_path, capsys, {name: (tmp_path / name).read_bytes(),
                                            "plate.toml": scene}, "plate.toml", word)


def _two_disks(degenerate: bool):
    """The 6-ring disk and, beside it, a second disk no edge names (unsupported), or (with
    ``degenerate``) the disk with one more triangle of no area (a repeated point)."""
    d = disk(0.5, 6)
    if degenerate:
        p = np.column_stack([d.points, d.points[:, :1]])
        t = np.column_stack([d.triangles, [0, 1, p.shape[1] - 1]])
    else:
        p = np.column_stack([d.points, d.points + [[2.0], [0.0]]])
        t = np.column_stack([d.triangles, d.triangles + d.points.shape[1]])
    return type(d)(p, t, {"rim": d.boundaries["rim"]})


@pytest.mark.parametrize("degenerate, scene, word", [
    # a repeated point: two vertices at one place, a seam that was never merged
    (True, DISK, "has 1 pair(s) of coincident vertices (the first at (0, 0)): a seam"),
    # the scene's static start of a plate whose second part nothing holds (energy_J[0] was
    # 9e13 J, then "unstable")
    (False, DISK, "a static deflection needs edges that hold the plate"),
])
def test_a_mesh_of_a_flat_triangle_or_an_unheld_part_is_refused(tmp_path, capsys, degenerate,
                                                                 scene, word):
    write_msh(_two_disks(degenerate), tmp_path / "two.msh")
    scene = scene.replace("plate_disk.msh", "two.msh")
    assert "two.msh" in scene
    assert_scene_refused(tmp_path, capsys, {"two.msh": (tmp_path / "two.msh").read_bytes(),
                                            "plate.toml": scene}, "plate.toml", word)


def test_a_folder_named_as_the_mesh_file_is_called_a_folder(tmp_path):
    (tmp_path / "dir.msh").mkdir()
    with pytest.raises(InputError, match="dir.msh: a folder, not a file"):
        read_plate_mesh(tmp_path / "dir.msh")


def test_what_a_mesh_file_would_lose_or_misplace_is_refused(tmp_path):
    """From a user pass: quads beside the triangles were left out (holes in the plate: a
    clamped square's ω₁ 564 → 1,024 rad/s); a disk moved 50 m off the origin lost digits
    in Argyris' global monomials (ω₁ 33 % off), silently."""
    import meshio
    from skfem_beam.plate import MeshPlate, plate_space
    d = disk(0.5, 2)
    path = tmp_path / "mixed.vtu"
    quad = np.array([[0, 1, 2, 3]])
    meshio.write(path, meshio.Mesh(np.column_stack([d.points.T, 0 * d.points[0]]),
                                   [("triangle", d.triangles.T), ("quad", quad)]))
    with pytest.raises(InputError, match="holds 1 quad cell.s. beside its triangles"):
        read_plate_mesh(path)
    far = type(d)(d.points + [[50.0], [0.0]], d.triangles, d.boundaries)
    with pytest.raises(InputError, match="lies up to 50.5 m from the origin, 50.5 times"):
        plate_space(MeshPlate(far, edges={"rim": "clamped"}, element="argyris"))
    plate_space(MeshPlate(far, edges={"rim": "clamped"}, element="morley"))   # its basis is local
