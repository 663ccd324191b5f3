"""What the field accepts beyond standard PDDL (noted leniencies), and what stays an error."""

from __future__ import annotations

import logging

import pytest

from sdar_tamp.language import (
    ArityError,
    DuplicateError,
    PddlSyntaxError,
    ProblemDefinitionError,
    StrictModeError,
    UndeclaredError,
    parse_domain,
    parse_problem,
    parse_stream_file,
)
from sdar_tamp.language.errors import UnboundVariableError
from sdar_tamp.language.formula_model import And, Atom, Exists, IncreaseCost
from sdar_tamp.language.leniency import (
    DUPLICATE_PREDICATE,
    DUPLICATE_TYPE,
    FREE_VARIABLE,
    FUNCTION_ARITY,
    GLUED_VARIABLE,
    IMPLICIT_PREDICATE,
    INIT_TYPE,
    REPEATED_VARIABLE,
    UNDECLARED_PARENT_TYPE,
)
from sdar_tamp.language.problem import PDDLProblem
from sdar_tamp.language.sexpr import Symbol, read_sexpr
from sdar_tamp.language.traversal import iter_effects

TYPED = """(define (domain t) (:requirements :strips :typing :action-costs)
 (:types block table)
 (:predicates (on ?x - block ?y - block) (clear ?x - block))
 (:functions (total-cost) - number)
 (:action a :parameters (?x - block) :precondition (clear ?x)
  :effect (and (not (clear ?x)) (increase (total-cost) 1))))
"""
OBJECTS = "(:objects b1 b2 - block t1 - table)"


def problem(body: str, domain_text: str = TYPED, strict: bool = False):  # type: ignore[no-untyped-def]
    domain = parse_domain(domain_text, "d.pddl")
    return parse_problem(
        f"(define (problem p) (:domain t)\n{body})", domain, "p.pddl", strict=strict
    )


# --- A: wrong PDDL that used to be accepted -----------------------------------------------------


def test_problem_without_goal_is_an_error() -> None:
    with pytest.raises(PddlSyntaxError, match=r"p\.pddl:1:1: expected a '\(:goal \.\.\.\)'"):
        problem(f"{OBJECTS} (:init (clear b1))")


def test_two_goal_sections_are_an_error() -> None:
    with pytest.raises(
        DuplicateError, match=r"p\.pddl:2:64: section :goal appears twice \(first at p\.pddl:2:45\)"
    ):
        problem(f"{OBJECTS} (:init) (:goal (clear b1)) (:goal (clear b2))")


@pytest.mark.parametrize("cost", ["nan", "inf", "-inf", "1e309", "infinity", "1_0", "0x1"])
def test_action_cost_must_be_a_finite_number(cost: str) -> None:
    with pytest.raises(PddlSyntaxError, match=rf"d\.pddl:6:56: expected a finite number.*{cost}"):
        parse_domain(TYPED.replace("(total-cost) 1)", f"(total-cost) {cost})"), "d.pddl")


@pytest.mark.parametrize("value", ["nan", "inf", "1e309", "NaN"])
def test_numeric_init_value_must_be_finite(value: str) -> None:
    with pytest.raises(PddlSyntaxError, match=r"p\.pddl:2:60: expected a finite number"):
        problem(f"{OBJECTS} (:init (= (total-cost) {value})) (:goal (clear b1))")


def test_ordinary_numbers_still_parse() -> None:
    domain = parse_domain(TYPED.replace("(total-cost) 1)", "(total-cost) 2.5e1)"), "d.pddl")
    costs = [e for e in iter_effects(domain.actions[0].effect) if isinstance(e, IncreaseCost)]
    assert costs == [IncreaseCost(25.0)]
    parsed = problem(f"{OBJECTS} (:init (= (total-cost) .0)) (:goal (clear b1))")
    assert parsed.numeric_init == {("total-cost", ()): 0.0}


def test_negative_initial_total_cost_is_an_error() -> None:
    with pytest.raises(PddlSyntaxError, match=r"p\.pddl:2:60: expected a non-negative initial"):
        problem(f"{OBJECTS} (:init (= (total-cost) -5)) (:goal (clear b1))")


