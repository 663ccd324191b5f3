"""Planning over numeric fluents: the classical planner (both searches, and through the
stream planner's optimistic rounds) finds plans that need a fluent's value, at their true cost,
and none where the values forbid every plan."""

from __future__ import annotations

import pytest

from sdar_tamp.language import parse_domain, parse_problem
from solvers.classical import GroundAction, PlanStatus, plan, task_from_problem

DOMAIN = """
(define (domain fuel)
  (:requirements :typing :numeric-fluents :action-costs)
  (:types loc rover)
  (:predicates (at ?r - rover ?l - loc) (road ?a ?b - loc) (depot ?l - loc))
  (:functions (fuel ?r - rover) (dist ?a ?b - loc) (capacity ?r - rover) (total-cost))
  (:action drive
    :parameters (?r - rover ?a ?b - loc)
    :precondition (and (at ?r ?a) (road ?a ?b) (>= (fuel ?r) (dist ?a ?b)))
    :effect (and (not (at ?r ?a)) (at ?r ?b) (decrease (fuel ?r) (dist ?a ?b))
                 (increase (total-cost) (dist ?a ?b))))
  (:action refuel
    :parameters (?r - rover ?l - loc)
    :precondition (and (at ?r ?l) (depot ?l) (< (fuel ?r) (capacity ?r)))
    :effect (and (assign (fuel ?r) (capacity ?r)) (increase (total-cost) 1))))
"""

PROBLEM = """
(define (problem p) (:domain fuel)
  (:objects a b c d - loc r - rover)
  (:init (at r a) (road a b) (road b a) (road b c) (road c b) (road c d) (road d c) (depot b)
    (= (fuel r) FUEL) (= (capacity r) CAPACITY) (= (dist a b) 2) (= (dist b a) 2)
    (= (dist b c) 3) (= (dist c b) 3) (= (dist c d) 1) (= (dist d c) 1) (= (total-cost) 0))
  (:goal (at r d))
  (:metric minimize (total-cost)))
"""


def _task(fuel: float, capacity: float):  # type: ignore[no-untyped-def]
    domain = parse_domain(DOMAIN, "d.pddl")
    text = PROBLEM.replace("FUEL", str(fuel)).replace("CAPACITY", str(capacity))
    return task_from_problem(domain, parse_problem(text, domain, "p.pddl"))


@pytest.mark.parametrize("search", ["gbfs", "astar", "lazy-gbfs"])
def test_a_refuel_is_planned_where_the_fuel_runs_short(search: str) -> None:
    result = plan(_task(3, 4), search=search)
    assert result.status is PlanStatus.SOLVED
    assert result.plan == (
        GroundAction("drive", ("r", "a", "b")),
        GroundAction("refuel", ("r", "b")),
        GroundAction("drive", ("r", "b", "c")),
        GroundAction("drive", ("r", "c", "d")),
    )
    assert result.cost == 7.0


def test_enough_fuel_needs_no_refuel() -> None:
    result = plan(_task(6, 6), search="astar")
    assert result.plan is not None
    assert [step.name for step in result.plan] == ["drive", "drive", "drive"]
    assert result.cost == 6.0


def test_a_tank_too_small_leaves_no_plan() -> None:
    result = plan(_task(2, 2), search="astar")  # b -> c needs 3
    assert result.status is PlanStatus.UNSOLVABLE
    assert result.plan is None


DURATIVE = """
(define (domain robot)
  (:requirements :durative-actions :numeric-fluents)
  (:predicates (at ?r ?q) (motion ?a ?t ?b) (dock ?q))
  (:functions (energy ?r) (capacity ?r) (rate ?r) (length ?t))
  (:durative-action recharge
   :parameters (?r ?q)
   :duration (= ?duration (/ (- (capacity ?r) (energy ?r)) (rate ?r)))
   :condition (and (at start (at ?r ?q)) (at start (dock ?q))
                   (at start (< (energy ?r) (capacity ?r))))
   :effect (at end (increase (energy ?r) (* (rate ?r) ?duration))))
  (:durative-action move
   :parameters (?r ?a ?t ?b)
   :duration (= ?duration (length ?t))
   :condition (and (at start (at ?r ?a)) (at start (motion ?a ?t ?b))
                   (at start (<= ?duration (energy ?r))))
   :effect (and (at start (decrease (energy ?r) ?duration)) (at start (not (at ?r ?a)))
                (at end (at ?r ?b)))))
"""
DURATIVE_PROBLEM = """
(define (problem p) (:domain robot)
  (:objects r a b c t1 t2)
  (:init (at r a) (dock b) (motion a t1 b) (motion b t2 c)
    (= (energy r) 5) (= (capacity r) 8) (= (rate r) 2) (= (length t1) 4) (= (length t2) 6))
  (:goal (at r c))
  (:metric minimize (total-time)))
"""


def test_durative_actions_with_numeric_fluents_recharge_on_the_way() -> None:
    domain = parse_domain(DURATIVE, "d.pddl")
    task = task_from_problem(domain, parse_problem(DURATIVE_PROBLEM, domain, "p.pddl"))
    result = plan(task, search="astar")
    assert result.plan == (
        GroundAction("move", ("r", "a", "t1", "b")),
        GroundAction("recharge", ("r", "b")),
        GroundAction("move", ("r", "b", "t2", "c")),
    )
    # 4 s, then (8 - 1) / 2 = 3.5 s of recharge, then 6 s
    assert result.cost == pytest.approx(4.0 + 3.5 + 6.0)
