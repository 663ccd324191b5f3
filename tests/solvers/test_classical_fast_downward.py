"""The optional Fast Downward backend: configuration mapping, plan files, missing install."""

from __future__ import annotations

import dataclasses
import importlib.util
import math
from pathlib import Path

import pytest
from classical_helpers import load, load_text

from sdar_tamp.errors import ParameterError
from sdar_tamp.language import parse_domain, parse_problem
from sdar_tamp.language.formula_model import Atom
from solvers.classical import (
    PlanningTask,
    fast_downward,
    ground,
    plan,
    task_from_problem,
    validated_plan_cost,
)
from solvers.classical.errors import BackendUnavailableError
from solvers.classical.fast_downward import (
    downward_binary,
    fast_downward_arguments,
    fast_downward_script,
    parse_plan,
    plan_task_with_fast_downward,
    plan_with_fast_downward,
    search_engine,
)
from solvers.classical.problem import GroundAction, PlanStatus
from solvers.classical.sas import SasTask, cost_scale, sas_task

needs_fd = pytest.mark.skipif(
    importlib.util.find_spec("up_fast_downward") is None, reason="needs up-fast-downward"
)
BLOCKS = Path(__file__).resolve().parents[2] / "domains" / "blocksworld"


def test_lama_configuration_is_fast_downwards_own_alias() -> None:
    assert fast_downward_arguments("lazy-gbfs", "ff-lmcount") == ["--alias", "lama-first"]


def test_other_configurations_map_onto_search_engines() -> None:
    (flag, engine) = fast_downward_arguments("wastar", "ff", weight=3.0)
    assert flag == "--search"
    assert engine.startswith("let(h0,eval_modify_costs(ff()")
    assert "eager_wastar([h0],preferred=[h0],w=3)" in engine
    (_, astar) = fast_downward_arguments("astar", "max")
    assert astar == "let(h0,hmax(),astar(h0))"
    (_, both) = fast_downward_arguments("gbfs", "ff-lmcount")
    assert "eager_greedy([h0,h1],preferred=[h0])" in both


@pytest.mark.parametrize(("search", "heuristic"), [("gbfs", "hm"), ("astar", "ff-lmcount")])
def test_unmapped_configuration_is_a_parameter_error(search: str, heuristic: str) -> None:
    with pytest.raises(ParameterError, match=r"heuristic|mapping"):
        fast_downward_arguments(search, heuristic)


def test_plan_file_is_parsed_with_its_cost() -> None:
    steps, cost = parse_plan("(pick-up a)\n(stack a b)\n; cost = 7 (general cost)\n")
    assert steps == (GroundAction("pick-up", ("a",)), GroundAction("stack", ("a", "b")))
    assert cost == 7.0
    assert parse_plan("(noop)\n")[1] == 1.0


