"""Moved to :mod:`skfem_beam.output.render` (this name is kept as an alias)."""
from .output.render import animate, render_beam  # noqa: F401
