"""Grounding: relaxed reachability, typing, statics, equality, costs, errors."""

from __future__ import annotations

import dataclasses

import pytest
from classical_helpers import load, load_text

from sdar_tamp.language.domain_model import ActionSchema, Axiom, Domain, TypeHierarchy
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.formula_model import And, Atom, Literal, Not, Parameter
from solvers.classical import GroundingError, PlanningTask, PlanStatus, ground, plan
from solvers.classical.normalize import normalize
from solvers.classical.reachability import reachable_facts


def test_blocksworld_grounding_counts_and_statics() -> None:
    task = ground(load("blocksworld", "sussman"))
    # 3 pick-up + 3 put-down + 9 stack + 9 unstack, all relaxed reachable (including (stack a a)).
    assert len(task.operators) == 24
    names = {str(op.action) for op in task.operators}
    assert "(unstack c a)" in names and "(stack a a)" in names
    assert task.goal_reachable and not task.axioms


def test_only_reachable_instances_are_created() -> None:
    task = ground(load("logistics", "two-cities"))
    ops = {str(op.action) for op in task.operators}
    # drive stays within a city: in-city is static and pruned the cross-city instances.
    assert "(drive truck1 house1 port1 c1)" in ops
    assert not any(op.startswith("(drive truck1") and "c2" in op for op in ops)
    # typing: only airplanes fly, only between airports; trucks never reach the other city.
    assert all(op.args[0] == "plane" for op in task.operators if op.name == "fly")
    assert "(load parcel truck1 house2)" not in ops
    # static facts are gone from the ground task
    assert all(atom.predicate not in {"in-city", "truck", "location"} for atom in task.facts)
    assert all(not op.precondition or len(op.precondition) <= 2 for op in task.operators)


def test_type_atoms_in_init_are_accepted_once() -> None:
    task = load("logistics", "two-cities")
    with_types = dataclasses.replace(
        task,
        init=task.init
        | {Atom("truck", ("truck1",)), Atom("vehicle", ("truck1",)), Atom("city", ("c1",))},
    )
    assert ground(with_types).operators == ground(task).operators
    assert ground(with_types).facts == ground(task).facts


def test_type_names_work_as_unary_predicates() -> None:
    hierarchy = TypeHierarchy({"block": "object", "ball": "object"})
    # (grab ?x): any object that is a block by type-predicate, not by parameter type.
    grab = ActionSchema(
        "grab",
        (Parameter("?x"),),
        And((Atom("block", ("?x",)), Not(Atom("held", ("?x",))))),
        Literal(Atom("held", ("?x",))),
    )
    domain = Domain("types", frozenset(), hierarchy, {}, {}, {}, (grab,), ())
    objects = {"b1": "block", "b2": "block", "r1": "ball"}
    task = ground(
        dataclasses.replace(
            load("blocksworld", "sussman"),
            domain=domain,
            objects=objects,
            init=frozenset(),
            goal=Atom("held", ("b1",)),
        )
    )
    assert sorted(str(op.action) for op in task.operators) == ["(grab b1)", "(grab b2)"]


def test_equality_and_negated_equality_prune_instances() -> None:
    task = ground(load("briefcase", "office"))
    moves = [op for op in task.operators if op.name == "move"]
    assert moves and all(op.args[0] != op.args[1] for op in moves)


def test_missing_cost_term_is_an_error_naming_it() -> None:
    task = load("delivery_costs", "detour")
    values = {k: v for k, v in task.numeric_init.items() if k != ("length", ("a", "b"))}
    with pytest.raises(GroundingError, match=r"\(length a b\)"):
        ground(dataclasses.replace(task, numeric_init=values))
    # without costs the numeric values are not needed at all
    unit = dataclasses.replace(task, numeric_init={}, use_costs=False)
    assert all(op.cost == 1.0 for op in ground(unit).operators)


def test_costs_of_number_and_function_terms() -> None:
    costs = {str(op.action): op.cost for op in ground(load("delivery_costs", "detour")).operators}
    assert costs["(drive van a d)"] == 20.0
    assert costs["(drive van a b)"] == 3.0
    assert costs["(load van box a)"] == 1.0


def test_unstratified_axioms_are_rejected() -> None:
    axioms = (
        Axiom("p", (), Not(Atom("q"))),
        Axiom("q", (), Not(Atom("p"))),
    )
    domain = Domain("loop", frozenset(), TypeHierarchy(), {}, {}, {}, (), axioms)
    task = dataclasses.replace(load("blocksworld", "sussman"), domain=domain, goal=Atom("p"))
    with pytest.raises(GroundingError, match="stratified"):
        ground(task)


def test_goal_on_a_static_fact_that_is_false_is_unsolvable() -> None:
    text = """(define (problem nope) (:domain logistics)
      (:objects c1 - city h1 - location t - truck p - package)
      (:init (at t h1) (at p h1))
      (:goal (and (at p h1) (in-city h1 c1))))"""
    task = load_text("logistics", text)
    assert not ground(task).goal_reachable
    assert plan(task).status is PlanStatus.UNSOLVABLE


GUARDED = """
(define (domain guarded)
  (:requirements :strips :negative-preconditions :derived-predicates :existential-preconditions)
  (:predicates (P ?x ?y) (Q ?y) (R ?x ?y) (Bad ?x) (Done ?x) (Item ?x))
  (:derived (Bad ?x) (exists (?y) (and (P ?x ?y) (not (and (Q ?y) (not (R ?x ?y)))))))
  (:action finish :parameters (?x) :precondition (and (Item ?x) (not (Bad ?x)))
    :effect (Done ?x)))
"""


def test_a_disjunction_is_grounded_within_its_enclosing_conjunction() -> None:
    """``(not (and (Q ?y) (not (R ?x ?y))))`` becomes a disjunction with an auxiliary predicate
    over ``?x ?y``; no positive atom of its disjuncts names them, so it takes its bindings from
    the conjunction around it (``(P ?x ?y)``), not from every pair of objects."""
    objects = {f"o{i}": "object" for i in range(40)}
    init = {Atom("p", ("o0", "o1")), Atom("p", ("o2", "o3")), Atom("q", ("o1",))}
    init |= {Atom("q", ("o3",)), Atom("r", ("o2", "o3")), Atom("item", ("o0",))}
    init.add(Atom("item", ("o2",)))
    task = PlanningTask(
        parse_domain(GUARDED, "guarded.pddl"),
        objects,
        frozenset(init),
        And((Atom("done", ("o0",)),)),
    )
    norm = normalize(task)
    base = reachable_facts(norm)
    aux = {p: facts for p, facts in base.relations.items() if p.startswith("~aux")}
    assert aux and sum(len(facts) for facts in aux.values()) <= 4  # not 40 * 40
    assert {f"(bad {x})" for (x,) in base.relations.get("bad", ())} == {"(bad o2)"}
    # the meaning is unchanged: o2's partner o3 is in Q and in R with o2, o0's is in Q only
    result = plan(task)
    assert result.status is PlanStatus.SOLVED
    assert [str(a) for a in result.plan or []] == ["(finish o0)"]
    blocked = dataclasses.replace(task, goal=And((Atom("done", ("o2",)),)))
    assert plan(blocked).status is PlanStatus.UNSOLVABLE
