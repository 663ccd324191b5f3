"""The short path for plain atoms (large :init sections and goals) gives what the general one does.

Plain atoms are read in a few lookups each; anything else (a list argument, an unknown name, a
keyword head...) takes the general path, so the model and every located error stay the same.
"""

from __future__ import annotations

import gc
import logging

import pytest

from sdar_tamp.language import (
    ArityError,
    PddlSyntaxError,
    UnboundVariableError,
    UndeclaredError,
    parse_domain,
    parse_problem,
)
from sdar_tamp.language.domain_model import Problem
from sdar_tamp.language.formula_model import And, Atom, Exists, Not, Parameter
from sdar_tamp.language.formula_reader import MAX_FORMULA_DEPTH, FormulaReader, Vocabulary
from sdar_tamp.language.leniency import IMPLICIT_PREDICATE, INIT_TYPE
from sdar_tamp.language.sexpr import read_sexpr

DOMAIN = parse_domain(
    """(define (domain d) (:requirements :strips :typing :derived-predicates)
  (:types block table)
  (:predicates (on ?x - block ?y - block) (clear ?x - block) (free) (above ?x ?y))
  (:derived (above ?x ?y) (on ?x ?y)))""",
    "d.pddl",
)
OBJECTS = "(:objects a b c - block t - table)"


def problem(body: str) -> Problem:
    return parse_problem(f"(define (problem p) (:domain d)\n{body})", DOMAIN, "p.pddl")


def test_mixed_init_and_goal_give_the_same_model() -> None:
    parsed = parse_problem(
        f"""(define (problem p) (:domain d) {OBJECTS}
  (:init (on a b) (clear a) (free) (= a a) (block t) (mark a) (mark b))
  (:goal (and (on a b) (not (clear b)) (mark c) (exists (?x - block) (and (on ?x c) (free))))))""",
        DOMAIN,
        "p.pddl",
    )
    assert parsed.init == (
        Atom("on", ("a", "b")),
        Atom("clear", ("a",)),
        Atom("free"),
        Atom("=", ("a", "a")),
        Atom("block", ("t",)),
        Atom("mark", ("a",)),
        Atom("mark", ("b",)),
    )
    assert parsed.goal == And(
        (
            Atom("on", ("a", "b")),
            Not(Atom("clear", ("b",))),
            Atom("mark", ("c",)),
            Exists((Parameter("?x", "block"),), And((Atom("on", ("?x", "c")), Atom("free")))),
        )
    )
    assert [item.kind for item in parsed.leniencies] == [IMPLICIT_PREDICATE]  # 'mark', once


@pytest.mark.parametrize(
    ("init", "error", "message"),
    [
        ("(on a (b))", PddlSyntaxError, r"p\.pddl:3:34: expected a term .* found a list \(b\)"),
        ("(on a z)", UndeclaredError, r"p\.pddl:3:34: undeclared constant or object 'z'"),
        ("(on a ?x)", UnboundVariableError, r"p\.pddl:3:34: variable \?x is not bound"),
        ("(on a)", ArityError, r"p\.pddl:3:28: predicate 'on' takes 2 argument\(s\), got 1"),
        ("(above a b)", PddlSyntaxError, r"p\.pddl:3:28: derived predicate 'above' cannot be"),
        ("((on) a b)", PddlSyntaxError, r"p\.pddl:3:29: expected a predicate name, found a list"),
    ],
)
def test_init_errors_stay_located(init: str, error: type[Exception], message: str) -> None:
    # the faulty fact follows plain ones, on line 3 from column 28
    with pytest.raises(error, match=message):
        problem(f"{OBJECTS}\n (:init (clear a) (on a b) {init}) (:goal (free))")


def test_goal_errors_stay_located() -> None:
    with pytest.raises(UndeclaredError, match=r"p\.pddl:3:35: undeclared constant or object 'z'"):
        problem(f"{OBJECTS}\n (:init) (:goal (and (on a b) (on z b)))")
    with pytest.raises(ArityError, match=r"p\.pddl:3:29: predicate 'clear' takes 1"):
        problem(f"{OBJECTS}\n (:init) (:goal (and (free) (clear a b)))")


def test_conjunction_at_the_depth_limit_still_checks_its_atoms() -> None:
    # MAX_FORMULA_DEPTH conjunctions: the atom inside is one level too deep
    goal = "(and " * MAX_FORMULA_DEPTH + "(free)" + ")" * MAX_FORMULA_DEPTH
    column = 9 + len("(and ") * MAX_FORMULA_DEPTH
    with pytest.raises(PddlSyntaxError, match=rf"p\.pddl:3:{column}: formula nested deeper"):
        problem(f"{OBJECTS}\n (:goal {goal})")
    inner = "(and " * (MAX_FORMULA_DEPTH - 1) + "(free)" + ")" * (MAX_FORMULA_DEPTH - 1)
    assert problem(f"{OBJECTS}\n (:goal {inner})") is not None


def test_each_wrongly_typed_fact_is_noted_at_its_place(caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.WARNING, logger="sdar_tamp.language"):
        parsed = problem(f"{OBJECTS}\n (:init (on a t) (on b b)\n (on b t))\n (:goal (free))")
    assert [(item.kind, str(item.location)) for item in parsed.leniencies] == [
        (INIT_TYPE, "p.pddl:3:9"),
        (INIT_TYPE, "p.pddl:4:2"),
    ]
    assert (
        "argument 2 of (on b t) is 't' of type 'table', but 'on' expects a 'block'" in caplog.text
    )


def test_plain_atoms_leaves_everything_else_to_the_general_path() -> None:
    vocabulary = Vocabulary(
        {"on": 2, "free": 0, "and": 1}, frozenset({"object", "block"}), {"a": "block", "b": "block"}
    )
    reader = FormulaReader(vocabulary)
    nodes = read_sexpr(
        "((on a b) (on ?x a) (on ?y a) (free) (on a) (on a (b)) (and a) (= a b) (block a)"
        " (mark a) () sym ((on) a b))"
    ).items
    assert reader.plain_atoms(nodes, {"?x": "block"}) == [
        Atom("on", ("a", "b")),
        Atom("on", ("?x", "a")),
        None,  # ?y is not bound
        Atom("free"),
        None,  # wrong arity
        None,  # a list argument
        None,  # a formula keyword
        None,  # equality
        None,  # a type used as a predicate
        None,  # undeclared
        None,  # empty
        None,  # a symbol
        None,  # a list head
    ]


@pytest.mark.parametrize("enabled", [True, False])
def test_parsing_leaves_the_garbage_collector_as_it_was(enabled: bool) -> None:
    was = gc.isenabled()
    try:
        gc.enable() if enabled else gc.disable()
        problem(f"{OBJECTS} (:init (on a b)) (:goal (free))")
        assert gc.isenabled() is enabled
        with pytest.raises(UndeclaredError):
            problem(f"{OBJECTS} (:init (on a z)) (:goal (free))")
        assert gc.isenabled() is enabled
    finally:
        gc.enable() if was else gc.disable()
