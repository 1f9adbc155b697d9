"""skfem_beam: beams and bars vibrating between obstacles, contact-implicit β-schemes."""
from .errors import InputError, SolverError
from .integrators import Result, solve
from .modes import Modes, modes
from .problem import Beam, BeamProblem, InitialState, Load, Obstacles, Support
from .semidiscrete import SemiDiscrete, beam_system

__version__ = "0.1.0"
__all__ = ["Beam", "BeamProblem", "InitialState", "InputError", "Load", "Modes", "Obstacles",
           "Result", "SemiDiscrete", "SolverError", "Support", "beam_system", "modes", "solve"]
