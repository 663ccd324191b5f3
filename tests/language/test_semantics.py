"""The shared PDDL semantics: conditions, derived predicates, effects, plans, and their errors."""

from __future__ import annotations

from collections.abc import Iterable

import pytest

from sdar_tamp.errors import ActionError, EvaluationError, SdarError
from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.evaluator import Evaluator
from sdar_tamp.language.formula_model import (
    TRUE,
    And,
    AndEffect,
    Atom,
    Exists,
    ForAll,
    ForAllEffect,
    FunctionTerm,
    Imply,
    IncreaseCost,
    Literal,
    Not,
    Or,
    Parameter,
    When,
)
from sdar_tamp.language.plan_run import check_arguments, run_plan
from sdar_tamp.language.state_changes import Changes, effect_changes
from sdar_tamp.language.state_index import FactIndex, TypedObjects
from sdar_tamp.language.substitution import bind, free_parameters, ground_args, ground_atom

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


@pytest.fixture(scope="module")
def domain() -> Domain:
    return parse_domain(DOMAIN)


def _evaluator(domain: Domain, atoms: Iterable[Atom] = STATE, explain: bool = False) -> Evaluator:
    return Evaluator(domain, FactIndex(atoms), TypedObjects(domain, OBJECTS), explain=explain)


# --- substitution and binding -----------------------------------------------------------------


def test_substitution_replaces_bound_variables_only() -> None:
    assert ground_args(("?x", "c", "?y"), {"?x": "a"}) == ("a", "c", "?y")
    assert ground_atom(Atom("on", ("?x", "?p")), {"?x": "b", "?p": "p"}) == Atom("on", ("b", "p"))


def test_bind_names_each_parameter_and_rejects_a_wrong_arity(domain: Domain) -> None:
    move = domain.action("move")
    assert bind(move, ("b1", "p1", "p2")) == {"?i": "b1", "?from": "p1", "?to": "p2"}
    with pytest.raises(ActionError, match="wrong number of arguments") as info:
        bind(move, ("b1",))
    assert isinstance(info.value, SdarError)


def test_free_parameters_skip_bound_and_quantified_variables() -> None:
    body = And((Atom("p", ("?a", "?x")), Exists((Parameter("?y"),), Atom("q", ("?y", "?z")))))
    assert [p.name for p in free_parameters(body, {"?a"})] == ["?x", "?z"]


# --- connectives, equality, quantifiers, types ------------------------------------------------


def test_connectives_and_equality(domain: Domain) -> None:
    ev = _evaluator(domain)
    on = Atom("on", ("?i", "p1"))
    b1, t1 = {"?i": "b1"}, {"?i": "t1"}
    assert ev.holds(on, b1) and not ev.holds(on, t1)
    assert ev.holds(Not(on), t1) and not ev.holds(Not(on), b1)
    assert ev.holds(TRUE, {}) and not ev.holds(Or(()), {})
    assert ev.holds(And((on, Atom("=", ("?i", "b1")))), b1)
    assert not ev.holds(And((on, Atom("=", ("?i", "t1")))), b1)
    assert ev.holds(Or((Atom("lit"), on)), b1) and not ev.holds(Or((Atom("lit"), on)), t1)
    assert ev.holds(Imply(Atom("lit"), Atom("busy")), {})  # false antecedent
    assert not ev.holds(Imply(on, Atom("busy")), b1)  # true antecedent, false consequent
    assert ev.holds(Imply(on, on), b1)


def test_exists_finds_a_witness_of_the_right_type(domain: Domain) -> None:
    ev = _evaluator(domain)
    block_at = Exists((Parameter("?b", "block"),), Atom("on", ("?b", "?p")))
    assert ev.holds(block_at, {"?p": "p1"})
    assert not ev.holds(block_at, {"?p": "p2"})  # a tool is there, not a block
    item_at = Exists((Parameter("?b", "item"),), Atom("on", ("?b", "?p")))
    assert ev.holds(item_at, {"?p": "p2"})  # a tool is an item
    # no positive atom names ?b: it ranges over the blocks
    assert ev.holds(Exists((Parameter("?b", "block"),), Not(Atom("clean", ("?b",)))), {})
    assert list(ev.witnesses((Parameter("?b", "block"),), Atom("on", ("?b", "p1")), {})) == [
        {"?b": "b1"}
    ]


