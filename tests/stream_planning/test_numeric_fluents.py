"""Numeric fluents with stream functions: a rover's fuel (a numeric fluent) limits the legs it
may drive, whose lengths a ``:function`` computes. The optimistic algorithms plan with the
function's optimistic value, evaluate the plan's terms for real, and return only a plan whose
fuel suffices with the real lengths."""

from __future__ import annotations

from typing import Any

import pytest

from sdar_tamp.language.options import PlanConstraints
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Status
from solvers.solve import solve

DOMAIN = """
(define (domain rover)
  (:requirements :strips :numeric-fluents :action-costs)
  (:predicates (At ?l) (Road ?a ?b) (Depot ?l))
  (:functions (Fuel) (Length ?a ?b) (total-cost))
  (:action drive :parameters (?a ?b)
    :precondition (and (At ?a) (Road ?a ?b) (>= (Fuel) (Length ?a ?b)))
    :effect (and (At ?b) (not (At ?a)) (decrease (Fuel) (Length ?a ?b))
                 (increase (total-cost) (Length ?a ?b))))
  (:action refuel :parameters (?l)
    :precondition (and (At ?l) (Depot ?l) (< (Fuel) 5))
    :effect (and (assign (Fuel) 5) (increase (total-cost) 1))))
"""
STREAMS = """
(define (stream rover)
  (:function (Length ?a ?b) (Road ?a ?b)))
"""
# a - b - c - d in a line; the depot is at b. Lengths: a-b 2, b-c 3, c-d 1.
LENGTHS = {("a", "b"): 2, ("b", "c"): 3, ("c", "d"): 1}


def _problem(calls: list[tuple[Any, ...]], fuel: float) -> PDDLProblem:
    def length(a: str, b: str) -> float:
        calls.append((a, b))
        return float(LENGTHS.get((a, b), LENGTHS.get((b, a), 0)))

    init: list[tuple[Any, ...]] = [("At", "a"), ("Depot", "b"), ("=", ("Fuel",), fuel)]
    for a, b in LENGTHS:
        init += [("Road", a, b), ("Road", b, a)]
    return PDDLProblem(DOMAIN, {}, STREAMS, {"length": length}, init, ("At", "d"))


@pytest.mark.parametrize("algorithm", ["adaptive", "focused", "incremental"])
def test_the_plan_refuels_where_the_real_lengths_need_it(algorithm: str) -> None:
    calls: list[tuple[Any, ...]] = []
    solution = solve(_problem(calls, 4.0), algorithm=algorithm, max_time=60)
    assert solution.plan is not None
    names = [(a.name, tuple(a.args)) for a in solution.plan]
    # 4 - 2 = 2 left at b: b -> c needs 3, so a refuel at b
    assert names == [
        ("drive", ("a", "b")),
        ("refuel", ("b",)),
        ("drive", ("b", "c")),
        ("drive", ("c", "d")),
    ]
    assert solution.cost == pytest.approx(7.0)
    assert ("b", "c") in calls


def test_enough_fuel_drives_straight_through() -> None:
    solution = solve(_problem([], 6.0), algorithm="adaptive", max_time=60)
    assert solution.plan is not None
    assert [a.name for a in solution.plan] == ["drive", "drive", "drive"]


def test_a_function_read_only_by_numeric_conditions_is_evaluated() -> None:
    # the leg lengths no longer cost anything: only the fuel condition reads them
    domain = DOMAIN.replace("(increase (total-cost) (Length ?a ?b))", "(increase (total-cost) 1)")
    calls: list[tuple[Any, ...]] = []
    problem = _problem(calls, 4.0)
    problem = PDDLProblem(domain, {}, STREAMS, problem.stream_map, problem.init, problem.goal)
    solution = solve(problem, algorithm="adaptive", max_time=60)
    assert solution.plan is not None
    assert [a.name for a in solution.plan] == ["drive", "refuel", "drive", "drive"]
    assert calls


def test_a_skeleton_keeps_the_fuel_condition() -> None:
    # without its numeric condition the skeleton's copy of drive would run dry between b and c
    straight = PlanConstraints(skeletons=[[("drive", ("a", "b")), ("drive", ("b", "c"))]])
    problem = _problem([], 4.0)
    problem = PDDLProblem(DOMAIN, {}, STREAMS, problem.stream_map, problem.init, ("At", "c"))
    solution = solve(problem, algorithm="adaptive", max_time=20, constraints=straight)
    assert solution.plan is None
    assert solution.status is not Status.SOLVED


def test_a_skeleton_keeps_the_numeric_effects() -> None:
    skeleton = [("drive", ("a", "b")), ("refuel", ("b",)), ("drive", ("b", "c"))]
    skeleton.append(("drive", ("c", "d")))
    solution = solve(
        _problem([], 4.0),
        algorithm="adaptive",
        max_time=60,
        constraints=PlanConstraints(skeletons=[skeleton]),
    )
    assert solution.plan is not None
    assert [a.name for a in solution.plan] == ["drive", "refuel", "drive", "drive"]
    # the legs' lengths (2 + 3 + 1) and the refuel (1), costed by expression
    assert solution.cost == pytest.approx(7.0)
