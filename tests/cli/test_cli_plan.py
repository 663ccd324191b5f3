"""`sdar plan`: LAMA-style defaults, the search choices and the Fast Downward backend switch."""

from __future__ import annotations

import importlib.util
from pathlib import Path

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


TEMPORAL_DOMAIN = """
(define (domain lights)
  (:requirements :durative-actions)
  (:predicates (on ?l) (warm ?l))
  (:functions (heat ?l))
  (:durative-action heat
   :parameters (?l)
   :duration (= ?duration (heat ?l))
   :condition (over all (on ?l))
   :effect (and (at start (on ?l)) (at end (warm ?l)) (at end (not (on ?l))))))
"""
TEMPORAL_PROBLEM = """
(define (problem two) (:domain lights) (:objects l1 l2)
  (:init (= (heat l1) 1.5) (= (heat l2) 2))
  (:goal (and (warm l1) (warm l2) (not (on l1)))) (:metric minimize (total-time)))
"""


def test_a_temporal_plan_is_printed_in_vals_format(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    domain, problem = tmp_path / "d.pddl", tmp_path / "p.pddl"
    domain.write_text(TEMPORAL_DOMAIN)
    problem.write_text(TEMPORAL_PROBLEM)
    assert main(["plan", str(domain), str(problem), "--search", "astar"]) == 0
    lines = capsys.readouterr().out.splitlines()
    timed = [line for line in lines if "]" in line]
    assert sorted(line.split(": ", 1)[1] for line in timed) == [
        "(heat l1) [1.500]",
        "(heat l2) [2.000]",
    ]
    assert {line.split(":")[0] for line in timed} in ({"0.000", "1.500"}, {"0.000", "2.000"})
    assert "cost: 3.5" in "\n".join(lines)


@pytest.mark.skipif(importlib.util.find_spec("up_fast_downward") is None, reason="needs [fd]")
def test_fast_downward_searches_a_temporal_domain_on_the_compilation(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    domain, problem = tmp_path / "d.pddl", tmp_path / "p.pddl"
    domain.write_text(TEMPORAL_DOMAIN)
    problem.write_text(TEMPORAL_PROBLEM)
    assert main(["plan", str(domain), str(problem), "--planner", "fd"]) == 0
    assert "(heat l1) [1.500]" in capsys.readouterr().out
