"""The impacting bar (:mod:`.problem`, moved here from bar.py; split next)."""
from .problem import (FAR_ENDS, OBSTACLES, SIDES, Bar, BarRun, BarSeries, Table,  # noqa: F401
                      bar_method, bar_run, bar_system, contact_periods, describe,
                      energy_report, errors, l2_time, profile_values, read_profile, run_bar,
                      spring_step_ratio, steps_to)
