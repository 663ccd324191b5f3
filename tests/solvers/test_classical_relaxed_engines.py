"""The relaxed heuristics' engines (queue-based, compiled, vectorised) against a plain fixpoint
reference."""

from __future__ import annotations

import random
from math import inf

import pytest
from classical_helpers import load

from sdar_tamp.errors import ParameterError
from solvers.classical import ground, jit
from solvers.classical.bitset_task import CompiledTask, bits
from solvers.classical.complements import complements
from solvers.classical.heuristics import VECTOR_MIN_SIZE, RelaxedHeuristic
from solvers.classical.problem import PlanningTask

needs_numba = pytest.mark.skipif(not jit.available(), reason="numba is not installed")

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
    """Costs by repeated sweeps to a fixpoint; best supporter = lowest relaxed-operator id.
    The relaxed task has the complements of negated facts (``solvers.classical.complements``)."""
    task = compiled.task
    comp = complements(task)
    relaxed: list[tuple[tuple[int, ...], tuple[int, ...], float, int]] = []
    for index, op in enumerate(task.operators):
        pre = comp.positive(op.precondition, op.negative_precondition)
        effects = [(pre, op.adds + comp.deleted(op.deletes, op.adds))]
        effects += [
            (pre + comp.positive(c.condition, c.negative_condition),
             c.adds + comp.deleted(c.deletes, c.adds))
            for c in op.conditional
        ]  # fmt: skip
        for condition, adds in effects:
            if adds:
                relaxed.append((tuple(set(condition)), adds, costs[index], index))
    for axiom in task.axioms:
        body = comp.positive(axiom.body, axiom.negative_body)
        relaxed.append((tuple(set(body)), (axiom.head,), 0.0, -1))
    for body, head in comp.rules:
        relaxed.append((tuple(set(body)), (head,), 0.0, -1))
    cost = [inf] * comp.count
    for fact in bits(comp.extend(state)):
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
    supporter = [-1] * comp.count
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
    task = compiled.task
    goal = sorted(set(complements(task).positive(task.goal, task.negative_goal)))
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
        for engine in ("python", "numpy") + (("numba",) if jit.available() else ())
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


def _gripper(balls: int) -> PlanningTask:
    """A gripper task with ``balls`` balls (large enough for the compiled engine from ~70)."""
    from sdar_tamp.language import parse_domain, parse_problem
    from solvers.classical import task_from_problem

    domain = parse_domain(
        """(define (domain gripper) (:requirements :strips :typing)
  (:types room ball gripper)
  (:predicates (at-robby ?r - room) (at ?b - ball ?r - room) (free ?g - gripper)
               (carry ?b - ball ?g - gripper))
  (:action move :parameters (?from ?to - room)
    :precondition (at-robby ?from) :effect (and (at-robby ?to) (not (at-robby ?from))))
  (:action pick :parameters (?b - ball ?r - room ?g - gripper)
    :precondition (and (at ?b ?r) (at-robby ?r) (free ?g))
    :effect (and (carry ?b ?g) (not (at ?b ?r)) (not (free ?g))))
  (:action drop :parameters (?b - ball ?r - room ?g - gripper)
    :precondition (and (carry ?b ?g) (at-robby ?r))
    :effect (and (at ?b ?r) (free ?g) (not (carry ?b ?g)))))"""
    )
    names = " ".join(f"b{i}" for i in range(balls))
    problem = parse_problem(
        f"""(define (problem g{balls}) (:domain gripper)
  (:objects r1 r2 r3 - room left right - gripper {names} - ball)
  (:init (at-robby r1) (free left) (free right)
         {" ".join(f"(at b{i} r{1 + i % 3})" for i in range(balls))})
  (:goal (and {" ".join(f"(at b{i} r{1 + (i + 1) % 3})" for i in range(balls))})))""",
        domain,
    )
    return task_from_problem(domain, problem)


@needs_numba
def test_auto_engine_compiles_large_tasks_and_agrees() -> None:
    from solvers.classical import plan

    task = _gripper(100)
    compiled = CompiledTask(ground(task))
    auto = RelaxedHeuristic(compiled, "ff", compiled.costs)
    assert auto.engine == "numba"
    size = sum(map(len, auto.upre)) + sum(map(len, auto.ueff))
    assert size >= VECTOR_MIN_SIZE
    python = RelaxedHeuristic(compiled, "ff", compiled.costs, engine="python")
    python.canonical, python.heap_order = False, True  # as "auto" on a large task
    for state in _states(compiled, 60, seed=3):
        assert auto(state, True) == python(state, True)
    # and the planner runs on it (its plan is validated by plan())
    fast = plan(task, search="lazy-gbfs", heuristic="ff-lmcount")
    assert fast.plan is not None and fast.statistics.expanded > 0


