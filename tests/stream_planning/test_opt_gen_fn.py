"""A callable ``StreamInfo(opt_gen_fn=...)``: optimistic outputs with values that chain."""

from __future__ import annotations

from collections import Counter
from typing import Any

import pytest

from sdar_tamp.language.generators import from_fn, from_list_fn
from sdar_tamp.language.options import FunctionInfo, StreamInfo
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Status
from solvers.solve import solve
from solvers.stream_planning.externals import StreamError, StreamOutputError
from solvers.stream_planning.opt_values import OptimisticValue

DOMAIN = """(define (domain counter) (:requirements :strips :action-costs)
  (:predicates (num ?x) (next ?x ?y) (at ?x) (big ?x))
  (:functions (total-cost) (gap ?x ?y))
  (:action advance :parameters (?x ?y) :precondition (and (at ?x) (next ?x ?y))
     :effect (and (at ?y) (not (at ?x)) (increase (total-cost) (gap ?x ?y)))))"""
STREAMS = """(define (stream counter)
  (:stream step :inputs (?x) :domain (num ?x) :outputs (?y) :certified (and (num ?y) (next ?x ?y)))
  (:stream is-big :inputs (?x) :domain (num ?x) :certified (big ?x))
  (:function (gap ?x ?y) (next ?x ?y)))"""


def _problem() -> PDDLProblem:
    return PDDLProblem(
        DOMAIN,
        {},
        STREAMS,
        {
            "step": from_fn(lambda x: (x + 1,)),
            "is-big": from_fn(lambda x: () if x >= 2 else None),
            "gap": lambda x, y: float(y - x),
        },
        [("num", 0), ("at", 0)],
        ("exists", ("?x",), ("and", ("at", "?x"), ("big", "?x"))),
    )


def _info(opt_gen_fn: Any, gaps: list[tuple[Any, Any]]) -> dict[str, Any]:
    def optimistic_gap(x: Any, y: Any) -> float:
        gaps.append((x, y))
        return float(y - x)  # fails on a placeholder without a value

    return {"step": StreamInfo(opt_gen_fn=opt_gen_fn), "gap": FunctionInfo(opt_fn=optimistic_gap)}


@pytest.mark.parametrize("algorithm", ["focused", "binding", "adaptive"])
def test_optimistic_values_chain_through_streams(algorithm: str) -> None:
    calls: list[Any] = []

    def guess(x: Any) -> tuple[Any]:
        calls.append(x)
        return (x + 1,)

    gaps: list[tuple[Any, Any]] = []
    solution = solve(
        _problem(), algorithm=algorithm, max_time=20, stream_info=_info(from_fn(guess), gaps)
    )
    assert solution.status is Status.SOLVED
    assert solution.plan is not None
    assert [a.args for a in solution.plan] == [(0, 1), (1, 2)]
    # the guess was called on its own guesses (1 is a placeholder's value before step ran)
    assert 1 in calls
    assert not any(isinstance(a, OptimisticValue) for pair in gaps for a in pair)
    assert (1, 2) in gaps
    # once per instance and solve, though the optimistic world is rebuilt every iteration
    # (1 is both a placeholder's value and, once sampled, a real object: two instances)
    assert Counter(calls)[0] == 1
    assert max(Counter(calls).values()) <= 2


def test_an_empty_guess_adds_no_optimistic_output() -> None:
    gaps: list[tuple[Any, Any]] = []
    solution = solve(
        _problem(),
        algorithm="focused",
        max_time=20,
        stream_info=_info(from_list_fn(lambda x: []), gaps),
    )
    assert solution.status is Status.INFEASIBLE
    assert solution.streams["step"].calls == 0  # never worth calling


def test_several_guesses_give_several_placeholders() -> None:
    gaps: list[tuple[Any, Any]] = []
    solution = solve(
        _problem(),
        algorithm="focused",
        max_time=20,
        stream_info=_info(from_list_fn(lambda x: [(x + 1,), (x + 5,)]), gaps),
    )
    assert solution.status is Status.SOLVED
    assert {pair for pair in gaps if pair[0] == 0} == {(0, 1), (0, 5)}


def test_a_raising_guess_names_the_stream() -> None:
    def broken(x: Any) -> tuple[Any]:
        raise ArithmeticError("no guess")

    with pytest.raises(StreamError, match=r"opt_gen_fn of stream 'step'.*ArithmeticError"):
        solve(_problem(), algorithm="focused", max_time=20, stream_info=_info(from_fn(broken), []))


def test_a_guess_of_the_wrong_shape_is_an_error() -> None:
    with pytest.raises(StreamOutputError, match=r"opt_gen_fn of stream 'step'.*tuples of 1"):
        solve(
            _problem(),
            algorithm="focused",
            max_time=20,
            stream_info=_info(from_list_fn(lambda x: [(x, x)]), []),
        )
