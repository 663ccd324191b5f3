"""The stream language features and the solve() contract, on small line-world problems."""

from __future__ import annotations

import itertools
import logging
import os
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from line_world import GOAL, INIT, LINE, SAMPLE, counting, line_problem

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.formulas import TOTAL_COST, Equal
from sdar_tamp.language.generators import (
    WildOutput,
    from_gen_fn,
    from_list_fn,
    from_sampler,
    from_test,
)
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Status
from solvers.solve import solve
from solvers.stream_planning.externals import StreamError, StreamOutputError
from solvers.stream_planning.negation import negated_predicates


@pytest.mark.parametrize("algorithm", ["incremental", "focused", "binding", "adaptive"])
def test_line_world_solves(algorithm: str) -> None:
    solution = solve(line_problem(counting()), algorithm=algorithm, verbose=False)
    assert solution.solved
    assert [(a.name, a.args) for a in solution.plan or []] == [("move", ("a", 0.0, 5.0))]
    assert ("contained", "a", 5.0, "goal") in solution.certificate.preimage_facts


def test_nothing_is_written_to_the_working_directory(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    for algorithm in ("incremental", "adaptive"):
        assert solve(line_problem(counting()), algorithm=algorithm, verbose=True).solved
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("verbose", [True, False])
def test_solve_leaves_logger_levels_alone_and_logs_a_summary(
    verbose: bool, caplog: pytest.LogCaptureFixture
) -> None:

    names = ("", "sdar_tamp", "sdar_tamp.solvers", "sdar_tamp.solvers.solve")
    loggers = [logging.getLogger(name) for name in names]
    with caplog.at_level(logging.DEBUG, logger="sdar_tamp.solvers"):
        before = [logger.level for logger in loggers]
        assert solve(line_problem(counting()), algorithm="focused", verbose=verbose).solved
        assert [logger.level for logger in loggers] == before
    summary = [
        r for r in caplog.records if r.name == "sdar_tamp.solvers.solve" and "focused:" in r.message
    ]
    assert len(summary) == 1 and "solved" in summary[0].message
    assert summary[0].levelno == (logging.INFO if verbose else logging.DEBUG)


def test_sampler_that_raises_names_stream_and_inputs() -> None:
    original = ZeroDivisionError("no pose today")

    def broken(b: str, r: str) -> Iterator[tuple[float]]:
        raise original
        yield (0.0,)

    with pytest.raises(StreamError) as info:
        solve(line_problem(from_gen_fn(broken)), algorithm="focused", verbose=False)
    message = str(info.value)
    assert "'sample-pose'" in message and "('a', 'goal')" in message
    assert "ZeroDivisionError" in message
    assert info.value.__cause__ is original


@pytest.mark.parametrize(
    ("sampler", "got"),
    [
        (from_list_fn(lambda b, r: [(1.0, 2.0)]), "(1.0, 2.0)"),  # two values for one output
        (from_list_fn(lambda b, r: [3.0]), "3.0"),  # not a tuple
        (lambda b, r: iter([{"p": 1.0}]), "dict"),  # not a list of tuples
    ],
)
def test_wrong_output_shape_names_stream_expected_and_got(sampler: Any, got: str) -> None:
    with pytest.raises(StreamOutputError) as info:
        solve(line_problem(sampler), algorithm="incremental", verbose=False)
    message = str(info.value)
    assert "'sample-pose'" in message and got in message
    assert "list of output tuples" in message or "tuples of 1 value(s) (?p)" in message


def test_function_returning_a_negative_cost_is_an_output_error() -> None:
    problem = cost_problem(lambda p, q: -1.0)
    with pytest.raises(StreamOutputError, match=r"'distance'.*non-negative"):
        solve(problem, algorithm="incremental", verbose=False)


@pytest.mark.parametrize("algorithm", ["incremental", "focused", "binding", "adaptive"])
def test_debug_stream_map(algorithm: str) -> None:
    problem = PDDLProblem(LINE, {}, SAMPLE, "debug", INIT, GOAL)
    solution = solve(problem, algorithm=algorithm, verbose=False)
    assert solution.solved and solution.plan is not None
    (move,) = solution.plan
    assert repr(move.args[2]).startswith("$sample-pose")


# --- :function costs -------------------------------------------------------------------

COST_DOMAIN = """
(define (domain roads)
  (:requirements :strips :action-costs)
  (:predicates (place ?x) (at ?x) (road ?x ?y))
  (:functions (total-cost) (distance ?x ?y))
  (:action drive :parameters (?x ?y)
    :precondition (and (at ?x) (road ?x ?y))
    :effect (and (at ?y) (not (at ?x)) (increase (total-cost) (distance ?x ?y)))))
"""
COST_STREAM = """
(define (stream roads)
  (:function (Distance ?x ?y) (and (place ?x) (place ?y))))
"""
POINTS = {"home": (0.0, 0.0), "north": (0.0, 5.0), "east": (1.0, 0.0), "work": (2.0, 0.0)}


def cost_problem(distance: Any) -> PDDLProblem:
    init: list[tuple[Any, ...]] = [("place", p) for p in POINTS]
    init += [("at", "home"), Equal((TOTAL_COST,), 0)]
    init += [("road", "home", "north"), ("road", "north", "work")]
    init += [("road", "home", "east"), ("road", "east", "work")]
    return PDDLProblem(COST_DOMAIN, {}, COST_STREAM, {"distance": distance}, init, ("at", "work"))


def euclid(x: str, y: str) -> float:
    (ax, ay), (bx, by) = POINTS[x], POINTS[y]
    return ((ax - bx) ** 2 + (ay - by) ** 2) ** 0.5


@pytest.mark.parametrize("algorithm", ["incremental", "focused", "binding", "adaptive"])
def test_function_costs_pick_the_cheaper_plan(algorithm: str) -> None:
    solution = solve(cost_problem(euclid), algorithm=algorithm, verbose=False)
    assert [a.args for a in solution.plan or []] == [("home", "east"), ("east", "work")]
    assert solution.cost == pytest.approx(2.0)
    unit = solve(cost_problem(euclid), algorithm=algorithm, unit_costs=True, verbose=False)
    assert unit.cost == 2.0
    assert solution.streams["distance"].calls >= 2


# --- :predicate, :rule, fluents, wild outputs --------------------------------------------

PREDICATE_STREAM = """
(define (stream line)
  (:stream sample-pose :inputs (?b ?r) :domain (and (block ?b) (region ?r))
    :outputs (?p) :certified (and (pose ?b ?p) (contained ?b ?p ?r)))
  (:predicate (Blocked ?b ?p) (pose ?b ?p)))
"""


@pytest.mark.parametrize("algorithm", ["incremental", "focused", "binding", "adaptive"])
def test_negated_predicate_through_a_derived_predicate(algorithm: str) -> None:
    """``(not (unsafe ?p))`` with ``unsafe`` derived from the external ``Blocked``: the first
    poses are blocked, so the solver must evaluate the predicate and sample past them."""
    blocked = {5.0, 6.0}
    asked: list[float] = []

    def is_blocked(b: str, p: float) -> bool:
        asked.append(p)
        return p in blocked

    problem = line_problem(counting(), PREDICATE_STREAM, blocked=is_blocked)
    solution = solve(problem, algorithm=algorithm, max_time=10, verbose=False)
    assert solution.solved
    assert [a.args for a in solution.plan or []] == [("a", 0.0, 7.0)]
    assert {5.0, 6.0, 7.0} <= set(asked)


def test_negated_predicates_follow_derived_predicates() -> None:
    from sdar_tamp.language import parse_domain

    domain = parse_domain(LINE)
    negated = negated_predicates(
        domain, PDDLProblem(LINE, {}, SAMPLE, "debug", INIT, GOAL).facts.goal
    )
    assert {"unsafe", "blocked"} <= negated
    assert "pose" not in negated and "contained" not in negated


def test_positive_predicate_is_evaluated_for_real() -> None:
    stream = """
    (define (stream line)
      (:stream sample-pose :inputs (?b ?r) :domain (and (block ?b) (region ?r))
        :outputs (?p) :certified (pose ?b ?p))
      (:predicate (Inside ?b ?p ?r) (and (pose ?b ?p) (region ?r)))
      (:rule :parameters (?b ?p ?r) :domain (inside ?b ?p ?r)
        :certified (contained ?b ?p ?r)))
    """
    domain = LINE.replace("(marked ?p)", "(marked ?p) (inside ?b ?p ?r)")
    problem = PDDLProblem(
        domain,
        {},
        stream,
        {"sample-pose": counting(1.0), "inside": lambda b, p, r: p >= 3.0},
        INIT,
        GOAL,
    )
    for algorithm in ("incremental", "focused", "adaptive"):
        solution = solve(problem, algorithm=algorithm, max_time=10, verbose=False)
        assert solution.solved, algorithm
        assert [a.args for a in solution.plan or []] == [("a", 0.0, 3.0)]
        assert ("contained", "a", 3.0, "goal") in solution.certificate.all_facts


def test_rule_certifies_facts() -> None:
    stream = """
    (define (stream line)
      (:stream sample-pose :inputs (?b ?r) :domain (and (block ?b) (region ?r))
        :outputs (?p) :certified (and (pose ?b ?p) (near ?b ?p ?r)))
      (:rule :parameters (?b ?p ?r) :domain (near ?b ?p ?r) :certified (contained ?b ?p ?r)))
    """
    problem = line_problem(counting(), stream)
    for algorithm in ("incremental", "focused", "binding", "adaptive"):
        solution = solve(problem, algorithm=algorithm, verbose=False)
        assert solution.solved, algorithm
        assert ("contained", "a", 5.0, "goal") in solution.certificate.preimage_facts


def test_fluent_stream_receives_fluents() -> None:
    stream = """
    (define (stream line)
      (:stream sample-pose :inputs (?b ?r) :domain (and (block ?b) (region ?r))
        :fluents (atpose) :outputs (?p) :certified (and (pose ?b ?p) (contained ?b ?p ?r))))
    """
    received: list[Any] = []

    def gen(b: str, r: str, fluents: list[tuple[Any, ...]]) -> Iterator[tuple[float]]:
        received.append(list(fluents))
        yield (9.0,)

    for algorithm in ("incremental", "adaptive"):
        received.clear()
        solution = solve(line_problem(from_gen_fn(gen), stream), algorithm=algorithm, verbose=False)
        assert solution.solved
        assert received == [[("atpose", "a", 0.0)]]


@pytest.mark.parametrize("algorithm", ["incremental", "focused", "binding", "adaptive"])
def test_wild_output_facts_are_added(algorithm: str) -> None:
    def gen(b: str, r: str) -> Iterator[WildOutput]:
        yield WildOutput([(4.0,)], [("marked", 4.0)])

    solution = solve(line_problem(from_gen_fn(gen)), algorithm=algorithm, verbose=False)
    assert solution.solved
    assert ("marked", 4.0) in solution.certificate.all_facts


# --- limits and arguments -----------------------------------------------------------------


@pytest.mark.parametrize("algorithm", ["incremental", "focused", "binding", "adaptive"])
def test_max_time_is_honoured_on_an_unsolvable_infinite_problem(algorithm: str) -> None:
    """The run ends with TIMEOUT after max_time instead of going on: the bound below only
    catches a run that ignores the limit. How closely the limit holds (overrun in %) is
    measured side by side for the four algorithms by benchmarks/bench_streams.py."""
    values = itertools.count()
    # infinite and always new, and the test below always fails
    never = from_sampler(lambda b, r: (-1.0 - next(values),))
    stream = """
    (define (stream line)
      (:stream sample-pose :inputs (?b ?r) :domain (and (block ?b) (region ?r))
        :outputs (?p) :certified (pose ?b ?p))
      (:stream test-inside :inputs (?b ?p ?r) :domain (and (pose ?b ?p) (region ?r))
        :certified (contained ?b ?p ?r)))
    """
    problem = line_problem(never, stream, **{"test-inside": from_test(lambda b, p, r: False)})
    start = time.perf_counter()
    solution = solve(problem, algorithm=algorithm, max_time=1.5, verbose=False)
    elapsed = time.perf_counter() - start
    # The problem never ends by itself: returning at all, with TIMEOUT and the time limit as
    # the reason, shows the limit stopped it. How closely it holds the limit is measured by
    # benchmarks/bench_streams.py (max_time_overrun).
    assert solution.status is Status.TIMEOUT
    assert elapsed >= 1.5
    assert any("time limit" in reason for reason in solution.diagnosis)


@pytest.mark.parametrize(
    ("kwargs", "named"),
    [
        ({"algorithm": "magic"}, "algorithm"),
        ({"max_time": -1}, "max_time"),
        ({"max_time": 0}, "max_time"),
        ({"success_cost": float("nan")}, "success_cost"),
        ({"search_sample_ratio": 0}, "search_sample_ratio"),
        ({"complexity_step": 0}, "complexity_step"),
        ({"max_iterations": "many"}, "max_iterations"),
        ({"max_tme": 3}, "max_tme"),
    ],
)
def test_bad_arguments_raise_parameter_error(kwargs: dict[str, Any], named: str) -> None:
    with pytest.raises(ParameterError, match=named):
        solve(line_problem(counting()), **kwargs)


def test_problem_must_be_a_pddl_problem() -> None:
    with pytest.raises(ParameterError, match="PDDLProblem"):
        solve("domain.pddl")  # type: ignore[arg-type]
