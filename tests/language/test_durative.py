"""Durative actions (PDDL 2.1), run one after the other: the reader, its located errors, the
sequential compilation (checked against the staged run of each action as written) and the
timing of plans."""

from __future__ import annotations

import itertools
import random

import pytest

from sdar_tamp.language import (
    DuplicateError,
    PddlSyntaxError,
    UnknownKeywordError,
    UnsupportedFeatureError,
    parse_domain,
    parse_problem,
)
from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.evaluator import Evaluator
from sdar_tamp.language.formula_model import TRUE, Atom, FunctionTerm
from sdar_tamp.language.plan_run import plan_timing, run_plan
from sdar_tamp.language.state_changes import effect_changes
from sdar_tamp.language.state_index import FactIndex, TypedObjects
from sdar_tamp.language.substitution import bind
from solvers.classical import GroundAction, plan, task_from_problem, validated_plan_cost
from solvers.classical.errors import PlanValidationError

DOMAIN = """
(define (domain rover)
  (:requirements :strips :durative-actions :derived-predicates :conditional-effects)
  (:predicates (at ?r ?p) (link ?a ?b) (moving ?r) (free ?p) (busy ?r) (idle ?r)
               (seen ?p) (lit ?p))
  (:functions (dist ?a ?b))
  (:derived (idle ?r) (and (at ?r ?r) (not (busy ?r))))
  (:durative-action move
   :parameters (?r ?a ?b)
   :duration (= ?duration (dist ?a ?b))
   :condition (and (at start (at ?r ?a)) (at start (link ?a ?b))
                   (over all (moving ?r)) (at end (free ?b)))
   :effect (and (at start (not (at ?r ?a))) (at start (moving ?r)) (at start (free ?a))
                (at end (not (moving ?r))) (at end (at ?r ?b)) (at end (not (free ?b)))))
  (:durative-action wait
   :parameters (?r)
   :duration (= ?duration 2)
   :condition (and (at start (idle ?r)) (over all (busy ?r)) (at end (not (idle ?r))))
   :effect (and (at start (busy ?r)) (at end (not (busy ?r)))))
  (:durative-action look
   :parameters (?r ?p)
   :duration (= ?duration 1.5)
   :condition (at end (lit ?p))
   :effect (and (at start (forall (?q) (when (link ?p ?q) (lit ?q))))
                (at end (forall (?q) (when (lit ?q) (seen ?q))))
                (at end (not (lit ?r)))))
)
"""
PROBLEM = """
(define (problem p1) (:domain rover)
 (:objects r a b c)
 (:init (at r a) (link a b) (link b c) (free b) (free c) (= (dist a b) 3) (= (dist b c) 4))
 (:goal (at r c))
 (:metric minimize (total-time)))
"""


@pytest.fixture(scope="module")
def domain() -> Domain:
    return parse_domain(DOMAIN, "rover.pddl")


def test_the_reader_keeps_each_timed_part(domain: Domain) -> None:
    move = domain.durative_action("MOVE")
    assert move is not None and domain.temporal
    assert move.duration == FunctionTerm("dist", ("?a", "?b"))
    assert move.over_all == Atom("moving", ("?r",))
    assert move.at_end == Atom("free", ("?b",))
    assert domain.durative_action("wait") is not None
    assert domain.durative_action("nothing") is None
    assert {a.name for a in domain.actions} == {"move", "wait", "look"}  # compiled
    assert not parse_domain("(define (domain d) (:predicates (p)))").temporal


ARITIES = {"at": 2, "link": 2, "moving": 1, "free": 1, "busy": 1, "seen": 1, "lit": 1}


def _compiled_step(
    domain: Domain, objects: TypedObjects, state: frozenset[Atom], name: str, args: tuple[str, ...]
) -> frozenset[Atom] | None:
    action = domain.action(name)
    binding = bind(action, args)
    evaluator = Evaluator(domain, FactIndex(state), objects)
    if evaluator.support(action.precondition, binding) is None:
        return None
    return effect_changes(evaluator, action.effect, binding).apply(state)


