"""The repository explains itself and keeps its shape (issue "One clear shape")."""
import ast
import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).parents[1]
MAX_PARAMETERS = 12


def tracked(*patterns):
    out = subprocess.run(["git", "ls-files", *patterns], cwd=ROOT, capture_output=True,
                         text=True, check=True).stdout.split()
    return [ROOT / p for p in out if (ROOT / p).is_file()]


def test_no_function_takes_more_than_twelve_parameters():
    wide = []
    for path in (ROOT / "skfem_beam").rglob("*.py"):
        for f in ast.walk(ast.parse(path.read_text())):
            if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef)):
                a = f.args
                names = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs]
                n = len(names) + bool(a.vararg) + bool(a.kwarg) \
                    - (bool(names) and names[0] in ("self", "cls"))
                if n > MAX_PARAMETERS:
                    wide.append(f"{path.relative_to(ROOT)}:{f.lineno} {f.name} ({n})")
    assert not wide, wide


def test_no_file_cites_a_document_outside_the_repository():
    cites = []
    outside = re.compile(r"\bDESIGN\b|\.\./shared|shared/seeds")
    for path in tracked("*.py", "*.md", "*.ipynb", "*.toml", ".ci/*"):
        if path.name == "test_repository.py":
            continue
        for m in outside.finditer(path.read_text(errors="replace")):
            cites.append(f"{path.relative_to(ROOT)}: {m.group()}")
    assert not cites, cites
    assert (ROOT / "docs" / "design.md").is_file()


def test_every_cited_repository_path_exists():
    # a docstring or a doc page that sends its reader to a test or a module names a file
    # that is there (a docstring once named a test file that never existed; NAME.toml
    # and other capitalised placeholders are not paths)
    cited = re.compile(r"\b((?:tests|skfem_beam|docs|notebooks|meshes)/[\w/.-]+\.(?:py|md|toml"
                       r"|ipynb|rst|txt|json))\b")
    missing = []
    for path in tracked("*.py", "*.md", "*.rst", "*.toml", ".ci/*"):
        if path.name == "test_repository.py":
            continue
        for m in cited.finditer(path.read_text(errors="replace")):
            placeholder = re.search(r"/[A-Z]+\.\w+$", m.group(1))
            if not placeholder and not (ROOT / m.group(1)).exists():
                missing.append(f"{path.relative_to(ROOT)}: {m.group(1)}")
    assert not missing, missing
