"""Nothing below output reaches into kernel state (issue #38): outside skfem_beam/scheme/
no module reads a run's ``.st`` (the compiled loop's State) or ``.ops`` (its Ops); they
read ``Run.record`` (scheme/run.py ``Record``), the saved series and ``impact_events``.

An AST scan of the package: an attribute ``st`` or ``ops`` of anything but ``self`` (an
object's own field of that name, as output/plate.py's curvature operators, is its own),
and ``getattr``/``hasattr``/``setattr`` with the name "st" or "ops".
"""
from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).parents[1]
PACKAGE = ROOT / "skfem_beam"
KERNEL_STATE = {"st", "ops"}
ATTRIBUTE_CALLS = {"getattr", "hasattr", "setattr", "delattr"}


def reaches(source: str) -> list[int]:
    """The lines of ``source`` that read a run's kernel state (one per access)."""
    lines = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Attribute) and node.attr in KERNEL_STATE and not (
                isinstance(node.value, ast.Name) and node.value.id == "self"):
            lines.append(node.lineno)
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
              and node.func.id in ATTRIBUTE_CALLS and len(node.args) > 1
              and isinstance(node.args[1], ast.Constant)
              and node.args[1].value in KERNEL_STATE):
            lines.append(node.lineno)
    return sorted(lines)


def outside_scheme() -> list[Path]:
    return [p for p in sorted(PACKAGE.rglob("*.py"))
            if p.relative_to(PACKAGE).parts[0] != "scheme"]


def test_the_scan_sees_every_form():
    """The scanner finds the forms this issue removed (so a pass below means something)."""
    source = ("w = run.st.rowwork\n"
              "n = int(run.st.counters[CONTACT_STEPS])\n"
              "if not hasattr(run.st, 'fres'): pass\n"
              "f = lam @ row_planes(run.ops.pair, run.ops.Nc)\n"
              "s = getattr(self.run, 'st')\n"
              "x = self.run.scheme.st.fc\n"
              "self.ops = curvature_operators(space)\n")     # an object's own: not counted
    assert reaches(source) == [1, 2, 3, 4, 4, 5, 6]


def test_nothing_outside_scheme_reads_kernel_state():
    files = outside_scheme()
    assert len(files) > 80, len(files)          # the scan covers the package, not a corner
    found = [f"{p.relative_to(ROOT).as_posix()}:{line}" for p in files
             for line in reaches(p.read_text())]
    print("\n".join(found))
    assert len(found) == 0, found

