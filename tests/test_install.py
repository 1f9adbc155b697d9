"""What a run needs and what it does not: the base install runs every scene; a sweep on a
cluster and a render need their extras, and say which in one line."""
import subprocess
import sys

import pytest

from skfem_beam.errors import InputError

CHECK = """
import sys
from skfem_beam.cases import flat_obstacles, point_stops
from skfem_beam.scenefile import run_main
from skfem_beam.cli import main_guard
for argv, main in ((["--out", sys.argv[1] + "/a", "--format", "both"], flat_obstacles.main),
                   (["--out", sys.argv[1] + "/b", "--T", "0.05"], point_stops.main)):
    try:
        main_guard(lambda: main(argv))
    except SystemExit as e:
        assert e.code == 0, e.code
heavy = sorted(m for m in sys.modules if m.split(".")[0] in ("dask", "distributed", "pyvista",
                                                            "vtk", "vtkmodules", "imageio"))
print("extras:", " ".join(heavy))
"""


def test_a_run_imports_no_extra(tmp_path):
    out = subprocess.run([sys.executable, "-c", CHECK, str(tmp_path)], capture_output=True,
                         text=True, check=True).stdout.splitlines()[-1]
    assert out == "extras: "          # neither Dask nor PyVista, VTK or imageio


def test_a_scene_loads_no_writer_or_chart_library_before_its_loop():
    """meshio and h5py come with the loop (a thread imports them while the loop runs),
    matplotlib with the first chart (in the chart process): before its loop a command runs
    on one core (docs/design.md)."""
    code = ("import sys, skfem_beam.scenefile, skfem_beam.cases.flat_obstacles, "
            "skfem_beam.cases.point_stops, skfem_beam.cases.impacting_bar; "
            "print(sorted({'meshio', 'h5py', 'matplotlib'} & set(sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["[]"]


def test_a_missing_extra_is_named_in_one_line(monkeypatch):
    from skfem_beam.output import render
    from skfem_beam.sweep_cluster import dask_client
    monkeypatch.setitem(sys.modules, "pyvista", None)        # as if not installed
    with pytest.raises(InputError, match=r'pip install "skfem_beam\[render\]"'):
        render._pyvista()
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(InputError, match=r'pip install "skfem_beam\[cluster\]"'):
        with dask_client(scheduler="tcp://127.0.0.1:1"):
            pass


def test_numba_gets_a_cache_folder_where_nothing_else_is_writable(tmp_path, monkeypatch):
    """A shared read-only install run by an account without a writable HOME: numba found
    no cache locator and every command, --help included, was a traceback at import."""
    import os
    import tempfile
    from skfem_beam import _startup
    blocked = tmp_path / "file"
    blocked.write_text("")
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocked))     # cannot hold a folder
    monkeypatch.setattr(_startup.os, "access", lambda path, mode: False)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    import numba
    monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)  # restored after
    _startup.numba_cache()
    assert os.environ["NUMBA_CACHE_DIR"] == str(tmp_path / f"skfem_beam-numba-{os.getuid()}")
    assert numba.config.CACHE_DIR == os.environ["NUMBA_CACHE_DIR"]
    # a NUMBA_CACHE_DIR of the user's that cannot be written (a file here): one warning
    # line, and the same folder of the temporary directory
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(blocked / "sub"))
    _startup.numba_cache()
    assert os.environ["NUMBA_CACHE_DIR"] == str(tmp_path / f"skfem_beam-numba-{os.getuid()}")

