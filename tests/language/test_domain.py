"""Domain and problem parsing: what comes out of a well-formed file."""

from sdar_tamp.language import parse_domain, parse_problem
from sdar_tamp.language.formula_model import (
    And,
    Atom,
    Exists,
    ForAllEffect,
    FunctionTerm,
    IncreaseCost,
    Literal,
    Not,
    Or,
    When,
)
from sdar_tamp.language.traversal import iter_effect_literals

DOMAIN = """
; a typed domain exercising every supported requirement
(define (domain Shop)
  (:requirements :strips :typing :negative-preconditions :disjunctive-preconditions :equality
                 :existential-preconditions :universal-preconditions :conditional-effects
                 :derived-predicates :action-costs)
  (:types crate tool - item  item room)
  (:constants Hall - room)
  (:predicates (at ?i - item ?r - room) (robot-at ?r - room) (holding ?i - item) (free)
               (reachable ?r - room) (door ?a ?b - room))
  (:functions (total-cost) - number (weight ?i - item) - number)
  (:derived (reachable ?r - room)
     (or (robot-at ?r) (exists (?s - room) (and (reachable ?s) (door ?s ?r)))))
  (:action MOVE :parameters (?a ?b - room)
     :precondition (and (robot-at ?a) (door ?a ?b) (not (= ?a ?b)))
     :effect (and (robot-at ?b) (not (robot-at ?a)) (increase (total-cost) 2)
                  (forall (?i - item) (when (holding ?i) (and (at ?i ?b) (not (at ?i ?a)))))))
  (:action pick :parameters (?i - item ?r - room)
     :precondition (and (robot-at ?r) (at ?i ?r) (free))
     :effect (and (holding ?i) (not (free)) (increase (total-cost) (weight ?i)))))
"""

PROBLEM = """
(define (problem Shop-1) (:domain SHOP)
  (:objects box - crate hammer - tool kitchen - room)
  (:init (robot-at hall) (door hall kitchen) (at box kitchen) (free)
         (= (weight box) 5) (= (total-cost) 0))
  (:goal (and (at box hall) (forall (?i - tool) (not (holding ?i)))))
  (:metric minimize (total-cost)))
"""


def test_domain_structure_is_lower_case_and_typed() -> None:
    domain = parse_domain(DOMAIN, "shop.pddl")
    assert domain.name == "shop"
    assert ":action-costs" in domain.requirements
    assert domain.types.ancestors("crate") == ("crate", "item", "object")
    assert domain.constants == {"hall": "room"}
    assert domain.predicates["at"].arity == 2
    assert set(domain.functions) == {"total-cost", "weight"}
    move = domain.action("move")
    assert [p.type for p in move.parameters] == ["room", "room"]
    assert isinstance(move.precondition, And)
    assert Not(Atom("=", ("?a", "?b"))) in move.precondition.parts
    literals = list(iter_effect_literals(move.effect))
    assert Literal(Atom("at", ("?i", "?b"))) in literals
    assert Literal(Atom("robot-at", ("?a",)), negated=True) in literals
    forall = [p for p in move.effect.parts if isinstance(p, ForAllEffect)]  # type: ignore[union-attr]
    assert isinstance(forall[0].effect, When)
    pick = domain.action("pick")
    assert IncreaseCost(FunctionTerm("weight", ("?i",))) in pick.effect.parts  # type: ignore[union-attr]


def test_derived_predicate_body() -> None:
    domain = parse_domain(DOMAIN, "shop.pddl")
    (axiom,) = domain.axioms
    assert axiom.predicate == "reachable"
    assert axiom.parameters[0].type == "room"
    assert isinstance(axiom.body, Or)
    assert isinstance(axiom.body.parts[1], Exists)
    assert domain.derived_predicates == {"reachable"}


def test_problem_objects_init_numeric_goal() -> None:
    domain = parse_domain(DOMAIN, "shop.pddl")
    problem = parse_problem(PROBLEM, domain, "p.pddl")
    assert problem.name == "shop-1"
    assert problem.objects == {"box": "crate", "hammer": "tool", "kitchen": "room"}
    assert Atom("robot-at", ("hall",)) in problem.init
    assert problem.numeric_init == {("weight", ("box",)): 5.0, ("total-cost", ()): 0.0}
    assert problem.minimize_cost
    assert isinstance(problem.goal, And)


def test_comments_and_case_are_ignored() -> None:
    text = "(DEFINE (DOMAIN d) ; comment (\n (:PREDICATES (P ?X)))"
    domain = parse_domain(text)
    assert "p" in domain.predicates
