"""skfem_beam: beams and bars vibrating between obstacles, contact-implicit β-schemes."""
from .errors import InputError, SolverError
from .modes import Modes, modes
from .problem import (Beam, BeamProblem, Damping, InitialState, Load, Material, Obstacles,
                      Section, Support)
from .results import SavedRun, read_run
from .scheme import Result, Stepping, solve
from .semidiscrete import SemiDiscrete, beam_system

__version__ = "0.1.0"
__all__ = ["Beam", "BeamProblem", "Damping", "InitialState", "InputError", "Load",
           "Material", "Modes", "Obstacles", "Result", "SavedRun", "Section", "SemiDiscrete",
           "SolverError", "Stepping", "Support", "beam_system", "modes", "read_run", "solve"]
