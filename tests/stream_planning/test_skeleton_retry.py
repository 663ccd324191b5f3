"""Binding a skeleton again after a failure keeps what single-call steps gave it.

The stream plan ``reach(a) -> #q``, ``sample() -> #v``, ``check(#q, #v)``: ``reach`` answers
once (``from_fn``), ``sample`` yields 1, 2, 3, ... and ``check`` passes from 3 on. When
``check`` fails, only ``sample`` can give something new; ``reach`` keeps its one answer (called
again it gives nothing). So one skeleton reaches the plan by resampling, without a new search
per failure.
"""

from __future__ import annotations

from collections.abc import Iterator
from itertools import count
from typing import Any

import pytest

from sdar_tamp.language.generators import from_fn, from_gen_fn, from_test
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Status
from solvers.solve import solve

DOMAIN = """(define (domain reach) (:requirements :strips)
  (:predicates (obj ?o) (conf ?q) (val ?v) (kin ?o ?q) (good ?q ?v) (done))
  (:action finish :parameters (?o ?q ?v)
     :precondition (and (kin ?o ?q) (good ?q ?v)) :effect (done)))"""
STREAMS = """(define (stream reach)
  (:stream reach :inputs (?o) :domain (obj ?o) :outputs (?q)
     :certified (and (conf ?q) (kin ?o ?q)))
  (:stream sample :outputs (?v) :certified (val ?v))
  (:stream check :inputs (?q ?v) :domain (and (conf ?q) (val ?v)) :certified (good ?q ?v)))"""


def _problem(calls: dict[str, int]) -> PDDLProblem:
    def reach(o: Any) -> tuple[Any]:
        calls["reach"] += 1
        return (f"q-{o}",)

    def sample() -> Iterator[tuple[int]]:
        for value in count(1):
            calls["sample"] += 1
            yield (value,)

    def check(q: Any, v: Any) -> bool:
        calls["check"] += 1
        return bool(v >= 3)

    stream_map = {
        "reach": from_fn(reach),
        "sample": from_gen_fn(sample),
        "check": from_test(check),
    }
    return PDDLProblem(DOMAIN, {}, STREAMS, stream_map, [("obj", "a")], ("done",))


def test_a_single_call_step_keeps_its_output_when_a_later_step_fails() -> None:
    calls = {"reach": 0, "sample": 0, "check": 0}
    solution = solve(_problem(calls), algorithm="adaptive", max_time=20, verbose=False)
    assert solution.status is Status.SOLVED
    assert solution.plan is not None
    assert [(a.name, a.args[0]) for a in solution.plan] == [("finish", "a")]
    assert calls["reach"] == 1
    assert calls["sample"] == 3  # 1 and 2 fail the check, 3 passes
    assert solution.statistics["skeletons"] == 1  # no new search after each failure


@pytest.mark.parametrize("algorithm", ["focused", "binding", "incremental"])
def test_the_other_algorithms_solve_it_calling_reach_once(algorithm: str) -> None:
    calls = {"reach": 0, "sample": 0, "check": 0}
    solution = solve(_problem(calls), algorithm=algorithm, max_time=20, verbose=False)
    assert solution.status is Status.SOLVED
    assert calls["reach"] == 1