def test_forall_ranges_over_the_objects_of_its_type(domain: Domain) -> None:
    ev = _evaluator(domain, [*STATE, Atom("clean", ("b1",)), Atom("clean", ("b2",))])
    assert ev.holds(ForAll((Parameter("?b", "block"),), Atom("clean", ("?b",))), {})
    assert not ev.holds(ForAll((Parameter("?b", "item"),), Atom("clean", ("?b",))), {})
    assert ev.holds(ForAll((Parameter("?x", "nothing-of-this-type"),), Or(())), {})


def test_type_names_are_unary_predicates(domain: Domain) -> None:
    ev = _evaluator(domain)
    assert ev.holds(Atom("item", ("b1",)), {}) and ev.holds(Atom("block", ("b1",)), {})
    assert not ev.holds(Atom("tool", ("b1",)), {})
    assert ev.holds(Atom("object", ("p1",)), {}) and not ev.holds(Atom("object", ("zz",)), {})


def test_an_unbound_variable_is_an_error(domain: Domain) -> None:
    with pytest.raises(EvaluationError, match="unbound variable"):
        _evaluator(domain).holds(Atom("on", ("?nobody", "p1")), {})


def test_a_derived_atom_with_the_wrong_arity_is_an_error(domain: Domain) -> None:
    with pytest.raises(EvaluationError, match="takes 1 argument") as info:
        _evaluator(domain).holds(Atom("empty", ("p1", "p2")), {})
    assert isinstance(info.value, SdarError)


# --- derived predicates -----------------------------------------------------------------------


def test_derived_predicates_with_negation_and_recursion(domain: Domain) -> None:
    ev = _evaluator(domain)
    assert ev.holds(Atom("empty", ("p3",)), {}) and not ev.holds(Atom("empty", ("p1",)), {})
    # reach is the transitive closure of edge, through a cycle, from either axiom
    for p in ("p1", "p2", "p3"):
        for q in ("p1", "p2", "p3"):
            assert ev.holds(Atom("reach", (p, q)), {})
    acyclic = _evaluator(domain, [a for a in STATE if a.args != ("p3", "p1")])
    assert acyclic.holds(Atom("reach", ("p1", "p3")), {})
    assert not acyclic.holds(Atom("reach", ("p3", "p1")), {})
    assert not acyclic.holds(Atom("reach", ("p1", "p1")), {})
    # derived atoms in the facts are ignored: the axioms decide
    assert not _evaluator(domain, [*STATE, Atom("empty", ("p1",))]).holds(
        Atom("empty", ("p1",)), {}
    )


def test_support_names_the_facts_a_condition_relies_on(domain: Domain) -> None:
    ev = _evaluator(domain, explain=True)
    on = Atom("on", ("b1", "p1"))
    assert ev.support(And((on, Atom("=", ("a", "a")))), {}) == {on}
    assert ev.support(Atom("reach", ("p1", "p2")), {}) == {Atom("edge", ("p1", "p2"))}
    # a negated derived atom relies on what makes its body false: p1 is not empty because of b1
    assert ev.support(Not(Atom("empty", ("p1",))), {}) == {on}
    assert ev.support(Not(Atom("busy")), {}) == frozenset()  # an absent fact needs nothing
    assert ev.support(Atom("busy"), {}) is None
    assert _evaluator(domain).support(on, {}) == frozenset()  # without explain: no facts


# --- effects ----------------------------------------------------------------------------------


def test_effects_are_evaluated_in_the_state_before_the_action(domain: Domain) -> None:
    ev = _evaluator(domain, [*STATE, Atom("lit")], explain=True)
    move = domain.action("move")
    changes = effect_changes(
        ev, move.effect, bind(move, ("b1", "p1", "p3")), lambda term: {"b1": 2.5}[term.args[0]]
    )
    assert changes.adds == {Atom("on", ("b1", "p3")), Atom("clean", ("b1",))}
    assert changes.deletes == {Atom("on", ("b1", "p1"))}
    assert changes.cost == 2.5  # (when (busy) ...) does not hold: its cost is not paid
    assert changes.support == {Atom("lit")}  # the condition of the effect that happened


