"""The plan validator: independent simulation of the lifted actions."""

from __future__ import annotations

import pytest
from classical_helpers import load

from solvers.classical import GroundAction, PlanValidationError, plan, validated_plan_cost


def test_valid_plan_returns_its_cost() -> None:
    task = load("delivery_costs", "detour")
    result = plan(task, search="astar", heuristic="max")
    assert result.plan is not None
    assert validated_plan_cost(task, result.plan) == 11.0


@pytest.mark.parametrize(
    ("corrupt", "message"),
    [
        (lambda p: p[1:], "precondition"),
        (lambda p: p[:-1], "goal"),
        (lambda p: (p[1], p[0], *p[2:]), "precondition"),
        (lambda p: (GroundAction("fly", ("c",)), *p), "unknown action"),
        (lambda p: (GroundAction("pick-up", ("a", "b")), *p), "number of arguments"),
        (lambda p: (GroundAction("pick-up", ("zz",)), *p), "unknown object"),
    ],
)
def test_validator_rejects_corrupted_plans(corrupt, message: str) -> None:  # type: ignore[no-untyped-def]
    task = load("blocksworld", "sussman")
    result = plan(task)
    assert result.plan is not None
    validated_plan_cost(task, result.plan)
    with pytest.raises(PlanValidationError, match=message):
        validated_plan_cost(task, corrupt(result.plan))


def test_validator_simulates_conditional_effects_and_axioms() -> None:
    task = load("briefcase", "office")
    result = plan(task)
    assert result.plan is not None
    steps = list(result.plan)
    validated_plan_cost(task, steps)
    # dropping a take-out leaves a document in the case: the goal (not (in ...)) fails
    index = next(i for i, a in enumerate(steps) if a.name == "take-out" and a.args[0] == "letter")
    with pytest.raises(PlanValidationError):
        validated_plan_cost(task, steps[:index] + steps[index + 1 :])
