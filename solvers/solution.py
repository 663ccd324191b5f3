"""What a solver hands back: ``Solution`` unpacks as PDDLStream's ``plan, cost, certificate``."""

from __future__ import annotations

import enum
import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple


class Action(NamedTuple):
    """One plan step; ``args`` are the original Python values."""

    name: str
    args: tuple[Any, ...]


class DurativeAction(NamedTuple):
    """One step of a plan of a domain with durative actions: it starts at ``start`` [time
    units of the domain] and lasts ``duration`` (0 for an instantaneous action); steps run one
    after the other."""

    name: str
    args: tuple[Any, ...]
    start: float
    duration: float


class Certificate(NamedTuple):
    """Facts known at the end (``all_facts``) and those the plan relies on (``preimage_facts``)."""

    all_facts: tuple[tuple[Any, ...], ...]
    preimage_facts: tuple[tuple[Any, ...], ...]


@dataclass(frozen=True)
class TaskTrace:
    """One decision of a solver that executes step by step (``algorithm="sdar"``): the task's
    kind (``single``, ``pair``, ``swap``, ...), its objects and arms (the problem's Python
    values), which of its moves went to a buffer, the time [s] spent selecting its grounding
    and planning its motions, the motions it executed (and their times [s]) and the
    groundings it tried."""

    kind: str
    objects: tuple[Any, ...]
    arms: tuple[Any, ...]
    to_buffer: tuple[bool, ...]
    selection_time: float
    motion_time: float
    motions: int
    tried: int
    motion_times: tuple[float, ...]


class Status(enum.Enum):
    SOLVED = "solved"
    INFEASIBLE = "infeasible"
    TIMEOUT = "timeout"
    ERROR = "error"


@dataclass(frozen=True)
class StreamStatistics:
    """Per-stream counters: calls made, calls that produced, outputs, time spent [s]."""

    calls: int = 0
    successes: int = 0
    outputs: int = 0
    time: float = 0.0


@dataclass(frozen=True)
class Solution:
    """A solver's result. ``plan, cost, certificate = solution`` works as in PDDLStream.

    Attributes:
        plan: the actions, or None when there is no plan (for a domain with durative actions,
            :class:`DurativeAction` steps, which have an Action's ``name`` and ``args``).
        cost: the plan's cost (``inf`` without a plan).
        certificate: the facts behind the plan.
        status: why the solver stopped.
        statistics: solver counters (search, grounding, iterations, times [s]).
        streams: per-stream statistics.
        diagnosis: when there is no plan, short sentences saying why.
        trace: per-decision records of solvers that execute step by step (``sdar``).
        partial_plan: the actions executed before a step-by-step solver stopped.
    """

    plan: list[Action] | None
    cost: float = math.inf
    certificate: Certificate = field(default_factory=lambda: Certificate((), ()))
    status: Status = Status.INFEASIBLE
    statistics: Mapping[str, float] = field(default_factory=dict)
    streams: Mapping[str, StreamStatistics] = field(default_factory=dict)
    diagnosis: Sequence[str] = ()
    trace: Sequence[TaskTrace] = ()
    partial_plan: Sequence[Action] = ()

    def __iter__(self) -> Iterator[Any]:
        return iter((self.plan, self.cost, self.certificate))

    def __getitem__(self, index: int) -> Any:
        return (self.plan, self.cost, self.certificate)[index]

    def __len__(self) -> int:
        return 3

    @property
    def solved(self) -> bool:
        return self.status is Status.SOLVED


def format_value(value: Any) -> str:
    """A short printable form of a plan argument."""
    text = repr(value) if not isinstance(value, str) else value
    return text if len(text) <= 40 else text[:37] + "..."


def format_solution(solution: Solution) -> str:
    """PDDLStream-style text: status, cost, length, then one numbered action a line."""
    lines = [f"Status: {solution.status.value}", f"Cost: {solution.cost:.3f}"]
    if solution.plan is None:
        lines.append("Plan: none")
        lines.extend(f"  - {reason}" for reason in solution.diagnosis)
        return "\n".join(lines)
    lines.append(f"Length: {len(solution.plan)}")
    for step, action in enumerate(solution.plan, 1):
        text = f"{step:3d}) {action.name} {' '.join(format_value(a) for a in action.args)}"
        if isinstance(action, DurativeAction):
            text = f"{text} [start {action.start:g}, duration {action.duration:g}]"
        lines.append(text)
    return "\n".join(lines)


def print_solution(solution: Solution) -> None:
    """Print :func:`format_solution` (PDDLStream's name)."""
    print(format_solution(solution))
