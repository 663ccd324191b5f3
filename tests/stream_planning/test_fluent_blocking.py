"""A failed fluent stream call blocks its facts in states like its own; a fluent output used in
two different states is certified in each.

Shelf: two jars stand on a shelf, ``front`` before ``back``. Reaching a jar is planned by a
``:fluents (onshelf)`` stream that fails while another jar stands in front of it. The goal
needs ``back`` held: the only plan takes ``front`` first. A solver that keeps offering the
failed reach in the initial state re-plans the same skeleton until its limits end it.

Corridor: a robot goes from ``a`` to ``b`` twice, once with the door open and once with it
shut. The route stream (``:fluents (open)``) goes through the door when it is open, else
around by the hall. An optimistic plan may use one route placeholder for both trips; each trip
must get a route planned in its own state.
"""

from __future__ import annotations

from typing import Any

import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.formula_model import Atom, Not
from sdar_tamp.language.generators import from_fn
from sdar_tamp.language.problem import PDDLProblem
from sdar_tamp.language.stream_model import Stream
from solvers.solution import Solution
from solvers.solve import solve
from solvers.stream_planning.blocked_calls import Blocks, blocked_predicate, guard_fluent_uses

ALGORITHMS = ("incremental", "focused", "binding", "adaptive")

SHELF = """
(define (domain shelf)
  (:requirements :strips)
  (:predicates (jar ?j) (onshelf ?j) (holding ?j) (reach ?j ?t))
  (:action take :parameters (?j ?t)
    :precondition (and (onshelf ?j) (reach ?j ?t))
    :effect (and (holding ?j) (not (onshelf ?j)))))
"""
SHELF_STREAMS = """
(define (stream shelf)
  (:stream plan-reach :inputs (?j) :domain (jar ?j) :fluents (onshelf)
    :outputs (?t) :certified (reach ?j ?t)))
"""
IN_FRONT = {"back": "front"}  # jar -> the jar standing in front of it


class Shelf:
    """The reach sampler, recording the jars on the shelf it was shown."""

    def __init__(self) -> None:
        self.calls: list[tuple[str, frozenset[str]]] = []

    def reach(self, jar: str, fluents: list[tuple[Any, ...]]) -> tuple[str] | None:
        on_shelf = frozenset(f[1] for f in fluents if f[0] == "onshelf")
        self.calls.append((jar, on_shelf))
        return None if IN_FRONT.get(jar) in on_shelf else (f"reach-{jar}",)

    def problem(self) -> PDDLProblem:
        init = [("jar", "front"), ("jar", "back"), ("onshelf", "front"), ("onshelf", "back")]
        stream_map = {"plan-reach": from_fn(self.reach)}
        return PDDLProblem(SHELF, {}, SHELF_STREAMS, stream_map, init, ("holding", "back"))


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_failed_fluent_reach_is_blocked_in_its_state(algorithm: str) -> None:
    shelf = Shelf()
    # the iteration limit ends a solver that re-plans the failed skeleton (within seconds)
    solution = solve(
        shelf.problem(), algorithm=algorithm, max_iterations=50, max_time=30, verbose=False
    )
    assert solution.solved, (solution.status, solution.diagnosis)
    assert [a.args[0] for a in solution.plan or []] == ["front", "back"]
    # back was reached with front gone, after one refusal with front in the way
    assert ("back", frozenset({"back"})) in shelf.calls
    refused = ("back", frozenset({"front", "back"}))
    assert refused in shelf.calls
    assert len(shelf.calls) <= 6, shelf.calls


