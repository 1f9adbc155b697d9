"""Sphinx configuration of the documentation site (python -m sphinx -W -b html docs DIR).

Sphinx with MyST: the pages are the Markdown the repository already reads on GitHub, and
autodoc builds the API reference from the docstrings in the same build.  The scene-file
reference (docs/scene_keys.md) is rewritten from the code's key tables before the build
(skfem_beam.scenedocs), where it differs.
"""
import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

project = "skfem_beam"
author = "the skfem_beam developers"
extensions = ["myst_parser", "sphinx.ext.autodoc"]
source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "**/.ipynb_checkpoints"]
myst_heading_anchors = 3
html_theme = "alabaster"
html_title = "skfem_beam"
autodoc_member_order = "bysource"
autodoc_typehints = "none"
os.environ.setdefault("MPLBACKEND", "Agg")


def write_scene_keys(app) -> None:
    from skfem_beam.scenedocs import PAGE, page
    out = HERE.parent / PAGE
    text = page()
    if not out.is_file() or out.read_text() != text:
        out.write_text(text)


def setup(app):
    app.connect("builder-inited", write_scene_keys)
