"""Search: optimal plan lengths, all algorithm/heuristic combinations, statuses, parameters."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import pytest
from classical_helpers import load, load_text

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.formula_model import Atom
from solvers.classical import HEURISTICS, SEARCHES, PlanStatus, ground, plan
from solvers.classical.bitset_task import CompiledTask
from solvers.classical.postprocess import eliminate_redundant_actions

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from _blocksworld import blocksworld_problem


@pytest.mark.parametrize("heuristic", ["max", "blind"])
@pytest.mark.parametrize("lazy", [False, True])
def test_astar_finds_the_optimal_sussman_plan(heuristic: str, lazy: bool) -> None:
    result = plan(load("blocksworld", "sussman"), search="astar", heuristic=heuristic, lazy=lazy)
    assert result.status is PlanStatus.SOLVED
    assert result.plan is not None and len(result.plan) == 6
    assert [str(a) for a in result.plan[:2]] == ["(unstack c a)", "(put-down c)"]
    assert result.cost == 6.0


def test_astar_hmax_expands_fewer_states_than_blind() -> None:
    task = load("blocksworld", "reverse4")
    informed = plan(task, search="astar", heuristic="max")
    blind = plan(task, search="astar", heuristic="blind")
    assert informed.plan is not None and blind.plan is not None
    assert len(informed.plan) == len(blind.plan) == 8
    assert informed.statistics.expanded < blind.statistics.expanded


@pytest.mark.parametrize("search", SEARCHES)
@pytest.mark.parametrize("heuristic", HEURISTICS)
@pytest.mark.parametrize("lazy", [False, True])
@pytest.mark.parametrize("preferred", [False, True])
def test_every_configuration_solves_reverse4(
    search: str, heuristic: str, lazy: bool, preferred: bool
) -> None:
    result = plan(
        load("blocksworld", "reverse4"),
        search=search,
        heuristic=heuristic,
        lazy=lazy,
        preferred_operators=preferred,
    )
    assert result.status is PlanStatus.SOLVED
    assert result.plan is not None and len(result.plan) >= 8
    stats = result.statistics
    assert stats.ground_actions == 40 and stats.reachable_facts == 29
    assert stats.expanded >= 1 and stats.evaluated >= 1
    assert stats.grounding_time > 0 and stats.search_time > 0


def test_gbfs_ff_solves_a_12_block_problem_with_few_expansions() -> None:
    # Work is asserted in expansions (machine-independent); seconds are in bench_classical.py.
    task = load_text("blocksworld", blocksworld_problem(12, seed=12))
    result = plan(task, search="gbfs", heuristic="ff", time_limit=120.0)
    assert result.status is PlanStatus.SOLVED
    stats = result.statistics
    assert stats.expanded <= 100 and stats.evaluated <= 1000


def test_wastar_weight_one_is_astar() -> None:
    task = load("delivery_costs", "two-vans")
    optimal = plan(task, search="astar", heuristic="max")
    weighted = plan(task, search="wastar", heuristic="max", weight=1.0, preferred_operators=False)
    assert optimal.cost == weighted.cost == 23.0


def test_astar_prefers_the_cheaper_plan_under_action_costs() -> None:
    task = load("delivery_costs", "detour")
    assert task.use_costs  # the problem has a (total-cost) metric
    result = plan(task, search="astar", heuristic="max")
    assert result.plan is not None
    assert [str(a) for a in result.plan] == [
        "(load van box a)",
        "(drive van a b)",
        "(drive van b c)",
        "(drive van c d)",
        "(unload van box d)",
    ]
    assert result.cost == 11.0
    unit = plan(load("delivery_costs", "detour", use_costs=False), search="astar", heuristic="max")
    assert unit.plan is not None and len(unit.plan) == 3 and unit.cost == 3.0


def test_relaxed_unreachable_goal_is_unsolvable_without_search() -> None:
    text = """(define (problem stuck) (:domain logistics)
      (:objects c1 c2 - city h1 h2 - location t - truck p - package)
      (:init (in-city h1 c1) (in-city h2 c2) (at t h1) (at p h1))
      (:goal (at p h2)))"""  # no airplane: the package cannot change cities
    result = plan(load_text("logistics", text))
    assert result.status is PlanStatus.UNSOLVABLE
    assert result.plan is None and result.statistics.expanded == 0


@pytest.mark.parametrize("lazy", [False, True])
def test_exhausted_state_space_is_unsolvable(lazy: bool) -> None:
    # Relaxed reachable, but every way of switching the last light off leaves the case in the dark.
    text = """(define (problem trapped) (:domain briefcase)
      (:objects hall kitchen study - room)
      (:init (case-at hall) (door hall kitchen) (door hall study)
             (light-on kitchen) (light-on study) (light-on hall)
             (switch kitchen study) (switch study hall) (switch hall kitchen))
      (:goal (and (case-at hall) (not (exists (?r - room) (light-on ?r))))))"""
    result = plan(load_text("briefcase", text), lazy=lazy)
    assert result.status is PlanStatus.UNSOLVABLE
    assert result.statistics.expanded > 1


def test_tiny_time_limit_reports_timeout() -> None:
    task = load_text("blocksworld", blocksworld_problem(40, seed=3))
    result = plan(task, time_limit=0.01)
    assert result.status is PlanStatus.TIMEOUT
    assert result.plan is None


def test_time_limit_during_search_reports_timeout() -> None:
    task = load_text("blocksworld", blocksworld_problem(14, seed=5))
    result = plan(task, search="astar", heuristic="blind", time_limit=0.3)
    assert result.status is PlanStatus.TIMEOUT
    assert result.statistics.expanded > 0


@pytest.mark.parametrize(
    ("options", "names"),
    [
        ({"search": "dfs"}, ("search", "gbfs", "astar", "wastar")),
        ({"heuristic": "lmcut"}, ("heuristic", "ff", "add", "max", "blind")),
        ({"weight": 0.5}, ("weight",)),
        ({"time_limit": -1.0}, ("time_limit",)),
    ],
)
def test_bad_parameters_raise(options: dict[str, object], names: tuple[str, ...]) -> None:
    with pytest.raises(ParameterError) as error:
        plan(load("blocksworld", "sussman"), **options)  # type: ignore[arg-type]
    for name in names:
        assert name in str(error.value)


def test_action_elimination_drops_detours() -> None:
    task = load("blocksworld", "sussman")
    compiled = CompiledTask(ground(task))
    index = {str(op.action): i for i, op in enumerate(compiled.task.operators)}
    steps = ["(pick-up b)", "(put-down b)", "(unstack c a)", "(put-down c)", "(pick-up b)"]
    steps += ["(stack b c)", "(pick-up a)", "(stack a b)"]
    shorter = eliminate_redundant_actions(compiled, [index[s] for s in steps])
    assert [str(compiled.task.operators[i].action) for i in shorter] == steps[2:]
    # an optimal plan is left alone
    assert eliminate_redundant_actions(compiled, [index[s] for s in steps[2:]]) == [
        index[s] for s in steps[2:]
    ]


def test_goal_true_initially_gives_the_empty_plan() -> None:
    task = load("blocksworld", "sussman")
    trivial = dataclasses.replace(task, goal=Atom("on", ("c", "a")))
    for search in SEARCHES:
        result = plan(trivial, search=search)
        assert result.status is PlanStatus.SOLVED and result.plan == () and result.cost == 0.0


@pytest.mark.parametrize("search", ["gbfs", "wastar", "astar", "lazy-wastar"])
@pytest.mark.parametrize("lazy", [False, True])
def test_cost_bound_keeps_only_cheaper_plans(search: str, lazy: bool) -> None:
    task = load("delivery_costs", "detour")
    at_bound = plan(task, search=search, heuristic="max", lazy=lazy, cost_bound=11.0)
    assert at_bound.status is PlanStatus.UNSOLVABLE  # 11 is the optimum: nothing cheaper
    above = plan(task, search=search, heuristic="max", lazy=lazy, cost_bound=11.5)
    assert above.status is PlanStatus.SOLVED and above.cost == 11.0


def test_batched_greedy_queues_pop_in_per_successor_order() -> None:
    import random

    from solvers.classical.open_lists import BatchedOpenLists, OpenLists

    rng = random.Random(7)
    single, batched = OpenLists(2, True), BatchedOpenLists(2, True)
    counter, taken_single, taken_batched = 0, [], []
    for expansion in range(60):
        values = (float(rng.randint(0, 5)), float(rng.randint(0, 5)))
        operators = [rng.randint(0, 99) for _ in range(rng.randint(1, 6))]
        chosen = [o for o in operators if o % 3 == 0]
        batched.push_batch(values, 1.0, expansion, expansion, 0.0, operators, chosen)
        for o in operators:
            single.push(values, 0.0, 1.0, counter, (expansion, o, 0.0), o % 3 == 0)
            counter += 1
        for queues in (single, batched):
            if expansion % 4 == 0:
                queues.boost()
        for _ in range(rng.randint(0, 4)):  # interleave pops with pushes
            entry = single.pop()
            taken_single.append(None if entry is None else entry[3][:2])
            pair = batched.pop_successor()
            taken_batched.append(None if pair is None else pair[:2])
    while (entry := single.pop()) is not None:
        taken_single.append(entry[3][:2])
    while (pair := batched.pop_successor()) is not None:
        taken_batched.append(pair[:2])
    assert len(taken_single) > 200
    assert taken_batched == taken_single


def test_lazy_weighted_astar_evaluates_only_the_states_it_expands() -> None:
    """``lazy-wastar`` (PDDLStream's ff-wastar planners): the same weighted A*, its states
    evaluated when taken from the queue, not when generated."""
    task = load("blocksworld", "sussman")
    eager = plan(task, search="wastar", weight=3.0)
    lazy = plan(task, search="lazy-wastar", weight=3.0)
    assert eager.status is lazy.status is PlanStatus.SOLVED
    assert lazy.statistics.evaluated <= lazy.statistics.expanded + 1
    assert eager.statistics.evaluated == eager.statistics.generated
    assert lazy.cost >= 6.0  # (the optimum of sussman)
