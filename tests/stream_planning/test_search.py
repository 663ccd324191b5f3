"""Search behaviour of the stream algorithms: the cost bound, single-answer streams, joins."""

from __future__ import annotations

import itertools
import random
from collections.abc import Iterator
from typing import Any

import pytest

from sdar_tamp.language.formula_model import Atom
from sdar_tamp.language.formulas import Equal
from sdar_tamp.language.generators import from_gen_fn, from_test
from sdar_tamp.language.options import PlanConstraints
from sdar_tamp.language.problem import PDDLProblem
from solvers.solve import solve
from solvers.stream_planning.facts import FactStore

ALGORITHMS = ("incremental", "focused", "binding", "adaptive")

# Roads: a direct road a-g (cost 10) and a detour a-b-c-g (cost 1 each). A greedy search that
# ignores costs takes the direct road first.
ROADS = """
(define (domain roads)
  (:requirements :strips :action-costs)
  (:predicates (road ?x ?y) (at ?x))
  (:functions (toll ?x ?y) (total-cost))
  (:action drive :parameters (?x ?y)
    :precondition (and (at ?x) (road ?x ?y))
    :effect (and (at ?y) (not (at ?x)) (increase (total-cost) (toll ?x ?y)))))
"""
TOLLS = {("a", "g"): 10.0, ("a", "b"): 1.0, ("b", "c"): 1.0, ("c", "g"): 1.0}


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_plans_above_max_cost_are_pruned_by_the_planner(algorithm: str) -> None:
    """With max_cost 5 the direct road (10) is no answer: the planner must look further at
    the same level instead of returning it (the solver would drop it and give up)."""
    init = [("at", "a"), *(("road", x, y) for x, y in TOLLS)]
    init += [Equal(("toll", x, y), c) for (x, y), c in TOLLS.items()]
    problem = PDDLProblem(ROADS, {}, None, {}, init, ("at", "g"))
    solution = solve(
        problem,
        algorithm=algorithm,
        planner="gbfs-ff",
        constraints=PlanConstraints(max_cost=5),
        max_complexity=3,
        max_time=20,
        verbose=False,
    )
    assert solution.solved, solution.diagnosis
    assert [a.args for a in solution.plan or []] == [("a", "b"), ("b", "c"), ("c", "g")]
    assert solution.cost == pytest.approx(3.0)


LINE = """
(define (domain hops)
  (:requirements :strips :derived-predicates)
  (:predicates (spot ?p) (at ?p) (clear ?p ?q) (far ?p) (arrived))
  (:derived (arrived) (exists (?p) (and (at ?p) (far ?p))))
  (:action hop :parameters (?p ?q)
    :precondition (and (at ?p) (clear ?p ?q))
    :effect (and (at ?q) (not (at ?p)))))
"""
HOP_STREAMS = """
(define (stream hops)
  (:stream sample-spot :inputs (?p) :domain (spot ?p) :outputs (?q) :certified (spot ?q))
  (:stream test-clear :inputs (?p ?q) :domain (and (spot ?p) (spot ?q))
    :certified (clear ?p ?q))
  (:stream test-far :inputs (?p) :domain (spot ?p) :certified (far ?p)))
"""


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_a_test_stream_is_called_once_per_instance(algorithm: str) -> None:
    """``from_test`` gives one answer: its instance is exhausted after one call (a second call
    would only find that out, and a failed test would look worth another optimistic try)."""
    asked: list[tuple[float, float]] = []

    def spots(p: float) -> Iterator[tuple[float]]:
        for k in itertools.count(1):
            yield (p + k,)

    def clear(p: float, q: float) -> bool:
        asked.append((p, q))
        return q == p + 1

    stream_map = {
        "sample-spot": from_gen_fn(spots),
        "test-clear": from_test(clear),
        "test-far": from_test(lambda p: p >= 3.0),
    }
    init = [("spot", 0.0), ("at", 0.0)]
    problem = PDDLProblem(LINE, {}, HOP_STREAMS, stream_map, init, ("arrived",))
    solution = solve(problem, algorithm=algorithm, max_time=20, verbose=False)
    assert solution.solved, solution.diagnosis
    assert len(asked) == len(set(asked))  # no pair tested twice
    assert solution.streams["test-clear"].calls == len(asked)


def test_join_with_bound_arguments_matches_a_full_scan() -> None:
    rng = random.Random(3)
    store = FactStore()
    facts = {
        Atom(rng.choice("pq"), (rng.choice("abcd"), rng.choice("abcd"), rng.choice("xy")))
        for _ in range(60)
    }
    for level, atom in enumerate(sorted(facts, key=str)):
        store.add(atom, level % 4)
    query = [
        Atom("p", ("?a", "?b", "x")),
        Atom("q", ("?b", "?c", "?d")),
        Atom("p", ("?c", "a", "?e")),
    ]
    found = sorted((tuple(sorted(b.items())), level) for b, level in store.join(query, {"?a": "b"}))
    expected = []
    for p1, q1, p2 in itertools.product(sorted(facts, key=str), repeat=3):
        if (p1.predicate, q1.predicate, p2.predicate) != ("p", "q", "p"):
            continue
        if p1.args[0] != "b" or p1.args[2] != "x" or q1.args[0] != p1.args[1]:
            continue
        if p2.args[0] != q1.args[1] or p2.args[1] != "a":
            continue
        binding = {"?a": "b", "?b": p1.args[1], "?c": q1.args[1], "?d": q1.args[2]}
        binding["?e"] = p2.args[2]
        level = max(store.levels[p1], store.levels[q1], store.levels[p2])
        expected.append((tuple(sorted(binding.items())), level))
    assert found == sorted(expected) and found


def test_a_world_of_later_calls_is_built_only_when_it_can_differ(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``OptimisticWorld.further_level``: when every later call's outputs lie above the level,
    the build with them gives the same facts (the solver skips it); else it adds some. Every
    world of pick_place_2d's searches that leaves later calls out is built again both ways."""
    from domains.pick_place_2d.samplers import make_problem
    from solvers.stream_planning.optimistic import OptimisticBuilder, OptimisticWorld

    build = OptimisticBuilder.build
    seen = {"above": 0, "within": 0}

    def checked(
        self: OptimisticBuilder, limit: int, lazy: bool = False, further: bool = False, **kw: Any
    ) -> OptimisticWorld:
        world = build(self, limit, lazy, further, **kw)
        if world.more_calls and not further:
            again = build(self, limit, lazy, True, **kw)
            above = world.further_level > limit
            seen["above" if above else "within"] += 1
            assert (again.facts.keys() == world.facts.keys()) is above
        return world

    monkeypatch.setattr(OptimisticBuilder, "build", checked)
    for algorithm in ("focused", "binding"):
        solution = solve(make_problem(seed=0), algorithm=algorithm, max_time=60, seed=0)
        assert solution.plan is not None
    assert seen["above"] and seen["within"]
