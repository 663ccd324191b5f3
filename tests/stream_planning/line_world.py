"""The line world the feature tests share: a block on a line, a pose sampler per region, one
move per plan step (:func:`line_problem`), and a counting sampler (:func:`counting`)."""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from typing import Any

from sdar_tamp.language.generators import from_gen_fn
from sdar_tamp.language.problem import PDDLProblem

# A block on a line: sample a pose in a region, then move it there (one move per plan step).
LINE = """
(define (domain line)
  (:requirements :strips :equality :negative-preconditions :derived-predicates)
  (:predicates (block ?b) (region ?r) (pose ?b ?p) (contained ?b ?p ?r) (atpose ?b ?p)
               (in ?b ?r) (blocked ?b ?p) (unsafe ?b ?p) (free ?p) (marked ?p))
  (:derived (in ?b ?r) (exists (?p) (and (contained ?b ?p ?r) (atpose ?b ?p))))
  (:derived (unsafe ?b ?p) (blocked ?b ?p))
  (:action move :parameters (?b ?p1 ?p2)
    :precondition (and (atpose ?b ?p1) (pose ?b ?p2) (not (unsafe ?b ?p2)))
    :effect (and (atpose ?b ?p2) (not (atpose ?b ?p1)))))
"""
SAMPLE = """
(define (stream line)
  (:stream sample-pose :inputs (?b ?r) :domain (and (block ?b) (region ?r))
    :outputs (?p) :certified (and (pose ?b ?p) (contained ?b ?p ?r))))
"""
INIT = [("block", "a"), ("region", "goal"), ("pose", "a", 0.0), ("atpose", "a", 0.0)]
GOAL = ("in", "a", "goal")


def line_problem(sampler: Any, stream_pddl: str = SAMPLE, **extra: Any) -> PDDLProblem:
    stream_map = {"sample-pose": sampler, **extra}
    return PDDLProblem(LINE, {}, stream_pddl, stream_map, INIT, GOAL)


def counting(start: float = 5.0) -> Any:
    def gen(b: str, r: str) -> Iterator[tuple[float]]:
        for k in itertools.count():
            yield (start + k,)

    return from_gen_fn(gen)
