"""skfem_beam: beams and bars vibrating between obstacles, contact-implicit β-schemes."""
import sys as _sys

if _sys.argv[:1] == ["-m"]:   # a command starting (runpy is importing it): Ctrl-C during
    from ._startup import command_starting   # the imports is one line and exit 130,
    command_starting()                        # until the command's own handlers take over
from ._startup import numba_cache as _numba_cache
_numba_cache()      # before the kernels' modules: numba needs a writable cache folder
if _sys.argv[:1] == ["-m"]:   # a command compiles without two of numba's idle costs
    from . import numba_speed as _numba_speed
    _numba_speed.apply()
from .errors import InputError, SolverError
from .modes import Modes, modes
from .problem import (Beam, BeamProblem, Damping, InitialState, Load, Material, Obstacles,
                      Plane, Section, Support)
from .results import SavedRun, read_run
from .scheme import Result, Stepping, solve
from .semidiscrete import SemiDiscrete, beam_system
from ._version import __version__

__all__ = ["Beam", "BeamProblem", "Damping", "InitialState", "InputError", "Load",
           "Material", "Modes", "Obstacles", "Plane", "Result", "SavedRun", "Section",
           "SemiDiscrete", "SolverError", "Stepping", "Support", "beam_system", "modes", "read_run", "solve"]
