"""Fast Downward as the stream algorithms' classical planner (``solve(planner="fd...")``)."""

from __future__ import annotations

import importlib
import importlib.util
from pathlib import Path

import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.problem import PDDLProblem
from solvers.classical import fast_downward
from solvers.classical.errors import BackendUnavailableError
from solvers.solution import Status
from solvers.solve import parse_planner_choice, solve

needs_fd = pytest.mark.skipif(
    importlib.util.find_spec("up_fast_downward") is None, reason="needs up-fast-downward"
)


def _problem(domain: str) -> PDDLProblem:
    module = importlib.import_module(f"domains.{domain}.samplers")
    problem: PDDLProblem = module.make_problem(seed=0)
    return problem


def _installed(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(fast_downward, "downward_binary", lambda: Path("/opt/fd/downward"))


def test_missing_fast_downward_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(fast_downward.importlib.util, "find_spec", lambda name: None)
    for planner in ("fd", "fd:ff-astar"):
        with pytest.raises(BackendUnavailableError, match=r"pip install 'sdar-tamp\[fd\]'"):
            solve(_problem("kitchen"), algorithm="focused", planner=planner, verbose=False)


def test_our_planner_stays_the_default() -> None:
    assert parse_planner_choice("wastar-ff") == ("sdar", "wastar", "ff", 2.0)
    assert parse_planner_choice("ff-astar") == ("sdar", "astar", "ff", 1.0)


@pytest.mark.parametrize(
    ("planner", "expected"),
    [
        ("fd", ("fd", "wastar", "ff", 2.0)),
        ("FD", ("fd", "wastar", "ff", 2.0)),
        ("fd:ff-astar", ("fd", "astar", "ff", 1.0)),
        ("fd:ff-wastar3", ("fd", "lazy-wastar", "ff", 3.0)),
        ("fd:lazy-gbfs-ff-lmcount", ("fd", "lazy-gbfs", "ff-lmcount", 2.0)),
    ],
)
def test_fd_planner_names(
    monkeypatch: pytest.MonkeyPatch, planner: str, expected: tuple[str, str, str, float]
) -> None:
    _installed(monkeypatch)
    assert parse_planner_choice(planner) == expected


@pytest.mark.parametrize(
    ("planner", "message"),
    [("fd:astar-ff-lmcount", "no Fast Downward mapping"), ("fd:nonsense", "SEARCH-HEURISTIC")],
)
def test_fd_planner_without_a_configuration(
    monkeypatch: pytest.MonkeyPatch, planner: str, message: str
) -> None:
    _installed(monkeypatch)
    with pytest.raises(ParameterError, match=message):
        solve(_problem("kitchen"), planner=planner, verbose=False)


@needs_fd
@pytest.mark.parametrize("algorithm", ["incremental", "focused", "adaptive"])
def test_fd_solves_kitchen_as_our_planner_does(algorithm: str) -> None:
    ours = solve(_problem("kitchen"), algorithm=algorithm, max_time=30, seed=0, verbose=False)
    theirs = solve(
        _problem("kitchen"), algorithm=algorithm, max_time=30, seed=0, verbose=False, planner="fd"
    )
    assert theirs.status is Status.SOLVED
    assert theirs.cost == pytest.approx(ours.cost)
    assert theirs.statistics["search_time"] > 0


@needs_fd
def test_fd_proves_infeasibility() -> None:
    solution = solve(_problem("infeasible"), algorithm="focused", planner="fd", verbose=False)
    assert solution.status is Status.INFEASIBLE
