"""``pddlstream.algorithms.search``: plain PDDL planning (``solve_from_pddl``)."""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from typing import Any

from sdar_tamp.compat.pddlstream.unsupported import NotProvidedError, not_provided
from sdar_tamp.errors import ParameterError
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.problem_reader import parse_problem
from solvers.classical import PlanStatus, task_from_problem
from solvers.classical import plan as plan  # replaced by the runner's --report
from solvers.solution import Action
from solvers.solve import parse_planner

__all__ = ["ABSTRIPSLayer", "solve_from_pddl"]
LOG = logging.getLogger(__name__)
_NOTED = ("temp_dir", "clean", "debug", "hierarchy")


def solve_from_pddl(
    domain_pddl: str,
    problem_pddl: str,
    planner: str = "ff-astar2",
    max_planner_time: float = 30.0,
    max_cost: float = math.inf,
    **keywords: Any,
) -> tuple[list[Action] | None, float]:
    """Solve a PDDL domain and problem (texts); returns ``(plan, cost)``: the plan a list of
    ``Action(name, args)`` with object names as strings, or ``(None, inf)`` without a plan.

    ``planner`` takes PDDLStream's names (``'dijkstra'``, ``'max-astar'``, ``'ff-astar'`` ...)
    or ``SEARCH-HEURISTIC``. ``temp_dir``, ``clean``, ``debug`` and ``hierarchy`` are accepted
    (nothing is written to disk). Costs follow the problem's ``(:metric minimize
    (total-cost))``, else every action costs 1.
    """
    unknown = sorted(set(keywords) - set(_NOTED))
    if unknown:
        raise TypeError(f"solve_from_pddl() got unexpected keyword(s): {', '.join(unknown)}")
    search, heuristic, weight = parse_planner(planner)
    domain = parse_domain(domain_pddl, "domain.pddl")
    problem = parse_problem(problem_pddl, domain, "problem.pddl")
    task = task_from_problem(domain, problem)
    limit = None if math.isinf(max_planner_time) or max_planner_time <= 0 else max_planner_time
    result = plan(
        task,
        search=search,
        heuristic=heuristic,
        weight=max(1.0, weight),
        time_limit=limit,
        cost_bound=max_cost,
    )
    if result.status is not PlanStatus.SOLVED or result.plan is None:
        LOG.info("solve_from_pddl: %s", result.status.value)
        return None, math.inf
    return [Action(step.name, tuple(step.args)) for step in result.plan], float(result.cost)


class ABSTRIPSLayer:
    """One layer of an ABSTRIPS planning hierarchy (``solve(..., hierarchy=[...])``).

    ``pos_pre``/``neg_pre``: predicate names whose positive/negative preconditions the layer
    keeps; ``horizon``: its plan-length bound (>= 1). The hierarchy is accepted and noted by
    ``solve`` (planning here is flat: every precondition is kept, which finds the same plans
    as the last, complete layer). Effect layers are refused, as in PDDLStream.
    """

    def __init__(
        self,
        pos_pre: Sequence[str] = (),
        neg_pre: Sequence[str] = (),
        pos_eff: Sequence[str] = (),
        neg_eff: Sequence[str] = (),
        horizon: float = math.inf,
    ) -> None:
        if not horizon >= 1:
            raise ParameterError(f"ABSTRIPSLayer horizon must be >= 1; got {horizon!r}")
        if pos_eff or neg_eff:
            raise NotProvidedError(
                "ABSTRIPSLayer effect layers (pos_eff, neg_eff) are not supported "
                "(PDDLStream refuses them too)"
            )
        self.pos_pre = list(pos_pre)
        self.neg_pre = list(neg_pre)
        self.pos_eff: list[str] = []
        self.neg_eff: list[str] = []
        self.horizon = horizon

    def __repr__(self) -> str:
        return (
            f"ABSTRIPSLayer(pos_pre={self.pos_pre!r}, neg_pre={self.neg_pre!r}, "
            f"horizon={self.horizon!r})"
        )


__getattr__ = not_provided(
    __name__, "Fast Downward's search internals (planning here is solvers.classical)"
)
