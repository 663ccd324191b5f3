"""``StreamInfo(negate=True)``: a test stream whose certified fact is used negated.

``(not (blocked ?x))`` holds for an instance exactly when the test ``test-blocked`` says False;
without ``negate`` such a use holds until the test certifies the fact (as in PDDLStream), noted in
the log with the option; PDDLStream's automatic negation of tests under negated derived
predicates is applied too.
"""

from __future__ import annotations

import itertools
import logging
from collections.abc import Iterator
from typing import Any

import pytest
from test_features import line_problem

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.generators import from_gen_fn, from_test
from sdar_tamp.language.options import StreamInfo
from sdar_tamp.language.problem import PDDLProblem
from solvers.solve import solve
from solvers.stream_planning.externals import StreamError

ALGORITHMS = ("incremental", "focused", "binding", "adaptive")
DOMAIN = """
(define (domain shelf)
  (:requirements :strips :negative-preconditions)
  (:predicates (item ?x) (blocked ?x) (taken ?x) (done))
  (:action take :parameters (?x)
    :precondition (and (item ?x) (not (blocked ?x)))
    :effect (and (taken ?x) (done))))
"""
TEST_STREAM = """
(define (stream shelf)
  (:stream test-blocked :inputs (?x) :domain (item ?x) :certified (blocked ?x)))
"""
ITEMS = ("x1", "x2", "x3")
NEGATE = {"test-blocked": StreamInfo(negate=True)}


def shelf(test: Any, stream_pddl: str = TEST_STREAM) -> PDDLProblem:
    init = [("item", x) for x in ITEMS]
    return PDDLProblem(DOMAIN, {}, stream_pddl, {"test-blocked": test}, init, ("done",))


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_negated_test_holds_where_the_test_fails(algorithm: str) -> None:
    asked: list[str] = []

    def blocked(x: str) -> bool:
        asked.append(x)
        return x != "x3"

    solution = solve(shelf(from_test(blocked)), algorithm=algorithm, stream_info=NEGATE,
                     max_time=10, verbose=False)  # fmt: skip
    assert solution.solved
    assert [(a.name, a.args) for a in solution.plan or []] == [("take", ("x3",))]
    assert sorted(asked) == list(ITEMS)  # each instance evaluated once
    assert solution.streams["test-blocked"].calls == 3
    assert ("blocked", "x1") in solution.certificate.all_facts


def test_negated_test_that_always_passes_leaves_no_plan() -> None:
    solution = solve(shelf(from_test(lambda x: True)), stream_info=NEGATE, verbose=False)
    assert not solution.solved


# The line world: a sampled pose must not be blocked (through a derived predicate); the test's
# inputs are in the other order than its certified fact's arguments.
LINE_STREAM = """
(define (stream line)
  (:stream sample-pose :inputs (?b ?r) :domain (and (block ?b) (region ?r))
    :outputs (?p) :certified (and (pose ?b ?p) (contained ?b ?p ?r)))
  (:stream test-blocked :inputs (?p ?b) :domain (pose ?b ?p) :certified (blocked ?b ?p)))
"""


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_negated_test_on_sampled_values(algorithm: str) -> None:
    def poses(b: str, r: str) -> Iterator[tuple[float]]:
        for k in itertools.count():
            yield (5.0 + k,)

    seen: list[tuple[Any, ...]] = []

    def blocked(p: float, b: str) -> bool:
        seen.append((p, b))
        return p in (5.0, 6.0)

    extra = {"test-blocked": from_test(blocked)}
    problem = line_problem(from_gen_fn(poses), LINE_STREAM, **extra)
    solution = solve(problem, algorithm=algorithm, stream_info=NEGATE, max_time=10,
                     verbose=False)  # fmt: skip
    assert solution.solved
    assert [a.args for a in solution.plan or []] == [("a", 0.0, 7.0)]
    assert (7.0, "a") in seen and all(isinstance(p, float) for p, _ in seen)


def test_negated_use_without_negate_is_noted_and_solved_closed_world(
    caplog: pytest.LogCaptureFixture,
) -> None:
    # as PDDLStream: no error; the negation is read against the facts known: the optimistic
    # algorithms assume the test passes (no plan), the incremental one holds it until certified
    for algorithm, solved in (("adaptive", False), ("focused", False), ("incremental", True)):
        caplog.clear()
        with caplog.at_level(logging.WARNING):
            solution = solve(shelf(from_test(lambda x: False)), algorithm=algorithm,
                             max_time=10, verbose=False)  # fmt: skip
        notes = [r.getMessage() for r in caplog.records if "uses negated" in r.getMessage()]
        assert len(notes) == 1
        assert "'test-blocked'" in notes[0] and "'blocked'" in notes[0]
        assert "StreamInfo(negate=True)" in notes[0]
        assert solution.solved is solved, algorithm


