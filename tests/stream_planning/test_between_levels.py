"""What the search does between complexity levels. As in PDDLStream, once a skeleton was
made, a level without a plan calls only the instances skeletons called (none that no plan
wanted); every sampler is called between levels only before the first skeleton, or once the
optimistic world holds every instance but later calls' outputs (then the real calls are what
can still make progress, and what lets a problem whose streams run dry end ``infeasible``)."""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator

import pytest

from sdar_tamp.language.generators import from_gen_fn, from_test
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Status
from solvers.solve import solve

DOMAIN = """(define (domain chain) (:requirements :strips)
  (:predicates (item ?i) (a ?x) (b ?y) (c ?z) (noise ?n) (good ?x) (done) (kept))
  (:action reach :parameters (?z) :precondition (c ?z) :effect (done))
  (:action keep :parameters (?x) :precondition (good ?x) :effect (kept))
  (:action shortcut :parameters (?x) :precondition (good ?x) :effect (done)))"""

#: ``done`` needs a chain of streams from a value of ``a`` (the initial ``x0``: level 2), or a
#: value ``test-good`` accepts (``shortcut``; it accepts none), as does ``kept``;
#: ``sample-noise`` gives values no action uses, without end
STREAMS = """(define (stream chain)
  (:stream sample-a :inputs (?i) :domain (item ?i) :outputs (?x) :certified (a ?x))
  (:stream step-b :inputs (?x) :domain (a ?x) :outputs (?y) :certified (b ?y))
  (:stream step-c :inputs (?y) :domain (b ?y) :outputs (?z) :certified (c ?z))
  (:stream sample-noise :inputs (?i) :domain (item ?i) :outputs (?n) :certified (noise ?n))
  (:stream test-good :inputs (?x) :domain (a ?x) :certified (good ?x)))"""


def _endless(tag: str, calls: dict[str, int]) -> Callable[[str], Iterator[tuple[str]]]:
    def gen(x: str) -> Iterator[tuple[str]]:
        for k in itertools.count():
            calls[tag] = calls.get(tag, 0) + 1
            yield (f"{x}-{tag}{k}",)

    return gen


def _problem(calls: dict[str, int], goal: tuple[object, ...] = ("done",)) -> PDDLProblem:
    streams = {
        name: from_gen_fn(_endless(name, calls))
        for name in ("sample-a", "step-b", "step-c", "sample-noise")
    }

    def good(x: str) -> bool:
        calls["test-good"] = calls.get("test-good", 0) + 1
        return False

    streams["test-good"] = from_test(good)
    return PDDLProblem(
        DOMAIN, {}, STREAMS, streams, [("item", "i1"), ("item", "i2"), ("a", "x0")], goal
    )


@pytest.mark.parametrize("algorithm", ["focused", "binding", "adaptive"])
def test_after_a_skeleton_only_its_samplers_are_called_between_levels(algorithm: str) -> None:
    """The first plan (``shortcut`` on ``x0``) fails its test; the levels then rise to the
    chain's plan. Between them, only instances a skeleton called are called again: the
    unused ``sample-noise`` never, ``step-b`` and ``step-c`` once (the plan's)."""
    calls: dict[str, int] = {}
    solution = solve(_problem(calls), algorithm=algorithm, max_time=60, verbose=False)
    assert solution.status is Status.SOLVED
    assert [a.name for a in solution.plan or []] == ["reach"]
    assert solution.statistics["complexity"] == 2
    assert calls["test-good"] > 0  # the shortcut's skeletons were tried
    assert calls.get("sample-noise", 0) == 0
    assert calls["step-b"] == calls["step-c"] == 1
