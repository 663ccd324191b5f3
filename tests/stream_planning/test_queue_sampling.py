"""A queued skeleton that needs many new values of one stream gets them before the world grows.

The skeleton's generator has no inputs and its values feed a sum stream that feeds itself: each
complexity level multiplies the optimistic world (sums of sums of placeholders), so raising the
level once per new value (one skeleton visit per failed search) soon makes a world too large
to build. After a search that finds nothing new, the queue works on in proportion to the
search (the facts it planned over) before the level rises.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Iterator

import pytest

from sdar_tamp.language.generators import from_fn, from_gen_fn, from_test
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Status
from solvers.solve import solve
from solvers.stream_planning import context as context_module

DOMAIN = """
(define (domain feedback)
  (:predicates (val ?x) (num ?x) (good ?x) (sum ?a ?b ?c) (done))
  (:action finish :parameters (?x) :precondition (and (val ?x) (good ?x)) :effect (done)))
"""
STREAMS = """
(define (stream feedback)
  (:stream sample-x :outputs (?x) :certified (and (val ?x) (num ?x)))
  (:stream add :inputs (?a ?b) :domain (and (num ?a) (num ?b)) :outputs (?c)
    :certified (and (sum ?a ?b ?c) (num ?c)))
  (:stream test-good :inputs (?x) :domain (num ?x) :certified (good ?x)))
"""
WANTED = 8  # only the eighth value of sample-x passes test-good


def _counting() -> Iterator[tuple[int]]:
    for k in itertools.count(1):
        yield (k,)


def _problem() -> PDDLProblem:
    stream_map = {
        "sample-x": from_gen_fn(_counting),
        "add": from_fn(lambda a, b: (a + b,)),
        "test-good": from_test(lambda x: x >= WANTED),
    }
    return PDDLProblem(DOMAIN, {}, STREAMS, stream_map, [], ("done",))


@pytest.mark.parametrize("ratio", [1.0, math.inf])
def test_the_queue_samples_a_skeleton_without_raising_the_level_per_value(ratio: float) -> None:
    # One visit per failed search needed complexity 8, where the world has millions of
    # sums; max_complexity=3 stops such a run as infeasible at once.
    solution = solve(
        _problem(),
        algorithm="adaptive",
        max_time=60,
        max_complexity=3,
        search_sample_ratio=ratio,
        verbose=False,
    )
    assert solution.status is Status.SOLVED, solution.diagnosis
    assert [(a.name, a.args) for a in solution.plan or []] == [("finish", (WANTED,))]
    assert solution.streams["sample-x"].calls == WANTED
    assert solution.statistics["complexity"] <= 3


@pytest.mark.parametrize("ratio", [0.5, 1.0])
def test_queue_work_stays_bounded_when_no_value_passes(ratio: float) -> None:
    # No value ever passes: the level still rises, and the run ends at max_complexity
    # with a bounded number of calls (the queue's share follows the searches).
    stream_map = {
        "sample-x": from_gen_fn(_counting),
        "add": from_fn(lambda a, b: (a + b,)),
        "test-good": from_test(lambda x: False),
    }
    problem = PDDLProblem(DOMAIN, {}, STREAMS, stream_map, [], ("done",))
    solution = solve(
        problem,
        algorithm="adaptive",
        max_time=60,
        max_complexity=2,
        search_sample_ratio=ratio,
        verbose=False,
    )
    assert solution.status is Status.INFEASIBLE
    assert solution.statistics["complexity"] == 2
    assert 1 <= solution.streams["sample-x"].calls <= 100


class _SlowClock:
    """The ``time`` module as the solve's context reads it, where each sampler call takes
    ``step`` seconds (the test's own clock: no real waiting)."""

    def __init__(self, step: float) -> None:
        self.step = step
        self.offset = 0.0

    def perf_counter(self) -> float:
        return time.perf_counter() + self.offset


@pytest.mark.parametrize("step", [0.0, 10.0])
def test_between_levels_the_queue_samples_within_the_time_balance(
    monkeypatch: pytest.MonkeyPatch, step: float
) -> None:
    # No value passes; between levels the queue works in proportion to the search, and
    # with samplers that take 10 s a call, only until its sampling time reaches the
    # searches' (PDDLStream's balance): one visit a level, not hundreds of calls.
    clock = _SlowClock(step)
    monkeypatch.setattr(context_module, "time", clock)

    def slow_counting() -> Iterator[tuple[int]]:
        for k in itertools.count(1):
            clock.offset += clock.step
            yield (k,)

    stream_map = {
        "sample-x": from_gen_fn(slow_counting),
        "add": from_fn(lambda a, b: (a + b,)),
        "test-good": from_test(lambda x: False),
    }
    problem = PDDLProblem(DOMAIN, {}, STREAMS, stream_map, [], ("done",))
    solution = solve(
        problem, algorithm="adaptive", max_complexity=3, search_sample_ratio=1.0, verbose=False
    )
    assert solution.status is Status.INFEASIBLE
    calls = solution.streams["sample-x"].calls
    if step:
        assert calls <= 6, calls
    else:
        assert calls > 6, calls
