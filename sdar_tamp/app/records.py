"""What a run reports: frozen records of one SDAR solve.

- :class:`TaskRecord`: one task (a step of the task planner) as SDAR-M executed it, read
  from ``Solution.trace``;
- :class:`StepTime`: planning time of one synchronous step, split into selection and motion;
- :class:`RunFigures`: the figures of one ``sdar solve`` (planners, seed, set-up, planning
  times, per-step times, motion levels, buffer moves);
- :class:`SolveOutcome`: the instance, the status, the plan file, the replay's verdict, the
  figures and the lower bound on the execution time.
"""

from __future__ import annotations

import statistics
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

from sdar_tamp.plan_file import PlanFile
from sdar_tamp.world.execution_bound import ExecutionBound
from sdar_tamp.world.instance import Instance
from solvers.solution import Solution, TaskTrace


@dataclass(frozen=True)
class TaskRecord:
    """One task of the task planner as executed: its kind (``single``, ``pair``, ``swap``,
    ...), objects, arms, which moves went to a buffer, the time [s] spent selecting its
    grounding and planning its motions, the motions it executed (and their times [s]) and
    the groundings it tried."""

    kind: str
    objects: tuple[str, ...]
    arms: tuple[str, ...]
    to_buffer: tuple[bool, ...]
    selection_time: float
    motion_time: float
    motions: int
    tried: int
    motion_times: tuple[float, ...]

    @classmethod
    def from_trace(cls, record: TaskTrace) -> TaskRecord:
        """The record of one entry of ``Solution.trace`` (``algorithm="sdar"``)."""
        return cls(
            kind=record.kind,
            objects=tuple(str(o) for o in record.objects),
            arms=tuple(str(a) for a in record.arms),
            to_buffer=record.to_buffer,
            selection_time=record.selection_time,
            motion_time=record.motion_time,
            motions=record.motions,
            tried=record.tried,
            motion_times=record.motion_times,
        )

    @property
    def buffer_moves(self) -> int:
        return sum(self.to_buffer)

    def step_times(self) -> list[StepTime]:
        """One :class:`StepTime` per executed motion: the selection time and the time of the
        motions tried in vain are shared equally by the motions executed, so the steps add
        up to the time of the task."""
        n = len(self.motion_times)
        wasted = self.motion_time - sum(self.motion_times)
        return [StepTime(self.selection_time / n, m + wasted / n) for m in self.motion_times]


def task_records(solution: Solution) -> tuple[TaskRecord, ...]:
    """The tasks of an SDAR solution, in execution order."""
    return tuple(TaskRecord.from_trace(r) for r in solution.trace)


class StepTime(NamedTuple):
    """Planning time [s] of one synchronous step: plan selection (IK, grasps, buffers,
    ranking) and motion generation."""

    selection: float
    motion: float

    @property
    def total(self) -> float:
        return self.selection + self.motion


def _median(values: Sequence[float]) -> float:
    return statistics.median(values) if values else 0.0


@dataclass(frozen=True)
class RunFigures:
    """The figures of one solve. Times in [s]; ``setup_time`` (world and motion planner) is
    not planning time; ``optimiser_build_time`` is the CPU time of the optimiser's build (in
    the background) and ``optimiser_wait`` how long planning waited for it. The per-step
    fields are empty without a plan."""

    task_planner: str
    motion_planner: str
    seed: int
    setup_time: float
    optimiser_build_time: float
    optimiser_wait: float
    planning_time: float
    selection_time: float
    motion_time: float
    task_selection_time: float = 0.0
    tasks: int = 0
    step_times: tuple[StepTime, ...] = ()
    levels: Mapping[str, int] = field(default_factory=dict)  # motion level -> motions
    buffer_moves: int = 0
    schedule_time: float = 0.0  # [s] spent on the asynchronous schedule (not planning time)

    @property
    def step_time_median(self) -> float:
        return _median([s.total for s in self.step_times])

    @property
    def step_time_max(self) -> float:
        return max((s.total for s in self.step_times), default=0.0)

    @property
    def step_selection_median(self) -> float:
        return _median([s.selection for s in self.step_times])

    @property
    def step_motion_median(self) -> float:
        return _median([s.motion for s in self.step_times])


@dataclass(frozen=True)
class SolveOutcome:
    """What one solve produced. ``valid`` is the independent replay's verdict."""

    instance: Instance
    status: str  # solved, infeasible, timeout
    plan: PlanFile | None
    valid: bool
    violation: str
    figures: RunFigures
    diagnosis: tuple[str, ...] = ()
    #: The lower bound on the execution time of any plan (``sdar_tamp.world.execution_bound``).
    bound: ExecutionBound | None = None

    @property
    def success(self) -> bool:
        return self.status == "solved" and self.valid

    @property
    def execution_over_bound(self) -> float | None:
        """The plan's execution time over the bound (``None`` without a plan or a bound)."""
        if self.plan is None or self.bound is None or self.plan.metrics.execution_time is None:
            return None
        return self.bound.ratio(float(self.plan.metrics.execution_time))
