"""``python -m skfem_beam``: the list of commands, and the package's own subcommands.

    python -m skfem_beam                          # every command and scene, one line each
    python -m skfem_beam export DIR --to mat      # a run folder as one .mat / .npz file

The subcommands are the table ``COMMANDS``: name → Command(usage, one-line help,
"module:function"),
the function taking the remaining arguments and returning an exit code; the module is
imported only when its subcommand runs.  Adding a subcommand is one line, e.g.::

    "run": Command("SCENE.toml", "run the scene a TOML file describes", "skfem_beam.scenefile.commands:run_main"),
    "modes": Command("SCENE.toml", "its natural frequencies", "skfem_beam.scenefile.commands:modes_main"),

The list also shows the commands that are modules of their own (``python -m
skfem_beam.cases.<scene>``, ``skfem_beam.sweep``, ``skfem_beam.bench.<study>``), each with the
first paragraph of its docstring, read from the source without importing it.
An unknown subcommand gives one line on stderr and exit code 2.
"""
from __future__ import annotations

import ast
import importlib
import importlib.util
import pkgutil
import sys
from typing import NamedTuple

class Command(NamedTuple):
    usage: str       # the arguments, for the listing
    help: str        # one line
    target: str      # "module:function"; function(argv) -> exit code


COMMANDS = {
    "export": Command("DIR --to npz|mat [--out FILE]", "a run folder as one .npz or .mat "
                      "(MATLAB) file", "skfem_beam.results:export_main"),
    "run": Command("SCENE.toml [--out DIR] [--set KEY=VALUE ...]", "run the scene a TOML file describes", "skfem_beam.scenefile.commands:run_main"),
    "modes": Command("SCENE.toml [--n 6] [--out DIR]", "natural frequencies and mode shapes of its beam", "skfem_beam.scenefile.commands:modes_main"),
}
EXIT_INPUT = 2     # as skfem_beam.errors (not imported here: the listing stays instant)


def _first_line(module: str) -> str:
    """The first paragraph of ``module``'s docstring, from its source (nothing is imported)."""
    spec = importlib.util.find_spec(module)
    with open(spec.origin, encoding="utf-8") as fh:
        doc = ast.get_docstring(ast.parse(fh.read())) or ""
    return " ".join(doc.strip().split("\n\n")[0].split())     # its first paragraph


def modules(package: str) -> list[str]:
    """The public modules of ``package`` (names not starting with an underscore)."""
    pkg = importlib.util.find_spec(package)
    return [f"{package}.{m.name}" for m in pkgutil.iter_modules(pkg.submodule_search_locations)
            if not m.name.startswith("_") and not m.ispkg]


def listing() -> str:
    """Every command, one line each."""
    groups = [
        ("Scenes (python -m MODULE --help for the flags)", modules("skfem_beam.cases")),
        ("Sweeps", ["skfem_beam.sweep"]),
        ("Studies (docs/ charts and tables)", modules("skfem_beam.bench")
         + ["skfem_beam.plate.bench", "skfem_beam.plate.convergence"]),
        ("Tools", ["skfem_beam.meshes"]),
    ]
    rows = [(f"python -m {m}", _first_line(m)) for _, ms in groups for m in ms]
    rows += [(f"python -m skfem_beam {name} {c.usage}", c.help) for name, c in COMMANDS.items()]
    width = max(len(r[0]) for r in rows) + 2
    lines, k = [], 0
    for title, ms in groups + [("Subcommands of python -m skfem_beam", COMMANDS)]:
        lines.append(f"{title}:")
        for cmd, doc in rows[k:k + len(ms)]:
            lines.append(f"  {cmd:<{width}}{doc}")
        k += len(ms)
        lines.append("")
    return "\n".join(lines).rstrip() + "\n"


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if not argv or argv[0] in ("-h", "--help", "help"):
        print(listing(), end="")
        return 0
    name, rest = argv[0], argv[1:]
    if name not in COMMANDS:
        print(f"error: unknown command {name!r}; commands: {', '.join(COMMANDS)} "
              "(python -m skfem_beam lists them all)", file=sys.stderr)
        return EXIT_INPUT
    module, _, function = COMMANDS[name].target.partition(":")
    from .cli import main_guard
    main_guard(lambda: getattr(importlib.import_module(module), function)(rest))
    return 0   # main_guard exits with the command's code


if __name__ == "__main__":
    sys.exit(main())
