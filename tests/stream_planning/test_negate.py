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


# The rovers' ray rule: a generator's outputs (?q ?y) certify (Ray ?y), and a test over
# (Ray ?y) (Conf ?v ?q) certifies the fact a derived predicate negates; the test is negated
# automatically and instantiated on the generator's rays.
RAY_DOMAIN = """
(define (domain rays)
  (:requirements :strips :derived-predicates :negative-preconditions)
  (:predicates (rover ?v) (objective ?o) (conf ?v ?q) (ray ?y) (atconf ?v ?q)
    (visible ?v ?q ?y ?o) (cfreerayconf ?y ?v ?q) (blocked ?y) (haveimage ?v ?o))
  (:action move :parameters (?v ?q1 ?q2)
    :precondition (and (atconf ?v ?q1) (conf ?v ?q2))
    :effect (and (atconf ?v ?q2) (not (atconf ?v ?q1))))
  (:action take :parameters (?v ?q ?y ?o)
    :precondition (and (visible ?v ?q ?y ?o) (atconf ?v ?q) (not (blocked ?y)))
    :effect (haveimage ?v ?o))
  (:derived (blocked ?y) (exists (?v ?q) (and (ray ?y) (conf ?v ?q)
    (not (cfreerayconf ?y ?v ?q)) (atconf ?v ?q)))))
"""
RAY_STREAMS = """
(define (stream rays)
  (:stream test-cfree-ray-conf :inputs (?y ?v ?q) :domain (and (ray ?y) (conf ?v ?q))
    :certified (cfreerayconf ?y ?v ?q))
  (:stream inv-visible :inputs (?v ?o) :domain (and (rover ?v) (objective ?o))
    :outputs (?q ?y) :certified (and (visible ?v ?q ?y ?o) (conf ?v ?q) (ray ?y))))
"""


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_rays_from_a_generator_reach_the_negated_test(algorithm: str) -> None:
    def visible(v: str, o: str) -> Iterator[tuple[str, str]]:
        for k in itertools.count():
            yield ("view0", f"ray{k}")  # one view, a new ray each time

    checked: list[tuple[str, str, str]] = []

    def cfree(y: str, v: str, q: str) -> bool:
        checked.append((y, v, q))
        return not (y == "ray0" and v == "v2")  # the other rover blocks the first ray

    init = [("rover", "v1"), ("rover", "v2"), ("objective", "o1")]
    init += [("conf", "v1", "view0"), ("atconf", "v1", "view0")]
    init += [("conf", "v2", "home"), ("atconf", "v2", "home")]
    stream_map = {"test-cfree-ray-conf": from_test(cfree), "inv-visible": from_gen_fn(visible)}
    problem = PDDLProblem(RAY_DOMAIN, {}, RAY_STREAMS, stream_map, init, ("haveimage", "v1", "o1"))
    solution = solve(problem, algorithm=algorithm, max_time=20, verbose=False)
    assert solution.solved, solution.diagnosis
    take = (solution.plan or [])[-1]
    assert take.name == "take" and take.args[2] != "ray0"  # ray0 is blocked by v2 at home
    assert any(y == "ray0" and v == "v2" for y, v, _ in checked)
