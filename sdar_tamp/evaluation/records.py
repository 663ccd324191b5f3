"""The records of one benchmark run: its ``results.csv`` row and what a worker sends back.

:class:`BenchRow` has one field per column of :data:`~sdar_tamp.evaluation.results.COLUMNS`,
in that order; :meth:`BenchRow.cells` turns it into the mapping the CSV writer takes (``None``:
an empty cell). :class:`RunAnswer` is a worker's answer: the row, the per-step planning times
and the plan file.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from sdar_tamp.evaluation.results import COLUMNS

if TYPE_CHECKING:
    from sdar_tamp.app.records import StepTime
    from sdar_tamp.plan_file import PlanFile


@dataclass(frozen=True)
class BenchRow:
    """One run of one (instance, combination). Times in [s]. The fields after ``valid`` are
    empty (``None``) where the run did not get that far: no plan, an error, a timeout."""

    instance: str
    family: str
    objects: int
    combination: str
    task_planner: str
    motion_planner: str
    seed: int
    time_limit_s: float
    success: bool
    status: str  # solved, infeasible, timeout, error
    valid: bool
    actions: int | None = None
    steps: int | None = None
    dual_arm_steps: int | None = None
    buffer_moves: int | None = None
    execution_time_s: float | None = None
    #: the lower bound on the execution time (``sdar_tamp.world.execution_bound``) and the
    #: plan's execution time over it
    bound_s: float | None = None
    execution_over_bound: float | None = None
    planning_time_s: float | None = None
    selection_time_s: float | None = None
    motion_time_s: float | None = None
    step_time_median_s: float | None = None
    setup_time_s: float | None = None
    wall_time_s: float | None = None
    abstract_actions: int | None = None
    abstract_buffer_moves: int | None = None
    abstract_steps: int | None = None
    violation: str | None = None
    diagnosis: str | None = None

    def cells(self) -> dict[str, object]:
        """Column -> value, in the order of :data:`COLUMNS` (the CSV writer formats them)."""
        return {c: getattr(self, c) for c in COLUMNS}


@dataclass(frozen=True)
class RunAnswer:
    """What a worker returns for one run: the row, the planning time of every synchronous
    step (empty without a plan) and the plan file (``None`` without one)."""

    row: BenchRow
    step_times: tuple[StepTime, ...] = ()
    plan: PlanFile | None = None
