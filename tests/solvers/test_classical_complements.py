"""Complements of derived facts: negated derived conditions in the delete relaxation."""

from __future__ import annotations

import random

import pytest

from sdar_tamp.language import parse_domain, parse_problem
from solvers.classical import bitset_task as compiled_module
from solvers.classical import ground, plan, task_from_problem
from solvers.classical.bitset_task import CompiledTask
from solvers.classical.complements import complements
from solvers.classical.heuristics import RelaxedHeuristic
from solvers.classical.landmarks import LandmarkCount
from solvers.classical.task import GroundTask

# finish ?w needs no loose part of ?w: (not (exists ...)) becomes a negated derived fact
KIT = """(define (domain kit) (:requirements :adl :derived-predicates)
 (:predicates (part ?p ?w) (fitted ?p ?w) (done ?w) (loose ?w) (spare ?p))
 (:derived (loose ?w) (exists (?p) (and (part ?p ?w) (not (fitted ?p ?w)))))
 (:action fit :parameters (?p ?w) :precondition (part ?p ?w) :effect (fitted ?p ?w))
 (:action finish :parameters (?w) :precondition (not (loose ?w))
  :effect (done ?w)))
"""
KIT_PROBLEM = """(define (problem three) (:domain kit) (:objects a b c w v)
 (:init (part a w) (part b w) (part c w) (part a v))
 (:goal (done w)))
"""


def _task(domain: str = KIT, problem: str = KIT_PROBLEM) -> GroundTask:
    parsed = parse_domain(domain)
    return ground(task_from_problem(parsed, parse_problem(problem, parsed)))


def _fact(task: GroundTask, text: str) -> int:
    return next(i for i, atom in enumerate(task.facts) if str(atom) == text)


@pytest.mark.parametrize("name", ["add", "ff", "max"])
def test_a_negated_existential_asks_for_every_part(name: str) -> None:
    task = _task()
    compiled = CompiledTask(task)
    h, _ = RelaxedHeuristic(compiled, name, compiled.costs)(compiled.init)
    assert h == {"add": 4.0, "ff": 4.0, "max": 2.0}[name]  # fit a, b, c, then finish w
    fitted = sum(1 << _fact(task, f"(fitted {p} w)") for p in "abc")
    assert RelaxedHeuristic(compiled, name, compiled.costs)(compiled.init | fitted)[0] == 1.0


def test_landmarks_see_through_the_complement() -> None:
    task = _task()
    landmarks = LandmarkCount(CompiledTask(task))
    found = {str(task.facts[i]) for i in range(len(task.facts)) if landmarks.landmarks >> i & 1}
    assert {"(fitted a w)", "(fitted b w)", "(fitted c w)", "(done w)"} <= found
    # the complement of (loose w) is one too, reached once the parts are fitted
    comp = complements(task)
    assert landmarks.landmarks >> comp.of[_fact(task, "(loose w)")] & 1
    compiled = CompiledTask(task)
    start = landmarks.initial(compiled.init)
    assert landmarks.value(start, compiled.init) == 6  # the parts, the two complements, done
    fitted = compiled.close(compiled.init | sum(1 << _fact(task, f"(fitted {p} w)") for p in "abc"))
    # LAMA's rule: a landmark is accepted once its predecessors were, in an earlier state
    reached = landmarks.update(start, fitted)
    assert landmarks.value(reached, fitted) == 3  # the complements wait for the parts
    assert landmarks.value(landmarks.update(reached, fitted), fitted) == 2  # ~(~aux0 w) first
    reached = landmarks.update(landmarks.update(reached, fitted), fitted)
    assert landmarks.value(reached, fitted) == 1  # only (done w) left


QUBITS = """(define (domain q) (:requirements :strips :negative-preconditions)
 (:predicates (pending ?g) (free ?q) (after ?g ?h))
 (:action apply :parameters (?g ?q) :precondition (and (pending ?g) (free ?q))
  :effect (and (not (pending ?g)) (not (free ?q)))))
"""


