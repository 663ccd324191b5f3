"""The planner's input (a lifted task) and its output values (ground actions, results)."""

from __future__ import annotations

import enum
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from sdar_tamp.language.domain_model import Domain, Problem
from sdar_tamp.language.formula_model import Atom, Formula


@dataclass(frozen=True)
class PlanningTask:
    """A lifted classical planning task.

    ``objects`` maps every object name to its type and includes the domain constants.
    ``init`` holds ground atoms; type atoms such as ``(block b1)`` may be present or not (they are
    derived from ``objects`` either way). ``numeric_init`` maps ``(function, args)`` to a value and
    supplies the cost terms. With ``use_costs=False`` every action costs 1.
    ``extra_cost``, when given, maps a ground action ``(name, args)`` to a non-negative amount
    the search adds to that action's cost (a penalty steering the search); the reported plan
    cost leaves it out.
    """

    domain: Domain
    objects: Mapping[str, str]
    init: frozenset[Atom]
    goal: Formula
    numeric_init: Mapping[tuple[str, tuple[str, ...]], float] = field(default_factory=dict)
    use_costs: bool = True
    extra_cost: Callable[[str, tuple[str, ...]], float] | None = None


def task_from_problem(
    domain: Domain, problem: Problem, *, use_costs: bool | None = None
) -> PlanningTask:
    """The planning task of ``problem``: objects are the domain constants plus the problem's.

    ``use_costs`` defaults to whether the problem asks to ``(:metric minimize (total-cost))``;
    without a metric every action costs 1.
    """
    objects = dict(domain.constants)
    objects.update(problem.objects)
    return PlanningTask(
        domain=domain,
        objects=objects,
        init=frozenset(problem.init),
        goal=problem.goal,
        numeric_init=dict(problem.numeric_init),
        use_costs=problem.minimize_cost if use_costs is None else use_costs,
    )


@dataclass(frozen=True)
class GroundAction:
    """One step of a plan: an action schema's name and its arguments."""

    name: str
    args: tuple[str, ...] = ()

    def __str__(self) -> str:
        return f"({' '.join((self.name, *self.args))})"


class PlanStatus(enum.Enum):
    SOLVED = "solved"
    UNSOLVABLE = "unsolvable"
    TIMEOUT = "timeout"


@dataclass(frozen=True)
class SearchStatistics:
    """Counters and times [s] of one planner run."""

    expanded: int
    generated: int
    evaluated: int
    ground_actions: int
    ground_axioms: int
    reachable_facts: int
    grounding_time: float
    search_time: float


@dataclass(frozen=True)
class SearchResult:
    """The outcome of :func:`solvers.classical.plan`. ``plan`` is ``None`` unless solved."""

    status: PlanStatus
    plan: tuple[GroundAction, ...] | None
    cost: float
    statistics: SearchStatistics

    @property
    def solved(self) -> bool:
        return self.status is PlanStatus.SOLVED
