"""Plan runs: a valid plan to the goal with its cost, and how a bad one fails."""

from __future__ import annotations

import pytest
from lab_semantics import DOMAIN, OBJECTS, STATE

from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.formula_model import TRUE, And, Atom
from sdar_tamp.language.plan_run import check_arguments, run_plan
from sdar_tamp.language.state_index import TypedObjects


@pytest.fixture(scope="module")
def domain() -> Domain:
    return parse_domain(DOMAIN)


def test_a_valid_plan_runs_to_the_goal_with_its_cost(domain: Domain) -> None:
    objects = TypedObjects(domain, OBJECTS)
    plan = [("move", ("b1", "p1", "p3")), ("move", ("t1", "p2", "p1"))]
    goal = And((Atom("on", ("b1", "p3")), Atom("empty", ("p2",))))
    run = run_plan(domain, objects, STATE, plan, goal, lambda term: 2.0, explain=True)
    assert run.valid and run.failed_step is None and run.cost == 4.0
    assert len(run.states) == len(run.supports) == len(run.changes) == 2
    assert run.states[0] == frozenset(STATE)
    assert Atom("on", ("b1", "p1")) in run.supports[0]
    assert run.goal_support == {Atom("on", ("b1", "p3"))}  # empty p2 needs no fact


@pytest.mark.parametrize(
    ("step", "reason"),
    [
        (("fly", ("b1",)), "unknown action"),
        (("move", ("b1", "p1")), "wrong number of arguments"),
        (("move", ("b1", "p1", "b2")), "b2 is not of type place"),
        (("move", ("zz", "p1", "p2")), "unknown object zz"),
        (("move", ("b1", "p1", "p3")), "precondition of (move b1 p1 p3) does not hold"),
    ],
)
def test_a_bad_step_ends_the_run_and_says_why(
    domain: Domain, step: tuple[str, tuple[str, ...]], reason: str
) -> None:
    objects = TypedObjects(domain, OBJECTS)
    plan = [("move", ("t1", "p2", "p3")), step]
    run = run_plan(domain, objects, STATE, plan, TRUE)
    assert not run.valid and run.failed_step == 1 and reason in run.reason
    assert len(run.states) == 1 and Atom("on", ("t1", "p3")) in run.final_state


def test_a_plan_that_misses_the_goal_fails_at_step_minus_one(domain: Domain) -> None:
    run = run_plan(domain, TypedObjects(domain, OBJECTS), STATE, [], Atom("lit"))
    assert run.failed_step == -1 and "goal" in run.reason and run.goal_support is None
    assert check_arguments(domain.action("toggle"), ("b1",), TypedObjects(domain, OBJECTS)) is None
