"""The API entry points check every numeric argument by the rules of ``sdar_tamp.arguments``."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.problem import PDDLProblem
from sdar_tamp.resources import domain_file
from solvers.solution import Status
from solvers.solve import solve

S4 = domain_file("dual_arm_rearrangement", "suites/paper/S4.yaml")

FLIP = """
(define (domain flip)
  (:predicates (off) (on))
  (:action flip :parameters () :precondition (off) :effect (and (on) (not (off)))))
"""


def flip() -> PDDLProblem:
    return PDDLProblem(FLIP, {}, None, {}, [("off",)], ("on",))


BAD = [
    ({"max_time": math.nan}, "max_time must be a number > 0 [s] or inf, got nan"),
    ({"max_time": 0}, "max_time must be"),
    ({"max_time": -math.inf}, "max_time must be"),
    ({"success_cost": math.nan}, "success_cost must be a number >= 0 or inf"),
    ({"success_cost": -1}, "success_cost must be"),
    ({"seed": -1}, "seed must be an integer >= 0, got -1"),
    ({"seed": 1.5}, "seed must be an integer >= 0, got 1.5"),
    ({"seed": True}, "seed must be an integer >= 0"),
    ({"max_complexity": math.nan}, "max_complexity must be"),
    ({"max_complexity": -1}, "max_complexity must be"),
    ({"initial_complexity": 0.5}, "initial_complexity must be an integer >= 0"),
    ({"complexity_step": 0.5}, "complexity_step must be an integer >= 1, got 0.5"),
    ({"max_iterations": math.nan}, "max_iterations must be"),
    ({"max_skeletons": 0}, "max_skeletons must be"),
    ({"search_sample_ratio": math.nan}, "search_sample_ratio must be"),
    ({"max_planner_time": math.nan}, "max_planner_time must be"),
    ({"effort_weight": math.nan}, "effort_weight must be a finite number >= 0"),
]


@pytest.mark.parametrize("algorithm", ["adaptive", "incremental", "sdar"])
@pytest.mark.parametrize(("kwargs", "message"), BAD)
def test_solve_checks_every_number_for_every_algorithm(
    algorithm: str, kwargs: dict[str, Any], message: str
) -> None:
    with pytest.raises(ParameterError, match="^" + message.replace("[", r"\[").replace("]", r"\]")):
        solve(flip(), algorithm=algorithm, verbose=False, **kwargs)


def test_solve_accepts_the_limits_of_the_ranges() -> None:
    solution = solve(
        flip(), algorithm="adaptive", max_time=math.inf, success_cost=0, max_complexity=0,
        initial_complexity=0, seed=0, effort_weight=0, verbose=False,
    )  # fmt: skip
    assert solution.status is Status.SOLVED


def test_solve_instance_refuses_bad_numbers_before_loading_anything() -> None:
    from sdar_tamp.app import solve_instance

    missing = Path("no-such-instance.yaml")
    for kwargs, message in [
        ({"time_limit": math.nan}, r"time_limit must be a finite number > 0 \[s\], got nan"),
        ({"time_limit": math.inf}, "time_limit must be a finite number"),
        ({"seed": -2}, "seed must be an integer >= 0, got -2"),
        ({"task_planner": "greedy"}, "task_planner must be one of sdar, baseline"),
        ({"motion_planner": "fast"}, "motion_planner must be one of sdar, plain, sequential"),
    ]:
        with pytest.raises(ParameterError, match=message):
            solve_instance(missing, **kwargs)


def test_solve_rearrangement_uses_the_checks_of_solve() -> None:
    from sdar_tamp.app import rearrangement_problem, solve_rearrangement
    from sdar_tamp.world.instance import load_instance
    from streams.context import WorldContext

    ctx = WorldContext.load()
    instance = load_instance(S4)
    with pytest.raises(ParameterError, match="seed must be an integer >= 0, got -1"):
        rearrangement_problem(instance, ctx, seed=-1)
    with pytest.raises(ParameterError, match="gripper_time must be a finite number >= 0"):
        rearrangement_problem(instance, ctx, gripper_time=math.nan)
    problem = rearrangement_problem(instance, ctx)
    for max_time in (math.nan, 0.0, -1.0, "60"):
        with pytest.raises(ParameterError, match=r"max_time must be a number > 0 \[s\] or inf"):
            solve_rearrangement(problem, "sdar", max_time)  # type: ignore[arg-type]


def test_show_checks_fps_and_the_suffix_before_reading(tmp_path: Path) -> None:
    from sdar_tamp.viewer.pictures import show

    missing = tmp_path / "none.yaml"
    with pytest.raises(ParameterError, match=r"fps must be a finite number > 0 \[1/s\], got 0"):
        show(missing, None, tmp_path / "x.png", fps=0)
    with pytest.raises(ParameterError, match="output must end in one of"):
        show(missing, None, tmp_path / "x.weird")
