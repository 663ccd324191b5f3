"""Universally quantified conditions: expanded when small, a negated axiom when large."""

from __future__ import annotations

import pytest

from sdar_tamp.language import parse_domain, parse_problem
from solvers.classical import PlanningTask, ground, plan, task_from_problem, validated_plan_cost
from solvers.classical import normalize as normalize_module
from solvers.classical.join import (
    DEADLINE_STRIDE,
    FactBase,
    GroundingTimeout,
    compile_join,
    run_join,
)
from solvers.classical.normalize import Lit

DOMAIN = """(define (domain shelf) (:requirements :adl)
 (:predicates (item ?b) (spot ?p) (holding ?b) (at ?b ?p) (apart ?p ?q))
 (:action place :parameters (?b ?p)
  :precondition (and (item ?b) (spot ?p) (holding ?b)
                     (forall (?b2 ?p2) (imply (at ?b2 ?p2) (apart ?p ?p2))))
  :effect (and (at ?b ?p) (not (holding ?b)))))
"""
# p1 is next to p0 (not apart), p2 and p3 are apart from p0; a0 sits at p0
PROBLEM = """(define (problem two) (:domain shelf)
 (:objects a0 a1 p0 p1 p2 p3)
 (:init (item a0) (item a1) (spot p0) (spot p1) (spot p2) (spot p3) (at a0 p0) (holding a1)
        (apart p2 p0) (apart p3 p0) (apart p0 p2) (apart p0 p3) (apart p2 p3) (apart p3 p2))
 (:goal (and (at a1 ?SPOT))))
"""


def _task(spot: str) -> PlanningTask:
    domain = parse_domain(DOMAIN, "domain.pddl")
    problem = parse_problem(PROBLEM.replace("?SPOT", spot), domain, "problem.pddl")
    return task_from_problem(domain, problem)


def test_a_large_forall_is_one_negated_axiom_literal() -> None:
    grounded = ground(_task("p2"))
    # 6 objects: 36 combinations > the limit, so no expansion into 36 literals
    assert normalize_module.FORALL_EXPANSION_LIMIT < 36
    places = [op for op in grounded.operators if op.name == "place"]
    assert places
    for op in places:
        assert len(op.negative_precondition) == 1
        (fact,) = op.negative_precondition
        assert grounded.facts[fact].predicate.startswith("~aux")
    assert grounded.axioms
    # the static sibling (spot ?p) restricts the axiom to spots, not every object
    heads = {grounded.facts[axiom.head] for axiom in grounded.axioms}
    assert heads and all(atom.args[0].startswith("p") for atom in heads)


@pytest.mark.parametrize("expanded", [False, True])
@pytest.mark.parametrize(("spot", "solvable"), [("p2", True), ("p1", False), ("p0", False)])
def test_both_compilations_agree(
    spot: str, solvable: bool, expanded: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    if expanded:
        monkeypatch.setattr(normalize_module, "FORALL_EXPANSION_LIMIT", 10**6)
    task = _task(spot)
    grounded = ground(task)
    if expanded:
        assert not any(op.negative_precondition for op in grounded.operators)
    result = plan(task)
    assert result.solved is solvable
    if solvable:
        assert result.plan is not None
        assert validated_plan_cost(task, result.plan) == 1


def test_a_join_checks_the_deadline_while_it_runs() -> None:
    facts = FactBase(("num", (str(i),)) for i in range(3 * DEADLINE_STRIDE))
    join = compile_join([Lit("num", ("?x",))], [])
    assert len(list(run_join(join, facts))) == 3 * DEADLINE_STRIDE
    seen = 0
    with pytest.raises(GroundingTimeout):
        for _ in run_join(join, facts, deadline=0.0):
            seen += 1
    assert seen < DEADLINE_STRIDE


def test_grounding_past_its_deadline_stops() -> None:
    with pytest.raises(GroundingTimeout):
        ground(_task("p2"), deadline=0.0)
