"""The one output pipeline every command writes through (commands → output → scheme).

- :mod:`.folder`: the output folder, checked before it is made, and its summary status;
- :mod:`.stream`: a run streamed to its folder (rows, field frames, checkpoints), and how it
  stops;
- :mod:`.series`: ``timeseries.csv``, written as the run goes and held for the charts;
- :mod:`.checkpoint`: checkpoints, and the checks of a resume;
- :mod:`.fields`: field time series for ParaView (XDMF, VTU);
- :mod:`.charts`: matplotlib charts, from data in memory;
- :mod:`.render`: pyvista pictures and animations of a run.
"""
from .folder import Folder, check_output_dir, report, stamp, write_summary  # noqa: F401
from .stream import Series, execute, prepare  # noqa: F401
