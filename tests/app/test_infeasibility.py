"""Instances proven unsolvable are reported ``infeasible`` before any search, with the stuck
objects; objects at the edge of graspability (a 0.05 m cube, a 3 cm bar) are planned for."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from sdar_tamp.app import PlannerCache, PlannerConfig, rearrangement_problem, solve_rearrangement
from sdar_tamp.app.pipeline import solve_instance
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D, save_instance
from sdar_tamp.world.scene import Workspace
from solvers.solution import Solution, Status

#: A solve's time budget: generous, so that a busy machine slows a test down but never turns
#: a solvable case into a timeout (the budget is not what these tests check).
BUDGET = 600.0

SIZE = (0.08, 0.04, 0.05)
WORKSPACE = Workspace((-0.25, 0.25), (-0.30, 0.30))


def _boxed_in(tmp_path: Path) -> Path:
    """Three objects 5 mm apart across their closing axis: none can be picked first."""
    objects = tuple(
        ObjectSpec(
            f"o{i}", SIZE, Pose2D(0.0, 0.045 * (i - 1), 0.0), Pose2D(0.15 * (i - 1), -0.2, 0)
        )
        for i in range(3)
    )
    return save_instance(Instance("boxed", WORKSPACE, objects), tmp_path / "boxed.yaml")


def test_a_boxed_in_instance_is_infeasible_before_any_search(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import sdar_tamp.app.solving as solving

    def never(*args: Any, **kwargs: Any) -> Solution:
        raise AssertionError("the search must not run")

    monkeypatch.setattr(solving, "solve", never)
    outcome = solve_instance(_boxed_in(tmp_path), time_limit=BUDGET)
    assert outcome.status == "infeasible" and outcome.plan is None and not outcome.success
    assert "none of o0, o1, o2 can ever be picked first" in outcome.diagnosis[0]
    assert "o1: no grasp clear of o0, o2" in outcome.diagnosis
    assert outcome.figures.planning_time > 0.0


def test_the_proof_can_be_left_out(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import sdar_tamp.app.solving as solving
    from sdar_tamp.world.instance import load_instance

    calls: list[str] = []

    def spy(*args: Any, **kwargs: Any) -> Solution:
        calls.append("solve")
        return Solution(None, status=Status.TIMEOUT, statistics={"planning_time": 1.0})

    monkeypatch.setattr(solving, "solve", spy)
    world = PlannerCache().world(None, PlannerConfig().trajopt)
    r = rearrangement_problem(load_instance(_boxed_in(tmp_path)), world.ctx, planner=world.planner)
    assert solve_rearrangement(r, prove=False).status is Status.TIMEOUT and calls == ["solve"]
    assert solve_rearrangement(r).status is Status.INFEASIBLE and calls == ["solve"]
    # a feasible instance goes on to the search; the proof's time is part of planning time
    free = Instance(
        "free", WORKSPACE, (ObjectSpec("a", SIZE, Pose2D(0, 0.1, 0), Pose2D(0, -0.1, 0)),)
    )
    solution = solve_rearrangement(rearrangement_problem(free, world.ctx, planner=world.planner))
    assert calls == ["solve", "solve"] and solution.status is Status.TIMEOUT
    assert solution.statistics["planning_time"] == 1.0 + solution.statistics["proof_time"]


def test_a_cube_and_a_short_bar_are_planned_for_and_validated(tmp_path: Path) -> None:
    cube = ObjectSpec("cube", (0.05, 0.05, 0.05), Pose2D(-0.1, 0.15, 0.0), Pose2D(-0.1, -0.15, 0.4))
    bar = ObjectSpec("bar", (0.08, 0.04, 0.03), Pose2D(0.1, 0.15, 0.0), Pose2D(0.1, -0.15, -0.3))
    path = save_instance(Instance("edge", WORKSPACE, (cube, bar)), tmp_path / "edge.yaml")
    outcome = solve_instance(path, time_limit=BUDGET)
    assert outcome.status == "solved" and outcome.valid, (outcome.violation, outcome.diagnosis)
