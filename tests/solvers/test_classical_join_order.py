"""Join order: pure lookups first, then shared terms, then the smaller relation.

A road-map task is the motivating case: ``(move ?a ?b)`` needs ``(at ?a)`` (one fact), the
sparse ``(edge ?a ?b)`` and a dense ``(dist ?a ?b)`` known for every pair. A join that starts
from ``dist`` visits every pair on every grounding; one that starts from ``at`` visits the few
edges out of one node.
"""

from __future__ import annotations

from itertools import pairwise

from sdar_tamp.language import parse_domain, parse_problem
from sdar_tamp.language.formula_model import Atom
from solvers.classical import PlanningTask, PlanStatus, ground, plan, task_from_problem
from solvers.classical.join import FactBase, compile_join, run_join
from solvers.classical.normalize import Lit

AT = Lit("at", ("?a",))
EDGE = Lit("edge", ("?a", "?b"))
DIST = Lit("dist", ("?a", "?b"))
OBJECT_A = Lit("object", ("?a",))
OBJECT_B = Lit("object", ("?b",))
BODY = [OBJECT_A, OBJECT_B, EDGE, AT, DIST]


def _order(sizes: dict[str, int] | None, first: int | None = None) -> list[str]:
    plan_ = compile_join(list(BODY), [], first=first, sizes=sizes)
    return [f"{s.predicate}/{len(s.key_positions)}" for s in plan_.steps]


def test_the_join_starts_from_the_smallest_relation_and_checks_early() -> None:
    sizes = {"object": 60, "edge": 59, "dist": 3600, "at": 1}
    # at (1 fact) first; then object(?a) is a pure lookup; edge (59) before dist (3600) binds
    # ?b; the rest are lookups (the one sharing more terms first)
    assert _order(sizes) == ["at/0", "object/1", "edge/1", "dist/2", "object/1"]


def test_a_seeded_join_still_prefers_the_smaller_relation() -> None:
    sizes = {"object": 60, "edge": 59, "dist": 3600, "at": 1}
    # seeded with a new (at ?a): edge, not dist, binds ?b
    assert _order(sizes, first=3) == ["at/0", "object/1", "edge/1", "dist/2", "object/1"]


def test_without_sizes_lookups_still_come_first() -> None:
    order = _order(None, first=3)
    assert order[:2] == ["at/0", "object/1"]


def test_the_order_does_not_change_the_bindings() -> None:
    nodes = [f"q{i}" for i in range(12)]
    facts = FactBase(
        [("object", (n,)) for n in nodes]
        + [("edge", (a, b)) for a, b in pairwise(nodes)]
        + [("dist", (a, b)) for a in nodes for b in nodes]
        + [("at", ("q3",))]
    )
    sizes = {p: len(r) for p, r in facts.relations.items()}
    found = {
        tuple(sorted(b.items())) for b in run_join(compile_join(list(BODY), [], sizes=sizes), facts)
    }
    plain = {tuple(sorted(b.items())) for b in run_join(compile_join(list(BODY), []), facts)}
    assert found == plain == {(("?a", "q3"), ("?b", "q4"))}


ROADMAP = """(define (domain roadmap) (:requirements :strips)
  (:predicates (at ?a) (edge ?a ?b) (dist ?a ?b))
  (:action move :parameters (?a ?b) :precondition (and (at ?a) (edge ?a ?b) (dist ?a ?b))
     :effect (and (at ?b) (not (at ?a)))))"""


def _roadmap(count: int) -> PlanningTask:
    nodes = [f"q{i}" for i in range(count)]
    init = ["(at q0)"]
    init += [f"(edge {x} {y})" for x, y in pairwise(nodes)]
    init += [f"(dist {x} {y})" for x in nodes for y in nodes]
    problem = (
        f"(define (problem line) (:domain roadmap) (:objects {' '.join(nodes)})"
        f" (:init {' '.join(init)}) (:goal (at {nodes[-1]})))"
    )
    domain = parse_domain(ROADMAP, "domain.pddl")
    return task_from_problem(domain, parse_problem(problem, domain))


def test_roadmap_grounding_and_static_facts() -> None:
    task = _roadmap(30)
    grounded = ground(task)
    assert len(grounded.operators) == 29  # one move per edge: dist alone makes none
    # static facts are still listed (built on first use)
    assert Atom("edge", ("q0", "q1")) in grounded.static_facts
    assert Atom("dist", ("q5", "q2")) in grounded.static_facts
    assert not any(a.predicate == "at" for a in grounded.static_facts)
    result = plan(task, search="astar", heuristic="max")
    assert result.status is PlanStatus.SOLVED and result.plan is not None
    assert len(result.plan) == 29