def test_the_compiled_action_does_what_the_staged_run_does(domain: Domain) -> None:
    """Every grounding of every durative action, from random states: the compiled action is
    applicable exactly when the staged run is, and reaches the same state."""
    names = ("r", "a", "b")
    objects = TypedObjects(domain, {n: "object" for n in names})
    atoms = [
        Atom(p, args)
        for p, arity in ARITIES.items()
        for args in itertools.product(names, repeat=arity)
    ]
    rng = random.Random(7)
    applicable = 0
    for _ in range(150):
        state = frozenset(a for a in atoms if rng.random() < 0.35)
        for durative in domain.durative_actions:
            for args in itertools.product(names, repeat=len(durative.parameters)):
                staged = run_plan(domain, objects, state, [(durative.name, args)], TRUE)
                compiled = _compiled_step(domain, objects, state, durative.name, args)
                assert staged.valid == (compiled is not None), (durative.name, args, state)
                if compiled is not None:
                    applicable += 1
                    assert staged.final_state == compiled, (durative.name, args, state)
    assert applicable > 100  # the comparison covered applicable steps, not only failures


def test_conditions_are_checked_after_the_start_effects(domain: Domain) -> None:
    objects = TypedObjects(domain, {n: "object" for n in ("r", "a", "b")})
    state = frozenset({Atom("at", ("r", "r"))})
    # wait: idle at start; over all busy (made by its own start); at end not idle (busy)
    run = run_plan(domain, objects, state, [("wait", ("r",))], TRUE)
    assert run.valid
    assert run.final_state == state  # busy added at start, deleted at end
    # move a->b needs (free b) at its end; when a == b its own start frees it
    state = frozenset({Atom("at", ("r", "a")), Atom("link", ("a", "a"))})
    assert run_plan(domain, objects, state, [("move", ("r", "a", "a"))], TRUE).valid
    state = frozenset({Atom("at", ("r", "a")), Atom("link", ("a", "b"))})
    run = run_plan(domain, objects, state, [("move", ("r", "a", "b"))], TRUE)
    assert run.failed_step == 0 and "at-end condition" in run.reason
    assert _compiled_step(domain, objects, state, "move", ("r", "a", "b")) is None


def test_a_start_add_that_the_end_deletes_is_gone(domain: Domain) -> None:
    move = domain.action("move")
    objects = TypedObjects(domain, {n: "object" for n in ("r", "a", "b")})
    state = frozenset({Atom("at", ("r", "a")), Atom("link", ("a", "b")), Atom("free", ("b",))})
    after = _compiled_step(domain, objects, state, "move", ("r", "a", "b"))
    assert after == {Atom("at", ("r", "b")), Atom("link", ("a", "b")), Atom("free", ("a",))}
    assert move.parameters == domain.durative_actions[0].parameters


def test_the_planner_plans_and_the_cost_is_the_total_duration(domain: Domain) -> None:
    problem = parse_problem(PROBLEM, domain, "p1.pddl")
    task = task_from_problem(domain, problem)
    result = plan(task, search="astar", heuristic="ff")
    assert result.plan is not None
    steps = [(a.name, a.args) for a in result.plan]
    assert steps == [("move", ("r", "a", "b")), ("move", ("r", "b", "c"))]
    assert result.cost == 7.0
    values = problem.numeric_init
    timing = plan_timing(domain, steps, lambda t: values[(t.name, t.args)])
    assert timing == ((0.0, 3.0), (3.0, 4.0))
    assert plan_timing(domain, [("wait", ("r",))], lambda t: 0.0) == ((0.0, 2.0),)


def test_the_validator_checks_durative_plans(domain: Domain) -> None:
    task = task_from_problem(domain, parse_problem(PROBLEM, domain))
    good = (GroundAction("move", ("r", "a", "b")), GroundAction("move", ("r", "b", "c")))
    assert validated_plan_cost(task, good) == 7.0
    with pytest.raises(PlanValidationError, match="at-start condition of \\(move r b c\\)"):
        validated_plan_cost(task, good[1:])
    with pytest.raises(PlanValidationError, match="goal"):
        validated_plan_cost(task, good[:1])


def test_a_mixed_domain_times_instantaneous_actions_at_zero_length() -> None:
    ping = "(:action ping :parameters (?r) :effect (busy ?r))\n"
    text = DOMAIN.replace("(:durative-action wait", ping + "(:durative-action wait")
    mixed = parse_domain(text)
    timing = plan_timing(mixed, [("ping", ("r",)), ("wait", ("r",))], lambda t: 0.0)
    assert timing == ((0.0, 0.0), (0.0, 2.0))


