"""SDAR-T and the baseline on abstract rearrangements (dependency graphs, no geometry)."""

from __future__ import annotations

import itertools
import random
from collections.abc import Callable, Sequence

import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.graph import DependencyGraph
from solvers.sdar.abstract import AbstractRunError, count_actions, run_abstract, view_of
from solvers.sdar.baseline import (
    BaselineTaskPlanner,
    minimum_feedback_vertex_set,
    optimal_single_arm_plan,
    pair_consecutive,
)
from solvers.sdar.buffer_sets import (
    breaks_cycles,
    extending_minimum,
    feedback_vertex_set,
    minimum_buffer_set,
    optimal_choices,
)
from solvers.sdar.sdar_t import SdarTaskPlanner
from solvers.sdar.tasks import Move, Step, TaskPlanner, TaskView, step_is_valid


def graph(n: int, edges: Sequence[tuple[int, int]]) -> DependencyGraph:
    return DependencyGraph(tuple(f"o{i}" for i in range(n)), tuple(edges))


def ring(n: int, offset: int = 0) -> list[tuple[int, int]]:
    return [(offset + k, offset + (k + 1) % n) for k in range(n)]


def random_graph(n: int, p: float, seed: int) -> DependencyGraph:
    rng = random.Random(seed)
    return graph(n, [(i, j) for i in range(n) for j in range(n) if i != j and rng.random() < p])


def random_scc(n: int, extra: int, seed: int) -> DependencyGraph:
    """A ring of ``n`` objects plus up to ``extra`` random edges per object: one component."""
    rng = random.Random(seed)
    edges = set(ring(n))
    for i in range(n):
        edges |= {(i, j) for j in rng.sample(range(n), extra) if j != i}
    return graph(n, sorted(edges))


# The paper's running example (Fig. 1): cycle 0-3, chain 6 -> 5 -> 4, leaf 8, orphan 7.
PAPER = graph(9, [*ring(4), (6, 5), (5, 4), (3, 8)])

HAND_MADE = {
    **{f"cycle{n}": graph(n, ring(n)) for n in range(2, 7)},
    "two_cycles": graph(7, [*ring(3), *ring(4, 3)]),
    "figure_eight": graph(5, [(0, 1), (1, 2), (2, 0), (2, 3), (3, 4), (4, 2)]),
    "chain": graph(5, [(0, 1), (1, 2), (2, 3), (3, 4)]),
    "chains_and_independent": graph(8, [(0, 1), (1, 2), (3, 4), (5, 2)]),
    "mixed": graph(12, [*ring(3), *ring(2, 3), (5, 6), (6, 7), (0, 5), (8, 9), (9, 0)]),
    "bidirected_k4": graph(4, [(i, j) for i in range(4) for j in range(4) if i != j]),
    "swap_chain": graph(4, [(0, 1), (1, 0), (1, 2), (2, 1), (2, 3), (3, 2)]),
    "paper": PAPER,
}
RANDOM = {f"random{s}": random_graph(3 + s % 10, (0.1, 0.2, 0.3)[s % 3], s) for s in range(60)}


def checked_first(candidates: Sequence[Step], view: TaskView) -> Step:
    """Every candidate is valid and distinct; execute the first."""
    assert all(step_is_valid(c, view) for c in candidates), candidates
    assert len({c.moves for c in candidates}) == len(candidates)
    return candidates[0]


def brute_force(g: DependencyGraph, allow_swaps: bool) -> int:
    for k in range(g.n + 1):
        for chosen in itertools.combinations(g.names, k):
            if breaks_cycles(g, frozenset(chosen), allow_swaps):
                return k
    raise AssertionError("unreachable")


@pytest.mark.parametrize("allow_swaps", [False, True])
def test_minimum_sets_match_brute_force(allow_swaps: bool) -> None:
    for seed in range(150):
        g = random_graph(2 + seed % 8, (0.15, 0.3, 0.5)[seed % 3], seed)
        found = feedback_vertex_set(g, allow_swaps=allow_swaps)
        assert found.exact and breaks_cycles(g, found.members, allow_swaps)
        assert len(found.members) == brute_force(g, allow_swaps), seed


def test_optimal_choices_are_the_members_of_some_minimum_set() -> None:
    for seed in range(40):
        g = random_graph(3 + seed % 5, 0.35, seed)
        k = brute_force(g, True)
        minimum = [
            frozenset(c)
            for c in itertools.combinations(g.names, k)
            if breaks_cycles(g, frozenset(c), True)
        ]
        assert optimal_choices(g, allow_swaps=True) == frozenset().union(*minimum)
        pairs = [frozenset(p) for p in itertools.combinations(g.names, 2)]
        expected = [p for p in pairs if any(p <= m for m in minimum)]
        assert extending_minimum(g, pairs, allow_swaps=True) == expected


