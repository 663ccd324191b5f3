"""Building the optimistic world honours max_time: with a stream whose outputs feed itself
(sums of sums of integers) the world grows fast from one complexity level to the next."""

from __future__ import annotations

import pytest

from sdar_tamp.language.generators import from_fn, from_gen_fn, from_test
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Status
from solvers.solve import solve
from solvers.stream_planning.options import StreamOptions
from solvers.stream_planning.solver import StreamSolver

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


class _TimeUp(Exception):
    pass


def test_a_large_world_asks_for_the_time_while_it_is_built() -> None:
    # At complexity 4 the sums make a world of thousands of facts: its building must stop when
    # the solve's time is up (before, it ran minutes past max_time). Counted, not timed.
    solver = StreamSolver(_problem(), StreamOptions(algorithm="focused"), None)
    solver.context.engine.start()
    asked = 0

    def time_is_up() -> None:
        nonlocal asked
        asked += 1
        raise _TimeUp

    with pytest.raises(_TimeUp):
        solver.context.builder.build(4, check_time=time_is_up)
    assert asked == 1
    small = solver.context.builder.build(1, check_time=time_is_up)  # a small world does not ask
    assert small.facts and asked == 1


@pytest.mark.parametrize("algorithm", ["focused", "adaptive"])
def test_a_fast_growing_world_ends_by_the_time_limit(algorithm: str) -> None:
    solution = solve(_problem(), algorithm=algorithm, max_time=2.0, verbose=False)
    assert solution.status in (Status.TIMEOUT, Status.SOLVED)
    if solution.status is Status.TIMEOUT:
        assert any("time limit" in reason for reason in solution.diagnosis)


def test_incremental_solves_it() -> None:
    solution = solve(_problem(), algorithm="incremental", max_time=60.0, verbose=False)
    assert solution.solved and solution.plan is not None
    assert solution.plan[0].args == (5, -1)
