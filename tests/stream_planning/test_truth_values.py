"""A test stream (and a ``:predicate``) must answer with a bool: ``bool`` or ``numpy.bool_``;
``None`` counts as False (a PDDLStream test that falls off its end). Anything else is an error
naming the stream and the value, never judged by its truthiness."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from test_features import PREDICATE_STREAM, counting, line_problem
from test_negate import NEGATE, shelf

from sdar_tamp.language.generators import from_test
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Status
from solvers.solve import solve
from solvers.stream_planning.externals import StreamOutputError

ALGORITHMS = ("incremental", "focused", "binding", "adaptive")
DOMAIN = """
(define (domain gate)
  (:predicates (item ?x) (ok ?x) (done))
  (:action take :parameters (?x) :precondition (and (item ?x) (ok ?x)) :effect (done)))
"""
STREAM = """
(define (stream gate)
  (:stream test-ok :inputs (?x) :domain (item ?x) :certified (ok ?x)))
"""


def gate(answer: Any) -> PDDLProblem:
    test = from_test(lambda x: answer)
    return PDDLProblem(DOMAIN, {}, STREAM, {"test-ok": test}, [("item", "x1")], ("done",))


@pytest.mark.parametrize("algorithm", ALGORITHMS)
@pytest.mark.parametrize(
    ("answer", "shown"), [("no", "str: 'no'"), (1, "int: 1"), ([True], "list: [True]")]
)
def test_test_returning_a_non_bool_is_an_error(algorithm: str, answer: Any, shown: str) -> None:
    with pytest.raises(StreamOutputError) as info:
        solve(gate(answer), algorithm=algorithm, max_time=30, verbose=False)
    message = str(info.value)
    assert "stream 'test-ok' on inputs ('x1')" in message
    assert shown in message and "must return a bool" in message


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_bools_numpy_bools_and_none(algorithm: str) -> None:
    for answer, solved in [(True, True), (np.True_, True), (np.bool_(False), False),
                           (False, False), (None, False)]:  # fmt: skip
        solution = solve(gate(answer), algorithm=algorithm, max_time=30, verbose=False)
        assert solution.solved is solved, (answer, solution.diagnosis)
        if not solved:
            assert solution.status is Status.INFEASIBLE


def test_predicate_returning_a_non_bool_is_an_error() -> None:
    problem = line_problem(counting(), PREDICATE_STREAM, blocked=lambda b, p: "yes")
    with pytest.raises(StreamOutputError, match=r"predicate 'blocked' on inputs .*str: 'yes'"):
        solve(problem, max_time=30, verbose=False)


def test_predicate_returning_a_numpy_bool_is_accepted() -> None:
    problem = line_problem(counting(), PREDICATE_STREAM, blocked=lambda b, p: np.bool_(p < 7))
    solution = solve(problem, max_time=30, verbose=False)
    assert [a.args for a in solution.plan or []] == [("a", 0.0, 7.0)]


def test_negated_test_returning_a_non_bool_is_an_error() -> None:
    with pytest.raises(StreamOutputError, match=r"negated test stream 'test-blocked'.*str: 'no'"):
        solve(shelf(from_test(lambda x: "no")), stream_info=NEGATE, max_time=30, verbose=False)
