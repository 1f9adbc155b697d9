"""The impacting bar of Do, Raupp & Feijoo: a 1-D (visco)elastic bar with an obstacle at
an end, in the beam's layers: :mod:`.problem` (the scene :class:`Bar` and its profiles),
:mod:`.system` (its P1 or P2 semi-discretisation, :func:`bar_system`), :mod:`.run` (its method,
run and series) and :mod:`.analysis` (errors against exact solutions, contact periods,
the energy report).  Each module imports only those before it."""
from .problem import (FAR_ENDS, OBSTACLES, SIDES, Bar, Table, describe, profile_values,
                      read_profile)
from .system import bar_system, spring_step_ratio
from .run import BarRun, BarSeries, bar_method, bar_run, run_bar, steps_to
from .analysis import contact_periods, energy_report, errors, l2_time

__all__ = ["Bar", "Table", "profile_values", "read_profile", "describe", "OBSTACLES",
           "FAR_ENDS", "SIDES", "bar_system", "spring_step_ratio", "BarRun",
           "steps_to", "bar_method", "bar_run", "BarSeries", "run_bar", "l2_time", "errors",
           "contact_periods", "energy_report"]