def test_negative_goals_on_fluents_count() -> None:
    # only negative goals: without complements every state looks like a goal to h_FF
    problem = """(define (problem p) (:domain q) (:objects g1 g2 g3 q1 q2 q3)
     (:init (pending g1) (pending g2) (pending g3) (free q1) (free q2) (free q3))
     (:goal (and (not (pending g1)) (not (pending g2)) (not (pending g3)))))"""
    task = _task(QUBITS, problem)
    compiled = CompiledTask(task)
    comp = complements(task)
    assert sorted(str(task.facts[f]) for f in comp.of) == [
        "(pending g1)", "(pending g2)", "(pending g3)",
    ]  # fmt: skip
    assert comp.rules == ()  # fluent complements come from the deleting effects
    assert RelaxedHeuristic(compiled, "ff", compiled.costs)(compiled.init)[0] == 3.0
    landmarks = LandmarkCount(compiled)
    assert len(landmarks) == 6  # the three goals, and the pending facts they need deleted
    assert landmarks.value(landmarks.initial(compiled.init), compiled.init) == 3
    parsed = parse_domain(QUBITS)
    result = plan(task_from_problem(parsed, parse_problem(problem, parsed)))
    assert result.plan is not None and len(result.plan) == 3


def test_an_effect_that_deletes_and_adds_a_fact_achieves_no_complement() -> None:
    domain = QUBITS.replace(
        "(not (pending ?g)) (not (free ?q))", "(not (pending ?g)) (pending ?g) (not (free ?q))"
    )
    problem = """(define (problem p) (:domain q) (:objects g1 q1)
     (:init (pending g1) (free q1)) (:goal (not (pending g1))))"""
    task = _task(domain, problem)
    compiled = CompiledTask(task)
    assert RelaxedHeuristic(compiled, "ff", compiled.costs)(compiled.init)[0] == float("inf")


def test_the_plan_is_found_and_fits_every_part() -> None:
    parsed = parse_domain(KIT)
    result = plan(task_from_problem(parsed, parse_problem(KIT_PROBLEM, parsed)))
    assert result.plan is not None
    assert sorted(str(s) for s in result.plan) == [
        "(finish w)", "(fit a w)", "(fit b w)", "(fit c w)",
    ]  # fmt: skip


def test_extend_adds_the_complements_of_false_derived_facts() -> None:
    task = _task()
    comp = complements(task)
    loose_w, loose_v = _fact(task, "(loose w)"), _fact(task, "(loose v)")
    some_w = _fact(task, "(~aux0 w)")  # the existential loose w is defined by
    fitted = {_fact(task, f"(fitted {p} {w})") for p, w in ("aw", "bw", "cw", "av")}
    # the derived facts, and the fluents negated in the existential's rules
    assert set(comp.of) == {loose_w, loose_v, some_w, _fact(task, "(~aux0 v)")} | fitted
    assert comp.count == len(task.facts) + 8
    everything = sum(1 << c for c in comp.of.values())
    assert comp.extend(0) == everything
    state = 1 << loose_w | 1 << some_w
    held = 1 << comp.of[loose_w] | 1 << comp.of[some_w]
    assert comp.extend(state) == state | everything & ~held
    rules = {head: sorted(str(task.facts[f]) if f < comp.base else f for f in body)
             for body, head in comp.rules}  # fmt: skip
    assert rules[comp.of[loose_w]] == [comp.of[some_w]]
    assert rules[comp.of[some_w]] == ["(fitted a w)", "(fitted b w)", "(fitted c w)"]


def test_a_rule_with_a_positive_fluent_literal_needs_no_blocking() -> None:
    # loose ?w also holds whenever a spare part exists: not (spare ?p) is free in the relaxation
    domain = KIT.replace(
        "(:derived (loose ?w) (exists (?p) (and (part ?p ?w) (not (fitted ?p ?w)))))",
        "(:derived (loose ?w) (exists (?p) (or (and (part ?p ?w) (not (fitted ?p ?w)))"
        " (spare ?p))))",
    ).replace("(:action fit", "(:action spoil :parameters (?p) :effect (spare ?p))\n (:action fit")
    task = _task(domain)
    compiled = CompiledTask(task)
    assert RelaxedHeuristic(compiled, "ff", compiled.costs)(compiled.init)[0] == 4.0


def test_an_always_true_derived_fact_has_an_unreachable_complement() -> None:
    domain = KIT.replace(
        "(:derived (loose ?w) (exists (?p) (and (part ?p ?w) (not (fitted ?p ?w)))))",
        "(:derived (loose ?w) (and))",
    )
    task = _task(domain)
    compiled = CompiledTask(task)
    comp = complements(task)
    loose_w = _fact(task, "(loose w)")
    assert [head for _body, head in comp.rules] == []  # no rule derives ~(loose w)
    assert comp.extend(compiled.init) == compiled.init  # loose w holds in the state
    h, _ = RelaxedHeuristic(compiled, "ff", compiled.costs)(compiled.init)
    assert h == float("inf") and compiled.init >> loose_w & 1  # a real dead end


