"""Substitution and binding: grounding atoms, an action's parameter binding, free variables."""

from __future__ import annotations

import pytest
from lab_semantics import DOMAIN

from sdar_tamp.errors import ActionError, SdarError
from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.formula_model import And, Atom, Exists, Parameter
from sdar_tamp.language.substitution import bind, free_parameters, ground_args, ground_atom


@pytest.fixture(scope="module")
def domain() -> Domain:
    return parse_domain(DOMAIN)


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
