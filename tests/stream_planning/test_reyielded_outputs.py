"""A generator that yields the same mutable object again, changed in between, gives a new value
each time (its earlier value is kept as it was yielded)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
from stream_helpers import ALGORITHMS

from sdar_tamp.language.generators import from_gen_fn, from_test
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Status
from solvers.solve import solve

DOMAIN = """
(define (domain reyield)
  (:predicates (val ?x) (good ?x) (done))
  (:action finish :parameters (?x) :precondition (and (val ?x) (good ?x)) :effect (done)))
"""
STREAMS = """
(define (stream reyield)
  (:stream sample-x :outputs (?x) :certified (val ?x))
  (:stream test-good :inputs (?x) :domain (val ?x) :certified (good ?x)))
"""


def _one_dict_changed_each_time() -> Iterator[tuple[dict[str, int]]]:
    value: dict[str, int] = {}
    for k in range(10):
        value["k"] = k  # the same dict, changed, yielded again
        yield (value,)


def _problem(seen: list[Any]) -> PDDLProblem:
    def good(x: dict[str, int]) -> bool:
        seen.append(dict(x))
        return x["k"] == 3

    stream_map = {
        "sample-x": from_gen_fn(_one_dict_changed_each_time),
        "test-good": from_test(good),
    }
    return PDDLProblem(DOMAIN, {}, STREAMS, stream_map, [], ("done",))


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_a_reyielded_changed_object_is_a_new_value(algorithm: str) -> None:
    seen: list[Any] = []
    solution = solve(_problem(seen), algorithm=algorithm, max_time=30, verbose=False)
    assert solution.status is Status.SOLVED, solution.diagnosis
    assert solution.plan is not None
    assert [(a.name, a.args) for a in solution.plan] == [("finish", ({"k": 3},))]
    # every value was tested as it was yielded, each once
    assert [x["k"] for x in seen] == [0, 1, 2, 3]


class _Uncopyable:
    __hash__ = None  # type: ignore[assignment]  # named by identity, like a dict

    def __deepcopy__(self, memo: dict[int, Any]) -> Any:
        raise TypeError("no copies")


def test_an_object_that_cannot_be_copied_keeps_its_one_name() -> None:
    # the same uncopyable object yielded twice stays one object (no error)
    only = _Uncopyable()
    stream_map = {
        "sample-x": from_gen_fn(lambda: iter([(only,), (only,)])),
        "test-good": from_test(lambda x: False),
    }
    problem = PDDLProblem(DOMAIN, {}, STREAMS, stream_map, [], ("done",))
    solution = solve(problem, algorithm="incremental", max_time=30, verbose=False)
    assert solution.status is Status.INFEASIBLE
    assert solution.streams["sample-x"].calls == 3  # two values and the end of the generator
    assert solution.streams["test-good"].calls == 1  # one object: tested once
