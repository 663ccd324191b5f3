"""Landmarks (label propagation), the landmark-count heuristic, and LAMA-style lazy search."""

from __future__ import annotations

import pytest
from classical_helpers import load

from sdar_tamp.language import parse_domain, parse_problem
from sdar_tamp.language.model import Atom
from solvers.classical import PlanStatus, ground, plan, task_from_problem
from solvers.classical.compiled import CompiledTask, mask
from solvers.classical.landmarks import LandmarkCount

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
