"""Heuristic values on a hand-computed task, and preferred operators."""

from __future__ import annotations

import math

import pytest

from sdar_tamp.language.domain_model import ActionSchema, Domain, TypeHierarchy
from sdar_tamp.language.formula_model import And, AndEffect, Atom, IncreaseCost, Literal
from solvers.classical import PlanningTask, ground
from solvers.classical.bitset_task import CompiledTask, mask
from solvers.classical.heuristics import RelaxedHeuristic


def _op(name: str, pre: list[str], add: list[str], cost: float) -> ActionSchema:
    effects = [Literal(Atom(p)) for p in add] + [IncreaseCost(cost)]
    return ActionSchema(name, (), And(tuple(Atom(p) for p in pre)), AndEffect(tuple(effects)))


def _task(goal: list[str], with_noop: bool = True) -> PlanningTask:
    spoil = ActionSchema("spoil", (), And(()), Literal(Atom("a"), negated=True))
    #   a --op1(2)--> b ;  a --op2(3)--> c ;  b,c --op3(1)--> g ;  b --op4(4)--> h
    actions = (
        _op("op1", ["a"], ["b"], 2.0),
        _op("op2", ["a"], ["c"], 3.0),
        _op("op3", ["b", "c"], ["g"], 1.0),
        _op("op4", ["b"], ["h"], 4.0),
        _op("noop", [], ["a"], 0.0) if with_noop else spoil,
    )
    domain = Domain("tiny", frozenset(), TypeHierarchy(), {}, {}, {}, actions, ())
    goal_formula = And(tuple(Atom(p) for p in goal))
    return PlanningTask(domain, {}, frozenset({Atom("a")}), goal_formula)


def _evaluate(goal: list[str], name: str) -> tuple[float, set[str] | None]:
    compiled = CompiledTask(ground(_task(goal)))
    heuristic = RelaxedHeuristic(compiled, name, compiled.costs)
    h, preferred = heuristic(compiled.init, True)
    ops = compiled.task.operators
    return h, None if preferred is None else {ops[i].name for i in preferred}


@pytest.mark.parametrize(
    ("name", "expected"),
    [("max", 6.0), ("add", 12.0), ("ff", 10.0), ("blind", 0.0)],
)
def test_heuristic_values_by_hand(name: str, expected: float) -> None:
    # b=2, c=3; g: max(2,3)+1=4 (h_max), 2+3+1=6 (h_add); h: 2+4=6.
    # h_max = max(4, 6) = 6; h_add = 6 + 6 = 12; h_FF = op1+op2+op3+op4 = 2+3+1+4 = 10.
    h, _ = _evaluate(["g", "h"], name)
    assert h == expected


def test_ff_preferred_operators_are_its_relaxed_plan() -> None:
    h, preferred = _evaluate(["g"], "ff")
    assert h == 6.0
    assert preferred == {"op1", "op2", "op3"}


def test_goal_state_has_zero_and_dead_end_infinite() -> None:
    assert _evaluate(["a"], "ff")[0] == 0.0
    assert _evaluate(["a"], "add")[0] == 0.0
    task = ground(_task(["g"], with_noop=False))
    compiled = CompiledTask(task)
    only_b = mask([task.facts.index(Atom("b"))])
    for name in ("add", "max", "ff"):
        heuristic = RelaxedHeuristic(compiled, name, compiled.costs)
        assert math.isinf(heuristic(only_b, False)[0])  # a is gone for good: no c
        assert heuristic(compiled.init, False)[0] < math.inf


def test_heuristic_from_a_later_state() -> None:
    compiled = CompiledTask(ground(_task(["g"])))
    task = compiled.task
    only_b = mask([task.facts.index(Atom("b"))])
    # c via noop (0) + op2 (3), then op3 (1): h_add = 4, h_max = 4, h_FF = 4.
    for name in ("add", "max", "ff"):
        assert RelaxedHeuristic(compiled, name, compiled.costs)(only_b, False)[0] == 4.0
