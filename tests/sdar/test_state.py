"""The lifted state SDAR applies actions with: derived predicates, quantifiers, costs."""

import pytest

from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.formula_model import Atom, FunctionTerm
from solvers.sdar.state import ActionError, LiftedState, fluent_predicates

DOMAIN = """
(define (domain shelf)
  (:requirements :strips :typing :equality :derived-predicates :existential-preconditions
                 :negative-preconditions :action-costs)
  (:types item spot)
  (:predicates (at ?i - item ?s - spot) (clear-pair ?i - item ?s - spot ?j - item ?t - spot)
               (holding ?i - item) (free) (blocked ?i - item ?s - spot))
  (:functions (total-cost) (effort ?i - item))
  (:derived (blocked ?i - item ?s - spot)
    (exists (?j - item ?t - spot)
      (and (at ?j ?t) (not (= ?i ?j)) (not (clear-pair ?i ?s ?j ?t)))))
  (:action pick :parameters (?i - item ?s - spot)
    :precondition (and (at ?i ?s) (free))
    :effect (and (holding ?i) (not (at ?i ?s)) (not (free)) (increase (total-cost) (effort ?i))))
  (:action put :parameters (?i - item ?s - spot)
    :precondition (and (holding ?i) (not (blocked ?i ?s)))
    :effect (and (at ?i ?s) (free) (not (holding ?i)) (increase (total-cost) 2))))
"""


def _state(clear: bool) -> LiftedState:
    domain = parse_domain(DOMAIN)
    static = [Atom("clear-pair", ("a", "s3", "b", "s2"))] if clear else []
    fluents = [Atom("at", ("a", "s1")), Atom("at", ("b", "s2")), Atom("free")]
    types = {"item": ["a", "b"], "spot": ["s1", "s2", "s3"]}
    return LiftedState(
        domain, static, fluents, lambda t: types.get(t, []), lambda term: 3.0 * len(term.args)
    )


def test_fluent_predicates_are_those_actions_change() -> None:
    assert fluent_predicates(parse_domain(DOMAIN)) == {"at", "holding", "free"}


def test_derived_predicate_with_existential_is_evaluated_from_the_facts() -> None:
    state = _state(clear=False)
    assert state.holds(Atom("blocked", ("a", "s3")), {})  # b rests, no clear-pair certified
    state.add_static([Atom("clear-pair", ("a", "s3", "b", "s2"))])
    assert not state.holds(Atom("blocked", ("a", "s3")), {})


def test_apply_checks_preconditions_and_sums_costs() -> None:
    state = _state(clear=True)
    assert state.apply("pick", ("a", "s1")) == 3.0  # (effort a) through the cost callback
    assert state.has("holding", "a") and not state.has("free")
    with pytest.raises(ActionError, match="precondition"):
        state.apply("pick", ("b", "s2"))  # the hand is not free
    assert state.apply("put", ("a", "s3")) == 2.0
    assert state.fluents() == {Atom("at", ("a", "s3")), Atom("at", ("b", "s2")), Atom("free")}


def test_put_on_an_uncertified_spot_is_refused() -> None:
    state = _state(clear=False)
    state.apply("pick", ("a", "s1"))
    assert not state.applicable("put", ("a", "s3"))
    with pytest.raises(ActionError):
        state.apply("put", ("a", "s3"))
    with pytest.raises(ActionError, match="wrong number"):
        state.apply("put", ("a",))


def test_streams_may_not_certify_fluents() -> None:
    with pytest.raises(ValueError, match="fluent"):
        _state(clear=True).add_static([Atom("at", ("a", "s2"))])


def test_cost_callback_receives_the_ground_term() -> None:
    seen: list[FunctionTerm] = []
    domain = parse_domain(DOMAIN)
    state = LiftedState(
        domain,
        [],
        [Atom("at", ("a", "s1")), Atom("free")],
        lambda t: [],
        lambda term: seen.append(term) or 1.0,
    )
    state.apply("pick", ("a", "s1"))
    assert seen == [FunctionTerm("effort", ("a",))]
