"""Every syntax or semantic error names file:line:col and what was expected: one test each."""

import pytest

from sdar_tamp.errors import SdarError
from sdar_tamp.language import (
    ArityError,
    DuplicateError,
    PddlSyntaxError,
    StreamDefinitionError,
    UnboundVariableError,
    UndeclaredError,
    UnknownKeywordError,
    UnsupportedFeatureError,
    parse_domain,
    parse_problem,
    parse_stream_file,
)

BASE = "(define (domain d) (:requirements :strips :typing) (:types block)\n"
PREDS = " (:predicates (on ?x - block ?y - block) (clear ?x))\n"


def domain_error(body: str) -> SdarError:
    with pytest.raises(SdarError) as info:
        parse_domain(BASE + PREDS + body + ")", "d.pddl")
    return info.value


def test_unbalanced_open_parenthesis() -> None:
    with pytest.raises(PddlSyntaxError, match=r"d\.pddl:1:1: unbalanced.*never closed"):
        parse_domain("(define (domain d)", "d.pddl")


def test_unbalanced_close_parenthesis() -> None:
    with pytest.raises(PddlSyntaxError, match=r"d\.pddl:1:20: unbalanced.*without a matching"):
        parse_domain("(define (domain d)))", "d.pddl")


def test_text_after_the_definition() -> None:
    with pytest.raises(PddlSyntaxError, match=r"d\.pddl:2:1: unexpected text after"):
        parse_domain("(define (domain d))\n(extra)", "d.pddl")


def test_empty_source() -> None:
    with pytest.raises(PddlSyntaxError, match="source is empty"):
        parse_domain("  ; nothing\n", "d.pddl")


def test_unknown_section_keyword() -> None:
    error = domain_error(" (:bogus)")
    assert isinstance(error, UnknownKeywordError)
    assert "d.pddl:3:3" in str(error) and ":action" in str(error)


def test_unknown_action_keyword() -> None:
    error = domain_error(" (:action a :parameters () :pre (clear ?x))")
    assert isinstance(error, UnknownKeywordError)
    assert "':pre'" in str(error) and ":precondition" in str(error)


def test_unknown_requirement() -> None:
    with pytest.raises(UnknownKeywordError, match=r"d\.pddl:1:35: unsupported requirement"):
        parse_domain("(define (domain d) (:requirements :fluents))", "d.pddl")


def test_undeclared_predicate() -> None:
    error = domain_error(" (:action a :parameters (?x) :precondition (holding ?x))")
    assert isinstance(error, UndeclaredError)
    assert "d.pddl:3:45: undeclared predicate 'holding'" in str(error)


def test_undeclared_type() -> None:
    error = domain_error(" (:action a :parameters (?x - ball) :precondition (clear ?x))")
    assert isinstance(error, UndeclaredError)
    assert "undeclared type 'ball'" in str(error)


def test_undeclared_constant() -> None:
    error = domain_error(" (:action a :parameters (?x) :precondition (clear table))")
    assert isinstance(error, UndeclaredError)
    assert "undeclared constant or object 'table'" in str(error)


def test_wrong_arity() -> None:
    error = domain_error(" (:action a :parameters (?x) :precondition (on ?x))")
    assert isinstance(error, ArityError)
    assert "'on' takes 2 argument(s), got 1" in str(error)


def test_unbound_variable() -> None:
    error = domain_error(" (:action a :parameters (?x) :effect (clear ?y))")
    assert isinstance(error, UnboundVariableError)
    assert "d.pddl:3:45: variable ?y is not bound" in str(error)


def test_quantifier_binds_only_inside() -> None:
    # outside its quantifier ?z is free: an error in an effect (in a precondition it is a
    # noted leniency, see tests/language/test_leniency.py)
    error = domain_error(
        " (:action a :parameters () :precondition (exists (?z) (clear ?z)) :effect (clear ?z))"
    )
    assert isinstance(error, UnboundVariableError)


def test_duplicate_parameter() -> None:
    error = domain_error(" (:action a :parameters (?x ?x) :effect (clear ?x))")
    assert isinstance(error, DuplicateError)
    assert "'?x' appears twice" in str(error)


def test_duplicate_action() -> None:
    error = domain_error(" (:action a :effect (and)) (:action A :effect (and))")
    assert isinstance(error, DuplicateError)


def test_effect_on_derived_predicate() -> None:
    text = (
        BASE
        + PREDS.replace("(clear ?x))", "(clear ?x) (d ?x))")
        + (" (:derived (d ?x) (clear ?x)) (:action a :parameters (?x) :effect (d ?x)))")
    )
    with pytest.raises(PddlSyntaxError, match="cannot appear in an effect"):
        parse_domain(text, "d.pddl")


def test_derived_predicate_must_be_declared() -> None:
    error = domain_error(" (:derived (above ?x) (clear ?x))")
    assert isinstance(error, UndeclaredError)


def test_unsupported_numeric_effect() -> None:
    error = domain_error(" (:action a :effect (decrease (total-cost) 1))")
    assert isinstance(error, UnsupportedFeatureError)


def test_negative_action_cost() -> None:
    error = domain_error(" (:action a :effect (increase (total-cost) -1))")
    assert isinstance(error, PddlSyntaxError)
    assert "non-negative" in str(error)


def test_either_type_is_refused_in_action_parameters() -> None:
    error = domain_error(" (:action a :parameters (?x - (either block)) :effect (clear ?x))")
    assert isinstance(error, UnsupportedFeatureError)
    assert "d.pddl:3:31" in str(error) and "not in the parameters of action 'a'" in str(error)


