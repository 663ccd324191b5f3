"""Building the optimistic world honours max_time: with a stream whose outputs feed itself
(sums of sums of integers) the world grows fast from one complexity level to the next."""

from __future__ import annotations

import time

import pytest

from sdar_tamp.language.generators import from_fn, from_gen_fn, from_test
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Status
from solvers.solve import solve

DOMAIN = """
(define (domain sums)
  (:predicates (integer ?x) (large ?x) (small ?x) (up ?x) (down ?x) (sum ?a ?b ?c) (done))
  (:action finish :parameters (?x ?y)
    :precondition (and (up ?x) (large ?x) (down ?y) (small ?y)) :effect (done)))
"""
STREAMS = """
(define (stream sums)
  (:stream count-up :outputs (?x) :certified (and (up ?x) (integer ?x)))
  (:stream count-down :outputs (?x) :certified (and (down ?x) (integer ?x)))
  (:stream addition :inputs (?a ?b) :domain (and (integer ?a) (integer ?b))
    :outputs (?c) :certified (and (sum ?a ?b ?c) (integer ?c)))
  (:stream test-large :inputs (?x) :domain (integer ?x) :certified (large ?x))
  (:stream test-small :inputs (?x) :domain (integer ?x) :certified (small ?x)))
"""


def _problem() -> PDDLProblem:
    stream_map = {
        "count-up": from_gen_fn(lambda: ((k,) for k in range(1, 6))),
        "count-down": from_gen_fn(lambda: ((-k,) for k in range(1, 6))),
        "addition": from_fn(lambda a, b: (a + b,)),
        "test-large": from_test(lambda x: x >= 5),  # only the fifth value of count-up
        "test-small": from_test(lambda x: x <= -1),
    }
    return PDDLProblem(DOMAIN, {}, STREAMS, stream_map, [], ("done",))


@pytest.mark.parametrize("algorithm", ["focused", "adaptive"])
def test_a_fast_growing_world_still_ends_at_max_time(algorithm: str) -> None:
    # Before, building one optimistic world could run for minutes past max_time.
    start = time.perf_counter()
    solution = solve(_problem(), algorithm=algorithm, max_time=2.0, verbose=False)
    elapsed = time.perf_counter() - start
    assert solution.status in (Status.TIMEOUT, Status.SOLVED)
    assert elapsed < 30.0  # a bound only a run that ignores the limit can break


def test_incremental_solves_it() -> None:
    solution = solve(_problem(), algorithm="incremental", max_time=60.0, verbose=False)
    assert solution.solved and solution.plan is not None
    assert solution.plan[0].args == (5, -1)