# PDDLStream's automatic negation: a test certifying a fact that a derived predicate negates,
# the derived predicate used negated by an action, the fact needed by no stream's domain.
UNSAFE_DOMAIN = """
(define (domain shelf)
  (:requirements :strips :negative-preconditions :derived-predicates)
  (:predicates (item ?x) (free ?x) (unsafe ?x) (taken ?x) (done))
  (:derived (unsafe ?x) (and (item ?x) (not (free ?x))))
  (:action take :parameters (?x)
    :precondition (and (item ?x) (not (unsafe ?x)))
    :effect (and (taken ?x) (done))))
"""
FREE_STREAM = """
(define (stream shelf)
  (:stream test-free :inputs (?x) :domain (item ?x) :certified (free ?x))
  {extra})
"""


@pytest.mark.parametrize(
    ("extra", "automatic"),
    [
        ("", True),
        # another stream needs (free ?x) in its domain: the test is a producer, not negated
        ("(:stream mark :inputs (?x) :domain (free ?x) :certified (taken ?x))", False),
    ],
)
def test_tests_negated_automatically_as_pddlstream_does(
    extra: str, automatic: bool, caplog: pytest.LogCaptureFixture
) -> None:
    asked: list[str] = []

    def free(x: str) -> bool:
        asked.append(x)
        return x == "x3"

    stream_map = {"test-free": from_test(free)}
    if extra:
        stream_map["mark"] = from_test(lambda x: True)
    init = [("item", x) for x in ITEMS]
    problem = PDDLProblem(
        UNSAFE_DOMAIN, {}, FREE_STREAM.format(extra=extra), stream_map, init, ("done",)
    )
    with caplog.at_level(logging.INFO):
        solution = solve(problem, max_time=10, verbose=False)
    messages = " ".join(r.getMessage() for r in caplog.records)
    assert ("negate=True set automatically" in messages) is automatic
    assert solution.solved
    assert [(a.name, a.args) for a in solution.plan or []] == [("take", ("x3",))]
    assert "x3" in asked


@pytest.mark.parametrize(
    "stream_pddl",
    [
        # a generator
        """(define (stream s) (:stream test-blocked :inputs (?x) :domain (item ?x)
             :outputs (?y) :certified (and (blocked ?x) (item ?y))))""",
        # two certified facts
        """(define (stream s) (:stream test-blocked :inputs (?x) :domain (item ?x)
             :certified (and (blocked ?x) (taken ?x))))""",
        # a fluent test
        """(define (stream s) (:stream test-blocked :inputs (?x) :domain (item ?x)
             :fluents (taken) :certified (blocked ?x)))""",
    ],
)
def test_negate_on_a_stream_that_is_not_a_plain_test_is_an_error(stream_pddl: str) -> None:
    problem = shelf(from_test(lambda x: False), stream_pddl)
    with pytest.raises(ParameterError, match=r"stream_info\['test-blocked'\]\.negate needs"):
        solve(problem, stream_info=NEGATE, verbose=False)


def test_negated_fact_with_two_sources_is_an_error() -> None:
    stream_pddl = """
    (define (stream shelf)
      (:stream test-blocked :inputs (?x) :domain (item ?x) :certified (blocked ?x))
      (:predicate (Blocked ?x) (item ?x)))
    """
    init = [("item", x) for x in ITEMS]
    stream_map = {"test-blocked": from_test(lambda x: False), "blocked": lambda x: False}
    problem = PDDLProblem(DOMAIN, {}, stream_pddl, stream_map, init, ("done",))
    with pytest.raises(ParameterError, match=r"'blocked' is already a :predicate"):
        solve(problem, stream_info=NEGATE, verbose=False)


def test_negated_test_that_raises_names_the_stream() -> None:
    def broken(x: str) -> bool:
        raise RuntimeError("sensor offline")

    with pytest.raises(StreamError, match=r"negated test stream 'test-blocked'.*sensor offline"):
        solve(shelf(from_test(broken)), stream_info=NEGATE, verbose=False)


def test_negated_test_in_debug_mode_fails_like_a_debug_predicate() -> None:
    problem = PDDLProblem(DOMAIN, {}, TEST_STREAM, "debug", [("item", x) for x in ITEMS], ("done",))
    solution = solve(problem, stream_info=NEGATE, verbose=False)
    assert solution.solved
