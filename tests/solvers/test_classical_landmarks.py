"""Landmarks (label propagation), the landmark-count heuristic, and LAMA-style lazy search."""

from __future__ import annotations

import pytest
from classical_helpers import load

from sdar_tamp.language import parse_domain, parse_problem
from sdar_tamp.language.formula_model import Atom
from solvers.classical import PlanStatus, ground, plan, task_from_problem
from solvers.classical.bitset_task import CompiledTask, bits, mask
from solvers.classical.landmarks import LandmarkCount
from solvers.classical.task import GroundTask

VISIT = """
(define (domain visit)
  (:requirements :strips :typing)
  (:types cell)
  (:predicates (at ?c - cell) (visited ?c - cell) (next ?a ?b - cell))
  (:action move
    :parameters (?from ?to - cell)
    :precondition (and (at ?from) (next ?from ?to))
    :effect (and (at ?to) (visited ?to) (not (at ?from)))))
"""


def _visit_problem(width: int) -> str:
    cells = [f"c{x}-{y}" for x in range(width) for y in range(width)]
    links = []
    for x in range(width):
        for y in range(width):
            for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                if 0 <= x + dx < width and 0 <= y + dy < width:
                    links.append(f"(next c{x}-{y} c{x + dx}-{y + dy})")
    goal = " ".join(f"(visited {c})" for c in cells)
    return (
        f"(define (problem grid{width}) (:domain visit) (:objects {' '.join(cells)} - cell)"
        f" (:init (at c0-0) (visited c0-0) {' '.join(links)}) (:goal (and {goal})))"
    )


def _visit(width: int) -> CompiledTask:
    domain = parse_domain(VISIT)
    task = task_from_problem(domain, parse_problem(_visit_problem(width), domain))
    return CompiledTask(ground(task))


def _ids(compiled: CompiledTask, *atoms: str) -> list[int]:
    facts = compiled.task.facts
    out = []
    for text in atoms:
        name, *args = text.split()
        out.append(facts.index(Atom(name, tuple(args))))
    return out


def test_sussman_landmarks_include_the_goals_and_what_every_plan_holds() -> None:
    compiled = CompiledTask(ground(load("blocksworld", "sussman")))
    landmarks = LandmarkCount(compiled)
    holding_a, holding_b, on_a_b, on_b_c = _ids(
        compiled, "holding a", "holding b", "on a b", "on b c"
    )
    assert landmarks.landmarks & mask([holding_a, holding_b, on_a_b, on_b_c]) == mask(
        [holding_a, holding_b, on_a_b, on_b_c]
    )
    # every landmark not true initially has (holding x) or a goal among its orderings
    assert landmarks.parents[on_a_b] >> holding_a & 1
    assert landmarks.children_gn[holding_a] >> on_a_b & 1
    # the initial state's value: every landmark false initially still has to be reached
    reached = landmarks.initial(compiled.init)
    expected = (landmarks.landmarks & ~compiled.init).bit_count()
    assert landmarks.value(reached, compiled.init) == expected


def test_visit_landmark_count_is_the_number_of_unvisited_cells() -> None:
    compiled = _visit(3)
    landmarks = LandmarkCount(compiled)
    visited = [
        compiled.task.facts.index(Atom("visited", (f"c{x}-{y}",)))
        for x in range(3)
        for y in range(3)
    ]
    assert landmarks.landmarks & mask(visited) == mask(visited)
    reached = landmarks.initial(compiled.init)
    h0 = landmarks.value(reached, compiled.init)
    ops = compiled.applicable(compiled.init)
    state = compiled.successor(compiled.init, ops[0])
    reached1 = landmarks.update(reached, state)
    assert reached1 != reached
    # one more cell visited: one landmark fewer, unless "at" landmarks were lost
    assert landmarks.value(reached1, state) <= h0 - 1


def test_a_lost_goal_landmark_counts_again() -> None:
    compiled = CompiledTask(ground(load("blocksworld", "sussman")))
    landmarks = LandmarkCount(compiled)
    (on_a_b,) = _ids(compiled, "on a b")
    everything = landmarks.landmarks
    state_without = compiled.init & ~(1 << on_a_b)
    state_with = compiled.init | (1 << on_a_b)
    # all accepted: only the lost goal (on a b) counts, once
    assert landmarks.value(everything, state_with) + 1 == landmarks.value(everything, state_without)