@needs_numba
@pytest.mark.parametrize("unit", [True, False])
@pytest.mark.parametrize("name", ["ff", "add", "max"])
def test_compiled_engine_follows_the_queue_exploration_order(unit: bool, name: str) -> None:
    """First-found supporters in the heap's order, for whole and fractional costs."""
    for task in (_gripper(100), load("logistics", "three-cities"), load("briefcase", "office")):
        compiled = CompiledTask(ground(task))
        costs = [1.0] * len(compiled.costs) if unit else [c + 0.5 for c in compiled.costs]
        python = RelaxedHeuristic(compiled, name, costs, engine="python")
        python.canonical, python.heap_order = False, True
        fast = RelaxedHeuristic(compiled, name, costs, engine="python")
        fast.canonical = False
        fast.use_compiled()
        assert fast.jit is not None and fast.heap_order
        for state in _states(compiled, 50, seed=9):
            assert fast(state, True) == python(state, True)


@needs_numba
def test_auto_engine_on_large_tasks_keeps_the_exploration_order() -> None:
    from solvers.classical import jit_relaxed

    compiled = CompiledTask(ground(_gripper(100)))
    loaded = jit_relaxed.kernel_loaded()
    auto = RelaxedHeuristic(compiled, "ff", compiled.costs)
    # compiled at once when an earlier task loaded the compiled code, else after a while
    assert (auto.jit is not None) if loaded else auto.jit_pending
    assert not auto.canonical
    assert auto.heap_order  # the heap, whose order the compiled engine follows fastest
    reference = RelaxedHeuristic(compiled, "ff", compiled.costs, engine="python")
    reference.canonical, reference.heap_order = False, True
    if not loaded:
        auto.use_compiled()
    assert auto.jit is not None and jit_relaxed.kernel_loaded()
    later = RelaxedHeuristic(compiled, "ff", compiled.costs)  # the next task of the process
    assert later.jit is not None and not later.jit_pending and later.engine == "numba"
    for state in _states(compiled, 40, seed=6):
        assert auto(state, True) == reference(state, True) == later(state, True)


@needs_numba
def test_compiled_engine_dead_end_and_goal_states() -> None:
    compiled = CompiledTask(ground(load("blocksworld", "sussman")))
    for name in ("ff", "add", "max"):
        heuristic = RelaxedHeuristic(compiled, name, compiled.costs, engine="numba")
        assert heuristic.engine == "numba"
        goal_state = compiled.init | compiled.goal_mask
        h, preferred = heuristic(goal_state, True)
        assert h == 0.0 and not preferred
    # a dead end: no fact at all is true, so no operator is applicable
    for name, expected in (("ff", set()), ("add", None), ("max", None)):
        heuristic = RelaxedHeuristic(compiled, name, compiled.costs, engine="numba")
        assert heuristic(0, True) == (inf, expected)


def test_numba_engine_without_numba_is_an_error(monkeypatch: pytest.MonkeyPatch) -> None:
    compiled = CompiledTask(ground(load("blocksworld", "sussman")))
    monkeypatch.setattr(jit, "available", lambda: False)
    with pytest.raises(
        ParameterError,
        match="engine 'numba' is unavailable: numba is not installed: pip install numba",
    ):
        RelaxedHeuristic(compiled, "ff", compiled.costs, engine="numba")
    # "auto" falls back to the other engines
    task = _gripper(100)
    large = CompiledTask(ground(task))
    assert RelaxedHeuristic(large, "ff", large.costs).engine in ("python", "numpy")


def test_auto_engine_keeps_small_tasks_on_the_queue() -> None:
    compiled = CompiledTask(ground(load("blocksworld", "sussman")))
    assert RelaxedHeuristic(compiled, "ff", compiled.costs).engine == "python"


def test_unknown_engine_is_an_error() -> None:
    compiled = CompiledTask(ground(load("blocksworld", "sussman")))
    with pytest.raises(ParameterError, match="engine must be one of auto, python, numpy, numba"):
        RelaxedHeuristic(compiled, "ff", compiled.costs, engine="cuda")
