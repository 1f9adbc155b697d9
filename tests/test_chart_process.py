"""The charts a command draws beside its run (skfem_beam.chart_process): the same pictures
as drawn in the command, its errors raised in the command, nothing left behind when the
command is killed, and a process that dies is replaced by drawing in the command."""
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from conftest import exit_code
from skfem_beam import chart_process
from skfem_beam._startup import CHART_MODULES
from skfem_beam.aside import cores
from skfem_beam.cases import flat_obstacles
from skfem_beam.output.charts import trajectory_chart

pytestmark = pytest.mark.usefixtures("charts")
ARGS = ["--T", "0.2", "--J", "8", "--format", "none"]
CHARTS = ("tip_displacement.png", "energy.png", "contact_force.png", "beam_shapes.png")


def pixels(path: Path) -> np.ndarray:
    return np.asarray(Image.open(path), dtype=float)


def servers(parent: int) -> list[int]:
    """The pids of the chart processes serving ``parent`` (their argv names it)."""
    found = []
    for proc in Path("/proc").iterdir():
        try:
            argv = (proc / "cmdline").read_bytes().split(b"\0")
        except OSError:
            continue
        if b"skfem_beam.chart_process" in b" ".join(argv) and str(parent).encode() in argv:
            found.append(int(proc.name))
    return found


def test_with_charts_off_a_command_draws_none_starts_no_process_and_keeps_no_old_one(
        tmp_path, monkeypatch):
    """SKFEM_BEAM_CHARTS=0: no picture and no chart process; a folder run again loses the
    pictures of its earlier run (they would not show this one)."""
    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "skfem_beam.cases.flat_obstacles", *ARGS, "--out", str(out)]
    assert subprocess.run(cmd, capture_output=True).returncode == 0
    assert all((out / name).exists() for name in CHARTS)
    monkeypatch.setenv(chart_process.CHARTS, "0")
    p = subprocess.Popen([*cmd, "--overwrite"], stderr=subprocess.PIPE)
    started = set()
    while p.poll() is None:             # looked for over the command's whole life
        started.update(servers(p.pid))
        time.sleep(0.05)
    assert p.returncode == 0, p.stderr.read()
    assert not started and not any((out / name).exists() for name in CHARTS)
    assert (out / "timeseries.csv").exists()


@pytest.fixture
def process():
    """A chart process for this test process, stopped after it."""
    chart_process.start(CHART_MODULES)
    assert chart_process.running()
    yield chart_process
    chart_process.stop()
    chart_process._process = None