def test_minimum_fvs_of_a_24_object_component_is_exact() -> None:
    g = random_scc(24, 2, seed=3)
    assert len(g.cycle_components()) == 1
    found = feedback_vertex_set(g)
    assert found.exact and breaks_cycles(g, found.members, False)
    size = len(found.members)
    smaller = itertools.combinations(g.names, size - 1)
    assert not any(breaks_cycles(g, frozenset(c), False) for c in smaller)


def test_over_budget_falls_back_to_a_flagged_greedy_set() -> None:
    g = random_scc(20, 3, seed=1)
    found = feedback_vertex_set(g, node_budget=1)
    assert not found.exact and breaks_cycles(g, found.members, False)
    planner = BaselineTaskPlanner(node_budget=1)
    run_abstract(planner, g, checked_first)
    assert not planner.exact
    sdar = SdarTaskPlanner(node_budget=1)
    run_abstract(sdar, g, checked_first)
    assert not sdar.exact


def test_view_of_drops_edges_into_moved_objects() -> None:
    view = view_of(graph(3, [(0, 1), (1, 2), (2, 0)]), frozenset({"o2"}), frozenset({"o1"}))
    assert view.remaining == ("o0", "o1")
    assert view.blockers("o0") == frozenset() and view.blockers("o1") == frozenset()
    assert view.in_buffer == frozenset({"o1"}) and view.done == frozenset({"o2"})


@pytest.mark.parametrize("name", sorted({**HAND_MADE, **RANDOM}))
def test_planners_finish_with_optimal_action_counts(name: str) -> None:
    g = {**HAND_MADE, **RANDOM}[name]
    sdar = run_abstract(SdarTaskPlanner(), g, checked_first)
    base = run_abstract(BaselineTaskPlanner(), g, checked_first)
    assert sdar.actions == g.n + len(minimum_buffer_set(g))
    assert base.actions == g.n + len(minimum_feedback_vertex_set(g))
    assert sdar.actions <= base.actions
    assert len(sdar.steps) <= len(base.steps) + 1


def test_sdar_t_never_needs_more_actions_than_the_baseline() -> None:
    worse = []
    for seed in range(300):
        g = random_graph(4 + seed % 14, (0.08, 0.15, 0.25)[seed % 3], 1000 + seed)
        ours = count_actions(SdarTaskPlanner, g)
        theirs = count_actions(BaselineTaskPlanner, g)
        if ours > theirs:
            worse.append((g, ours, theirs))
    assert worse == []


def test_paper_example_takes_ten_actions() -> None:
    # "7, 8, 4, 5, 6, 0, 1, 3, 2, 1": object 1 visits a buffer once.
    run = run_abstract(SdarTaskPlanner(), PAPER, checked_first)
    assert run.actions == 10 and run.buffer_moves == 1
    assert len(run.steps) == 5


def test_two_cycle_is_one_swap_and_chains_start_at_the_leaf() -> None:
    swap = SdarTaskPlanner().candidates(view_of(HAND_MADE["cycle2"], frozenset(), frozenset()))
    assert swap[0].kind == "swap" and swap[0].progress == 2
    chain = SdarTaskPlanner().candidates(view_of(HAND_MADE["chain"], frozenset(), frozenset()))
    assert chain[0].kind == "chain" and set(chain[0].objects) == {"o3", "o4"}


def test_cycle_breaking_sends_one_object_to_a_buffer_and_its_predecessor_home() -> None:
    view = view_of(graph(4, ring(4)), frozenset(), frozenset())
    best = SdarTaskPlanner().candidates(view)[0]
    assert best.kind == "cycle" and best.rank == 2
    home, buffered = best.moves
    assert not home.to_buffer and buffered.to_buffer
    assert view.blockers(home.obj) == {buffered.obj}


def test_stuck_component_buffers_two_objects_of_one_minimum_set() -> None:
    # Every object is blocked by two others: no adjacent (goal, buffer) pair exists.
    g = graph(6, [(i, (i + d) % 6) for i in range(6) for d in (1, 2)])
    best = SdarTaskPlanner().candidates(view_of(g, frozenset(), frozenset()))[0]
    assert best.kind == "cycle" and all(m.to_buffer for m in best.moves)
    assert len(best.moves) == 2