def test_too_many_rules_leave_the_negation_ignored() -> None:
    # a loose part of w is unfitted and w not done: three rules of two literals each, so the
    # complement of the existential picks one of two from each (8 choices; minimal: 2 rules)
    domain = KIT.replace(
        "(and (part ?p ?w) (not (fitted ?p ?w)))",
        "(and (part ?p ?w) (not (fitted ?p ?w)) (not (done ?w)))",
    )
    task = _task(domain)
    some_w, some_v = _fact(task, "(~aux0 w)"), _fact(task, "(~aux0 v)")
    wide = complements(task, max_rules=8)
    rules = sorted(
        sorted(str(task.facts[f]) for f in body) for body, head in wide.rules
        if head == wide.of[some_w]
    )  # fmt: skip
    assert rules == [["(done w)"], ["(fitted a w)", "(fitted b w)", "(fitted c w)"]]
    narrow = complements(task, max_rules=7)
    assert some_w not in narrow.of and some_v in narrow.of  # v's needs only 2
    compiled = CompiledTask(task)
    assert RelaxedHeuristic(compiled, "ff", compiled.costs)(compiled.init)[0] == 4.0


def test_recursive_rules_count_as_free() -> None:
    # reach is recursive: the complement of reach cannot use ~reach of its own stratum
    domain = """(define (domain g) (:requirements :adl :derived-predicates)
     (:predicates (edge ?a ?b) (open ?a ?b) (reach ?a) (start ?a) (cut ?a))
     (:derived (reach ?b) (or (start ?b) (exists (?a) (and (reach ?a) (edge ?a ?b) (open ?a ?b)))))
     (:action close :parameters (?a ?b) :precondition (open ?a ?b) :effect (not (open ?a ?b)))
     (:action isolate :parameters (?b) :precondition (not (reach ?b)) :effect (cut ?b)))"""
    problem = """(define (problem p) (:domain g) (:objects x y)
     (:init (start x) (edge x y) (open x y)) (:goal (cut y)))"""
    parsed = parse_domain(domain)
    result = plan(task_from_problem(parsed, parse_problem(problem, parsed)))
    assert result.plan is not None
    assert [str(s) for s in result.plan] == ["(close x y)", "(isolate y)"]


def test_counted_closure_equals_the_sweep(monkeypatch: pytest.MonkeyPatch) -> None:
    # reach over a ring of 10 rooms with doors that open and close: 21 rules in one stratum
    rooms = [f"r{i}" for i in range(10)]
    domain = """(define (domain ring) (:requirements :adl :derived-predicates)
     (:predicates (door ?a ?b) (open ?a ?b) (reach ?a) (start ?a) (lit ?a))
     (:derived (reach ?b) (or (start ?b) (exists (?a) (and (reach ?a) (door ?a ?b) (open ?a ?b)))))
     (:action shut :parameters (?a ?b) :precondition (open ?a ?b) :effect (not (open ?a ?b)))
     (:action unshut :parameters (?a ?b) :precondition (and (door ?a ?b) (not (open ?a ?b)))
      :effect (open ?a ?b))
     (:action light :parameters (?a) :precondition (not (reach ?a)) :effect (lit ?a)))"""
    doors = " ".join(
        f"(door {a} {b}) (open {a} {b})"
        for i, a in enumerate(rooms)
        for b in (rooms[(i + 1) % 10], rooms[(i + 3) % 10])
    )
    problem = f"""(define (problem p) (:domain ring) (:objects {" ".join(rooms)})
     (:init (start r0) {doors}) (:goal (lit r5)))"""
    task = _task(domain, problem)
    monkeypatch.setattr(compiled_module, "COUNTED_STRATUM", 16)
    compiled = CompiledTask(task)
    assert [c is not None for c in compiled.counted] == [True]  # one stratum, counted
    rng = random.Random(3)
    state, states = compiled.init, []
    for _ in range(200):
        state = compiled.successor(state, rng.choice(compiled.applicable(state)))
        states.append(state)
    counted = [compiled.close(s) for s in states]
    compiled.counted = [None]  # the sweep to a fixpoint
    assert counted == [compiled.close(s) for s in states]
    assert len({c & compiled.derived_mask for c in counted}) > 10  # the walk changes reach
