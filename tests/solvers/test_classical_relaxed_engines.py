"""The relaxed heuristics' engines (queue-based, vectorised) against a plain fixpoint reference."""

from __future__ import annotations

import random
from math import inf

import pytest
from classical_helpers import load

from sdar_tamp.errors import ParameterError
from solvers.classical import ground
from solvers.classical.compiled import CompiledTask, bits
from solvers.classical.heuristics import RelaxedHeuristic

CASES = [
    ("blocksworld", "reverse4"),
    ("blocksworld", "sussman"),
    ("logistics", "three-cities"),
    ("logistics", "two-cities"),
    ("briefcase", "office"),
    ("briefcase", "lights-out"),
    ("delivery_costs", "two-vans"),
]


def _reference(
    compiled: CompiledTask, costs: list[float], state: int, use_max: bool
) -> tuple[list[float], list[int], list[tuple[tuple[int, ...], tuple[int, ...], int]]]:
    """Costs by repeated sweeps to a fixpoint; best supporter = lowest relaxed-operator id."""
    task = compiled.task
    relaxed: list[tuple[tuple[int, ...], tuple[int, ...], float, int]] = []
    for index, op in enumerate(task.operators):
        for pre, adds in [(op.precondition, op.adds)] + [
            (op.precondition + c.condition, c.adds) for c in op.conditional
        ]:
            if adds:
                relaxed.append((tuple(set(pre)), adds, costs[index], index))
    for axiom in task.axioms:
        relaxed.append((tuple(set(axiom.body)), (axiom.head,), 0.0, -1))
    cost = [inf] * len(task.facts)
    for fact in bits(state):
        cost[fact] = 0.0
    changed = True
    while changed:
        changed = False
        for pre, adds, c, _op in relaxed:
            pre_costs = [cost[p] for p in pre]
            value = c + (max(pre_costs, default=0.0) if use_max else sum(pre_costs))
            for g in adds:
                if value < cost[g]:
                    cost[g] = value
                    changed = True
    supporter = [-1] * len(task.facts)
    for u, (pre, adds, c, _op) in enumerate(relaxed):
        pre_costs = [cost[p] for p in pre]
        value = c + (max(pre_costs, default=0.0) if use_max else sum(pre_costs))
        for g in adds:
            if supporter[g] < 0 and value == cost[g] < inf and cost[g] > 0:
                supporter[g] = u
    return cost, supporter, [(pre, adds, op) for pre, adds, _c, op in relaxed]


def _reference_values(
    compiled: CompiledTask, costs: list[float], state: int
) -> dict[str, tuple[float, frozenset[int]]]:
    goal = sorted(set(compiled.task.goal))
    result: dict[str, tuple[float, frozenset[int]]] = {}
    for name in ("add", "max"):
        cost, supporter, relaxed = _reference(compiled, costs, state, name == "max")
        values = [cost[g] for g in goal]
        h = (max(values) if name == "max" else sum(values)) if values else 0.0
        # relaxed plan: the supporters of every fact needed, recursively
        needed = [g for g in goal if cost[g] > 0]
        if any(cost[g] == inf for g in needed):
            result[name] = (inf, frozenset())
            if name == "add":
                result["ff"] = (inf, frozenset())
            continue
        seen, ops = set(needed), set()
        while needed:
            pre, _adds, op = relaxed[supporter[needed.pop()]]
            if op >= 0:
                ops.add(op)
            for p in pre:
                if cost[p] > 0 and p not in seen:
                    seen.add(p)
                    needed.append(p)
        result[name] = (h, frozenset(ops))
        if name == "add":
            result["ff"] = (sum(costs[op] for op in ops), frozenset(ops))
    return result


def _states(compiled: CompiledTask, count: int, seed: int) -> list[int]:
    """The initial state and states of random walks from it."""
    rng = random.Random(seed)
    states = [compiled.init]
    while len(states) < count:
        state = compiled.init
        for _ in range(rng.randint(1, 12)):
            ops = compiled.applicable(state)
            if not ops:
                break
            state = compiled.successor(state, rng.choice(ops))
            states.append(state)
    return states[:count]


@pytest.mark.parametrize(("domain", "problem"), CASES)
@pytest.mark.parametrize("unit", [False, True])
def test_engines_equal_the_reference(domain: str, problem: str, unit: bool) -> None:
    compiled = CompiledTask(ground(load(domain, problem)))
    costs = [1.0] * len(compiled.costs) if unit else [c + 0.5 for c in compiled.costs]
    heuristics = {
        (name, engine): RelaxedHeuristic(compiled, name, costs, engine=engine)
        for name in ("add", "ff", "max")
        for engine in ("python", "numpy")
    }
    assert heuristics["ff", "numpy"].engine == "numpy"
    assert heuristics["max", "numpy"].engine == "python"  # h_max has no vectorised engine
    checked = 0
    for state in _states(compiled, 40, seed=len(problem)):
        expected = _reference_values(compiled, costs, state)
        for (name, _engine), heuristic in heuristics.items():
            h, preferred = heuristic(state, True)
            h_ref, ops_ref = expected[name]
            assert h == pytest.approx(h_ref) if h_ref < inf else h == inf
            if h < inf:
                assert frozenset(preferred or ()) == ops_ref
                checked += 1
    assert checked > 0


def test_integral_costs_use_the_bucket_queue_and_agree() -> None:
    compiled = CompiledTask(ground(load("logistics", "three-cities")))
    costs = [1.0] * len(compiled.costs)
    python = RelaxedHeuristic(compiled, "ff", costs, engine="python")
    numpy = RelaxedHeuristic(compiled, "ff", costs, engine="numpy")
    assert python.integral
    for state in _states(compiled, 30, seed=7):
        assert python(state, True) == numpy(state, True)


def test_auto_engine_keeps_small_tasks_on_the_queue() -> None:
    compiled = CompiledTask(ground(load("blocksworld", "sussman")))
    assert RelaxedHeuristic(compiled, "ff", compiled.costs).engine == "python"


def test_unknown_engine_is_an_error() -> None:
    compiled = CompiledTask(ground(load("blocksworld", "sussman")))
    with pytest.raises(ParameterError, match="engine must be one of auto, python, numpy"):
        RelaxedHeuristic(compiled, "ff", compiled.costs, engine="cuda")
