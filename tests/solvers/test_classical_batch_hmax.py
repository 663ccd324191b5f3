"""h_max of many states at once (solvers/classical/batch_hmax.py): exactly the queue's values,
and A* with batched evaluation expands the same states and finds the same plan; the closures a
task remembers are the ones it computes."""

from __future__ import annotations

import random
from math import inf

import pytest
from classical_helpers import load

from solvers.classical import ground
from solvers.classical.astar import deferred_astar
from solvers.classical.batch_hmax import BatchHMax
from solvers.classical.bitset_task import CompiledTask
from solvers.classical.heuristics import RelaxedHeuristic

CASES = [
    ("blocksworld", "sussman"),
    ("blocksworld", "reverse4"),
    ("delivery_costs", "detour"),
    ("delivery_costs", "two-vans"),
    ("logistics", "two-cities"),
    ("briefcase", "office"),
    ("briefcase", "lights-out"),
]


def _reachable(compiled: CompiledTask, limit: int = 300) -> list[int]:
    states, frontier, seen = [], [compiled.init], {compiled.init}
    while frontier and len(states) < limit:
        state = frontier.pop(0)
        states.append(state)
        for op in compiled.applicable(state):
            succ = compiled.successor(state, op)
            if succ not in seen:
                seen.add(succ)
                frontier.append(succ)
    return states


@pytest.mark.parametrize(("domain", "problem"), CASES)
def test_batched_values_are_the_queues(domain: str, problem: str) -> None:
    compiled = CompiledTask(ground(load(domain, problem)))
    batched = RelaxedHeuristic(compiled, "max", compiled.costs)
    queue = RelaxedHeuristic(compiled, "max", compiled.costs, engine="python")
    assert batched.batch is not None and queue.batch is None
    states = _reachable(compiled)
    expected = [queue(state)[0] for state in states]
    assert batched.values(states) == expected
    assert queue.values(states) == expected
    assert batched.values(states[:1]) == expected[:1]
    assert batched.values([]) == []


@pytest.mark.parametrize(("domain", "problem"), CASES)
def test_batched_astar_expands_the_same_states(domain: str, problem: str) -> None:
    compiled = CompiledTask(ground(load(domain, problem)))
    relaxed = RelaxedHeuristic(compiled, "max", compiled.costs)
    one_by_one = deferred_astar(compiled, relaxed, None)
    batched = deferred_astar(compiled, relaxed, None, batch=relaxed.values)
    assert batched.status == one_by_one.status == "solved"
    assert batched.operators == one_by_one.operators
    assert (batched.expanded, batched.generated) == (one_by_one.expanded, one_by_one.generated)
    assert batched.evaluated >= one_by_one.evaluated


def _queue_hmax(
    count: int, upre: list[list[int]], ueff: list[list[int]], ucost: list[float],
    goal: list[int], state: set[int],
) -> float:  # fmt: skip
    cost = [0.0 if fact in state else inf for fact in range(count)]
    changed = True
    while changed:  # plain fixed point, the definition
        changed = False
        for pre, eff, c in zip(upre, ueff, ucost, strict=True):
            value = max((cost[p] for p in pre), default=0.0) + c
            for g in eff:
                if value < cost[g]:
                    cost[g] = value
                    changed = True
    return max((cost[g] for g in goal), default=0.0)


@pytest.mark.parametrize("seed", range(20))
def test_random_relaxed_tasks(seed: int) -> None:
    rng = random.Random(seed)
    count = rng.randint(1, 40)
    n_ops = rng.randint(0, 60)
    upre = [rng.sample(range(count), rng.randint(0, min(3, count))) for _ in range(n_ops)]
    ueff = [rng.sample(range(count), rng.randint(1, min(2, count))) for _ in range(n_ops)]
    # real-valued costs (sums that round), zeros (axioms) and repeated precondition sets
    ucost = [rng.choice([0.0, 0.1, 0.7, 1.3, rng.random() * 10]) for _ in range(n_ops)]
    goal = rng.sample(range(count), rng.randint(0, min(4, count)))
    batch = BatchHMax(count, upre, ueff, ucost, goal)
    states = [{f for f in range(count) if rng.random() < 0.3} for _ in range(12)]
    bitsets = [sum(1 << f for f in state) for state in states]
    expected = [_queue_hmax(count, upre, ueff, ucost, goal, state) for state in states]
    assert batch.evaluate(bitsets) == expected


def test_an_unreachable_goal_is_infinite() -> None:
    batch = BatchHMax(3, [[0]], [[1]], [2.5], [1, 2])
    assert batch.evaluate([0b001, 0b100, 0b101]) == [inf, inf, 2.5]


@pytest.mark.parametrize(
    ("domain", "problem"), [("briefcase", "office"), ("briefcase", "lights-out")]
)
def test_remembered_closures_are_the_computed_ones(
    domain: str, problem: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    warm = CompiledTask(ground(load(domain, problem)))
    assert warm.strata  # the domain has derived facts
    states = _reachable(warm)  # closes every state reached, most of them more than once
    assert len(warm._closed) > 1
    monkeypatch.setattr("solvers.classical.bitset_task.CLOSED_MEMO", 0)
    cold = CompiledTask(ground(load(domain, problem)))
    assert _reachable(cold) == states and not cold._closed
    for state in states:
        assert warm.close(state) == cold.close(state) == state
