"""The application layer: one planner configuration for every entry point, typed run
records, plan actions read through the vocabulary, the planner cache."""

from __future__ import annotations

import dataclasses
import logging
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from sdar_tamp.app import (
    ActionDecoder,
    PlannerCache,
    PlannerConfig,
    TaskRecord,
    rearrangement_problem,
    solve_rearrangement,
)
from sdar_tamp.app.plan_export import GripperAction
from sdar_tamp.app.problem import grasp_set_sizes, table_plane
from sdar_tamp.errors import ParameterError
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.problem import PDDLProblem
from sdar_tamp.resources import domain_file
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D
from sdar_tamp.world.scene import Workspace
from solvers.sdar.solver import SdarOptions
from solvers.solution import Action, Solution, TaskTrace
from solvers.solve import solve
from streams.context import WorldContext
from streams.grasps import GraspOptions
from streams.motion.optimiser_cache import OptimiserCache
from streams.motion.optimiser_records import TrajOptOptions
from streams.motion.planner import MotionPlanner

#: A solve's time budget: generous, so that a busy machine slows a test down but never turns
#: a solvable case into a timeout (the budget is not what these tests check).
BUDGET = 600.0

SQUARE = (0.04, 0.04, 0.05)  # graspable across both sides: 12 grasps in the default set
WORKSPACE = Workspace((-0.25, 0.25), (-0.30, 0.30))


def _one() -> Instance:
    spec = ObjectSpec("a", SQUARE, Pose2D(-0.1, 0.15, 0.0), Pose2D(-0.1, -0.15, 0.3))
    return Instance("one", WORKSPACE, (spec,))


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"task_planner": "greedy"}, "task_planner must be one of sdar, baseline"),
        ({"motion_planner": "fast"}, "motion_planner must be one of sdar, plain, sequential"),
        ({"max_time": math.nan}, r"max_time must be a number > 0 \[s\] or inf"),
        ({"seed": -1}, "seed must be an integer >= 0, got -1"),
        ({"gripper_time": -0.1}, "gripper_time must be a finite number >= 0"),
        ({"sdar": SdarOptions(max_time=5.0)}, "sdar.max_time is set by the configuration"),
        ({"sdar": SdarOptions(progress=print)}, "sdar.progress is set by the configuration"),
        (
            {"sdar": SdarOptions(one_arm_at_a_time=True)},
            "sdar.one_arm_at_a_time .*motion_planner='sequential'",
        ),
        ({"grasps": (0.5,)}, "grasps must be a GraspOptions, got tuple"),
        ({"trajopt": {}}, "trajopt must be a TrajOptOptions, got dict"),
    ],
)
def test_planner_config_refuses_bad_values(changes: dict[str, Any], message: str) -> None:
    with pytest.raises(ParameterError, match=message):
        PlannerConfig(**changes)


def test_grasp_options_refuse_tilts_outside_the_open_quarter_turn() -> None:
    with pytest.raises(ParameterError, match=r"grasp tilts must lie in \(0, pi/2\)"):
        GraspOptions(tilts=(np.pi / 2,))


@pytest.mark.parametrize(
    ("motion", "one_arm", "quick"),
    [("sdar", False, 5), ("plain", False, 0), ("sequential", True, 0)],
)
def test_sdar_options_follow_the_motion_planner(motion: str, one_arm: bool, quick: int) -> None:
    config = PlannerConfig(
        motion_planner=motion, max_time=7.0, sdar=SdarOptions(quick_attempts=5, grasps=9)
    )
    options = config.sdar_options(progress=print)
    assert (options.one_arm_at_a_time, options.quick_attempts) == (one_arm, quick)
    assert (options.max_time, options.progress, options.grasps) == (7.0, print, 9)


def test_replace_keeps_fields_given_as_none() -> None:
    config = PlannerConfig(seed=3).replace(seed=None, task_planner="baseline")
    assert (config.seed, config.task_planner) == (3, "baseline")