def test_conditional_costs_and_costs_without_a_callback(domain: Domain) -> None:
    ev = _evaluator(domain, [*STATE, Atom("busy")])
    move = domain.action("move")
    binding = bind(move, ("b1", "p1", "p3"))
    assert effect_changes(ev, move.effect, binding, lambda term: 1.0).cost == 11.0
    assert effect_changes(ev, move.effect, binding).cost == 0.0
    assert effect_changes(ev, IncreaseCost(3.0), {}, lambda term: 1.0).cost == 3.0


def test_universal_effects_and_add_after_delete(domain: Domain) -> None:
    ev = _evaluator(domain)
    changes = effect_changes(ev, domain.action("wipe-all").effect, {})
    assert changes.adds == {Atom("clean", ("b1",)), Atom("clean", ("b2",))}
    toggle = domain.action("toggle")
    both = effect_changes(ev, toggle.effect, bind(toggle, ("b1",)))
    state = frozenset({Atom("clean", ("b1",))})
    assert both.apply(state) == state  # deleted and added: it stays true
    assert Changes(deletes=state).apply(state) == frozenset()


def test_an_unbound_variable_in_an_effect_is_an_error(domain: Domain) -> None:
    ev = _evaluator(domain)
    with pytest.raises(EvaluationError, match="effect"):
        effect_changes(ev, Literal(Atom("clean", ("?x",))), {})
    with pytest.raises(EvaluationError, match="cost term"):
        effect_changes(ev, IncreaseCost(FunctionTerm("weight", ("?x",))), {}, lambda t: 1.0)
    forall = ForAllEffect((Parameter("?b", "block"),), When(Atom("lit"), Literal(Atom("busy"))))
    assert effect_changes(ev, AndEffect((forall,)), {}).adds == frozenset()


# --- plans ------------------------------------------------------------------------------------


def test_a_valid_plan_runs_to_the_goal_with_its_cost(domain: Domain) -> None:
    objects = TypedObjects(domain, OBJECTS)
    plan = [("move", ("b1", "p1", "p3")), ("move", ("t1", "p2", "p1"))]
    goal = And((Atom("on", ("b1", "p3")), Atom("empty", ("p2",))))
    run = run_plan(domain, objects, STATE, plan, goal, lambda term: 2.0, explain=True)
    assert run.valid and run.failed_step is None and run.cost == 4.0
    assert len(run.states) == len(run.supports) == len(run.changes) == 2
    assert run.states[0] == frozenset(STATE)
    assert Atom("on", ("b1", "p1")) in run.supports[0]
    assert run.goal_support == {Atom("on", ("b1", "p3"))}  # empty p2 needs no fact


@pytest.mark.parametrize(
    ("step", "reason"),
    [
        (("fly", ("b1",)), "unknown action"),
        (("move", ("b1", "p1")), "wrong number of arguments"),
        (("move", ("b1", "p1", "b2")), "b2 is not of type place"),
        (("move", ("zz", "p1", "p2")), "unknown object zz"),
        (("move", ("b1", "p1", "p3")), "precondition of (move b1 p1 p3) does not hold"),
    ],
)
def test_a_bad_step_ends_the_run_and_says_why(
    domain: Domain, step: tuple[str, tuple[str, ...]], reason: str
) -> None:
    objects = TypedObjects(domain, OBJECTS)
    plan = [("move", ("t1", "p2", "p3")), step]
    run = run_plan(domain, objects, STATE, plan, TRUE)
    assert not run.valid and run.failed_step == 1 and reason in run.reason
    assert len(run.states) == 1 and Atom("on", ("t1", "p3")) in run.final_state


def test_a_plan_that_misses_the_goal_fails_at_step_minus_one(domain: Domain) -> None:
    run = run_plan(domain, TypedObjects(domain, OBJECTS), STATE, [], Atom("lit"))
    assert run.failed_step == -1 and "goal" in run.reason and run.goal_support is None
    assert check_arguments(domain.action("toggle"), ("b1",), TypedObjects(domain, OBJECTS)) is None
