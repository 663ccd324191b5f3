"""The lab domain, objects and state shared by the tests of the PDDL semantics (substitution,
evaluator, state changes, plan runs)."""

from __future__ import annotations

from collections.abc import Iterable

from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.evaluator import Evaluator
from sdar_tamp.language.formula_model import Atom
from sdar_tamp.language.state_index import FactIndex, TypedObjects

DOMAIN = """
(define (domain lab)
  (:requirements :strips :typing :equality :derived-predicates :existential-preconditions
                 :universal-preconditions :negative-preconditions :conditional-effects
                 :action-costs)
  (:types block - item tool - item item place)
  (:predicates (on ?i - item ?p - place) (edge ?p - place ?q - place) (reach ?p - place ?q - place)
               (empty ?p - place) (clean ?i - item) (lit) (busy))
  (:functions (total-cost) (weight ?i - item))
  (:derived (empty ?p - place) (not (exists (?i - item) (on ?i ?p))))
  (:derived (reach ?p - place ?q - place) (edge ?p ?q))
  (:derived (reach ?p - place ?q - place) (and (edge ?p ?r) (reach ?r ?q)))
  (:action move :parameters (?i - item ?from - place ?to - place)
    :precondition (and (on ?i ?from) (empty ?to) (reach ?from ?to))
    :effect (and (on ?i ?to) (not (on ?i ?from)) (increase (total-cost) (weight ?i))
                 (when (lit) (clean ?i)) (when (busy) (increase (total-cost) 10))))
  (:action wipe-all :parameters ()
    :precondition (forall (?b - block) (not (clean ?b)))
    :effect (forall (?b - block) (clean ?b)))
  (:action toggle :parameters (?i - item)
    :precondition (clean ?i)
    :effect (and (not (clean ?i)) (clean ?i))))
"""

OBJECTS = {"b1": "block", "b2": "block", "t1": "tool", "p1": "place", "p2": "place", "p3": "place"}
STATE = [
    Atom("on", ("b1", "p1")),
    Atom("on", ("t1", "p2")),
    Atom("edge", ("p1", "p2")),
    Atom("edge", ("p2", "p3")),
    Atom("edge", ("p3", "p1")),  # a cycle: reach is recursive through it
]


def lab_evaluator(
    domain: Domain, atoms: Iterable[Atom] = STATE, explain: bool = False
) -> Evaluator:
    """An evaluator on ``atoms`` (the lab state by default) over the lab objects."""
    return Evaluator(domain, FactIndex(atoms), TypedObjects(domain, OBJECTS), explain=explain)
