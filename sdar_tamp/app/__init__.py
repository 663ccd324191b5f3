"""The application layer: the one place that wires an instance, the dual-arm domain, its
streams, a planner configuration and a solver, and turns a solution into a plan file and a
report. Besides the command line and :mod:`sdar_tamp.compat`, nothing else imports
``solvers`` and ``streams`` together; nothing below this package imports it.

One question per module:

- :mod:`~sdar_tamp.app.config`: which planner configuration applies (:class:`PlannerConfig`);
- :mod:`~sdar_tamp.app.problem`: how an instance becomes a problem (:class:`Rearrangement`);
- :mod:`~sdar_tamp.app.solving`: how it is solved (:func:`solve_rearrangement`);
- :mod:`~sdar_tamp.app.plan_export`: how a solution becomes a plan file;
- :mod:`~sdar_tamp.app.records`: what a run reports (:class:`TaskRecord`, :class:`RunFigures`,
  :class:`SolveOutcome`);
- :mod:`~sdar_tamp.app.cache`: what stays built between solves (:class:`PlannerCache`);
- :mod:`~sdar_tamp.app.pipeline`: the ``sdar solve`` pipeline (:func:`solve_instance`);
- :mod:`~sdar_tamp.app.summary`: what people see (summary lines, progress bar);
- :mod:`~sdar_tamp.app.abstract`: the task planner's geometry-free counts.
"""

from __future__ import annotations

from sdar_tamp.app.cache import PlannerCache
from sdar_tamp.app.config import GRIPPER_TIME, MOTION_PLANNERS, TASK_PLANNERS, PlannerConfig
from sdar_tamp.app.pipeline import solve_instance
from sdar_tamp.app.plan_export import ActionDecoder, plan_file_from_solution, timeline
from sdar_tamp.app.problem import DOMAIN, Rearrangement, rearrangement_problem
from sdar_tamp.app.records import RunFigures, SolveOutcome, StepTime, TaskRecord, task_records
from sdar_tamp.app.solving import solve_rearrangement
from sdar_tamp.app.summary import ProgressBar, format_summary

__all__ = [
    "DOMAIN",
    "GRIPPER_TIME",
    "MOTION_PLANNERS",
    "TASK_PLANNERS",
    "ActionDecoder",
    "PlannerCache",
    "PlannerConfig",
    "ProgressBar",
    "Rearrangement",
    "RunFigures",
    "SolveOutcome",
    "StepTime",
    "TaskRecord",
    "format_summary",
    "plan_file_from_solution",
    "rearrangement_problem",
    "solve_instance",
    "solve_rearrangement",
    "task_records",
    "timeline",
]
