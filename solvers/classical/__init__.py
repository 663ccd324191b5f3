"""A fast classical planner: grounding by relaxed reachability and heuristic search.

Two steps, each usable on its own::

    from solvers.classical import PlanningTask, ground, plan

    ground_task = ground(task)          # inspect facts, operators, axioms
    result = plan(task, search="gbfs", heuristic="ff")
    result.status, result.plan, result.cost, result.statistics

Supported: typing, negative/disjunctive/quantified preconditions and goals, equality, derived
predicates (stratified axioms), conditional and universal effects, action costs.
"""

from solvers.classical.errors import GroundingError, PlanValidationError
from solvers.classical.ground import ground
from solvers.classical.heuristics import HEURISTICS
from solvers.classical.plan_check import validated_plan_cost
from solvers.classical.planner import SEARCHES, plan
from solvers.classical.problem import (
    GroundAction,
    PlanningTask,
    PlanStatus,
    SearchResult,
    SearchStatistics,
    task_from_problem,
)
from solvers.classical.task import GroundTask

__all__ = [
    "HEURISTICS",
    "SEARCHES",
    "GroundAction",
    "GroundTask",
    "GroundingError",
    "PlanStatus",
    "PlanValidationError",
    "PlanningTask",
    "SearchResult",
    "SearchStatistics",
    "ground",
    "plan",
    "task_from_problem",
    "validated_plan_cost",
]