@pytest.mark.parametrize("search", ["lazy-gbfs", "gbfs"])
def test_landmark_search_reports_an_unreachable_goal(search: str) -> None:
    domain = parse_domain(VISIT)
    text = _visit_problem(2).replace("(next c0-0 c1-0)", "").replace("(next c0-0 c0-1)", "")
    task = task_from_problem(domain, parse_problem(text, domain))
    result = plan(task, search=search, heuristic="lmcount")
    assert result.status is PlanStatus.UNSOLVABLE


@pytest.mark.parametrize("heuristic", ["ff", "lmcount", "ff-lmcount"])
def test_lazy_gbfs_solves_a_visit_grid(heuristic: str) -> None:
    domain = parse_domain(VISIT)
    task = task_from_problem(domain, parse_problem(_visit_problem(4), domain))
    result = plan(task, search="lazy-gbfs", heuristic=heuristic)
    assert result.status is PlanStatus.SOLVED
    assert result.plan is not None and len(result.plan) >= 15
    assert result.statistics.evaluated == result.statistics.expanded + 1


def test_landmarks_cut_the_search_on_a_visit_grid() -> None:
    domain = parse_domain(VISIT)
    task = task_from_problem(domain, parse_problem(_visit_problem(3), domain))
    count_only = plan(task, search="lazy-gbfs", heuristic="lmcount")
    blind = plan(task, search="gbfs", heuristic="blind", lazy=True)
    assert count_only.plan is not None and blind.plan is not None
    # the count alone is an informed heuristic here: far fewer expansions than blind search
    assert 2 * count_only.statistics.expanded < blind.statistics.expanded


# two trucks can bring the parcel: "in one of the trucks" and "one truck at B" must each hold
# before it is at B, though no single fact must
TRUCKS = """(define (domain trucks) (:requirements :strips)
 (:predicates (at ?x ?l) (in ?p ?t) (truck ?t) (parcel ?p))
 (:action load :parameters (?p ?t ?l)
  :precondition (and (parcel ?p) (truck ?t) (at ?p ?l) (at ?t ?l))
  :effect (and (in ?p ?t) (not (at ?p ?l))))
 (:action unload :parameters (?p ?t ?l) :precondition (and (in ?p ?t) (at ?t ?l))
  :effect (and (at ?p ?l) (not (in ?p ?t))))
 (:action drive :parameters (?t ?a ?b) :precondition (and (truck ?t) (at ?t ?a))
  :effect (and (at ?t ?b) (not (at ?t ?a)))))
"""
TRUCKS_PROBLEM = """(define (problem two) (:domain trucks) (:objects p t1 t2 a b)
 (:init (parcel p) (truck t1) (truck t2) (at p a) (at t1 a) (at t2 a)) (:goal (at p b)))
"""


def _trucks() -> tuple[GroundTask, CompiledTask]:
    domain = parse_domain(TRUCKS)
    task = ground(task_from_problem(domain, parse_problem(TRUCKS_PROBLEM, domain)))
    return task, CompiledTask(task)


def test_disjunctive_landmarks_of_every_achiever() -> None:
    task, compiled = _trucks()
    landmarks = LandmarkCount(compiled)
    found = sorted(
        sorted(str(task.facts[f]) for f in bits(members)) for members, _ in landmarks.disjunctions
    )
    assert found == [["(at t1 b)", "(at t2 b)"], ["(in p t1)", "(in p t2)"]]
    goal = task.facts.index(Atom("at", ("p", "b")))
    for _members, bit in landmarks.disjunctions:
        assert landmarks.parents[goal] & bit  # ordered before the goal
    plain = LandmarkCount(compiled, disjunctive=False)
    assert plain.disjunctions == [] and len(landmarks) == len(plain) + 2
    start = landmarks.initial(compiled.init)
    assert (
        landmarks.value(start, compiled.init)
        == plain.value(plain.initial(compiled.init), compiled.init) + 2
    )


def test_a_disjunctive_landmark_is_reached_by_any_of_its_facts() -> None:
    task, compiled = _trucks()
    landmarks = LandmarkCount(compiled)
    ops = {str(op.action): i for i, op in enumerate(task.operators)}
    start = landmarks.initial(compiled.init)
    h0 = landmarks.value(start, compiled.init)
    loaded = compiled.successor(compiled.init, ops["(load p t2 a)"])
    reached = landmarks.update(start, loaded)
    assert landmarks.value(reached, loaded) == h0 - 1  # "in one of the trucks" is done
    moved = compiled.successor(loaded, ops["(drive t2 a b)"])
    reached = landmarks.update(reached, moved)
    assert landmarks.value(reached, moved) == h0 - 2
    done = compiled.successor(moved, ops["(unload p t2 b)"])
    assert landmarks.value(landmarks.update(reached, done), done) == 0
