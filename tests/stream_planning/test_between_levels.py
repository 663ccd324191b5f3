"""What the search does between complexity levels: as in PDDLStream, a level without a plan
raises the level and calls no sampler while the optimistic world still leaves instances out
above it; samplers are called between levels only once every instance is in the world but
later calls' outputs (then the real calls are what can still make progress, and what lets a
problem whose streams run dry end ``infeasible``)."""

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
  (:action keep :parameters (?x) :precondition (good ?x) :effect (kept)))"""

#: ``done`` needs a chain of three streams (level 3), ``kept`` a value ``test-good`` accepts
#: (it accepts none); ``sample-noise`` gives values no action uses, without end
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
    return PDDLProblem(DOMAIN, {}, STREAMS, streams, [("item", "i1"), ("item", "i2")], goal)


@pytest.mark.parametrize("algorithm", ["focused", "binding", "adaptive"])
def test_no_sampler_is_called_while_levels_rise_to_the_plan(algorithm: str) -> None:
    calls: dict[str, int] = {}
    solution = solve(_problem(calls), algorithm=algorithm, max_time=60, verbose=False)
    assert solution.status is Status.SOLVED
    assert solution.statistics["complexity"] == 3
    assert calls.get("sample-noise", 0) == 0  # no plan needs it: never called
    # the chain's streams: called for the plans' skeletons only (one per item at most)
    assert all(calls.get(name, 0) <= 2 for name in ("sample-a", "step-b", "step-c"))


def test_samplers_are_called_between_levels_once_every_instance_is_in() -> None:
    """A goal no value reaches (``test-good`` is false on all; adaptive, whose failed
    skeletons leave its queue): once the world holds every instance, the samplers with later
    calls on offer are called between levels (the level cap ends the solve: the samplers never
    run dry)."""
    calls: dict[str, int] = {}
    solution = solve(
        _problem(calls, goal=("kept",)),
        algorithm="adaptive",
        max_time=60,
        max_complexity=6,
        verbose=False,
    )
    assert solution.status is Status.INFEASIBLE
    # the skeletons alone call sample-a at most twice a level; the calls between levels give
    # it many more values (each tried by test-good)
    assert calls["sample-a"] > 2 * 6
    assert calls["test-good"] == calls["sample-a"]
