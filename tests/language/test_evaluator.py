"""The condition evaluator: connectives, equality, quantifiers, types, derived predicates and
the support of a condition."""

from __future__ import annotations

import functools

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


# --- universals over an implication -------------------------------------------------------


def _brute(ev_factory, formula, binding):  # type: ignore[no-untyped-def]
    """The support of a universal with every binding of its parameters tried."""
    ev = ev_factory()
    collected: set[Atom] = set()
    for extended in ev.every(formula.parameters, binding):  # no body: every object
        found = ev.support(formula.body, extended)
        if found is None:
            return None
        collected |= found
    return frozenset(collected)


def test_forall_over_an_implication_visits_the_bindings_its_antecedent_allows(
    domain: Domain,
) -> None:
    """A parameter named by a positive atom of the antecedent takes that atom's values only
    (the atom with the fewest facts): elsewhere the antecedent is false and the body holds."""
    ev = lab_evaluator(domain)
    params = (Parameter("?i", "item"), Parameter("?p", "place"))
    body = Imply(Atom("on", ("?i", "?p")), Atom("edge", ("?p", "?q")))
    assert list(ev.every(params, {"?q": "p2"})) == [  # no body: every object of the types
        {"?q": "p2", "?i": i, "?p": p} for i in ("b1", "b2", "t1") for p in ("p1", "p2", "p3")
    ]
    assert list(ev.every(params, {"?q": "p2"}, body)) == [
        {"?q": "p2", "?i": i, "?p": p} for i in ("b1", "t1") for p in ("p1", "p2")
    ]
    # the same in PDDL's written-out form, (or (not A) C)
    rewritten = Or((Not(Atom("on", ("?i", "?p"))), Atom("edge", ("?p", "?q"))))
    assert list(ev.every(params, {}, rewritten)) == list(ev.every(params, {}, body))
    # a body that is no implication, or an antecedent atom with no facts: every object
    assert len(list(ev.every(params, {}, Atom("on", ("?i", "?p"))))) == 9
    assert len(list(ev.every(params, {}, Imply(Atom("busy"), Atom("lit"))))) == 9


def test_forall_over_an_implication_keeps_its_truth_and_support(domain: Domain) -> None:
    """Truth and support are those of trying every binding, with and without explanation; an
    antecedent with a negation or a derived atom is not narrowed when explaining (its
    refutation may rely on facts)."""
    state = [*STATE, Atom("clean", ("b1",)), Atom("on", ("b2", "p3"))]
    params = (Parameter("?i", "item"), Parameter("?p", "place"))
    bodies = [
        Imply(Atom("on", ("?i", "?p")), Atom("edge", ("?p", "?q"))),
        Imply(And((Atom("on", ("?i", "?p")), Atom("clean", ("?i",)))), Atom("edge", ("?p", "?q"))),
        Imply(And((Not(Atom("clean", ("?i",))), Atom("on", ("?i", "?p")))), Atom("lit")),
        Imply(And((Atom("on", ("?i", "?p")), Atom("empty", ("?p",)))), Atom("lit")),
        Or((Not(Atom("on", ("?i", "?p"))), Not(Atom("reach", ("?p", "?q"))))),
    ]
    for explain in (False, True):
        for body in bodies:
            formula = ForAll(params, body)
            for q in ("p1", "p2", "p3"):
                factory = functools.partial(lab_evaluator, domain, state, explain)

                expected = _brute(factory, formula, {"?q": q})
                assert factory().support(formula, {"?q": q}) == expected, (explain, body, q)
                refuted = factory().refutation(formula, {"?q": q})
                assert refuted == _first_refutation(factory, formula, {"?q": q})


def _first_refutation(ev_factory, formula, binding):  # type: ignore[no-untyped-def]
    ev = ev_factory()
    for extended in ev.every(formula.parameters, binding):
        if ev.support(formula.body, extended) is None:
            return ev.refutation(formula.body, extended)
    return frozenset()


def test_forall_with_a_negated_antecedent_is_not_narrowed_when_explaining(domain: Domain) -> None:
    ev = lab_evaluator(domain, explain=True)
    params = (Parameter("?i", "item"),)
    body = Imply(And((Not(Atom("clean", ("?i",))), Atom("on", ("?i", "p1")))), Atom("lit"))
    assert len(list(ev.every(params, {}, body))) == 3  # every item
    assert len(list(lab_evaluator(domain).every(params, {}, body))) == 2  # items on a place


def test_exists_takes_its_candidates_from_the_atom_with_the_fewest_facts(domain: Domain) -> None:
    """?p is named by (edge ?p ?q) (3 edge facts) and (on b1 ?p) (2 on facts): its
    candidates are those of on. A refutation covers those only: at p3, b1 is not there (an
    absent fact), so (edge p3 p1), which would make the first part false, is not relied on."""
    params = (Parameter("?p", "place"),)
    body = And(
        (
            Not(Atom("edge", ("?p", "p1"))),
            Atom("edge", ("?p", "?q")),
            Atom("on", ("b1", "?p")),
        )
    )
    ev = lab_evaluator(domain, explain=True)
    assert [b["?p"] for b in ev.witnesses(params, body, {"?q": "p3"})] == ["p1", "p2"]
    formula = Exists(params, body)
    assert ev.support(formula, {"?q": "p3"}) is None
    assert ev.refutation(formula, {"?q": "p3"}) == frozenset()
    assert ev.support(Not(formula), {"?q": "p3"}) == frozenset()
    # the first witness is the same as with every place tried
    assert ev.support(formula, {"?q": "p2"}) == {
        Atom("edge", ("p1", "p2")),
        Atom("on", ("b1", "p1")),
    }
