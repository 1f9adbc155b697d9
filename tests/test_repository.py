"""The repository explains itself and keeps its shape (issue "One clear shape")."""
import ast
import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).parents[1]


def tracked(*patterns):
    out = subprocess.run(["git", "ls-files", *patterns], cwd=ROOT, capture_output=True,
                         text=True, check=True).stdout.split()
    return [ROOT / p for p in out if (ROOT / p).is_file()]


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


def import_graph() -> dict[str, set[str]]:
    """skfem_beam's own modules → the modules of skfem_beam each imports, at module level
    or inside a function (a deferred import dodges a circle, it does not cut it).  ``from
    P import N`` is an edge to P.N when that is a module, else to P; relative imports are
    resolved; a package's ``__init__`` is the package's name."""
    package = ROOT / "skfem_beam"
    files = {}
    for path in package.rglob("*.py"):
        parts = path.relative_to(ROOT).with_suffix("").parts
        is_init = parts[-1] == "__init__"
        files[".".join(parts[:-1] if is_init else parts)] = (path, is_init)
    graph = {name: set() for name in files}

    def edge(source, target):
        while target and target not in files:       # a name inside a module: the module
            target = target.rpartition(".")[0]
        if target and target != source:
            graph[source].add(target)

    for name, (path, is_init) in files.items():
        here = name if is_init else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name.split(".")[0] == "skfem_beam":
                        edge(name, alias.name)
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = here.split(".")[:len(here.split(".")) - node.level + 1]
                    module = ".".join(base + ([node.module] if node.module else []))
                else:
                    module = node.module or ""
                if module.split(".")[0] != "skfem_beam":
                    continue
                for alias in node.names:
                    sub = f"{module}.{alias.name}"
                    edge(name, sub if sub in files else module)
    return graph


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of ``graph`` with more than one module (Tarjan)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_import_circle():
    """No module of skfem_beam imports, even inside a function, a module that imports it
    back through any chain: each layer imports only the ones below it (docs/design.md,
    "Layout and data flow").  A third-party library imported late is no circle."""
    graph = import_graph()
    assert "skfem_beam.scheme.kernels" in graph["skfem_beam.scheme.beta"]   # the graph is read
    found = circles(graph)
    assert not found, "\n".join(
        " ↔ ".join(c) + ": " + "; ".join(f"{a} → {b}" for a in c for b in sorted(graph[a])
                                          if b in c) for c in found)
