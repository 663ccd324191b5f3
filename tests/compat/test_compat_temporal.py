"""A domain with durative actions through ``solve``: every algorithm returns a plan of
``DurativeAction`` steps (one after the other, each lasting its duration, a stream
``:function`` giving it), which the temporal helpers and the re-check accept."""

from __future__ import annotations

import pytest

from sdar_tamp.compat.pddlstream import DurativeAction, PDDLProblem, solve
from sdar_tamp.compat.pddlstream.check import check_solution
from sdar_tamp.compat.pddlstream.language.temporal import compute_duration, get_end
from solvers.solution import format_solution

DOMAIN = """
(define (domain roads)
  (:requirements :strips :durative-actions)
  (:predicates (at ?p) (road ?a ?b) (driving) (visited ?p))
  (:functions (length ?a ?b))
  (:durative-action drive
   :parameters (?a ?b)
   :duration (= ?duration (length ?a ?b))
   :condition (and (at start (at ?a)) (at start (road ?a ?b)) (over all (driving)))
   :effect (and (at start (not (at ?a))) (at start (driving))
                (at end (not (driving))) (at end (at ?b)) (at end (visited ?b))))
  (:durative-action rest
   :parameters (?p)
   :duration (= ?duration 0.5)
   :condition (and (at start (at ?p)) (at end (at ?p)))
   :effect (at end (visited ?p))))
"""
STREAMS = """
(define (stream roads)
  (:function (length ?a ?b) (road ?a ?b)))
"""
LENGTHS = {("a", "b"): 2.0, ("b", "c"): 5.0, ("a", "c"): 9.0}


def _problem() -> PDDLProblem:
    init = [("at", "a"), *(("road", a, b) for a, b in LENGTHS)]
    goal = ("and", ("at", "c"), ("visited", "b"))
    return PDDLProblem(DOMAIN, {}, STREAMS, {"length": lambda a, b: LENGTHS[(a, b)]}, init, goal)


@pytest.mark.parametrize("algorithm", ["adaptive", "focused", "binding", "incremental"])
def test_plans_are_durative_actions_one_after_the_other(algorithm: str) -> None:
    problem = _problem()
    solution = solve(problem, algorithm=algorithm, max_time=60)
    plan = solution.plan
    assert plan is not None and all(isinstance(a, DurativeAction) for a in plan)
    assert [(a.name, a.args) for a in plan] == [("drive", ("a", "b")), ("drive", ("b", "c"))]
    assert [(a.start, a.duration) for a in plan] == [(0.0, 2.0), (2.0, 5.0)]
    assert get_end(plan[-1]) == compute_duration(plan) == solution.cost == 7.0
    assert check_solution(problem, solution) is None
    assert "[start 2, duration 5]" in format_solution(solution)


def test_the_recheck_runs_each_durative_step_in_its_stages() -> None:
    problem = _problem()
    solution = solve(problem, algorithm="adaptive", max_time=60)
    assert solution.plan is not None
    broken = type(solution)(
        [DurativeAction("rest", ("b",), 0.0, 0.5), *solution.plan], solution.cost
    )
    assert "step 1: the at-start condition of (rest " in str(check_solution(problem, broken))
