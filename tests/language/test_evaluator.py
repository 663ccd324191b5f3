"""The condition evaluator: connectives, equality, quantifiers, types, derived predicates and
the support of a condition."""

from __future__ import annotations

import pytest
from lab_semantics import DOMAIN, STATE, lab_evaluator

from sdar_tamp.errors import EvaluationError, SdarError
from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.formula_model import (
    TRUE,
    And,
    Atom,
    Exists,
    ForAll,
    Imply,
    Not,
    Or,
    Parameter,
)


@pytest.fixture(scope="module")
def domain() -> Domain:
    return parse_domain(DOMAIN)


# --- connectives, equality, quantifiers, types ------------------------------------------------


def test_connectives_and_equality(domain: Domain) -> None:
    ev = lab_evaluator(domain)
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
    ev = lab_evaluator(domain)
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
    ev = lab_evaluator(domain, [*STATE, Atom("clean", ("b1",)), Atom("clean", ("b2",))])
    assert ev.holds(ForAll((Parameter("?b", "block"),), Atom("clean", ("?b",))), {})
    assert not ev.holds(ForAll((Parameter("?b", "item"),), Atom("clean", ("?b",))), {})
    assert ev.holds(ForAll((Parameter("?x", "nothing-of-this-type"),), Or(())), {})


def test_type_names_are_unary_predicates(domain: Domain) -> None:
    ev = lab_evaluator(domain)
    assert ev.holds(Atom("item", ("b1",)), {}) and ev.holds(Atom("block", ("b1",)), {})
    assert not ev.holds(Atom("tool", ("b1",)), {})
    assert ev.holds(Atom("object", ("p1",)), {}) and not ev.holds(Atom("object", ("zz",)), {})


def test_an_unbound_variable_is_an_error(domain: Domain) -> None:
    with pytest.raises(EvaluationError, match="unbound variable"):
        lab_evaluator(domain).holds(Atom("on", ("?nobody", "p1")), {})


def test_a_derived_atom_with_the_wrong_arity_is_an_error(domain: Domain) -> None:
    with pytest.raises(EvaluationError, match="takes 1 argument") as info:
        lab_evaluator(domain).holds(Atom("empty", ("p1", "p2")), {})
    assert isinstance(info.value, SdarError)


# --- derived predicates -----------------------------------------------------------------------


def test_derived_predicates_with_negation_and_recursion(domain: Domain) -> None:
    ev = lab_evaluator(domain)
    assert ev.holds(Atom("empty", ("p3",)), {}) and not ev.holds(Atom("empty", ("p1",)), {})
    # reach is the transitive closure of edge, through a cycle, from either axiom
    for p in ("p1", "p2", "p3"):
        for q in ("p1", "p2", "p3"):
            assert ev.holds(Atom("reach", (p, q)), {})
    acyclic = lab_evaluator(domain, [a for a in STATE if a.args != ("p3", "p1")])
    assert acyclic.holds(Atom("reach", ("p1", "p3")), {})
    assert not acyclic.holds(Atom("reach", ("p3", "p1")), {})
    assert not acyclic.holds(Atom("reach", ("p1", "p1")), {})
    # derived atoms in the facts are ignored: the axioms decide
    assert not lab_evaluator(domain, [*STATE, Atom("empty", ("p1",))]).holds(
        Atom("empty", ("p1",)), {}
    )


def test_support_names_the_facts_a_condition_relies_on(domain: Domain) -> None:
    ev = lab_evaluator(domain, explain=True)
    on = Atom("on", ("b1", "p1"))
    assert ev.support(And((on, Atom("=", ("a", "a")))), {}) == {on}
    assert ev.support(Atom("reach", ("p1", "p2")), {}) == {Atom("edge", ("p1", "p2"))}
    # a negated derived atom relies on what makes its body false: p1 is not empty because of b1
    assert ev.support(Not(Atom("empty", ("p1",))), {}) == {on}
    assert ev.support(Not(Atom("busy")), {}) == frozenset()  # an absent fact needs nothing
    assert ev.support(Atom("busy"), {}) is None
    assert lab_evaluator(domain).support(on, {}) == frozenset()  # without explain: no facts
