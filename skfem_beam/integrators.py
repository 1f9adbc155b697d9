"""Alias of :mod:`skfem_beam.scheme` (the name this module had before the redesign)."""
from .scheme import Result, Run, Stepping, drive, solve  # noqa: F401
