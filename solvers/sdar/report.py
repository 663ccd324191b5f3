"""What an SDAR-M run reports: per-task records, why candidates failed, the solution."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from sdar_tamp.logs import get_logger
from solvers.sdar.cache import StreamCache
from solvers.sdar.tasks import Step
from solvers.solution import Action, Certificate, Solution, Status, StreamStatistics, TaskTrace

LOG = get_logger(__name__)


@dataclass
class TaskRecord:
    """One executed task (filled while its decision runs): what moved, how long it took."""

    kind: str
    objects: tuple[str, ...]
    arms: tuple[str, ...]
    to_buffer: tuple[bool, ...]
    selection_time: float = 0.0  # [s]
    motion_time: float = 0.0  # [s]
    motions: int = 0
    tried: int = 0
    motion_times: list[float] = field(default_factory=list)  # [s] per motion planned


class Failures:
    """Why the candidates of the current decision failed (for the diagnosis of a dead end)."""

    def __init__(self, show: Callable[[str], str]) -> None:
        self._show = show
        self.reasons: list[str] = []

    def clear(self) -> None:
        self.reasons = []

    def why(self, step: Step, arms: tuple[str, ...], reason: str) -> None:
        show = self._show
        what = ", ".join(
            f"{show(m.obj)}{'->buffer' if m.to_buffer else ''} by {show(a)}"
            for m, a in zip(step.moves, arms, strict=True)
        )
        self.reasons.append(f"{step.kind} ({what}): {reason}")
        LOG.debug("sdar: %s (%s): %s", step.kind, what, reason)

    def unassigned(self, step: Step, reason: str) -> None:
        """``step`` got no arms (``reason`` says why)."""
        show = self._show
        what = ", ".join(f"{show(m.obj)}{'->buffer' if m.to_buffer else ''}" for m in step.moves)
        self.reasons.append(f"{step.kind} ({what}): {reason}")
        LOG.debug("sdar: %s (%s): %s", step.kind, what, reason)


@dataclass(frozen=True)
class PlannedStep:
    """One decision as :meth:`~solvers.sdar.solver.SdarSolver.steps` yields it, once its
    motions are planned and its actions applied: its index (from 0), the task (the problem's
    Python values) and the plan actions it added, in order."""

    index: int
    task: TaskTrace
    actions: tuple[Action, ...]


def task_trace(cache: StreamCache, record: TaskRecord) -> TaskTrace:
    """``record`` with the problem's Python values for its objects and arms."""
    value = cache.table.value
    return TaskTrace(
        kind=record.kind,
        objects=tuple(value(o) for o in record.objects),
        arms=tuple(value(a) for a in record.arms),
        to_buffer=tuple(record.to_buffer),
        selection_time=record.selection_time,
        motion_time=record.motion_time,
        motions=record.motions,
        tried=record.tried,
        motion_times=tuple(record.motion_times),
    )


def planned_step(
    cache: StreamCache,
    index: int,
    record: TaskRecord,
    actions: Sequence[tuple[str, tuple[str, ...]]],
) -> PlannedStep:
    """The :class:`PlannedStep` of decision ``index``: its record and its ``actions``
    (names and argument ids)."""
    value = cache.table.value
    plan = tuple(Action(name, tuple(value(a) for a in args)) for name, args in actions)
    return PlannedStep(index, task_trace(cache, record), plan)


@dataclass(frozen=True)
class RunSummary:
    """The outcome of a run, before it becomes a :class:`~solvers.solution.Solution`."""

    status: Status
    diagnosis: tuple[str, ...]
    elapsed: float  # [s]
    motion_time: float  # [s] spent in the motion streams
    plan: tuple[tuple[str, tuple[str, ...]], ...]
    cost: float


def build_solution(
    cache: StreamCache, summary: RunSummary, records: Sequence[TaskRecord]
) -> Solution:
    """The solution of a run: plan values, certificate, statistics and the per-task trace."""
    value = cache.table.value
    state = cache.state
    plan = [Action(name, tuple(value(a) for a in args)) for name, args in summary.plan]
    facts = tuple(
        (p, *(value(a) for a in args))
        for p in sorted(state._by_predicate)
        if p not in state.fluent_names
        for args in state.atoms(p)
    )
    statistics = {
        "planning_time": summary.elapsed,
        "selection_time": summary.elapsed - summary.motion_time,
        "motion_time": summary.motion_time,
        "tasks": float(len(records)),
        "steps": float(sum(r.motions for r in records)),
        "task_selection_time": sum(r.selection_time for r in records),
    }
    streams = {
        name: StreamStatistics(c.calls, c.successes, c.outputs, c.time)
        for name, c in (
            *((n, e.counters) for n, e in cache.streams.items()),
            *((n, f.counters) for n, f in cache.functions.items()),
        )
    }
    trace = tuple(task_trace(cache, r) for r in records)
    solved = summary.status is Status.SOLVED
    return Solution(
        plan if solved else None,
        summary.cost if solved else math.inf,
        Certificate(facts, facts),
        summary.status,
        statistics,
        streams,
        summary.diagnosis,
        trace=trace,
        partial_plan=tuple(plan),
    )
