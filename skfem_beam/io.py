"""Moved to :mod:`skfem_beam.output.folder` (this name is kept as an alias)."""
from .output.folder import (Folder, check_output_dir, csv_rows,  # noqa: F401
                            write_summary, write_timeseries)
