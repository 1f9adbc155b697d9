"""The one output pipeline every command writes through (commands → output → scheme).

- :mod:`.folder`: the output folder, checked before it is made, and its summary status;
- :mod:`.series`: a run streamed to ``timeseries.csv`` and field files, checkpoints, resume;
- :mod:`.fields`: field time series for ParaView (XDMF, VTU);
- :mod:`.charts`: matplotlib charts, from data in memory;
- :mod:`.render`: pyvista pictures and animations of a run.
"""
from .folder import Folder, check_output_dir, report, stamp, write_summary  # noqa: F401
from .series import Series, execute, prepare  # noqa: F401