CORRIDOR = """
(define (domain corridor)
  (:requirements :strips :negative-preconditions :conditional-effects)
  (:predicates (room ?r) (at ?r) (open) (route ?r1 ?r2 ?t) (seen-open ?r) (seen-shut ?r))
  (:action go :parameters (?r1 ?r2 ?t)
    :precondition (and (at ?r1) (route ?r1 ?r2 ?t))
    :effect (and (at ?r2) (not (at ?r1))
                 (when (open) (seen-open ?r2)) (when (not (open)) (seen-shut ?r2))))
  (:action shut :parameters () :precondition (open) :effect (not (open))))
"""
CORRIDOR_STREAMS = """
(define (stream corridor)
  (:stream plan-route :inputs (?r1 ?r2) :domain (and (room ?r1) (room ?r2)) :fluents (open)
    :outputs (?t) :certified (route ?r1 ?r2 ?t)))
"""


def route(r1: str, r2: str, fluents: list[tuple[Any, ...]]) -> tuple[str] | None:
    if r1 == r2:
        return None
    return (f"door-{r1}-{r2}",) if ("open",) in fluents else (f"hall-{r1}-{r2}",)


def replay_corridor(solution: Solution) -> None:
    """Independent check: a route through the door only while the door is open."""
    assert solution.plan is not None
    at, door_open, seen = "a", True, set()
    for action in solution.plan:
        if action.name == "shut":
            assert door_open
            door_open = False
            continue
        r1, r2, path = action.args
        assert r1 == at and path in (f"door-{r1}-{r2}", f"hall-{r1}-{r2}")
        assert path.startswith("door") == door_open, (action, door_open)
        at = r2
        seen.add((r2, door_open))
    assert {("b", True), ("b", False)} <= seen


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_fluent_output_used_in_two_states_is_certified_in_each(algorithm: str) -> None:
    init = [("room", "a"), ("room", "b"), ("at", "a"), ("open",)]
    goal = ("and", ("seen-open", "b"), ("seen-shut", "b"))
    stream_map = {"plan-route": from_fn(route)}
    problem = PDDLProblem(CORRIDOR, {}, CORRIDOR_STREAMS, stream_map, init, goal)
    solution = solve(problem, algorithm=algorithm, max_iterations=200, max_time=30, verbose=False)
    assert solution.solved, (solution.status, solution.diagnosis)
    replay_corridor(solution)


# --- the domain guard and the blocks ------------------------------------------------------


def _reach_stream(name: str = "plan-reach") -> Stream:
    certified = (Atom("reach", ("?j", "?t")),)
    return Stream(name, ("?j",), (Atom("jar", ("?j",)),), ("?t",), certified, ("onshelf",))


def test_guard_adds_the_blocked_condition_to_positive_uses() -> None:
    domain = guard_fluent_uses(parse_domain(SHELF), [_reach_stream()])
    take = domain.action("take")
    blocked = Atom(blocked_predicate("plan-reach"), ("?j",))
    assert Not(blocked) in take.precondition.parts[1].parts  # type: ignore[union-attr]
    assert blocked.predicate in domain.predicates


def test_two_fluent_streams_certifying_one_predicate_are_refused() -> None:
    with pytest.raises(ParameterError, match="both certify 'reach'"):
        guard_fluent_uses(parse_domain(SHELF), [_reach_stream("a"), _reach_stream("b")])


def test_blocks_apply_to_supersets_and_temporary_ones_lift() -> None:
    blocks = Blocks(guard_fluent_uses(parse_domain(SHELF), [_reach_stream()]))
    both = (Atom("onshelf", ("back",)), Atom("onshelf", ("front",)))
    assert blocks.add("plan-reach", ("back",), both, permanent=False)
    assert not blocks.add("plan-reach", ("back",), both, permanent=False)
    assert blocks.blocked("plan-reach", ("back",), [*both, Atom("onshelf", ("x",))])
    assert not blocks.blocked("plan-reach", ("back",), both[:1])
    assert len(blocks.domain().axioms) == 1 and len(blocks.facts()) == 1
    blocks.lift()
    assert len(blocks) == 0 and not blocks.domain().axioms
    assert blocks.add("plan-reach", ("back",), both, permanent=True)
    blocks.lift()
    assert blocks.blocked("plan-reach", ("back",), both) and blocks.temporary == 0