def test_init_fact_with_a_wrongly_typed_object_is_a_located_warning(
    caplog: pytest.LogCaptureFixture,
) -> None:
    with caplog.at_level(logging.WARNING, logger="sdar_tamp.language"):
        parsed = problem(f"{OBJECTS}\n (:init (on b1 t1)) (:goal (clear b1))")
    assert [item.kind for item in parsed.leniencies] == [INIT_TYPE]
    message = "p.pddl:3:9: argument 2 of (on b1 t1) is 't1' of type 'table'"
    assert message in caplog.text
    with pytest.raises(StrictModeError, match=r"p\.pddl:3:9: argument 2"):
        problem(f"{OBJECTS}\n (:init (on b1 t1)) (:goal (clear b1))", strict=True)


def test_init_type_facts_refine_the_type_before_the_check() -> None:
    domain = TYPED.replace("(:types block table)", "(:types block table - thing thing)")
    parsed = problem("(:objects b1 b2 - block x - thing) (:init (table x)) (:goal (and))", domain)
    assert parsed.leniencies == ()
    parsed = problem("(:objects b1 b2 - block x - thing) (:init (on b1 x)) (:goal (and))", domain)
    assert [item.kind for item in parsed.leniencies] == [INIT_TYPE]


def test_undeclared_parent_type_is_a_located_warning(caplog: pytest.LogCaptureFixture) -> None:
    text = TYPED.replace("(:types block table)", "(:types block table - furniture)")
    with caplog.at_level(logging.WARNING, logger="sdar_tamp.language"):
        domain = parse_domain(text, "d.pddl")
    assert domain.types.parents["furniture"] == "object"
    assert [item.kind for item in domain.leniencies] == [UNDECLARED_PARENT_TYPE]
    assert "d.pddl:2:24: parent type 'furniture' is not declared" in caplog.text
    with pytest.raises(StrictModeError, match=r"d\.pddl:2:24"):
        parse_domain(text, "d.pddl", strict=True)


def test_problem_sections_appear_once() -> None:
    with pytest.raises(DuplicateError, match="section :init appears twice"):
        problem(f"{OBJECTS} (:init) (:init) (:goal (clear b1))")


# --- B: what the field accepts ------------------------------------------------------------------


def test_question_mark_starts_a_new_token() -> None:
    root = read_sexpr("(aircraft?a ?x?y)", "f")
    assert [(s.text, s.location.column) for s in root.items if isinstance(s, Symbol)] == [
        ("aircraft", 2),
        ("?a", 10),
        ("?x", 13),
        ("?y", 15),
    ]
    assert [str(item) for item in read_sexpr("(? ?? a)").items] == ["?", "?", "?", "a"]


def test_glued_variable_is_noted_and_rejected_when_strict() -> None:
    text = TYPED.replace("(clear ?x)\n  :effect", "(clear?x)\n  :effect")
    domain = parse_domain(text, "d.pddl")
    assert domain.actions[0].precondition == Atom("clear", ("?x",))
    (leniency,) = domain.leniencies
    assert leniency.kind == GLUED_VARIABLE and str(leniency.location) == "d.pddl:5:58"
    with pytest.raises(StrictModeError, match=r"d\.pddl:5:58: '\?x' is glued"):
        parse_domain(text, "d.pddl", strict=True)
    assert parse_domain(TYPED, "d.pddl", strict=True).leniencies == ()


def test_repeated_variable_in_a_predicate_declaration() -> None:
    text = "(define (domain u) (:predicates (in ?obj ?obj) (p ?x)))"
    domain = parse_domain(text, "u.pddl")
    assert domain.predicates["in"].arity == 2
    assert [(i.kind, str(i.location)) for i in domain.leniencies] == [
        (REPEATED_VARIABLE, "u.pddl:1:42")
    ]
    with pytest.raises(StrictModeError):
        parse_domain(text, "u.pddl", strict=True)


def test_repeated_action_parameter_is_still_an_error() -> None:
    with pytest.raises(DuplicateError, match="appears twice"):
        parse_domain("(define (domain u) (:action a :parameters (?x ?x) :effect (and)))")


