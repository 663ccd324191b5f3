"""A* with deferred evaluation (solvers/classical/astar.py) against the eager A* loop: the same
optimal costs, fewer heuristic evaluations."""

from __future__ import annotations

import pytest
from classical_helpers import load

from solvers.classical import ground
from solvers.classical.astar import deferred_astar
from solvers.classical.bitset_task import CompiledTask
from solvers.classical.heuristics import RelaxedHeuristic
from solvers.classical.search import best_first_search

CASES = [
    ("blocksworld", "sussman"),
    ("blocksworld", "reverse4"),
    ("delivery_costs", "detour"),
    ("delivery_costs", "two-vans"),
    ("logistics", "two-cities"),
    ("briefcase", "office"),
    ("briefcase", "lights-out"),
]


def _cost(compiled: CompiledTask, operators: tuple[int, ...]) -> float:
    state = compiled.init
    for op in operators:
        assert op in compiled.applicable(state)
        state = compiled.successor(state, op)
    assert compiled.is_goal(state)
    return sum(compiled.costs[op] for op in operators)


@pytest.mark.parametrize(("domain", "problem"), CASES)
@pytest.mark.parametrize("heuristic", ["max", "blind"])
def test_deferred_astar_finds_plans_as_cheap_as_eager_astar(
    domain: str, problem: str, heuristic: str
) -> None:
    compiled = CompiledTask(ground(load(domain, problem)))
    relaxed = RelaxedHeuristic(compiled, heuristic, compiled.costs)
    eager = best_first_search(
        compiled, relaxed, g_weight=1.0, h_weight=1.0, preferred=False, lazy=False,
        reopen=True, deadline=None,
    )  # fmt: skip
    deferred = deferred_astar(compiled, relaxed, None)
    assert eager.status == deferred.status == "solved"
    assert _cost(compiled, deferred.operators) == pytest.approx(_cost(compiled, eager.operators))
    assert deferred.evaluated <= eager.evaluated


def test_deferred_astar_respects_the_cost_bound_and_reports_unsolvable() -> None:
    compiled = CompiledTask(ground(load("delivery_costs", "detour")))
    relaxed = RelaxedHeuristic(compiled, "max", compiled.costs)
    optimal = deferred_astar(compiled, relaxed, None)
    cost = _cost(compiled, optimal.operators)
    assert deferred_astar(compiled, relaxed, None, cost_bound=cost + 1e-9).status == "solved"
    assert deferred_astar(compiled, relaxed, None, cost_bound=cost).status == "unsolvable"


def test_deferred_astar_stops_at_the_deadline() -> None:
    compiled = CompiledTask(ground(load("logistics", "three-cities")))
    relaxed = RelaxedHeuristic(compiled, "blind", compiled.costs)
    assert deferred_astar(compiled, relaxed, 0.0).status == "timeout"