def test_candidates_are_deterministic_capped_and_end_with_singles() -> None:
    view = view_of(graph(12, []), frozenset(), frozenset())
    first = SdarTaskPlanner(max_candidates=5).candidates(view)
    assert first == SdarTaskPlanner(max_candidates=5).candidates(view)
    assert [len(s.moves) for s in first] == [2] * 5 + [1] * 24
    assert [s.kind for s in first[5:]] == ["single"] * 12 + ["buffer"] * 12
    with pytest.raises(ParameterError):
        SdarTaskPlanner(max_candidates=0)


def test_no_buffer_to_buffer_moves_while_anything_else_is_possible() -> None:
    g = graph(3, [(0, 1), (1, 2), (2, 0)])
    view = view_of(g, frozenset(), frozenset({"o1"}))
    for planner in (SdarTaskPlanner(), BaselineTaskPlanner()):
        steps = planner.candidates(view)
        assert not any(m.to_buffer and m.obj == "o1" for s in steps for m in s.moves)


def test_single_arm_plan_has_n_plus_mfvs_actions_and_pairs_consecutively() -> None:
    for name, g in {**HAND_MADE, **RANDOM}.items():
        moves = optimal_single_arm_plan(g)
        assert len(moves) == g.n + len(minimum_feedback_vertex_set(g)), name
        steps = pair_consecutive(moves, g)
        assert [m for s in steps for m in s.moves] == moves
        run = run_abstract(_Scripted(steps), g)
        assert run.steps == tuple(steps)


class _Scripted:
    """Proposes a fixed list of steps in order (to replay a plan through the simulator)."""

    def __init__(self, steps: list[Step]) -> None:
        self.steps = steps

    @property
    def name(self) -> str:
        return "scripted"

    def candidates(self, view: TaskView) -> list[Step]:
        return self.steps[:1]

    def commit(self, step: Step, view: TaskView) -> None:
        self.steps = self.steps[1:]


def only(k: int) -> Callable[[Sequence[Step], TaskView], Step]:
    """SDAR-M grounds only move ``k`` of a pair (one arm at a time), if it is valid alone."""

    def choose(candidates: Sequence[Step], view: TaskView) -> Step:
        step = checked_first(candidates, view)
        moves = step.moves[min(k, len(step.moves) - 1) :] + step.moves
        return next(s for m in moves if step_is_valid(s := Step((m,), step.kind), view))

    return choose


@pytest.mark.parametrize("k", [0, 1])
def test_baseline_keeps_its_plan_when_pairs_are_executed_one_move_at_a_time(k: int) -> None:
    for g in [*HAND_MADE.values(), *RANDOM.values()]:
        run = run_abstract(BaselineTaskPlanner(), g, only(k))
        assert run.actions == g.n + len(minimum_feedback_vertex_set(g))


@pytest.mark.parametrize("factory", [SdarTaskPlanner, BaselineTaskPlanner])
def test_planners_finish_whatever_candidate_sdar_m_manages_to_ground(
    factory: Callable[[], TaskPlanner],
) -> None:
    for seed, g in enumerate([*HAND_MADE.values(), *RANDOM.values()]):
        rng = random.Random(seed)

        def choose(candidates: Sequence[Step], view: TaskView, rng: random.Random = rng) -> Step:
            checked_first(candidates, view)
            return rng.choice(list(candidates))

        run = run_abstract(factory(), g, choose)
        assert run.actions >= g.n


def test_an_invalid_planner_is_reported() -> None:
    bad = _Scripted([Step((Move("o0"),), "single")])
    with pytest.raises(AbstractRunError):
        run_abstract(bad, graph(2, [(0, 1)]))


def test_a_swappable_two_cycle_may_also_be_broken_beside_another_goal_move() -> None:
    # o0 <-> o1 swap first; if the grippers cannot close on both, o0 or o1 goes to a buffer
    # while the free o2 (or the other member of the cycle) goes to its goal
    view = view_of(graph(3, ((0, 1), (1, 0))), frozenset(), frozenset())
    steps = SdarTaskPlanner().candidates(view)
    assert steps[0].kind == "swap" and steps[0].rank == 1
    breaks = [s for s in steps if s.kind == "cycle"]
    assert breaks and all(s.rank == 3 and step_is_valid(s, view) for s in breaks)
    pairs = {(m.obj, m.to_buffer) for s in breaks for m in s.moves}
    assert {("o2", False), ("o0", True), ("o1", True)} <= pairs
    # a 2-cycle that is not a swap (o0 also waits for o2) gets no such break
    view = view_of(graph(3, ((0, 1), (1, 0), (0, 2))), frozenset(), frozenset())
    assert not any(
        m.to_buffer and m.obj == "o1" and len(s.moves) == 2
        for s in SdarTaskPlanner().candidates(view)
        if s.rank == 3
        for m in s.moves
    )
