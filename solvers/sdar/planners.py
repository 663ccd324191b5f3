"""The task planners SDAR-M can ground, by name."""

from __future__ import annotations

from sdar_tamp.errors import ParameterError
from solvers.sdar.tasks import TaskPlanner

TASK_PLANNERS = ("sdar", "baseline")


def make_task_planner(name: str) -> TaskPlanner:
    """A fresh task planner: ``sdar`` (SDAR-T) or ``baseline`` (our reconstruction of the
    optimal single-arm plan split over the cell's arms)."""
    if name == "sdar":
        from solvers.sdar.sdar_t import SdarTaskPlanner

        return SdarTaskPlanner()
    if name == "baseline":
        from solvers.sdar.baseline import BaselineTaskPlanner

        return BaselineTaskPlanner()
    raise ParameterError(f"task_planner must be one of {', '.join(TASK_PLANNERS)}; got {name!r}")
