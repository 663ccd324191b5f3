"""Effects: evaluated in the state before the action, conditional and universal, costs."""

from __future__ import annotations

import pytest
from lab_semantics import DOMAIN, STATE, lab_evaluator

from sdar_tamp.errors import EvaluationError
from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.formula_model import (
    AndEffect,
    Atom,
    ForAllEffect,
    FunctionTerm,
    IncreaseCost,
    Literal,
    Parameter,
    When,
)
from sdar_tamp.language.state_changes import Changes, effect_changes
from sdar_tamp.language.substitution import bind


@pytest.fixture(scope="module")
def domain() -> Domain:
    return parse_domain(DOMAIN)


def test_effects_are_evaluated_in_the_state_before_the_action(domain: Domain) -> None:
    ev = lab_evaluator(domain, [*STATE, Atom("lit")], explain=True)
    move = domain.action("move")
    changes = effect_changes(
        ev, move.effect, bind(move, ("b1", "p1", "p3")), lambda term: {"b1": 2.5}[term.args[0]]
    )
    assert changes.adds == {Atom("on", ("b1", "p3")), Atom("clean", ("b1",))}
    assert changes.deletes == {Atom("on", ("b1", "p1"))}
    assert changes.cost == 2.5  # (when (busy) ...) does not hold: its cost is not paid
    assert changes.support == {Atom("lit")}  # the condition of the effect that happened


def test_conditional_costs_and_costs_without_a_callback(domain: Domain) -> None:
    ev = lab_evaluator(domain, [*STATE, Atom("busy")])
    move = domain.action("move")
    binding = bind(move, ("b1", "p1", "p3"))
    assert effect_changes(ev, move.effect, binding, lambda term: 1.0).cost == 11.0
    assert effect_changes(ev, move.effect, binding).cost == 0.0
    assert effect_changes(ev, IncreaseCost(3.0), {}, lambda term: 1.0).cost == 3.0


def test_universal_effects_and_add_after_delete(domain: Domain) -> None:
    ev = lab_evaluator(domain)
    changes = effect_changes(ev, domain.action("wipe-all").effect, {})
    assert changes.adds == {Atom("clean", ("b1",)), Atom("clean", ("b2",))}
    toggle = domain.action("toggle")
    both = effect_changes(ev, toggle.effect, bind(toggle, ("b1",)))
    state = frozenset({Atom("clean", ("b1",))})
    assert both.apply(state) == state  # deleted and added: it stays true
    assert Changes(deletes=state).apply(state) == frozenset()


def test_an_unbound_variable_in_an_effect_is_an_error(domain: Domain) -> None:
    ev = lab_evaluator(domain)
    with pytest.raises(EvaluationError, match="effect"):
        effect_changes(ev, Literal(Atom("clean", ("?x",))), {})
    with pytest.raises(EvaluationError, match="cost term"):
        effect_changes(ev, IncreaseCost(FunctionTerm("weight", ("?x",))), {}, lambda t: 1.0)
    forall = ForAllEffect((Parameter("?b", "block"),), When(Atom("lit"), Literal(Atom("busy"))))
    assert effect_changes(ev, AndEffect((forall,)), {}).adds == frozenset()