STORAGE_TYPES = """(define (domain s) (:requirements :typing)
 (:types hoist surface place area - object
  container depot - place
  storearea transitarea - area
  area crate - surface)
 (:predicates (in ?x - (either storearea crate) ?p - place) (at ?h - hoist ?a - area)))
"""


def test_type_declared_twice_keeps_the_specific_parent() -> None:
    domain = parse_domain(STORAGE_TYPES, "s.pddl")
    assert domain.types.parents["area"] == "surface"
    assert domain.types.is_subtype("storearea", "surface")
    assert [(i.kind, str(i.location)) for i in domain.leniencies] == [
        (DUPLICATE_TYPE, "s.pddl:5:3")
    ]
    with pytest.raises(StrictModeError, match=r"s\.pddl:5:3: type 'area' is declared twice"):
        parse_domain(STORAGE_TYPES, "s.pddl", strict=True)
    again = parse_domain("(define (domain u) (:types a - b a - b b))", "u.pddl")
    assert again.types.parents["a"] == "b"
    assert [i.kind for i in again.leniencies] == [DUPLICATE_TYPE]


def test_either_type_in_a_predicate_declaration_reads_as_the_common_supertype() -> None:
    domain = parse_domain(STORAGE_TYPES, "s.pddl")
    assert [p.type for p in domain.predicates["in"].parameters] == ["surface", "place"]
    text = STORAGE_TYPES.replace("(either storearea crate)", "(either storearea hoist)")
    assert parse_domain(text).predicates["in"].parameters[0].type == "object"
    text = STORAGE_TYPES.replace("(either storearea crate)", "(either storearea transitarea)")
    assert parse_domain(text).predicates["in"].parameters[0].type == "area"
    parsed = parse_problem(
        "(define (problem p) (:domain s) (:objects s1 - storearea c1 - crate d - depot)"
        " (:init (in s1 d) (in c1 d)) (:goal (in c1 d)))",
        domain,
        "p.pddl",
        strict=True,
    )
    assert parsed.leniencies == ()


def test_predicate_declared_twice_with_the_same_arity() -> None:
    text = "(define (domain u) (:predicates (p ?x) (q) (P ?y)))"
    domain = parse_domain(text, "u.pddl")
    assert sorted(domain.predicates) == ["p", "q"]
    assert [(i.kind, str(i.location)) for i in domain.leniencies] == [
        (DUPLICATE_PREDICATE, "u.pddl:1:44")
    ]


def test_predicate_declared_twice_with_different_arities_is_an_error() -> None:
    with pytest.raises(DuplicateError, match=r"u\.pddl:1:40: .*different arities \(1 and 2\)"):
        parse_domain("(define (domain u) (:predicates (p ?x) (p ?x ?y)))", "u.pddl")


def test_predicate_with_the_name_of_a_type_is_still_an_error() -> None:
    with pytest.raises(DuplicateError, match="name of a type"):
        parse_domain("(define (domain u) (:requirements :typing) (:types b) (:predicates (b ?x)))")


def test_undeclared_predicate_in_init_and_goal_is_declared_by_first_use(
    caplog: pytest.LogCaptureFixture,
) -> None:
    with caplog.at_level(logging.INFO, logger="sdar_tamp.language"):
        parsed = problem(f"{OBJECTS}\n (:init (clear b1) (Heavy b1))\n (:goal (and (heavy b1)))")
    assert Atom("heavy", ("b1",)) in parsed.init
    assert [(i.kind, str(i.location)) for i in parsed.leniencies] == [
        (IMPLICIT_PREDICATE, "p.pddl:3:21")
    ]
    assert "p.pddl:3:21: predicate 'heavy' is not declared in the domain" in caplog.text
    with pytest.raises(StrictModeError, match="'heavy'"):
        problem(f"{OBJECTS} (:init (heavy b1)) (:goal (and))", strict=True)


def test_implicit_predicate_used_with_two_arities_is_an_error() -> None:
    with pytest.raises(ArityError, match=r"p\.pddl:3:28: predicate 'heavy' takes 1"):
        problem(f"{OBJECTS}\n (:init (heavy b1)) (:goal (heavy b1 b2))")


