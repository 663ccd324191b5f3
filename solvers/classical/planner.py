"""The planner's entry point: ground, search, validate."""

from __future__ import annotations

import dataclasses
import math
import time

from sdar_tamp.errors import ParameterError
from sdar_tamp.logs import get_logger
from solvers.classical.astar import deferred_astar
from solvers.classical.bitset_task import CompiledTask
from solvers.classical.errors import PlanValidationError
from solvers.classical.ground import ground
from solvers.classical.heuristics import HEURISTICS, RelaxedHeuristic
from solvers.classical.landmarks import LandmarkCount
from solvers.classical.numeric_task import plan_numeric
from solvers.classical.plan_check import validated_plan_cost
from solvers.classical.postprocess import eliminate_redundant_actions
from solvers.classical.problem import (
    PlanningTask,
    PlanStatus,
    SearchResult,
    SearchStatistics,
)
from solvers.classical.reachability import GroundingTimeout
from solvers.classical.search import Evaluator, SearchOutcome, best_first_search
from solvers.classical.task import GroundTask

SEARCHES = ("gbfs", "astar", "wastar", "lazy-gbfs", "lazy-wastar")
logger = get_logger(__name__)


def _check(name: str, value: object, choices: tuple[str, ...]) -> None:
    if value not in choices:
        raise ParameterError(f"{name} must be one of {', '.join(choices)}; got {value!r}")


def ground_or_timeout(
    task: PlanningTask, start: float, deadline: float | None
) -> GroundTask | SearchResult:
    """``task`` grounded, or a ``TIMEOUT`` result when grounding passes ``deadline``
    (``time.perf_counter`` [s]; the clock started at ``start``)."""
    try:
        return ground(task, deadline=deadline)
    except GroundingTimeout:
        elapsed = time.perf_counter() - start
        return SearchResult(
            PlanStatus.TIMEOUT, None, 0.0, SearchStatistics(0, 0, 0, 0, 0, 0, elapsed, 0.0)
        )


def plan(
    task: PlanningTask,
    *,
    search: str = "gbfs",
    heuristic: str = "ff",
    weight: float = 2.0,
    preferred_operators: bool = True,
    lazy: bool = False,
    time_limit: float | None = None,
    cost_bound: float = math.inf,
    exploration: bool | None = None,
) -> SearchResult:
    """Find a plan for ``task``.

    ``search``: ``"gbfs"`` (greedy best-first), ``"lazy-gbfs"`` (greedy best-first with lazy
    evaluation and unit action costs inside the heuristics, as LAMA's first iteration),
    ``"astar"`` or ``"wastar"`` (f = g + weight·h), ``"lazy-wastar"`` (weighted A* with lazy
    evaluation and 1 added to every action cost inside the heuristic, as Fast Downward's
    ``lazy_wastar`` in PDDLStream's ``ff-wastar`` planners).
    ``heuristic``: ``"ff"``, ``"add"``, ``"max"``, ``"blind"``, ``"lmcount"`` (landmark count,
    path-dependent and not admissible) or ``"ff-lmcount"`` (h_FF and landmark count in
    alternating queues, LAMA's guidance). Preferred operators (from the relaxed plan; not used
    by ``"blind"`` and ``"lmcount"``) feed boosted queues of their own; A* ignores them so that
    with an admissible heuristic (``"max"``, ``"blind"``) its plans stay optimal. ``lazy`` defers
    evaluation to expansion time (always on for ``"lazy-gbfs"``). Plans of greedy and weighted
    search are post-processed by greedy action elimination (steps whose removal still reaches
    the goal are dropped; the cost never rises); A* plans are returned as found. ``"gbfs"`` adds
    1 to every action cost inside the heuristic (so zero-cost actions still count as steps);
    plan costs are always the true costs.
    ``exploration``: a type-based exploration queue beside the heuristic queues (greedy lazy
    search only; None: on for ``"lazy-gbfs"``). It takes successors of random parents grouped
    by (h, g), so that a search stuck on a plateau still samples the states its heuristic ranks
    badly (Xie, Mueller and Holte 2014); its random choices are seeded, so runs are repeatable.
    ``time_limit`` [s] covers grounding and search. ``cost_bound``: only plans cheaper than it
    (states whose cost so far reaches it are pruned; the initial state is never pruned).
    """
    _check("search", search, SEARCHES)
    _check("heuristic", heuristic, HEURISTICS)
    if task.domain.numeric:  # numeric fluents: compiled away for their reachable values
        options = dict(search=search, heuristic=heuristic, weight=weight, lazy=lazy)
        options.update(preferred_operators=preferred_operators, exploration=exploration)
        return plan_numeric(
            task,
            lambda t: plan(t, time_limit=time_limit, cost_bound=cost_bound, **options),  # type: ignore[arg-type]
        )
    if not weight >= 1.0:
        raise ParameterError(f"weight must be >= 1; got {weight!r}")
    greedy_lazy = search == "lazy-gbfs" or (search == "gbfs" and lazy)
    if exploration is None:
        exploration = search == "lazy-gbfs"
    elif exploration and not greedy_lazy:
        raise ParameterError(
            "exploration needs greedy lazy search (search='lazy-gbfs', or 'gbfs' with lazy=True);"
            f" got search={search!r}, lazy={lazy!r}"
        )
    if time_limit is not None and not time_limit > 0:
        raise ParameterError(f"time_limit must be > 0 seconds or None; got {time_limit!r}")
    start = time.perf_counter()
    deadline = None if time_limit is None else start + time_limit
    ground_task = ground_or_timeout(task, start, deadline)
    if isinstance(ground_task, SearchResult):
        return ground_task
    grounded = time.perf_counter()
    outcome = _search(
        ground_task,
        search,
        heuristic,
        weight,
        preferred_operators,
        lazy,
        deadline,
        cost_bound,
        exploration,
    )
    searched = time.perf_counter()
    statistics = SearchStatistics(
        expanded=outcome.expanded,
        generated=outcome.generated,
        evaluated=outcome.evaluated,
        ground_actions=len(ground_task.operators),
        ground_axioms=len(ground_task.axioms),
        reachable_facts=len(ground_task.facts),
        grounding_time=grounded - start,
        search_time=searched - grounded,
    )
    if outcome.status != "solved":
        return SearchResult(PlanStatus(outcome.status), None, 0.0, statistics)
    steps = tuple(ground_task.operators[i].action for i in outcome.operators)
    try:
        cost = validated_plan_cost(task, steps)
    except PlanValidationError as error:  # a bug in the planner, never a user error
        raise PlanValidationError(f"planner bug: the plan found is invalid: {error}") from error
    return SearchResult(PlanStatus.SOLVED, steps, cost, statistics)