def test_a_command_draws_in_its_chart_process_the_pictures_drawn_in_it(tmp_path):
    """``python -m`` draws in the chart process, ``main()`` here: the same pixels."""
    p = subprocess.run([sys.executable, "-m", "skfem_beam.cases.flat_obstacles", *ARGS,
                        "--out", str(tmp_path / "command")], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert not chart_process.running()
    assert flat_obstacles.main([*ARGS, "--out", str(tmp_path / "here")]) == 0
    for name in CHARTS:
        a, b = pixels(tmp_path / "command" / name), pixels(tmp_path / "here" / name)
        assert a.shape == b.shape and np.abs(a - b).max() == 0.0, name


def test_the_chart_process_loads_matplotlib_and_not_the_package(process):
    """Its charts need numpy and matplotlib only: none of numba, scipy, scikit-fem, h5py
    (~100 MB and 0.5 s of imports the package's __init__ would cost it)."""
    process.draw(exec, "import sys\n"
                 "loaded = {'numba', 'scipy', 'skfem', 'h5py', 'meshio'} & set(sys.modules)\n"
                 "assert 'matplotlib.pyplot' in sys.modules and not loaded, loaded")
    process.wait()


def test_each_chart_is_drawn_in_a_child_of_the_single_threaded_chart_process(tmp_path, process):
    """The chart process has one thread (BLAS's workers are off), so it forks its workers,
    one per core; two charts are drawn by two of them (one on one core), never by the chart
    process."""
    server = process._process.pid
    for name in ("a", "b"):
        process.draw(exec, f"import os; open({str(tmp_path / name)!r}, 'w').write(str(os.getpid()))")
    process.wait()
    drawers = {int((tmp_path / name).read_text()) for name in ("a", "b")}
    assert len(os.listdir(f"/proc/{server}/task")) == 1
    assert len(drawers) == min(2, cores()) and server not in drawers


def test_a_chart_whose_child_died_is_drawn_again_by_the_chart_process(tmp_path, process):
    server = process._process.pid
    process.draw(exec, f"import os\nif os.getpid() != {server}: os._exit(1)\n"
                       f"open({str(tmp_path / 'drawn')!r}, 'w').write(str(os.getpid()))")
    process.wait()
    assert (tmp_path / "drawn").read_text() == str(server)


def test_charts_are_drawn_when_every_worker_died_while_idle(tmp_path, process):
    """Workers killed between charts: each chart sent to a dead one is drawn by the chart
    process and that worker is dropped, so that no chart waits for a worker that is gone."""
    server = process._process.pid
    time.sleep(2)                       # its workers forked (matplotlib loaded)
    children = Path(f"/proc/{server}/task/{server}/children").read_text().split()
    assert len(children) == cores()
    for pid in children:
        os.kill(int(pid), signal.SIGKILL)
    time.sleep(0.2)
    t = np.linspace(0, 1, 11)
    for k in range(len(children) + 2):
        process.draw(trajectory_chart, tmp_path / f"{k}.png", t, {"y": t})
    waiter = threading.Thread(target=process.wait, daemon=True)
    waiter.start()
    waiter.join(timeout=60)
    assert not waiter.is_alive(), "a chart waits for a dead worker"
    assert all((tmp_path / f"{k}.png").stat().st_size > 0 for k in range(len(children) + 2))


def test_a_chart_error_is_raised_in_the_command_with_its_errno(tmp_path, process):
    t = np.linspace(0, 1, 11)
    process.draw(trajectory_chart, tmp_path / "no such folder" / "x.png", t, {"y": t})
    process.draw(trajectory_chart, tmp_path / "drawn.png", t, {"y": t})
    with pytest.raises(FileNotFoundError) as e:
        process.wait()
    assert "in the chart process" in "".join(getattr(e.value, "__notes__", []))
    assert (tmp_path / "drawn.png").stat().st_size > 0     # the next chart is still drawn


def test_a_chart_larger_than_the_pipe_does_not_hold_the_command(tmp_path, process):
    """While the chart process is busy (stopped here), ``draw`` of a chart whose data
    (4 MB) exceed the pipe (1 MiB) returns at once: a thread writes it, and the command
    goes on writing its fields; the chart is drawn once the process reads it."""
    t = np.linspace(0, 1, 125_001)
    os.kill(process._process.pid, signal.SIGSTOP)
    try:
        sender = threading.Thread(target=process.draw, args=(
            trajectory_chart, tmp_path / "big.png", t, {f"y{k}": t * k for k in range(3)}))
        sender.start()
        sender.join(timeout=30)
        assert not sender.is_alive(), "draw() waited for the stopped chart process"
    finally:
        os.kill(process._process.pid, signal.SIGCONT)
    process.wait()
    assert (tmp_path / "big.png").stat().st_size > 0 and not process._pending


def test_charts_of_a_process_that_died_are_drawn_here(tmp_path, process):
    t = np.linspace(0, 1, 11)
    os.kill(process._process.pid, signal.SIGSTOP)   # it takes the job but draws nothing
    process.draw(trajectory_chart, tmp_path / "a.png", t, {"y": t})
    process._process.kill()
    process.wait()
    assert (tmp_path / "a.png").stat().st_size > 0 and not process._pending
    process.draw(trajectory_chart, tmp_path / "b.png", t, {"y": t})   # no process: here
    assert (tmp_path / "b.png").stat().st_size > 0


def test_a_killed_command_leaves_no_chart_process(tmp_path):
    """SIGKILL at the run's last chunk (SKFEM_BEAM_KILL_AT): its chart process goes with
    it (PR_SET_PDEATHSIG), as it does when the command ends normally."""
    for kill_at, code in (("last-chunk", -signal.SIGKILL), (None, 0)):
        env = {**os.environ, **({"SKFEM_BEAM_KILL_AT": kill_at} if kill_at else {})}
        p = subprocess.Popen([sys.executable, "-m", "skfem_beam.cases.flat_obstacles", *ARGS,
                              "--out", str(tmp_path / str(kill_at))], env=env,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(0.3)
        assert servers(p.pid), "the command started no chart process"
        assert p.wait(timeout=120) == code
        deadline = time.monotonic() + 5
        while servers(p.pid) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert servers(p.pid) == [], kill_at


def test_commands_that_draw_no_chart_start_no_process():
    """Only the scenes (``skfem_beam.cases.*``) and ``python -m skfem_beam run`` draw charts."""
    code = ("import sys; sys.orig_argv = [sys.executable, '-m', *sys.orig_argv[3:]]; "
            "from skfem_beam import _startup, chart_process; _startup.command_starting(); "
            "print(chart_process.running()); chart_process.stop()")
    for command, expected in (("skfem_beam.cases.point_stops --T 1", "True"),
                              ("skfem_beam run scene.toml", "True"),
                              ("skfem_beam.sweep", "False"), ("skfem_beam export DIR", "False")):
        p = subprocess.run([sys.executable, "-c", code, *command.split()], capture_output=True,
                           text=True, timeout=60)
        assert p.stdout.strip() == expected, (command, p.stdout, p.stderr)


def test_every_chart_a_command_sends_is_a_function_of_the_modules_the_process_loads():
    """A chart whose function lives elsewhere makes its worker import that module when the
    job is unpickled (the plate's deflection chart in output/plate.py: scikit-fem and scipy,
    0.7 s on the run's last chart)."""
    import ast
    import importlib
    package = Path(chart_process.__file__).parent
    loaded = [importlib.import_module(m) for m in CHART_MODULES]
    sent = set()
    for path in package.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "draw" \
                    and node.args and isinstance(node.args[0], ast.Name):
                sent.add((path.name, node.args[0].id))
    assert len(sent) >= 8, sent
    for where, name in sent:
        assert any(hasattr(m, name) for m in loaded), (where, name)


@pytest.mark.parametrize("value", ["no", "false", "2", ""])
def test_a_bad_charts_value_is_one_line_and_nothing_written(tmp_path, monkeypatch, capsys,
                                                             value):
    """SKFEM_BEAM_CHARTS takes 0 or 1: another value is one line naming it, exit 2 and no
    folder, from the command line (as it starts) and from a command's main()."""
    monkeypatch.setenv(chart_process.CHARTS, value)
    out = tmp_path / "run"
    p = subprocess.run([sys.executable, "-m", "skfem_beam.cases.flat_obstacles", *ARGS,
                        "--out", str(out)], capture_output=True, text=True)
    assert p.returncode == 2 and not out.exists(), p.stderr
    err = p.stderr.strip().splitlines()
    assert len(err) == 1 and f"SKFEM_BEAM_CHARTS={value!r}" in err[0] and "0" in err[0], err
    assert exit_code(flat_obstacles.main, [*ARGS, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"SKFEM_BEAM_CHARTS={value!r}" in err[0] and not out.exists()
    for command in (["skfem_beam.cases.flat_obstacles"], ["skfem_beam", "run"]):
        p = subprocess.run([sys.executable, "-m", *command, "--help"], capture_output=True,
                           text=True)      # --help draws nothing: it is shown
        assert p.returncode == 0 and p.stdout.startswith("usage:") and not p.stderr, p
