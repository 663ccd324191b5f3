"""PDDLStream programs that rely on what PDDLStream accepts: predicates used only in a stream's
:domain and the init, init facts of predicates used nowhere, and '?' glued to a name."""

from __future__ import annotations

import itertools
from collections.abc import Iterator

import pytest

from sdar_tamp.language.generators import from_gen_fn
from sdar_tamp.language.leniency import GLUED_VARIABLE, IMPLICIT_PREDICATE
from sdar_tamp.language.problem import PDDLProblem
from solvers.solve import solve

# (block ?b) and (region ?r) are never declared: the stream's :domain and the init use them.
DOMAIN = """
(define (domain line)
  (:requirements :strips :negative-preconditions :derived-predicates)
  (:predicates (pose ?b ?p) (contained ?b ?p ?r) (atpose ?b ?p) (in ?b ?r))
  (:derived (in ?b ?r) (exists (?p) (and (contained ?b ?p ?r) (atpose ?b ?p))))
  (:action move :parameters (?b ?p1 ?p2)
    :precondition (and (atpose ?b ?p1) (pose ?b?p2))
    :effect (and (atpose ?b ?p2) (not (atpose ?b ?p1)))))
"""
STREAM = """
(define (stream line)
  (:stream sample-pose :inputs (?b ?r) :domain (and (Block ?b) (region ?r))
    :outputs (?p) :certified (and (pose ?b ?p) (contained ?b ?p ?r))))
"""
INIT = [("block", "a"), ("region", "goal"), ("pose", "a", 0.0), ("atpose", "a", 0.0)]


def _samples(b: str, r: str) -> Iterator[tuple[float]]:
    for k in itertools.count():
        yield (5.0 + k,)


def make() -> PDDLProblem:
    init = [*INIT, ("Colour", "a", "red")]  # a predicate used nowhere else
    stream_map = {"sample-pose": from_gen_fn(_samples)}
    return PDDLProblem(DOMAIN, {}, STREAM, stream_map, init, ("in", "a", "goal"))


def test_the_leniencies_are_noted() -> None:
    problem = make()
    assert [item.kind for item in problem.domain.leniencies] == [GLUED_VARIABLE]
    assert [(item.kind, item.message.split("'")[1]) for item in problem.streams.leniencies] == [
        (IMPLICIT_PREDICATE, "block"),
        (IMPLICIT_PREDICATE, "region"),
    ]
    assert [item.message.split("'")[1] for item in problem.leniencies] == ["colour"]


@pytest.mark.parametrize("algorithm", ["incremental", "focused", "binding", "adaptive"])
def test_a_lenient_program_solves(algorithm: str) -> None:
    solution = solve(make(), algorithm=algorithm, verbose=False)
    assert solution.solved
    assert [(a.name, a.args) for a in solution.plan or []] == [("move", ("a", 0.0, 5.0))]
