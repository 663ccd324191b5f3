"""SDAR-T, the buffer sets and the baseline for one to four arms (no geometry)."""

from __future__ import annotations

import hashlib
import itertools
import json
import random
from collections.abc import Sequence
from pathlib import Path

import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.graph import DependencyGraph, strongly_connected_components
from sdar_tamp.world.dependency import instance_dependency_graph
from sdar_tamp.world.instance import load_instance
from solvers.sdar.abstract import AbstractRunError, run_abstract, view_of
from solvers.sdar.baseline import BaselineTaskPlanner, group_consecutive, pair_consecutive
from solvers.sdar.buffer_sets import feedback_vertex_set, minimum_buffer_set
from solvers.sdar.sdar_t import SdarTaskPlanner
from solvers.sdar.tasks import Move, Step, TaskView, step_is_valid

SUITES = Path(__file__).parents[2] / "domains" / "dual_arm_rearrangement" / "suites"
#: Per instance (paper and dense suites) and random graph, the SHA-256 (16 hex digits) of SDAR-T's
#: ranked candidate list at every view of a first-candidate run, recorded with the two-arm
#: SDAR-T of main d551ef3 (before k arms): :func:`_listing` is the text hashed.
REFERENCE = Path(__file__).parent / "data" / "sdar_t_k2_reference.json"


def graph(n: int, edges: Sequence[tuple[int, int]]) -> DependencyGraph:
    return DependencyGraph(tuple(f"o{i}" for i in range(n)), tuple(edges))


def ring(n: int, offset: int = 0) -> list[tuple[int, int]]:
    return [(offset + k, offset + (k + 1) % n) for k in range(n)]


def random_graph(seed: int) -> DependencyGraph:
    """The random graphs of the reference (their recipe must not change)."""
    rng = random.Random(seed)
    n = 6 + seed % 10
    p = 0.1 + 0.02 * (seed % 7)
    edges = ((i, j) for i in range(n) for j in range(n) if i != j and rng.random() < p)
    return graph(n, tuple(edges))


def _listing(steps: Sequence[Step]) -> str:
    return "\n".join(
        f"{s.kind}|{s.rank}|{s.tie}|"
        + ",".join(m.obj + ("*" if m.to_buffer else "") for m in s.moves)
        for s in steps
    )


def _hashes(g: DependencyGraph) -> list[str]:
    hashes: list[str] = []

    def choose(candidates: Sequence[Step], view: TaskView) -> Step:
        hashes.append(hashlib.sha256(_listing(candidates).encode()).hexdigest()[:16])
        return candidates[0]

    run_abstract(SdarTaskPlanner(), g, choose, arms=2)
    return hashes


def test_two_arm_candidates_are_those_of_the_two_arm_sdar_t() -> None:
    reference = json.loads(REFERENCE.read_text(encoding="utf-8"))
    graphs = {
        f"{suite}/{path.stem}": instance_dependency_graph(load_instance(path))
        for suite in ("paper", "dense")
        for path in sorted((SUITES / suite).glob("*.yaml"))
    }
    graphs.update({f"random/{seed}": random_graph(seed) for seed in range(20)})
    assert sorted(graphs) == sorted(reference)
    for name, g in graphs.items():
        assert _hashes(g) == reference[name], name


def test_a_three_cycle_is_rotated_by_three_arms_without_a_buffer() -> None:
    cycle = graph(3, ring(3))
    best = SdarTaskPlanner().candidates(view_of(cycle, frozenset(), frozenset(), arms=3))[0]
    assert best.kind == "rotate" and sorted(best.objects) == ["o0", "o1", "o2"]
    assert not any(m.to_buffer for m in best.moves)
    run = run_abstract(SdarTaskPlanner(), cycle, arms=3)
    assert (len(run.steps), run.actions, run.buffer_moves) == (1, 3, 0)
    two = run_abstract(SdarTaskPlanner(), cycle, arms=2)
    assert two.buffer_moves == 1  # two arms need a buffer for the same cycle


