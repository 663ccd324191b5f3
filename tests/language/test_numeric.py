"""Numeric fluents: reading conditions and effects, evaluation, the compilation into atoms over
the reachable values, durative actions with numeric parts, and the located errors of what is
not supported."""

from __future__ import annotations

import pytest

from sdar_tamp.language import PddlSyntaxError, UnsupportedFeatureError, parse_domain
from sdar_tamp.language.formula_model import FunctionTerm
from sdar_tamp.language.numeric import (
    Arithmetic,
    Comparison,
    NumericEffect,
    evaluate,
    holds,
)
from sdar_tamp.language.numeric_compile import compile_numeric, value_object
from sdar_tamp.language.plan_run import plan_timing

FUEL = """
(define (domain fuel)
  (:requirements :typing :numeric-fluents :action-costs)
  (:types loc rover)
  (:predicates (at ?r - rover ?l - loc) (road ?a ?b - loc) (depot ?l - loc))
  (:functions (fuel ?r - rover) (dist ?a ?b - loc) (capacity ?r - rover) (total-cost))
  (:action drive
    :parameters (?r - rover ?a ?b - loc)
    :precondition (and (at ?r ?a) (and (road ?a ?b) (>= (fuel ?r) (dist ?a ?b))))
    :effect (and (not (at ?r ?a)) (at ?r ?b) (decrease (fuel ?r) (dist ?a ?b))
                 (increase (total-cost) (dist ?a ?b))))
  (:action refuel
    :parameters (?r - rover ?l - loc)
    :precondition (and (at ?r ?l) (depot ?l) (< (fuel ?r) (capacity ?r)))
    :effect (and (assign (fuel ?r) (capacity ?r)) (increase (total-cost) 1))))
"""


def test_numeric_conditions_and_effects_are_read() -> None:
    domain = parse_domain(FUEL, "d.pddl")
    drive = domain.action("drive")
    fuel, dist = FunctionTerm("fuel", ("?r",)), FunctionTerm("dist", ("?a", "?b"))
    assert drive.numeric_conditions == (Comparison(">=", fuel, dist),)
    assert drive.numeric_effects == (NumericEffect("decrease", fuel, dist),)
    refuel = domain.action("refuel")
    assert refuel.numeric_effects[0].operator == "assign"
    assert domain.numeric_fluents == {"fuel"}
    assert domain.numeric
    # the propositional parts stay as they were; the plain cost stays an action cost
    assert "road" in str(drive.precondition)
    assert "IncreaseCost" in repr(drive.effect)


def test_evaluation_of_expressions_and_conditions() -> None:
    values = {FunctionTerm("f"): 6.0, FunctionTerm("g"): 2.0}
    f, g = FunctionTerm("f"), FunctionTerm("g")
    assert evaluate(Arithmetic("/", (Arithmetic("-", (f, g)), g)), values.get) == 2.0
    assert evaluate(Arithmetic("-", (g,)), values.get) == -2.0
    assert evaluate(Arithmetic("*", (f, g, 0.5)), values.get) == 6.0
    assert evaluate(Arithmetic("/", (f, 0.0)), values.get) is None  # undefined
    assert evaluate(FunctionTerm("h"), values.get) is None
    assert holds(Comparison("=", f, Arithmetic("*", (g, 3.0))), values.get)
    assert not holds(Comparison("<", f, g), values.get)
    assert not holds(Comparison(">=", FunctionTerm("h"), g), values.get)  # undefined: false
    effect = NumericEffect("scale-up", f, g)
    assert evaluate(effect.as_assignment(), values.get) == 12.0