def test_undeclared_predicate_in_an_action_is_still_an_error() -> None:
    with pytest.raises(UndeclaredError, match="undeclared predicate 'heavy'"):
        parse_domain(TYPED.replace("(clear ?x)\n  :effect", "(heavy ?x)\n  :effect"))


STREAM_DOMAIN = "(define (domain s) (:predicates (clear ?x)))"


def test_stream_domain_predicate_declared_by_first_use() -> None:
    domain = parse_domain(STREAM_DOMAIN)
    text = (
        "(define (stream s)\n"
        " (:stream f :inputs (?x) :domain (and (Pose ?x) (clear ?x)) :outputs (?y)"
        " :certified (Grasp ?x ?y))\n"
        " (:stream g :inputs (?x ?y) :domain (Grasp ?x ?y) :outputs (?z) :certified (ok ?z)))"
    )
    streams = parse_stream_file(text, domain, "s.pddl")
    assert streams.streams[0].domain[0] == Atom("pose", ("?x",))
    assert [(i.kind, str(i.location)) for i in streams.leniencies] == [
        (IMPLICIT_PREDICATE, "s.pddl:2:40")
    ]
    with pytest.raises(StrictModeError, match=r"s\.pddl:2:40: predicate 'pose'"):
        parse_stream_file(text, domain, "s.pddl", strict=True)


def test_stream_domain_predicate_with_two_arities_is_an_error() -> None:
    text = (
        "(define (stream s)\n"
        " (:stream f :inputs (?x) :domain (pose ?x) :outputs (?y) :certified (clear ?y))\n"
        " (:stream g :inputs (?x) :domain (pose ?x ?x) :outputs (?y) :certified (clear ?y)))"
    )
    with pytest.raises(ArityError, match=r"s\.pddl:3:34: predicate 'pose' takes 1"):
        parse_stream_file(text, parse_domain(STREAM_DOMAIN), "s.pddl")


# --- PDDLProblem (init and goal over Python values) ---------------------------------------------


def _pddl_problem(init: list[tuple[object, ...]], goal: object = ("clear", "a")) -> PDDLProblem:
    return PDDLProblem(TYPED, {}, None, {}, init, goal)


def test_pddl_problem_declares_an_undeclared_init_predicate() -> None:
    made = _pddl_problem([("clear", "a"), ("Robot", "r")], ("robot", "r"))
    assert Atom("robot", (made.objects.name("r"),)) in made.facts.init
    assert [i.kind for i in made.leniencies] == [IMPLICIT_PREDICATE]
    with pytest.raises(ArityError, match="'robot' takes 1"):
        _pddl_problem([("robot", "r"), ("robot", "r", "s")])


@pytest.mark.parametrize("value", [float("nan"), float("inf"), "1e309"])
def test_pddl_problem_numeric_value_must_be_finite(value: object) -> None:
    with pytest.raises(ProblemDefinitionError, match=r"init\[0\].*finite number"):
        _pddl_problem([("=", ("total-cost",), value)])


def test_pddl_problem_negative_initial_total_cost() -> None:
    with pytest.raises(ProblemDefinitionError, match="non-negative initial total-cost"):
        _pddl_problem([("=", ("total-cost",), -1)])


# --- free variables in preconditions and derived bodies -----------------------------------------

FREE = """(define (domain f) (:requirements :strips :derived-predicates)
 (:predicates (on ?x ?y) (clear ?x) (covered ?x) (p ?x))
 (:derived (covered ?x) (and (clear ?x) (on ?y ?x)))
 (:action a :parameters (?x) :precondition (and (clear ?x) (on ?x ?z) (p ?z))
  :effect (not (clear ?x))))
"""


