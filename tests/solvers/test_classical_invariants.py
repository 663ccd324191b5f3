"""Mutex groups by invariant synthesis, and the reasonable landmark orderings they give."""

from __future__ import annotations

import random

from classical_helpers import load, load_text

from sdar_tamp.language import parse_domain, parse_problem
from sdar_tamp.language.formula_model import Atom
from solvers.classical import ground, plan, task_from_problem
from solvers.classical.bitset_task import CompiledTask, bits
from solvers.classical.invariants import MutexGroups, mutex_groups
from solvers.classical.landmarks import LandmarkCount
from solvers.classical.task import GroundTask


def _ground(domain: str, problem: str) -> GroundTask:
    parsed = parse_domain(domain)
    return ground(task_from_problem(parsed, parse_problem(problem, parsed)))


def _named(task: GroundTask, groups: MutexGroups) -> set[frozenset[str]]:
    return {frozenset(str(task.facts[f]) for f in group) for group in groups.groups}


def _fact(task: GroundTask, text: str) -> int:
    name, *args = text.strip("()").split()
    return task.facts.index(Atom(name, tuple(args)))


def test_blocksworld_groups_are_the_hand_each_block_and_what_is_on_each_block() -> None:
    task = ground(load("blocksworld", "sussman"))
    groups = mutex_groups(task)
    named = _named(task, groups)
    assert frozenset({"(hand-empty)", "(holding a)", "(holding b)", "(holding c)"}) in named
    # where block a is: refined from {(on a *)} by pick-up (adds holding, deletes on-table)
    where_a = {g for g in named if "(on-table a)" in g and "(holding a)" in g}
    assert where_a and all("(on a b)" in g and "(on a c)" in g for g in where_a)
    # what is on block b: clear, something on it, or in the hand
    assert any({"(clear b)", "(on a b)", "(on c b)", "(holding b)"} <= g for g in named)
    assert any(len(invariant) > 1 for invariant in groups.invariants)


def test_mutex_query() -> None:
    task = ground(load("blocksworld", "sussman"))
    groups = mutex_groups(task)
    empty, holding_a, holding_b = (
        _fact(task, t) for t in ("(hand-empty)", "(holding a)", "(holding b)")
    )
    clear_c = _fact(task, "(clear c)")
    assert groups.mutex(empty, holding_a) and groups.mutex(holding_a, holding_b)
    assert not groups.mutex(holding_a, holding_a)
    assert not groups.mutex(empty, clear_c)
    assert groups.of(empty) and all(empty in groups.groups[g] for g in groups.of(empty))


def _walk_states(task: GroundTask, steps: int, seed: int) -> list[int]:
    compiled = CompiledTask(task)
    rng = random.Random(seed)
    state, seen = compiled.init, [compiled.init]
    for _ in range(steps):
        options = compiled.applicable(state)
        if not options:
            break
        state = compiled.successor(state, rng.choice(options))
        seen.append(state)
    return seen


def test_no_reachable_state_holds_two_facts_of_a_group() -> None:
    for domain, problem in (
        ("blocksworld", "reverse4"),
        ("blocksworld", "sussman"),
        ("logistics", "three-cities"),
        ("briefcase", "office"),
    ):
        try:
            task = ground(load(domain, problem))
        except FileNotFoundError:
            continue
        groups = mutex_groups(task)
        assert groups.groups, (domain, problem)
        masks = [sum(1 << f for f in g) for g in groups.groups]
        for seed in range(5):
            for state in _walk_states(task, 60, seed):
                assert all((state & m).bit_count() <= 1 for m in masks), (domain, problem)


def test_an_initial_state_with_two_facts_of_a_group_rejects_it() -> None:
    task = ground(
        load_text(
            "blocksworld",
            "(define (problem p) (:domain blocksworld) (:objects a b)"
            " (:init (on-table a) (holding b) (clear a) (hand-empty)) (:goal (on a b)))",
        )
    )
    named = _named(task, mutex_groups(task))
    assert not any({"(hand-empty)", "(holding b)"} <= g for g in named)


SPLIT = """
(define (domain split)
  (:predicates (p ?x) (q ?x) (flag))
  (:action split :parameters (?x ?y)
    :precondition (and (p ?x) (q ?y))
    :effect (and (not (p ?x)) (p ?y) (q ?x)))
  (:action fork :parameters (?x ?y ?z)
    :precondition (and (p ?x) (flag))
    :effect (and (not (p ?x)) (p ?y) (p ?z)))
  (:action when :parameters (?x)
    :precondition (q ?x)
    :effect (when (flag) (q ?x))))
"""


def test_two_new_facts_at_once_or_a_conditional_add_reject_a_candidate() -> None:
    task = _ground(
        SPLIT,
        "(define (problem s) (:domain split) (:objects a b c)"
        " (:init (p a) (q b) (q c) (flag)) (:goal (p c)))",
    )
    named = _named(task, mutex_groups(task))
    # split moves p from x to y: one p at a time would hold, but fork adds two at once
    assert not any({"(p a)", "(p b)"} <= g for g in named)
    # q is added under a condition: never a group
    assert not any("(q a)" in g or "(q b)" in g for g in named)


def test_the_synthesis_is_bounded_by_a_count_not_a_clock() -> None:
    task = ground(load("blocksworld", "reverse4"))
    assert mutex_groups(task, max_checks=0).groups == ()
    first, again = mutex_groups(task), mutex_groups(task)
    assert first.groups == again.groups and first.invariants == again.invariants


def test_reasonable_order_tower_bottom_before_top() -> None:
    compiled = CompiledTask(ground(load("blocksworld", "sussman")))
    task = compiled.task
    on_a_b, on_b_c = _fact(task, "(on a b)"), _fact(task, "(on b c)")
    plain = LandmarkCount(compiled, mutexes=False)
    assert not plain.parents[on_a_b] >> on_b_c & 1 and plain.reasonable == 0
    ordered = LandmarkCount(compiled)
    # stacking b on c needs b in the hand, which (on a b) excludes: (on b c) comes first
    assert ordered.parents[on_a_b] >> on_b_c & 1 and ordered.reasonable >= 1
    assert not ordered.parents[on_b_c] >> on_a_b & 1
    # (on a b) reached first is not accepted, so it still counts
    path = [compiled.init]
    for name in ("unstack c a", "put-down c", "pick-up a", "stack a b"):
        op = next(
            i
            for i, o in enumerate(task.operators)
            if o.name == name.split()[0] and o.args == tuple(name.split()[1:])
        )
        path.append(compiled.successor(path[-1], op))
    assert path[-1] >> on_a_b & 1
    for landmarks in (plain, ordered):
        reached = landmarks.initial(path[0])
        for state in path[1:]:
            reached = landmarks.update(reached, state)
        assert (reached >> on_a_b & 1) == (landmarks is plain)
    assert ordered.value(reached, path[-1]) > plain.value(_along(plain, path), path[-1])


def _along(landmarks: LandmarkCount, path: list[int]) -> int:
    reached = landmarks.initial(path[0])
    for state in path[1:]:
        reached = landmarks.update(reached, state)
    return reached


def test_reasonable_orders_make_no_cycle_and_plans_stay_valid() -> None:
    for domain, problem in (("blocksworld", "reverse4"), ("logistics", "three-cities")):
        compiled = CompiledTask(ground(load(domain, problem)))
        landmarks = LandmarkCount(compiled)
        for fact in bits(landmarks.landmarks):
            assert not landmarks._ancestors(fact) >> fact & 1
        result = plan(compiled.task.source, search="lazy-gbfs", heuristic="ff-lmcount")
        assert result.plan is not None