def test_compilation_lists_the_reachable_values() -> None:
    domain = parse_domain(FUEL, "d.pddl")
    objects = {"a": "loc", "b": "loc", "r": "rover"}
    numeric = {
        ("fuel", ("r",)): 3.0,
        ("capacity", ("r",)): 4.0,
        ("dist", ("a", "b")): 2.0,
        ("dist", ("b", "a")): 2.0,
    }
    compiled = compile_numeric(domain, objects, frozenset(), numeric)
    values = {a.args[1] for a in compiled.init if a.predicate == "#=fuel"}
    assert values == {value_object(3.0)}
    # 3 -> 1 (drive), 4 (refuel), 4 -> 2 -> 0: every value in some drive row
    rows = [a for a in compiled.init if a.predicate == "#num-drive"]
    olds = {row.args[3] for row in rows}
    assert olds == {value_object(v) for v in (2.0, 3.0, 4.0)}  # fuel >= 2 to drive
    assert all(row.args[4] == value_object(float(row.args[3][2:]) - 2.0) for row in rows)
    assert compiled.original_args("drive", ("r", "a", "b", "x", "y")) == ("r", "a", "b")
    assert not compiled.domain.numeric


def test_unbounded_fluents_are_refused_with_the_action_location() -> None:
    text = FUEL.replace("(assign (fuel ?r) (capacity ?r))", "(increase (fuel ?r) 1)").replace(
        "(< (fuel ?r) (capacity ?r))", "(>= (fuel ?r) 0)"
    )
    domain = parse_domain(text, "d.pddl")
    numeric = {("fuel", ("r",)): 0.0}
    with pytest.raises(
        UnsupportedFeatureError, match=r"d.pddl:12:3: .*\(fuel r\) takes more than 50"
    ):
        compile_numeric(domain, {"a": "loc", "r": "rover"}, frozenset(), numeric, max_values=50)


DURATIVE = """
(define (domain robot)
  (:requirements :durative-actions :numeric-fluents)
  (:predicates (at ?r ?q) (motion ?a ?t ?b))
  (:functions (energy ?r) (capacity ?r) (rate ?r) (length ?t))
  (:durative-action recharge
   :parameters (?r ?q)
   :duration (= ?duration (/ (- (capacity ?r) (energy ?r)) (rate ?r)))
   :condition (and (at start (at ?r ?q)) (at start (< (energy ?r) (capacity ?r))))
   :effect (at end (increase (energy ?r) (* (rate ?r) ?duration))))
  (:durative-action move
   :parameters (?r ?a ?t ?b)
   :duration (= ?duration (length ?t))
   :condition (and (at start (at ?r ?a)) (at start (motion ?a ?t ?b))
                   (at start (<= ?duration (energy ?r))) (over all (>= (energy ?r) 0)))
   :effect (and (at start (decrease (energy ?r) ?duration)) (at start (not (at ?r ?a)))
                (at end (at ?r ?b)))))
"""


def test_durative_numeric_parts_are_said_before_the_action() -> None:
    domain = parse_domain(DURATIVE, "d.pddl")
    move = domain.action("move")
    energy = FunctionTerm("energy", ("?r",))
    length = FunctionTerm("length", ("?t",))
    # the over-all condition reads the energy after the start effect
    assert move.numeric_conditions[1].left == Arithmetic("-", (energy, length))
    assert move.numeric_effects[0] == NumericEffect(
        "assign", energy, Arithmetic("-", (energy, length))
    )
    recharge = domain.action("recharge")
    assert "?duration" not in repr(recharge.numeric_effects)  # replaced by the duration
    assert recharge.numeric_effects[-1].target.name == "total-cost"  # its cost: the duration


def test_plan_timing_follows_the_numeric_state() -> None:
    domain = parse_domain(DURATIVE, "d.pddl")
    numeric = {
        ("energy", ("r",)): 10.0,
        ("capacity", ("r",)): 10.0,
        ("rate", ("r",)): 2.0,
        ("length", ("t",)): 6.0,
    }

    def value(term: FunctionTerm) -> float:
        return numeric[(term.name, term.args)]

    plan = [("move", ("r", "a", "t", "b")), ("recharge", ("r", "b"))]
    # move: 6 s, energy 10 -> 4; recharge: (10 - 4) / 2 = 3 s
    assert plan_timing(domain, plan, value) == ((0.0, 6.0), (6.0, 3.0))


