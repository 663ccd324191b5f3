"""`sdar plan`: LAMA-style defaults, the search choices and the Fast Downward backend switch."""

from __future__ import annotations

import importlib.util

import pytest

from sdar_tamp.cli import main
from sdar_tamp.resources import domain_file


def _sussman() -> list[str]:
    return [
        "plan",
        str(domain_file("blocksworld")),
        str(domain_file("blocksworld", "problems/sussman.pddl")),
    ]


def test_default_is_lazy_search_with_landmarks(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(_sussman()) == 0
    out = capsys.readouterr().out
    assert "status: solved" in out
    assert "length: 6" in out


@pytest.mark.parametrize("search", ["lazy-gbfs", "gbfs", "astar", "wastar"])
def test_every_search_choice_plans(search: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([*_sussman(), "--search", search, "--heuristic", "ff"]) == 0
    assert "status: solved" in capsys.readouterr().out


def test_no_exploration_plans_with_the_heuristic_queues_only(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main([*_sussman(), "--no-exploration"]) == 0
    out = capsys.readouterr().out
    assert "status: solved" in out and "length: 6" in out


def test_unknown_heuristic_lists_the_choices(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main([*_sussman(), "--heuristic", "hm"])
    assert info.value.code == 2
    assert "ff-lmcount" in capsys.readouterr().err


def test_fast_downward_refuses_unit(capsys: pytest.CaptureFixture[str]) -> None:
    assert main([*_sussman(), "--planner", "fd", "--unit"]) == 2
    assert "--unit" in capsys.readouterr().err


@pytest.mark.skipif(
    importlib.util.find_spec("up_fast_downward") is None, reason="needs up-fast-downward"
)
def test_fast_downward_backend(capsys: pytest.CaptureFixture[str]) -> None:
    assert main([*_sussman(), "--planner", "fd"]) == 0
    out = capsys.readouterr().out
    assert "status: solved" in out and "length: 6" in out