def test_a_rotation_waits_for_what_blocks_it_from_outside() -> None:
    g = graph(4, [*ring(3), (0, 3)])  # o0's goal is also blocked by o3, outside the cycle
    candidates = SdarTaskPlanner().candidates(view_of(g, frozenset(), frozenset(), arms=3))
    assert not any(s.kind == "rotate" and "o3" not in s.objects for s in candidates)
    best = candidates[0]
    assert best.objects[0] == "o3" or "o3" in best.objects
    run = run_abstract(SdarTaskPlanner(), g, arms=4)
    assert (len(run.steps), run.buffer_moves) == (1, 0)  # o3 and the cycle in one step


def test_a_four_cycle_is_rotated_by_four_arms_and_broken_once_by_three() -> None:
    cycle = graph(4, ring(4))
    four = run_abstract(SdarTaskPlanner(), cycle, arms=4)
    assert (len(four.steps), four.actions, four.buffer_moves) == (1, 4, 0)
    three = run_abstract(SdarTaskPlanner(), cycle, arms=3)
    assert (len(three.steps), three.actions, three.buffer_moves) == (2, 5, 1)


def test_a_rotatable_cycle_can_still_be_broken_when_the_rotation_fails() -> None:
    candidates = SdarTaskPlanner().candidates(
        view_of(graph(3, ring(3)), frozenset(), frozenset(), arms=3)
    )
    assert any(any(m.to_buffer for m in s.moves) and s.progress > 0 for s in candidates)


@pytest.mark.parametrize("arms", [3, 4])
def test_extended_steps_keep_their_base_and_hold_no_more_moves_than_arms(arms: int) -> None:
    g = graph(8, [(0, 1), (1, 2), (3, 4), (4, 3), (5, 6)])
    view = view_of(g, frozenset(), frozenset(), arms=arms)
    candidates = SdarTaskPlanner().candidates(view)
    assert all(len(s.moves) <= arms and step_is_valid(s, view) for s in candidates)
    assert len(candidates[0].moves) == arms
    sets = [frozenset(s.moves) for s in candidates]
    assert len(sets) == len(set(sets))
    for s in candidates:
        if len(s.moves) > 2 and s.kind != "rotate":
            base = frozenset(s.moves[:2])
            assert base in sets or frozenset(s.moves[:1]) in sets


@pytest.mark.parametrize("seed", range(30))
def test_more_arms_never_take_more_steps_or_actions(seed: int) -> None:
    g = random_graph(seed)
    runs = {k: run_abstract(SdarTaskPlanner(), g, arms=k) for k in (1, 2, 3, 4)}
    for k, run in runs.items():
        assert all(len(s.moves) <= k for s in run.steps)
    assert runs[1].actions == g.n + len(feedback_vertex_set(g).members)
    for k in (2, 3, 4):
        assert runs[k].actions <= runs[k - 1].actions
        assert len(runs[k].steps) <= len(runs[k - 1].steps)


def test_one_arm_solves_a_chain_and_a_cycle_one_move_at_a_time() -> None:
    chain = run_abstract(SdarTaskPlanner(), graph(5, [(0, 1), (1, 2), (2, 3), (3, 4)]), arms=1)
    assert [s.objects for s in chain.steps] == [("o4",), ("o3",), ("o2",), ("o1",), ("o0",)]
    assert chain.actions == 5
    cycle = run_abstract(SdarTaskPlanner(), graph(2, ring(2)), arms=1)
    assert (cycle.actions, cycle.buffer_moves) == (3, 1)  # no swap with one arm
    base = run_abstract(BaselineTaskPlanner(), graph(4, ring(4)), arms=1)
    assert base.actions == 5 and all(len(s.moves) == 1 for s in base.steps)


def _brute_buffer_set(g: DependencyGraph, arms: int) -> int:
    for size in range(g.n + 1):
        for removed in itertools.combinations(range(g.n), size):
            keep = [v for v in range(g.n) if v not in removed]
            index = {v: k for k, v in enumerate(keep)}
            edges = tuple((index[i], index[j]) for i, j in g.edges if i in index and j in index)
            if all(len(c) <= arms for c in strongly_connected_components(len(keep), edges)):
                return size
    raise AssertionError("unreachable")


@pytest.mark.parametrize("seed", range(25))
def test_buffer_sets_for_k_arms_are_minimum(seed: int) -> None:
    rng = random.Random(seed)
    n = 5 + seed % 5
    g = graph(n, [(i, j) for i in range(n) for j in range(n) if i != j and rng.random() < 0.3])
    for arms in (1, 2, 3, 4):
        found = feedback_vertex_set(g, arms=arms)
        assert found.exact and len(found.members) == _brute_buffer_set(g, arms), arms


