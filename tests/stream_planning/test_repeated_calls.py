"""A plan that needs several new outputs of one stream instance (a stream without inputs)."""

from __future__ import annotations

import itertools
from collections.abc import Iterator

import pytest
from stream_helpers import ALGORITHMS

from sdar_tamp.language.generators import from_gen_fn, from_list_fn, from_test
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Status
from solvers.solve import solve

# Two steps, each taking a value no step took before: the goal needs two distinct values.
DOMAIN = """(define (domain pairs) (:requirements :strips :negative-preconditions)
  (:predicates (val ?x) (taken ?x) (one) (two) (good ?x) (done))
  (:action first :parameters (?x) :precondition (and (val ?x) (not (taken ?x)) (not (one)))
     :effect (and (taken ?x) (one)))
  (:action second :parameters (?x) :precondition (and (val ?x) (not (taken ?x)) (one))
     :effect (and (taken ?x) (two)))
  (:action finish :parameters (?x) :precondition (good ?x) :effect (done)))"""
STREAMS = """(define (stream pairs)
  (:stream sample-x :outputs (?x) :certified (val ?x))
  (:stream test-good :inputs (?x) :domain (val ?x) :certified (good ?x)))"""


def counting() -> Iterator[tuple[int]]:
    for k in itertools.count():
        yield (k,)


def problem(goal: tuple[str, ...], sampler: object = None) -> PDDLProblem:
    stream_map = {
        "sample-x": sampler if sampler is not None else from_gen_fn(counting),
        "test-good": from_test(lambda x: x >= 2),
    }
    return PDDLProblem(DOMAIN, {}, STREAMS, stream_map, [], goal)


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_two_distinct_values_of_a_stream_without_inputs(algorithm: str) -> None:
    solution = solve(problem(("two",)), algorithm=algorithm, max_time=20, verbose=False)
    assert solution.status is Status.SOLVED, solution.diagnosis
    assert solution.plan is not None
    values = [a.args[0] for a in solution.plan]
    assert [a.name for a in solution.plan] == ["first", "second"]
    assert len(set(values)) == 2
    assert solution.streams["sample-x"].calls >= 2


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_values_failing_a_test_are_followed_by_new_ones(algorithm: str) -> None:
    solution = solve(problem(("done",)), algorithm=algorithm, max_time=20, verbose=False)
    assert solution.status is Status.SOLVED, solution.diagnosis
    assert [(a.name, a.args) for a in solution.plan or []] == [("finish", (2,))]


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_one_value_only_is_still_proven_infeasible(algorithm: str) -> None:
    # the sampler runs dry after one value: no second distinct value exists
    once = from_list_fn(lambda: [(0,)])
    solution = solve(problem(("two",), once), algorithm=algorithm, max_time=20, verbose=False)
    assert solution.status is Status.INFEASIBLE
    assert solution.streams["sample-x"].calls <= 1


@pytest.mark.parametrize("algorithm", ["focused", "binding", "adaptive"])
def test_goal_out_of_relaxed_reach_is_proven_infeasible(algorithm: str) -> None:
    # (incremental calls the generator for ever)
    # no value is called "nothing", however many the endless generator gives: the goal is
    # not reachable even ignoring deletes, so later calls could not help
    solution = solve(problem(("taken", "nothing")), algorithm=algorithm, max_time=20, verbose=False)
    assert solution.status is Status.INFEASIBLE
    assert solution.statistics["iterations"] <= 20


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_a_test_adds_no_complexity_on_its_first_call(algorithm: str) -> None:
    # one sample (level 1) and its test (still level 1, as in PDDLStream): solved at level 1
    stream_map = {"sample-x": from_gen_fn(counting), "test-good": from_test(lambda x: True)}
    goal_problem = PDDLProblem(DOMAIN, {}, STREAMS, stream_map, [], ("done",))
    solution = solve(goal_problem, algorithm=algorithm, max_time=20, verbose=False)
    assert solution.status is Status.SOLVED
    assert solution.statistics["complexity"] == 1
