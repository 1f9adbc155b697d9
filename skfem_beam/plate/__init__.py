"""Kirchhoff–Love plates on a rectangle or on a triangle mesh read from a file
(:mod:`.meshfile`): the model (:mod:`.model`), its finite element
space and matrices (:mod:`.space`), the static deflection (:mod:`.static`) and the
natural frequencies (:mod:`.modes`), and its semi-discrete system with obstacles at the
vertices (:mod:`.system`), which the beam's one time scheme steps
(:func:`skfem_beam.scheme.solve`).  docs/plate.md gives the equations and the measured
errors."""
from .model import MeshPlate, Plate
from .modes import natural_frequencies
from .space import PlateSpace, load_vector, plate_space
from .static import deflection_at_vertex, static_deflection
from .system import PlateInitial, PlateObstacle, PointForce, Pressure, full_dofs, plate_system

__all__ = ["Plate", "MeshPlate", "PlateSpace", "plate_space", "load_vector", "static_deflection",
           "deflection_at_vertex", "natural_frequencies", "plate_system", "PlateObstacle",
           "Pressure", "PointForce", "PlateInitial", "full_dofs"]
