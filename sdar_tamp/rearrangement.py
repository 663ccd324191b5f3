"""Former home of the rearrangement wiring; the names live in :mod:`sdar_tamp.app` now."""

from __future__ import annotations

from sdar_tamp.app.config import GRIPPER_TIME, MOTION_PLANNERS, TASK_PLANNERS, PlannerConfig
from sdar_tamp.app.plan_export import plan_file_from_solution, timeline
from sdar_tamp.app.problem import DOMAIN, Rearrangement, rearrangement_problem
from sdar_tamp.app.solving import solve_rearrangement

__all__ = [
    "DOMAIN",
    "GRIPPER_TIME",
    "MOTION_PLANNERS",
    "TASK_PLANNERS",
    "PlannerConfig",
    "Rearrangement",
    "plan_file_from_solution",
    "rearrangement_problem",
    "solve_rearrangement",
    "timeline",
]
