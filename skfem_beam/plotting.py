"""Moved to :mod:`skfem_beam.output.charts` (this name is kept as an alias)."""
from .output.charts import (compare_chart, energy_chart, figure,  # noqa: F401
                            penetration_chart, plt, shape_chart, trajectory_chart)