def _search(
    ground_task: GroundTask,
    search: str,
    heuristic: str,
    weight: float,
    preferred: bool,
    lazy: bool,
    deadline: float | None,
    cost_bound: float = math.inf,
    exploration: bool = False,
) -> SearchOutcome:
    if not ground_task.goal_reachable:
        logger.info("goal not relaxed-reachable: unsolvable")
        return SearchOutcome("unsolvable", (), 0, 0, 0)
    compiled = CompiledTask(ground_task)
    costs = compiled.costs
    if search == "lazy-gbfs":
        costs = [1.0] * len(costs)  # as LAMA's first iteration: distance to the goal in steps
    elif search in ("gbfs", "lazy-wastar") and ground_task.source.use_costs:
        costs = [c + 1.0 for c in costs]  # "plusone": zero-cost actions still count
    relaxed_name = heuristic.removesuffix("-lmcount")
    relaxed = None if relaxed_name == "lmcount" else RelaxedHeuristic(compiled, relaxed_name, costs)
    landmarks = LandmarkCount(compiled) if heuristic.endswith("lmcount") else None
    if landmarks is not None:
        logger.info(
            "%d landmarks (%d disjunctive), %d reasonable orderings",
            len(landmarks),
            len(landmarks.disjunctions),
            landmarks.reasonable,
        )
    if search == "astar" and not lazy and landmarks is None and relaxed is not None:
        # evaluated when taken out of the open list: the same optimal plans, without the
        # heuristic on the successors that are never expanded (see astar.py)
        batch = relaxed.values if relaxed.batch is not None else None
        return deferred_astar(compiled, relaxed, deadline, cost_bound, batch)
    g_weight, h_weight = {
        "gbfs": (0.0, 1.0),
        "lazy-gbfs": (0.0, 1.0),
        "astar": (1.0, 1.0),
        "wastar": (1.0, weight),
        "lazy-wastar": (1.0, weight),
    }[search]
    outcome = best_first_search(
        compiled,
        Evaluator(relaxed, landmarks),
        g_weight=g_weight,
        h_weight=h_weight,
        preferred=preferred and relaxed_name not in ("blind", "lmcount") and search != "astar",
        lazy=lazy or search in ("lazy-gbfs", "lazy-wastar"),
        reopen=search not in ("gbfs", "lazy-gbfs"),
        deadline=deadline,
        cost_bound=cost_bound,
        exploration=exploration,
    )
    if outcome.status == "solved" and search != "astar":
        shorter = eliminate_redundant_actions(compiled, list(outcome.operators), deadline)
        outcome = dataclasses.replace(outcome, operators=tuple(shorter))
    return outcome