def test_either_type_with_an_undeclared_member() -> None:
    text = BASE + " (:predicates (on ?x - (either block ghost)))\n)"
    with pytest.raises(UndeclaredError, match=r"d\.pddl:2:38: undeclared type 'ghost'"):
        parse_domain(text, "d.pddl")


def test_either_type_without_members() -> None:
    text = BASE + " (:predicates (on ?x - (either)))\n)"
    with pytest.raises(PddlSyntaxError, match=r"d\.pddl:2:24: expected a type name or"):
        parse_domain(text, "d.pddl")


def test_type_declared_under_two_parents() -> None:
    text = "(define (domain d) (:types a b - object c - a\n c - b))"
    with pytest.raises(DuplicateError, match=r"d\.pddl:2:2: type 'c' is declared twice, as a "
                       "subtype of 'a' and of 'b'"):  # fmt: skip
        parse_domain(text, "d.pddl")


def test_problem_for_another_domain() -> None:
    domain = parse_domain(BASE + PREDS + ")")
    with pytest.raises(PddlSyntaxError, match="problem is for domain 'e'"):
        parse_problem("(define (problem p) (:domain e))", domain, "p.pddl")


def test_problem_undeclared_object() -> None:
    domain = parse_domain(BASE + PREDS + ")")
    text = "(define (problem p) (:domain d) (:objects a - block)\n (:init (clear b)))"
    with pytest.raises(UndeclaredError, match=r"p\.pddl:2:16: undeclared constant or object 'b'"):
        parse_problem(text, domain, "p.pddl")


def test_problem_duplicate_object() -> None:
    domain = parse_domain(BASE + PREDS + ")")
    with pytest.raises(DuplicateError):
        parse_problem("(define (problem p) (:domain d) (:objects a a - block))", domain)


def test_problem_unsupported_metric() -> None:
    domain = parse_domain(BASE + PREDS + ")")
    with pytest.raises(UnknownKeywordError, match="unsupported metric"):
        parse_problem("(define (problem p) (:domain d) (:metric maximize (total-cost)))", domain)


# --- stream files ---------------------------------------------------------------------------

DOMAIN = parse_domain(BASE + PREDS + ")", "d.pddl")


def stream_error(body: str) -> SdarError:
    with pytest.raises(SdarError) as info:
        parse_stream_file("(define (stream s)\n" + body + ")", DOMAIN, "s.pddl")
    return info.value


def test_stream_domain_uses_non_input() -> None:
    error = stream_error(
        " (:stream f :inputs (?x) :domain (on ?x ?y) :outputs (?y) :certified (on ?x ?y))"
    )
    assert isinstance(error, StreamDefinitionError)
    assert "s.pddl:2:41: ?y in stream 'f' must be an input" in str(error)


def test_stream_certified_uses_unknown_parameter() -> None:
    error = stream_error(
        " (:stream f :inputs (?x) :domain (clear ?x) :outputs (?y) :certified (on ?x ?z))"
    )
    assert isinstance(error, StreamDefinitionError)
    assert "must be an input or an output" in str(error)


def test_stream_duplicate_parameter() -> None:
    error = stream_error(
        " (:stream f :inputs (?x) :domain (clear ?x) :outputs (?x) :certified (clear ?x))"
    )
    assert isinstance(error, DuplicateError)


def test_stream_domain_must_be_a_conjunction_of_atoms() -> None:
    error = stream_error(" (:stream f :inputs (?x) :domain (not (clear ?x)))")
    assert isinstance(error, PddlSyntaxError)
    assert "conjunction of atoms" in str(error)


def test_stream_unknown_option() -> None:
    error = stream_error(" (:stream f :input (?x))")
    assert isinstance(error, UnknownKeywordError)


def test_stream_unknown_section() -> None:
    error = stream_error(" (:generator f)")
    assert isinstance(error, UnknownKeywordError)


def test_optimizer_is_refused_with_a_clear_message() -> None:
    error = stream_error(" (:optimizer motion)")
    assert isinstance(error, UnsupportedFeatureError)
    assert "not supported" in str(error)


def test_stream_undeclared_fluent_predicate() -> None:
    error = stream_error(
        " (:stream f :inputs (?x) :domain (clear ?x) :fluents (pose) :outputs (?y))"
    )
    assert isinstance(error, UndeclaredError)


def test_stream_inconsistent_arity_of_stream_only_predicate() -> None:
    error = stream_error(
        " (:stream f :inputs (?x) :domain (clear ?x) :outputs (?p) :certified (Pose ?x ?p))\n"
        " (:stream g :inputs (?x) :domain (clear ?x) :outputs (?p) :certified (Pose ?x))"
    )
    assert isinstance(error, ArityError)


def test_stream_duplicate_name() -> None:
    error = stream_error(
        " (:stream f :inputs (?x) :domain (clear ?x)) (:stream F :inputs (?x) :domain (clear ?x))"
    )
    assert isinstance(error, DuplicateError)


def test_stream_undeclared_fluent() -> None:
    error = stream_error(" (:stream f :inputs (?x) :domain (clear ?x) :fluents (atpose))")
    assert isinstance(error, UndeclaredError)


def test_cyclic_type_hierarchy() -> None:
    with pytest.raises(PddlSyntaxError, match="its own ancestor"):
        parse_domain("(define (domain d) (:types a - b b - a))", "d.pddl")


def test_stream_input_missing_from_domain() -> None:
    error = stream_error(" (:stream f :inputs (?x ?y) :domain (clear ?x) :outputs (?z))")
    assert isinstance(error, StreamDefinitionError)
    assert "input ?y of stream 'f' must appear in its :domain" in str(error)


def test_function_input_missing_from_domain() -> None:
    error = stream_error(" (:function (dist ?x ?y) (clear ?x))")
    assert isinstance(error, StreamDefinitionError)
