"""Tiny domains written for the compatibility tests (a line world with one gripper)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

DOMAIN = """(define (domain line)
  (:requirements :strips :negative-preconditions :action-costs)
  (:predicates (block ?b) (pose ?b ?p) (at ?b ?p) (holding ?b) (free) (safe ?p) (on-shelf ?b))
  (:functions (total-cost) (lift ?b))
  (:action pick :parameters (?b ?p) :precondition (and (at ?b ?p) (free))
     :effect (and (holding ?b) (not (at ?b ?p)) (not (free)) (increase (total-cost) (lift ?b))))
  (:action place :parameters (?b ?p) :precondition (and (holding ?b) (pose ?b ?p) (safe ?p))
     :effect (and (at ?b ?p) (on-shelf ?b) (free) (not (holding ?b)))))"""

STREAMS = """(define (stream line)
  (:stream sample-pose :inputs (?b) :domain (block ?b) :outputs (?p)
     :certified (pose ?b ?p))
  (:stream test-safe :inputs (?b ?p) :domain (pose ?b ?p) :certified (safe ?p))
  (:function (lift ?b) (block ?b)))"""


def sample_pose(block: str) -> Iterator[tuple[float]]:
    x = 1.0
    while True:
        yield (x,)
        x += 1.0


def stream_map() -> dict[str, Any]:
    from sdar_tamp.compat.pddlstream import from_gen_fn, from_test

    return {
        "sample-pose": from_gen_fn(sample_pose),
        "test-safe": from_test(lambda b, p: p >= 2.0),
        "lift": lambda b: 2.0,
    }


INIT = [("free",), ("block", "cup"), ("at", "cup", 0.0)]
GOAL = ("on-shelf", "cup")

#: a stream whose domain holds a fluent fact (``observed`` is set by an action): exogenous
EXO_DOMAIN = """(define (domain watch)
  (:requirements :strips)
  (:predicates (item ?i) (observed ?i) (reading ?i ?v) (have ?i))
  (:action look :parameters (?i) :precondition (item ?i) :effect (observed ?i))
  (:action take :parameters (?i ?v) :precondition (and (reading ?i ?v) (observed ?i))
     :effect (have ?i)))"""

EXO_STREAMS = """(define (stream watch)
  (:stream read :inputs (?i) :domain (and (item ?i) (observed ?i)) :outputs (?v)
     :certified (reading ?i ?v)))"""