def test_missing_install_is_reported(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(fast_downward.importlib.util, "find_spec", lambda name: None)
    assert fast_downward_script() is None
    with pytest.raises(BackendUnavailableError, match=r"sdar-tamp\[fd\]"):
        plan_with_fast_downward(BLOCKS / "domain.pddl", BLOCKS / "problems" / "sussman.pddl")


def test_bad_time_limit_is_a_parameter_error() -> None:
    if fast_downward_script() is None:
        pytest.skip("up-fast-downward is not installed")
    with pytest.raises(ParameterError, match="time_limit"):
        plan_with_fast_downward(
            BLOCKS / "domain.pddl", BLOCKS / "problems" / "sussman.pddl", time_limit=0
        )


@pytest.mark.skipif(
    importlib.util.find_spec("up_fast_downward") is None, reason="needs up-fast-downward"
)
@pytest.mark.parametrize(("search", "heuristic"), [("lazy-gbfs", "ff-lmcount"), ("astar", "max")])
def test_fast_downward_solves_sussman(search: str, heuristic: str) -> None:
    result = plan_with_fast_downward(
        BLOCKS / "domain.pddl",
        BLOCKS / "problems" / "sussman.pddl",
        search=search,
        heuristic=heuristic,
        time_limit=60,
    )
    assert result.status is PlanStatus.SOLVED
    assert result.plan is not None and len(result.plan) == 6 == result.cost
    assert result.statistics.expanded >= 1


# --- Fast Downward's search on this package's grounding (SAS+ input) -------------------------


def _sas_blocks(text: str, kind: str) -> list[list[str]]:
    blocks, current = [], None
    for line in text.splitlines():
        if line == f"begin_{kind}":
            current = []
        elif line == f"end_{kind}":
            assert current is not None
            blocks.append(current)
            current = None
        elif current is not None:
            current.append(line)
    return blocks


def _operator_parts(block: list[str]) -> tuple[list[str], list[str], str]:
    """Prevail lines, effect lines and cost of an operator block."""
    prevail = int(block[1])
    effects = int(block[2 + prevail])
    return block[2 : 2 + prevail], block[3 + prevail : 3 + prevail + effects], block[-1]


def test_sas_encoding_of_derived_facts_and_conditional_effects() -> None:
    task = ground(load("briefcase", "lights-out"))
    sas = sas_task(task)
    assert sas.scale == 1
    variables = _sas_blocks(sas.text, "variable")
    assert len(variables) == len(task.facts)
    for fact, (_, layer, values, *_) in enumerate(variables):
        assert values == "2"
        assert (int(layer) >= 0) == (fact in task.derived)
    dark = task.facts.index(Atom("dark", ("hall",)))
    (state,) = _sas_blocks(sas.text, "state")
    light = task.facts.index(Atom("light-on", ("hall",)))
    assert state[light] == "0" and state[dark] == "1"  # true = 0, derived start false
    toggle = next(
        i for i, op in enumerate(task.operators) if str(op.action) == "(toggle hall hall)"
    )
    (block,) = [b for b in _sas_blocks(sas.text, "operator") if b[0] == f"o{toggle}"]
    # no precondition on the light; off-if-on comes before on-if-off; cost 1
    prevail, effects, cost = _operator_parts(block)
    assert str(light) not in {line.split()[0] for line in prevail}
    assert effects == [f"1 {light} 0 {light} -1 1", f"1 {light} 1 {light} -1 0"]
    assert cost == "1"
    rules = _sas_blocks(sas.text, "rule")
    assert len(rules) == len(task.axioms)
    assert all(rule[-1].endswith(" 1 0") for rule in rules)  # false (default) -> true


STRATA_DOMAIN = """(define (domain strata) (:requirements :strips :derived-predicates
  :negative-preconditions) (:predicates (p) (q) (free) (blocked) (done))
  (:derived (free) (p))
  (:derived (blocked) (not (free)))
  (:action make-p :parameters () :precondition (q) :effect (p))
  (:action finish :parameters () :precondition (not (blocked)) :effect (done)))"""
STRATA_PROBLEM = "(define (problem s) (:domain strata) (:init (q)) (:goal (done)))"


def _strata_task() -> PlanningTask:
    domain = parse_domain(STRATA_DOMAIN)
    return task_from_problem(domain, parse_problem(STRATA_PROBLEM, domain))


def test_negation_over_a_derived_fact_gets_a_higher_layer() -> None:
    task = ground(_strata_task())
    variables = _sas_blocks(sas_task(task).text, "variable")
    layer = {str(task.facts[i]): int(block[1]) for i, block in enumerate(variables)}
    assert layer["(p)"] == -1 and layer["(free)"] >= 0
    assert layer["(blocked)"] > layer["(free)"]


@needs_fd
def test_fast_downward_evaluates_layered_axioms() -> None:
    task = _strata_task()
    result = plan_task_with_fast_downward(task, search="astar", heuristic="blind")
    assert result.plan == (GroundAction("make-p"), GroundAction("finish"))


def test_preconditions_decide_effect_conditions() -> None:
    task = ground(load("briefcase", "office"))
    sas = sas_task(task)
    for block in _sas_blocks(sas.text, "operator"):
        prevail, effects, _ = _operator_parts(block)
        decided = {line.split()[0] for line in prevail}
        assert effects
        for effect in effects:
            numbers = effect.split()
            decided |= {numbers[-3]} if numbers[-2] != "-1" else set()
        for effect in effects:
            numbers = effect.split()
            conditioned = set(numbers[1 : 1 + 2 * int(numbers[0]) : 2])
            assert not decided & conditioned


@pytest.mark.parametrize(
    ("costs", "scale"), [([1.0, 2.0, 0.0], 1), ([0.5, 3.0], 10), ([0.25], 100), ([1 / 3], 1000)]
)
def test_costs_are_scaled_to_integers(costs: list[float], scale: int) -> None:
    assert cost_scale(costs) == scale


def test_cost_bound_is_scaled_exclusively() -> None:
    assert SasTask("", 1).scaled_bound(math.inf) is None
    assert SasTask("", 1).scaled_bound(11.0) == 11  # cost 11 is not below 11
    assert SasTask("", 1).scaled_bound(10.5) == 11  # cost 10 < 10.5 < 11
    assert SasTask("", 10).scaled_bound(2.5) == 25
    assert SasTask("", 1000).scaled_bound(1e12) is None


def test_grounded_backend_reports_missing_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(fast_downward.importlib.util, "find_spec", lambda name: None)
    assert downward_binary() is None
    with pytest.raises(BackendUnavailableError, match=r"pip install 'sdar-tamp\[fd\]'"):
        plan_task_with_fast_downward(load("blocksworld", "sussman"))


def test_non_integer_weight_is_refused_for_fast_downward() -> None:
    for search in ("wastar", "lazy-wastar"):
        with pytest.raises(ParameterError, match="weight must be an integer"):
            search_engine(search, "ff", weight=1.5)
    assert search_engine("lazy-wastar", "ff", weight=3.0).endswith(
        "lazy_wastar([h0],preferred=[h0],reopen_closed=true,w=3,cost_type=plusone))"
    )
    assert search_engine("lazy-gbfs", "ff-lmcount", options=",bound=3").endswith(
        "reopen_closed=false,bound=3)))"
    )


@needs_fd
@pytest.mark.parametrize(
    ("domain", "problem", "optimum"),
    [("briefcase", "lights-out", 8), ("briefcase", "office", 16), ("delivery_costs", "detour", 11)],
)
def test_grounded_backend_is_optimal_with_astar(domain: str, problem: str, optimum: int) -> None:
    task = load(domain, problem)
    result = plan_task_with_fast_downward(task, search="astar", heuristic="blind", time_limit=60)
    assert result.status is PlanStatus.SOLVED and result.plan is not None
    assert result.cost == optimum == validated_plan_cost(task, result.plan)
    assert result.statistics.expanded >= 1 and result.statistics.ground_actions > 0


@needs_fd
@pytest.mark.parametrize(("search", "heuristic"), [("lazy-gbfs", "ff-lmcount"), ("wastar", "ff")])
def test_grounded_backend_plans_are_valid(search: str, heuristic: str) -> None:
    task = load("briefcase", "office")
    result = plan_task_with_fast_downward(task, search=search, heuristic=heuristic)
    assert result.status is PlanStatus.SOLVED and result.plan is not None
    assert result.cost == validated_plan_cost(task, result.plan)


@needs_fd
def test_grounded_backend_keeps_the_cost_bound() -> None:
    task = load("delivery_costs", "detour")
    below = plan_task_with_fast_downward(task, search="astar", heuristic="blind", cost_bound=11)
    assert below.status is PlanStatus.UNSOLVABLE
    above = plan_task_with_fast_downward(task, search="astar", heuristic="blind", cost_bound=11.5)
    assert above.status is PlanStatus.SOLVED and above.cost == 11


@needs_fd
def test_grounded_backend_handles_fractional_costs() -> None:
    task = load("delivery_costs", "two-vans")
    task = dataclasses.replace(
        task, numeric_init={key: value * 0.37 for key, value in task.numeric_init.items()}
    )
    ours = plan(task, search="astar", heuristic="blind")
    theirs = plan_task_with_fast_downward(task, search="astar", heuristic="blind")
    assert theirs.status is PlanStatus.SOLVED and theirs.plan is not None
    assert theirs.cost == pytest.approx(ours.cost)
    assert theirs.cost == validated_plan_cost(task, theirs.plan)


@needs_fd
def test_grounded_backend_unreachable_goal_expands_nothing() -> None:
    task = load_text(
        "blocksworld",
        "(define (problem stuck) (:domain blocksworld) (:objects a b)"
        " (:init (on-table a) (on-table b) (clear a) (clear b))"
        " (:goal (on a a)))",
    )
    result = plan_task_with_fast_downward(task)
    assert result.status is PlanStatus.UNSOLVABLE and result.statistics.expanded == 0