def test_buffer_sets_of_hand_made_graphs() -> None:
    figure_eight = graph(5, [(0, 1), (1, 2), (2, 0), (2, 3), (3, 4), (4, 2)])
    assert minimum_buffer_set(figure_eight, arms=3) == frozenset({"o2"})
    assert minimum_buffer_set(figure_eight, arms=5) == frozenset()
    assert minimum_buffer_set(graph(3, ring(3)), arms=3) == frozenset()
    assert minimum_buffer_set(graph(3, ring(3))) == minimum_buffer_set(graph(3, ring(3)), arms=2)


def test_the_baseline_groups_up_to_k_consecutive_moves() -> None:
    g = graph(5, [(0, 1)])
    moves = [Move(f"o{i}") for i in (1, 0, 2, 3, 4)]
    assert [len(s.moves) for s in group_consecutive(moves, g, arms=3)] == [3, 2]
    assert [len(s.moves) for s in group_consecutive(moves, g, arms=1)] == [1] * 5
    assert group_consecutive(moves, g, arms=2) == pair_consecutive(moves, g)
    run = run_abstract(BaselineTaskPlanner(), graph(6, []), arms=4)
    assert [len(s.moves) for s in run.steps] == [4, 2]


# -- error paths ---------------------------------------------------------------------------------


class _Scripted:
    def __init__(self, steps: list[Step]) -> None:
        self.steps = steps

    @property
    def name(self) -> str:
        return "scripted"

    def candidates(self, view: TaskView) -> list[Step]:
        return self.steps[:1]

    def commit(self, step: Step, view: TaskView) -> None:
        self.steps.pop(0)


def test_a_step_with_more_moves_than_arms_is_invalid() -> None:
    g = graph(3, [])
    three = Step((Move("o0"), Move("o1"), Move("o2")), "pair")
    assert step_is_valid(three, view_of(g, frozenset(), frozenset(), arms=3))
    assert not step_is_valid(three, view_of(g, frozenset(), frozenset(), arms=2))
    with pytest.raises(AbstractRunError, match="invalid step"):
        run_abstract(_Scripted([three]), g, arms=2)


def test_bad_arm_counts_are_refused() -> None:
    g = graph(2, [])
    with pytest.raises(ValueError, match="arms >= 1"):
        view_of(g, frozenset(), frozenset(), arms=0)
    with pytest.raises(ParameterError, match="arms"):
        feedback_vertex_set(g, arms=0)
    with pytest.raises(ParameterError, match="arms"):
        group_consecutive([Move("o0")], g, arms=0)
    with pytest.raises(ValueError, match="at least one move"):
        Step((), "pair")


def test_abstract_figures_count_the_arms_of_the_instances_scene() -> None:
    from sdar_tamp.app.abstract import abstract_figures

    data = Path(__file__).parent / "data"
    three = abstract_figures(data / "three_arm_cycle.yaml", "sdar")
    assert (three.actions, three.buffer_moves, three.steps) == (3, 0, 1)
    two = abstract_figures(data / "three_arm_cycle.yaml", "sdar", arms=2)
    assert (two.actions, two.buffer_moves) == (4, 1)
    one = abstract_figures(data / "one_arm_chain.yaml", "baseline")
    assert (one.actions, one.steps) == (3, 3)
    with pytest.raises(ParameterError, match="arms"):
        abstract_figures(data / "one_arm_chain.yaml", "sdar", arms=0)


def test_the_benchmark_counts_the_arms_of_the_cell_that_replaces_the_instances() -> None:
    """`sdar bench --scene CELL`: the geometry-free figures are those of CELL's arms."""
    from sdar_tamp.evaluation.bench_task import _abstract_figures

    data = Path(__file__).parent / "data"
    cells = Path(__file__).parents[2] / "domains" / "dual_arm_rearrangement" / "cells"
    own = _abstract_figures(data / "three_arm_cycle.yaml", "sdar", None)
    assert (own.actions, own.buffer_moves) == (3, 0)
    two = _abstract_figures(data / "three_arm_cycle.yaml", "sdar", cells / "ur5e_table_2arm.yaml")
    assert (two.actions, two.buffer_moves) == (4, 1)