def test_both_entry_points_pass_the_same_sdar_options(
    ctx: WorldContext, planner: MotionPlanner, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``solve_rearrangement`` is ``solve(..., algorithm="sdar", sdar_options=...)`` with the
    options of the rearrangement's configuration (here: the sequential motion planner)."""
    import sdar_tamp.app.solving as solving

    calls: list[dict[str, Any]] = []

    def spy(problem: PDDLProblem, **kwargs: Any) -> Solution:
        calls.append(kwargs)
        return Solution(None)

    monkeypatch.setattr(solving, "solve", spy)
    config = PlannerConfig(sdar=SdarOptions(grasps=12, candidates=4))
    r = rearrangement_problem(_one(), ctx, config=config, motion="sequential", planner=planner)
    solve_rearrangement(r, "baseline", 9.0)
    (kwargs,) = calls
    assert kwargs["algorithm"] == "sdar" and kwargs["task_planner"] == "baseline"
    assert kwargs["max_time"] == 9.0
    expected = dataclasses.replace(config.sdar, max_time=9.0, one_arm_at_a_time=True)
    plane = table_plane(ctx)  # where poses lie: the cell's (used beyond two arms)
    assert kwargs["sdar_options"] == dataclasses.replace(expected, quick_attempts=0, plane=plane)
    configured = r.config.replace(max_time=9.0).sdar_options()
    assert kwargs["sdar_options"] == dataclasses.replace(configured, plane=plane)


def test_plain_solve_of_a_rearrangement_plans_as_solve_rearrangement(
    ctx: WorldContext, planner: MotionPlanner, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``solve(r.problem, algorithm="sdar")`` takes the task planner and SDAR-M options the
    rearrangement was configured with (carried by the problem), as ``solve_rearrangement``;
    arguments given to ``solve`` win."""
    import solvers.sdar.solver as sdar_solver

    seen: list[tuple[str, SdarOptions]] = []

    class Spy:
        def __init__(self, problem: Any, task: Any, options: SdarOptions, info: Any) -> None:
            seen.append((type(task).__name__, options))

        def solve(self) -> Solution:
            return Solution(None)

    monkeypatch.setattr(sdar_solver, "SdarSolver", Spy)
    config = PlannerConfig(task_planner="baseline", sdar=SdarOptions(grasps=12, candidates=4))
    r = rearrangement_problem(_one(), ctx, config=config, motion="sequential", planner=planner)
    solve(r.problem, algorithm="sdar", max_time=9.0, verbose=False)
    solve(r.problem, algorithm="sdar", max_time=9.0, task_planner="sdar", verbose=False)
    explicit = SdarOptions(candidates=2)
    solve(r.problem, algorithm="sdar", max_time=9.0, sdar_options=explicit, verbose=False)
    expected = dataclasses.replace(
        r.config.replace(max_time=9.0).sdar_options(), plane=table_plane(ctx)
    )
    assert expected.one_arm_at_a_time and expected.grasps == 12
    assert seen[0][1] == expected and seen[1][1] == expected
    assert seen[2][1] == dataclasses.replace(explicit, max_time=9.0)
    assert seen[0][0] != seen[1][0]  # the baseline by default, SDAR-T when asked


def test_solve_refuses_unknown_solve_defaults() -> None:
    from domains.pick_place_2d.samplers import make_problem

    problem = make_problem()
    problem.solve_defaults = {"planner": "ff-astar"}
    with pytest.raises(ParameterError, match="solve_defaults may hold task_planner, sdar_options"):
        solve(problem, algorithm="sdar")
    problem.solve_defaults = [("task_planner", "sdar")]  # type: ignore[assignment]
    with pytest.raises(ParameterError, match="solve_defaults must be a mapping, got list"):
        solve(problem, algorithm="sdar")


def test_solve_checks_sdar_options() -> None:
    from domains.pick_place_2d.samplers import make_problem

    with pytest.raises(ParameterError, match="sdar_options applies to algorithm 'sdar' only"):
        solve(make_problem(), algorithm="adaptive", sdar_options=SdarOptions())
    with pytest.raises(ParameterError, match="sdar_options must be a SdarOptions, got int"):
        solve(make_problem(), algorithm="sdar", sdar_options=5)  # type: ignore[arg-type]


def test_a_larger_grasp_set_reaches_the_stream_and_its_cut_is_logged(
    ctx: WorldContext, planner: MotionPlanner, caplog: pytest.LogCaptureFixture
) -> None:
    grasps = GraspOptions(tilts=(np.pi / 8, np.pi / 4))  # 5 angles x 2 sides x 2 wrists
    config = PlannerConfig(grasps=grasps)
    assert grasp_set_sizes(_one(), ctx, config) == {"a": 20}
    with caplog.at_level(logging.INFO, logger="sdar_tamp.app"):
        r = rearrangement_problem(_one(), ctx, config=config, planner=planner)
    sample = r.problem.stream_map["sample-grasp"]
    # the grasp set, then the pair grasps (20 and 30 degrees: 4 angles x 2 sides x 2 wrists)
    assert len(_outputs(sample("a"))) == 20 + 16
    assert any("tries the first 6 grasps" in m and "up to 20" in m for m in caplog.messages)
    caplog.clear()
    wide = config.replace(sdar=SdarOptions(grasps=20))
    with caplog.at_level(logging.INFO, logger="sdar_tamp.app"):
        rearrangement_problem(_one(), ctx, config=wide, planner=planner)
    assert not any("tries the first" in m for m in caplog.messages)


def _outputs(generator: Any) -> list[Any]:
    """Every output of a wrapped stream generator (it yields lists of output tuples)."""
    return [output for batch in generator for output in batch]


def test_actions_are_read_by_name_through_the_vocabulary(
    ctx: WorldContext, optimisers: OptimiserCache
) -> None:
    r = rearrangement_problem(_one(), ctx, planner=MotionPlanner(ctx, optimisers=optimisers))
    decoder = ActionDecoder(r.problem.domain, r.problem.streams)
    g1, g2 = object(), object()
    args = ("d", "left", "o1", "p1", g1, "q1", "right", "o2", "p2", g2, "q2")
    pick, parts = decoder.gripper(Action("pick-both", args))
    assert pick and [(p.arm, p.obj, p.grasp) for p in parts] == [
        ("left", "o1", g1),
        ("right", "o2", g2),
    ]
    place, (one,) = decoder.gripper(Action("place", ("right", "o", "p", g1, "q", "d")))
    assert not place and one == GripperAction("right", "o", g1)  # type: ignore[arg-type]
    assert decoder.is_move(Action("move", ("d1", "t", "d2")))
    with pytest.raises(ParameterError, match="move: no trajectory"):
        decoder.trajectory(Action("move", ("d1", "t", "d2")))
    with pytest.raises(ParameterError, match="'wave' is neither a move nor a gripper action"):
        decoder.gripper(Action("wave", ()))


def test_a_domain_without_the_vocabulary_cannot_be_decoded() -> None:
    text = domain_file("dual_arm_rearrangement").read_text(encoding="utf-8")
    domain = parse_domain(text.replace("(:action place\n", "(:action put\n"))
    problem_streams = rearrangement_streams()
    with pytest.raises(ParameterError, match=r"the domain has no action\(s\) place$"):
        ActionDecoder(domain, problem_streams)


def test_a_domain_without_two_gripper_actions_is_decoded() -> None:
    """The two-gripper actions are optional: a domain (say, for k arms) that works several
    grippers by consecutive one-gripper actions is read without them."""
    text = domain_file("dual_arm_rearrangement").read_text(encoding="utf-8")
    text = text.replace("(:action place-both", "(:action put-both")
    decoder = ActionDecoder(parse_domain(text), rearrangement_streams())
    g = object()
    place, (one,) = decoder.gripper(Action("place", ("right", "o", "p", g, "q", "d")))
    assert not place and one == GripperAction("right", "o", g)  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match="'place-both' is neither a move nor a gripper"):
        decoder.gripper(Action("place-both", ()))


def rearrangement_streams() -> Any:
    from sdar_tamp.language.streams import parse_stream_file

    domain = parse_domain(domain_file("dual_arm_rearrangement").read_text(encoding="utf-8"))
    text = domain_file("dual_arm_rearrangement", "stream.pddl").read_text(encoding="utf-8")
    return parse_stream_file(text, domain)


def test_task_records_are_typed_and_share_wasted_time() -> None:
    record = TaskRecord.from_trace(
        TaskTrace(
            kind="swap", objects=("a", "b"), arms=("left", "right"),
            to_buffer=(False, True), selection_time=0.4, motion_time=1.0,
            motions=2, tried=3, motion_times=(0.3, 0.5),
        )
    )  # fmt: skip
    assert record.buffer_moves == 1 and record.objects == ("a", "b")
    steps = record.step_times()
    assert [s.selection for s in steps] == [0.2, 0.2]
    assert [round(s.motion, 9) for s in steps] == [0.4, 0.6]
    assert math.isclose(sum(s.total for s in steps), 1.4)
    with pytest.raises(dataclasses.FrozenInstanceError):
        record.kind = "pair"  # type: ignore[misc]


def test_planner_cache_builds_once_per_scene_and_optimiser_options() -> None:
    cache = PlannerCache()
    first = cache.world(None, TrajOptOptions())
    again = cache.world(None, TrajOptOptions())
    assert again.ctx is first.ctx and again.planner is first.planner and cache.builds == 1
    other = cache.world(None, TrajOptOptions(knots=12))
    assert other.planner is not first.planner and cache.builds == 2
    scene = Path(domain_file("dual_arm_rearrangement", "cells/ur5e_facing.yaml"))
    if scene.exists():
        cache.world(scene, TrajOptOptions(knots=12))
        assert cache.builds == 3


def test_the_command_line_reaches_the_planner_config(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import sdar_tamp.app.pipeline as command
    from sdar_tamp.cli import main

    instance = str(domain_file("dual_arm_rearrangement", "suites/paper/S4.yaml"))
    seen: list[PlannerConfig] = []

    class Stop(Exception):
        pass

    def capture(path: Path, config: PlannerConfig, **kwargs: Any) -> None:
        seen.append(config)
        raise Stop

    monkeypatch.setattr(command, "solve_instance", capture)
    args = ["solve", instance, "-q", "--grasps", "10", "--motion-planner", "sequential"]
    with pytest.raises(Stop):
        main([*args, "--time-limit", "5", "--seed", "2", "--execution", "async"])
    config = seen[0]
    assert config.sdar.grasps == 10 and config.motion_planner == "sequential"
    assert (config.max_time, config.seed, config.execution) == (5.0, 2, "async")
    with pytest.raises(Stop):
        main(["solve", instance, "-q"])
    assert seen[-1].execution == "async"  # the default of `sdar solve`
    with pytest.raises(Stop):
        main(["solve", instance, "-q", "--execution", "timelines"])
    assert seen[-1].execution == "timelines"
    with pytest.raises(SystemExit):
        main(["solve", instance, "--execution", "later"])
    assert "argument --execution: invalid choice: 'later'" in capsys.readouterr().err
    with pytest.raises(ParameterError, match="execution must be one of sync, async, timelines"):
        PlannerConfig(execution="later")
    with pytest.raises(SystemExit):
        main(["solve", instance, "--grasps", "0"])
    assert "argument --grasps: expected an integer >= 1" in capsys.readouterr().err


def test_an_asynchronous_run_is_scheduled_validated_and_reported(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``execution="async"``: the solved plan goes through the scheduler before the replay;
    the run reports the scheduling time, and the plan says which execution it holds."""
    from sdar_tamp.app import execution
    from sdar_tamp.app.pipeline import solve_instance
    from sdar_tamp.app.summary import format_summary
    from sdar_tamp.world.instance import save_instance

    a = ObjectSpec("a", SQUARE, Pose2D(-0.1, 0.15, 0.0), Pose2D(0.1, -0.15, 0.3))
    b = ObjectSpec("b", SQUARE, Pose2D(0.1, 0.15, 0.0), Pose2D(-0.1, -0.15, 0.0))
    path = save_instance(Instance("two", WORKSPACE, (a, b)), tmp_path / "two.yaml")
    stages: list[str] = []
    replays: list[object] = []
    real = execution.validate_plan

    def counting(*args: Any, **kwargs: Any) -> Any:
        replays.append(args[1])
        return real(*args, **kwargs)

    monkeypatch.setattr("sdar_tamp.app.execution.validate_plan", counting)
    monkeypatch.setattr("sdar_tamp.app.pipeline.validate_plan", counting)
    outcome = solve_instance(
        path, PlannerConfig(execution="async"), time_limit=BUDGET, stage=stages.append
    )
    assert outcome.plan is not None and outcome.valid, outcome.violation
    assert stages == ["scheduling", "validating"]  # named as they start
    assert replays == [outcome.plan]  # the plan kept is replayed once
    assert outcome.figures.schedule_time > 0.0
    metrics = outcome.plan.metrics
    assert outcome.bound is not None and outcome.bound.arms == 2
    assert 0.0 < outcome.bound.seconds < float(metrics.execution_time)  # async or not
    ratio = float(metrics.execution_time) / outcome.bound.seconds
    assert outcome.execution_over_bound == pytest.approx(ratio)
    assert f"bound {outcome.bound.seconds:.1f} s ({ratio:.2f}x)" in format_summary(outcome)
    assert "with both arms moving at once" in format_summary(outcome)
    plan = outcome.plan
    three = dataclasses.replace(
        outcome, plan=dataclasses.replace(plan, arms=(*plan.arms, plan.arms[0]))
    )
    assert "with two arms or more moving at once" in format_summary(three)
    if metrics.execution == "async":
        assert float(metrics.execution_time) < float(metrics.execution_time_sync)
        assert "asynchronous (synchronous" in format_summary(outcome)
    else:
        assert "synchronous kept" in format_summary(outcome)


def test_a_timelines_run_keeps_the_shorter_schedule_and_replays_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``execution="timelines"``: both schedules are made, the scheduler is told which, and
    the plan kept is valid and never longer than the synchronous one."""
    from sdar_tamp.app import execution
    from sdar_tamp.app.pipeline import solve_instance
    from sdar_tamp.world.instance import save_instance

    a = ObjectSpec("a", SQUARE, Pose2D(-0.1, 0.15, 0.0), Pose2D(0.1, -0.15, 0.3))
    b = ObjectSpec("b", SQUARE, Pose2D(0.1, 0.15, 0.0), Pose2D(-0.1, -0.15, 0.0))
    path = save_instance(Instance("two", WORKSPACE, (a, b)), tmp_path / "two.yaml")
    made: list[str] = []
    real = execution.schedule_timelines

    def counting(*args: Any, **kwargs: Any) -> Any:
        made.append("timelines")
        return real(*args, **kwargs)

    monkeypatch.setattr("sdar_tamp.app.execution.schedule_timelines", counting)
    outcome = solve_instance(path, PlannerConfig(execution="timelines"), time_limit=BUDGET)
    assert outcome.plan is not None and outcome.valid, outcome.violation
    assert made == ["timelines"]
    metrics = outcome.plan.metrics
    if metrics.execution == "async":
        assert float(metrics.execution_time) < float(metrics.execution_time_sync)


def test_an_assigned_run_makes_every_schedule_and_keeps_a_valid_one_never_longer(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``execution="assigned"``: the moves are assigned anew (with motions planned for the
    arms), the other two schedules are made too, and the plan kept is valid and never longer
    than the synchronous one."""
    from sdar_tamp.app import execution
    from sdar_tamp.app.pipeline import solve_instance
    from sdar_tamp.world.instance import save_instance

    a = ObjectSpec("a", SQUARE, Pose2D(-0.1, 0.15, 0.0), Pose2D(0.1, -0.15, 0.3))
    b = ObjectSpec("b", SQUARE, Pose2D(0.1, 0.15, 0.0), Pose2D(-0.1, -0.15, 0.0))
    path = save_instance(Instance("two", WORKSPACE, (a, b)), tmp_path / "two.yaml")
    made: list[str] = []
    for name in ("schedule_timelines", "schedule_assigned"):
        real = getattr(execution, name)

        def counting(*args: Any, _real: Any = real, _name: str = name, **kwargs: Any) -> Any:
            made.append(_name)
            return _real(*args, **kwargs)

        monkeypatch.setattr(f"sdar_tamp.app.execution.{name}", counting)
    outcome = solve_instance(path, PlannerConfig(execution="assigned"), time_limit=BUDGET)
    assert outcome.plan is not None and outcome.valid, outcome.violation
    assert sorted(made) == ["schedule_assigned", "schedule_timelines"]
    metrics = outcome.plan.metrics
    if metrics.execution in ("async", "assigned"):
        assert float(metrics.execution_time) < float(metrics.execution_time_sync)
