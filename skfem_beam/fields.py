"""Moved to :mod:`skfem_beam.output.fields` (this name is kept as an alias)."""
from .output.fields import (FORMATS, FieldWriter, LineSamples, check_format,  # noqa: F401
                            lifting_dd, sample_line, write_fields)
