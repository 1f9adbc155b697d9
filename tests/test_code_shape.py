"""No function over 60 lines or over 8 parameters (issue #38, "One home for every idea").

An AST walk of skfem_beam/.  Exempt: numba-compiled functions (a decorator that is
numba's ``njit``/``jit``/``cfunc``, the contact laws' ``compiled_law`` /
``compiled_explicit``, or a module's alias of one, such as ``internal = njit(...)``), and
the allow-lists below, each with its reason.  ``self``/``cls`` are not counted; ``*args``
and ``**kwargs`` count one each.
"""
from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).parents[1]
PACKAGE = ROOT / "skfem_beam"
MAX_LINES = 60
MAX_PARAMETERS = 8
MAX_COMPILED_PARAMETERS = 12    # the compiled kernels too have a ceiling

# decorators that compile the function they wrap
COMPILERS = {"njit", "jit", "cfunc", "vectorize", "guvectorize", "compiled_law",
             "compiled_explicit"}

# (path under skfem_beam/, function name): why it may be longer than MAX_LINES
LONG: dict = {}

# (path under skfem_beam/, function name): why it may take more than MAX_PARAMETERS
WIDE = {
    # the QP calling convention (contact.base): the engines' exact finish takes the
    # Delassus system, the box, the engine's duals and the law's outputs as they come
    ("contact/active_set.py", "exact_finish"): "QP calling convention (D, yf, lo, hi, "
                                               "duals, state, mu, scale, engine, tol)",
    ("contact/active_set.py", "repair"): "QP calling convention (exact_finish's tail)",
}


def _name(node) -> str | None:
    """The bare name a decorator or a call is made of: njit, njit(...), numba.njit."""
    if isinstance(node, ast.Call):
        node = node.func
    if isinstance(node, ast.Attribute):
        return node.attr
    if isinstance(node, ast.Name):
        return node.id
    return None


def _compilers(tree) -> set[str]:
    """COMPILERS and this module's aliases of them (``internal = njit(cache=True)``)."""
    names = set(COMPILERS)
    for node in tree.body:
        if isinstance(node, ast.Assign) and _name(node.value) in COMPILERS:
            names |= {t.id for t in node.targets if isinstance(t, ast.Name)}
    return names


def _parameters(f) -> int:
    a = f.args
    names = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs]
    return len([n for n in names if n not in ("self", "cls")]) + bool(a.vararg) \
        + bool(a.kwarg)


def _defs(node, prefix=""):
    """(qualified name, node) of every function under ``node``: Class.method, outer.inner."""
    for child in ast.iter_child_nodes(node):
        if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            name = prefix + child.name
            if not isinstance(child, ast.ClassDef):
                yield name, child
            yield from _defs(child, name + ".")
        else:
            yield from _defs(child, prefix)


def functions(compiled_too: bool = False):
    """(path under skfem_beam/, qualified name, line, lines, parameters) of every
    function not compiled by numba (``compiled_too``: of every function)."""
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text())
        compiled = _compilers(tree)
        rel = path.relative_to(PACKAGE).as_posix()
        for name, f in _defs(tree):
            if not compiled_too and any(_name(d) in compiled for d in f.decorator_list):
                continue
            yield rel, name, f.lineno, f.end_lineno - f.lineno + 1, _parameters(f)


def test_no_function_over_60_lines():
    long = [f"{p}:{line} {name} ({n} lines)" for p, name, line, n, _ in functions()
            if n > MAX_LINES and (p, name) not in LONG]
    print("\n".join(long))
    assert not long, long


def test_no_function_over_8_parameters():
    wide = [f"{p}:{line} {name} ({k} parameters)" for p, name, line, _, k in functions()
            if k > MAX_PARAMETERS and (p, name) not in WIDE]
    print("\n".join(wide))
    assert not wide, wide


def test_allow_lists_name_real_offenders():
    """An entry whose function is gone or now fits is dropped, so the lists stay true."""
    found = {(p, name): (n, k) for p, name, _, n, k in functions()}
    stale = [key for key in LONG if found.get(key, (0, 0))[0] <= MAX_LINES]
    stale += [key for key in WIDE if found.get(key, (0, 0))[1] <= MAX_PARAMETERS]
    print("\n".join(map(str, stale)))
    assert not stale, stale


def test_no_function_at_all_over_12_parameters():
    wide = [f"{p}:{line} {name} ({k} parameters)" for p, name, line, _, k
            in functions(compiled_too=True) if k > MAX_COMPILED_PARAMETERS]
    print("\n".join(wide))
    assert not wide, wide