ERRORS = [
    (
        "(:action a :parameters (?x) :precondition (or (p ?x) (> (f ?x) 1)))",
        UnsupportedFeatureError,
        "numeric condition \\('>'\\) is supported only as a conjunct",
    ),
    (
        "(:action a :parameters (?x) :precondition (not (= (f ?x) 1)))",
        UnsupportedFeatureError,
        "numeric condition \\('='\\)",
    ),
    (
        "(:action a :parameters (?x) :effect (when (p ?x) (decrease (f ?x) 1)))",
        UnsupportedFeatureError,
        "numeric effect \\('decrease'\\) is supported only as a conjunct",
    ),
    (
        "(:action a :parameters (?x) :effect (forall (?y) (increase (f ?y) 1)))",
        UnsupportedFeatureError,
        "'increase'\\) on a fluent other than 'total-cost'",
    ),
    (
        "(:action a :parameters (?x) :effect (assign (total-cost) 1))",
        UnsupportedFeatureError,
        "action costs may only be increased",
    ),
    (
        "(:action a :parameters (?x) :effect (increase (f ?x) ?x))",
        UnsupportedFeatureError,
        "variable \\?x is an object, not a number",
    ),
    (
        "(:action a :parameters (?x) :effect (increase (f ?x) ?duration))",
        PddlSyntaxError,
        "only defined in a durative action",
    ),
    (
        "(:action a :parameters (?x) :precondition (>= (f ?x)))",
        PddlSyntaxError,
        "takes two expressions",
    ),
    ("(:action a :parameters (?x) :effect (increase (f ?x) (+ 1)))", PddlSyntaxError, "operands"),
    (
        "(:derived (q ?x) (and (p ?x) (> (f ?x) 0)))",
        UnsupportedFeatureError,
        "numeric condition",
    ),
]


@pytest.mark.parametrize(("section", "error", "message"), ERRORS)
def test_unsupported_and_malformed_numeric_parts_are_located(
    section: str, error: type[Exception], message: str
) -> None:
    text = (
        "(define (domain d) (:requirements :numeric-fluents :derived-predicates)\n"
        "(:predicates (p ?x) (q ?x)) (:functions (f ?x))\n" + section + ")"
    )
    with pytest.raises(error, match=f"d.pddl:\\d+:\\d+: .*{message}"):
        parse_domain(text, "d.pddl")


def test_numeric_goals_are_refused_located() -> None:
    from sdar_tamp.language import parse_problem

    domain = parse_domain(FUEL, "d.pddl")
    problem = "(define (problem p) (:domain fuel) (:objects r - rover)\n(:goal (> (fuel r) 1)))"
    with pytest.raises(UnsupportedFeatureError, match=r"p.pddl:2:8: .*numeric condition"):
        parse_problem(problem, domain, "p.pddl")


def test_a_plan_run_checks_numeric_conditions_and_follows_the_values() -> None:
    from sdar_tamp.language.formula_model import Atom
    from sdar_tamp.language.plan_run import run_plan
    from sdar_tamp.language.state_index import TypedObjects

    domain = parse_domain(FUEL, "d.pddl")
    objects = TypedObjects(domain, {"a": "loc", "b": "loc", "c": "loc", "r": "rover"})
    init = {Atom("at", ("r", "a")), Atom("depot", ("b",))}
    init |= {Atom("road", pair) for pair in (("a", "b"), ("b", "c"))}
    values = {
        ("fuel", ("r",)): 3.0,
        ("capacity", ("r",)): 4.0,
        ("dist", ("a", "b")): 2.0,
        ("dist", ("b", "c")): 3.0,
    }

    def value(term: FunctionTerm) -> float:
        return values[(term.name, term.args)]

    goal = Atom("at", ("r", "c"))
    short = [("drive", ("r", "a", "b")), ("drive", ("r", "b", "c"))]
    run = run_plan(domain, objects, init, short, goal, value)
    assert run.failed_step == 1
    assert "numeric condition '>=' at d.pddl:9" in run.reason
    refuel = [short[0], ("refuel", ("r", "b")), short[1]]
    run = run_plan(domain, objects, init, refuel, goal, value)
    assert run.valid
    assert run.cost == 2.0 + 1.0 + 3.0
    # without the values, numeric conditions are not checked
    assert run_plan(domain, objects, init, short, goal).valid
