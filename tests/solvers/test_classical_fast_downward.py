"""The optional Fast Downward backend: configuration mapping, plan files, missing install."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from sdar_tamp.errors import ParameterError
from solvers.classical import fast_downward
from solvers.classical.errors import BackendUnavailableError
from solvers.classical.fast_downward import (
    fast_downward_arguments,
    fast_downward_script,
    parse_plan,
    plan_with_fast_downward,
)
from solvers.classical.problem import GroundAction, PlanStatus

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
