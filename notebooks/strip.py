"""Strip outputs from the notebooks before committing them.

    python notebooks/strip.py            # strip every notebooks/*.ipynb in place
    python notebooks/strip.py A.ipynb …  # strip the named notebooks
    python notebooks/strip.py --check    # exit 1 (and name them) if any has outputs

Clears outputs and execution counts of code cells and the per-cell and notebook metadata
a Jupyter session adds (execution timings, widget state, collapsed/scrolled flags); keeps
the kernelspec, so ``tests/test_notebooks.py`` can run them with the ``python3`` kernel.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import nbformat

HERE = Path(__file__).resolve().parent
KEEP_NOTEBOOK_METADATA = ("kernelspec", "language_info")


def strip(nb: nbformat.NotebookNode) -> nbformat.NotebookNode:
    """The notebook without outputs, execution counts or session metadata (in place)."""
    nb.metadata = nbformat.NotebookNode(
        {k: v for k, v in nb.metadata.items() if k in KEEP_NOTEBOOK_METADATA})
    if "language_info" in nb.metadata:     # a kernel adds its version, mimetype, …
        nb.metadata.language_info = nbformat.NotebookNode(
            name=nb.metadata.language_info.get("name", "python"))
    for cell in nb.cells:
        cell.metadata = nbformat.NotebookNode()
        if cell.cell_type == "code":
            cell.outputs = []
            cell.execution_count = None
    return nb


def is_stripped(nb: nbformat.NotebookNode) -> bool:
    return all(not c.get("outputs") and c.get("execution_count") is None
               for c in nb.cells if c.cell_type == "code")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("notebooks", nargs="*", type=Path,
                   help="notebooks to strip (default: every notebooks/*.ipynb)")
    p.add_argument("--check", action="store_true",
                   help="change nothing; exit 1 if a notebook has outputs or execution counts")
    args = p.parse_args(argv)
    paths = args.notebooks or sorted(HERE.glob("*.ipynb"))
    dirty = []
    for path in paths:
        nb = nbformat.read(path, as_version=4)
        if args.check:
            if not is_stripped(nb):
                dirty.append(path)
            continue
        before = nbformat.writes(nb)
        after = nbformat.writes(strip(nb))
        if after != before:
            nbformat.validate(nb)
            nbformat.write(nb, path)
            print(f"stripped {path}")
    if dirty:
        print("notebooks with outputs (run python notebooks/strip.py): "
              + ", ".join(str(p) for p in dirty), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