def test_free_variable_in_a_derived_body_is_existential(caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.INFO, logger="sdar_tamp.language"):
        domain = parse_domain(FREE, "f.pddl")
    (axiom,) = domain.axioms
    assert isinstance(axiom.body, Exists)
    assert [p.name for p in axiom.body.parameters] == ["?y"]
    assert isinstance(axiom.body.body, And)
    (action,) = domain.actions
    assert isinstance(action.precondition, Exists)
    assert [p.name for p in action.precondition.parameters] == ["?z"]
    kinds = [item.kind for item in domain.leniencies]
    assert kinds == [FREE_VARIABLE, FREE_VARIABLE]
    assert "f.pddl:3:45: variable ?y in the body of derived predicate 'covered'" in caplog.text
    assert any(r.levelno == logging.INFO for r in caplog.records)


def test_free_variable_is_rejected_when_strict() -> None:
    with pytest.raises(StrictModeError) as info:
        parse_domain(FREE, "f.pddl", strict=True)
    text = str(info.value)
    assert "f.pddl:3:45: variable ?y" in text
    assert "f.pddl:4:67: variable ?z in the precondition of action 'a'" in text
    assert "[free-variable]" in text


def test_free_variable_in_an_effect_is_still_an_error() -> None:
    text = FREE.replace(":effect (not (clear ?x))", ":effect (not (clear ?w))")
    with pytest.raises(UnboundVariableError, match=r"f\.pddl:5:23: variable \?w is not bound"):
        parse_domain(text, "f.pddl")


# --- the PDDLStream projects' (:functions (Cost)) used as (Cost ?a ?b) --------------------------

COST_DOMAIN = """(define (domain nav) (:requirements :strips :action-costs)
 (:predicates (at ?x) (road ?x ?y))
 (:functions (Cost) (total-cost))
 (:action move :parameters (?a ?b) :precondition (and (at ?a) (road ?a ?b))
  :effect (and (at ?b) (not (at ?a)) (increase (total-cost) (Cost ?a ?b)))))
"""
COST_STREAMS = """(define (stream nav)
 (:function (Cost ?a ?b) (road ?a ?b)))
"""


def test_zero_arity_function_used_with_arguments_is_a_located_warning(
    caplog: pytest.LogCaptureFixture,
) -> None:
    with caplog.at_level(logging.WARNING, logger="sdar_tamp.language"):
        domain = parse_domain(COST_DOMAIN, "nav.pddl")
    assert len(domain.functions["cost"].parameters) == 2
    (item,) = domain.leniencies
    assert item.kind == FUNCTION_ARITY and item.level == logging.WARNING
    assert str(item).startswith("nav.pddl:5:")
    assert "'cost' is declared with no arguments and used with 2" in caplog.text
    with pytest.raises(StrictModeError, match=r"nav\.pddl:5:\d+: function 'cost'.*function-arity"):
        parse_domain(COST_DOMAIN, "nav.pddl", strict=True)


def test_the_stream_file_function_gives_the_cost_and_must_match() -> None:
    init = [("at", "a"), ("road", "a", "b")]
    problem = PDDLProblem(COST_DOMAIN, {}, COST_STREAMS, {"cost": lambda a, b: 3.0}, init,
                          ("at", "b"))  # fmt: skip
    from solvers.solve import solve

    solution = solve(problem, max_time=10, verbose=False)
    assert solution.solved and solution.cost == pytest.approx(3.0)
    wrong = COST_STREAMS.replace("(Cost ?a ?b)", "(Cost ?a)")
    with pytest.raises(ArityError, match=r"function 'cost' takes 2 argument\(s\), got 1"):
        parse_stream_file(wrong, parse_domain(COST_DOMAIN, "nav.pddl"), "s.pddl")


def test_function_arity_set_by_its_first_use_binds_later_uses() -> None:
    two_uses = COST_DOMAIN.replace(
        "(increase (total-cost) (Cost ?a ?b))",
        "(increase (total-cost) (Cost ?a ?b)) (increase (total-cost) (Cost ?a))",
    )
    with pytest.raises(ArityError, match=r"function 'cost' takes 2 argument\(s\), got 1"):
        parse_domain(two_uses, "nav.pddl")
    declared = COST_DOMAIN.replace("(Cost) (total-cost)", "(Cost ?x ?y) (total-cost)")
    assert parse_domain(declared, "nav.pddl", strict=True).leniencies == ()