def test_total_time_is_a_metric_of_temporal_domains_only() -> None:
    classical = parse_domain("(define (domain d) (:predicates (p)) (:action a :effect (p)))")
    text = "(define (problem q) (:domain d) (:init) (:goal (p)) (:metric minimize (total-time)))"
    with pytest.raises(
        UnknownKeywordError, match=r"q.pddl:1:53: .*expected 'minimize \(total-cost\)'"
    ):
        parse_problem(text, classical, "q.pddl")


def _durative(body: str) -> str:
    return (
        "(define (domain d) (:requirements :durative-actions)\n"
        "(:predicates (p ?x) (q ?x) (r ?x) (s ?x))\n(:functions (f ?x))\n"
        "(:derived (r ?x) (or (p ?x) (exists (?y) (and (q ?y) (r ?y)))))\n"
        f"(:durative-action go :parameters (?x)\n{body})\n)"
    )


ERRORS = [
    ("", PddlSyntaxError, "has no ':duration'"),
    (":duration 3", PddlSyntaxError, "'\\(= \\?duration VALUE\\)'"),
    (":duration (= ?d 3)", PddlSyntaxError, "expected '\\?duration' after '='"),
    (":duration (<= ?duration 3)", UnsupportedFeatureError, "duration inequalities \\('<='\\)"),
    (
        ":duration (and (>= ?duration 1) (<= ?duration 3))",
        UnsupportedFeatureError,
        "duration inequalities are not supported",
    ),
    (":duration (= ?duration -1)", PddlSyntaxError, "non-negative"),
    (":duration (= ?duration 1) :condition (p ?x)", PddlSyntaxError, "expected a timed part"),
    (
        ":duration (= ?duration 1) :condition (at middle (p ?x))",
        PddlSyntaxError,
        "expected a timed part",
    ),
    (
        ":duration (= ?duration 1) :effect (over all (p ?x))",
        PddlSyntaxError,
        "an effect cannot be '\\(over all ...\\)'",
    ),
    (
        ":duration (= ?duration 1) :effect (forall (?y) (at end (p ?y)))",
        UnsupportedFeatureError,
        "a 'forall' around timed parts",
    ),
    (
        ":duration (= ?duration 1) :condition (at end (p ?duration))",
        UnsupportedFeatureError,
        "'\\?duration' may only appear in ':duration', numeric conditions",
    ),
    (
        ":duration (= ?duration 1) :effect (at end (increase (f ?x) (* #t 2)))",
        UnsupportedFeatureError,
        "continuous effects \\('#t'\\) are not supported",
    ),
    (
        ":duration (= ?duration 1) :condition (at end (r ?x)) :effect (at start (q ?x))",
        UnsupportedFeatureError,
        "derived predicate 'r' is recursive",
    ),
]


@pytest.mark.parametrize(("body", "error", "message"), ERRORS)
def test_malformed_durative_actions_are_located_errors(
    body: str, error: type[Exception], message: str
) -> None:
    with pytest.raises(error, match=f"d.pddl:\\d+:\\d+: .*{message}"):
        parse_domain(_durative(body), "d.pddl")


def test_duration_cannot_be_a_parameter() -> None:
    text = _durative(":duration (= ?duration 1)").replace(
        "(?x)\n:duration", "(?duration)\n:duration"
    )
    with pytest.raises(PddlSyntaxError, match=r"d.pddl:5:1: .*'\?duration' cannot be a parameter"):
        parse_domain(text, "d.pddl")


def test_a_durative_action_and_an_action_with_one_name_are_refused() -> None:
    text = _durative(":duration (= ?duration 1)").replace(
        "(:durative-action", "(:action go :parameters (?x) :effect (p ?x))\n(:durative-action"
    )
    with pytest.raises(DuplicateError, match=r"d.pddl:6:1: action 'go' is defined twice"):
        parse_domain(text, "d.pddl")


def test_a_derived_predicate_the_start_effects_leave_alone_is_not_unfolded() -> None:
    text = _durative(
        ":duration (= ?duration 1) :condition (at end (r ?x)) :effect (at start (s ?x))"
    )
    go = parse_domain(text).action("go")
    assert go.precondition == Atom("r", ("?x",))
