"""One timeline per arm (:mod:`sdar_tamp.schedule.timelines`): arms that start their next task
while the others still move, the task order's dependencies kept, collisions waited out, and
the application's fallback when a schedule does not replay."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.app.execution import execution_options, schedule_plan
from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_rules import STILL_TOL
from sdar_tamp.replay import validate_plan
from sdar_tamp.schedule import Schedule
from sdar_tamp.schedule.pieces import arm_blocks, arm_columns
from sdar_tamp.schedule.scheduler import retimer
from sdar_tamp.schedule.sweep import Conflict, TimedEvent, WorldSweep
from sdar_tamp.schedule.timelines import (
    TimelineOptions,
    Timelines,
    dependencies,
    schedule_timelines,
)
from sdar_tamp.world.instance import Instance, load_instance
from sdar_tamp.world.suites import shipped_suite_dir
from sdar_tamp.world.transforms import FloatArray
from streams.context import WorldContext

SOLVED = Path(__file__).resolve().parent / "solved"


def _solved(ctx: WorldContext, name: str) -> tuple[Instance, PlanFile]:
    instance = load_instance(shipped_suite_dir("paper") / f"{name}.yaml")
    plan = load_plan(SOLVED / f"{name}.plan.json")
    return instance, plan


@pytest.fixture(scope="module")
def uneven(ctx: WorldContext) -> tuple[Instance, PlanFile, Schedule]:
    """R5 of the paper suite (five independent objects), and its timelines."""
    instance, plan = _solved(ctx, "R5")
    return (
        instance,
        plan,
        schedule_timelines(plan, instance, ctx.scene, execution_options(ctx.scene)),
    )


def _starts_while_another_moves(plan: PlanFile) -> int:
    """Samples where an arm starts from rest while another arm is in the middle of a motion
    (moving over the intervals before and after)."""
    moving = [
        np.abs(np.diff(plan.q[:, arm_columns(plan, a)], axis=0)).max(axis=1) > STILL_TOL
        for a in range(len(plan.arms))
    ]
    count = 0
    for a, m in enumerate(moving):
        for i in np.flatnonzero(~m[:-1] & m[1:]) + 1:  # a rests over i - 1, moves over i
            count += any(o[i - 1] and o[i] for b, o in enumerate(moving) if b != a)
    return count


def test_an_arm_starts_its_next_task_while_the_other_still_moves(
    ctx: WorldContext, uneven: tuple[Instance, PlanFile, Schedule]
) -> None:
    instance, plan, s = uneven
    assert s.asynchronous, s.reason
    assert s.async_duration is not None and s.plan.duration < plan.duration
    assert s.order == "timelines"
    report = validate_plan(instance, s.plan, ctx.scene)
    assert report.ok, report.violation
    assert _starts_while_another_moves(plan) == 0  # synchronous: steps start together
    assert _starts_while_another_moves(s.plan) >= 2
    figures = dict(s.figures)
    assert figures["motions"] == sum(len(arm_blocks(plan, ctx.scene, a, 0.02)) for a in range(2))
    # every object's events in the synchronous order
    for name in instance.names:
        sync = [(e.arm, e.type) for e in plan.events if e.object == name]
        assert [(e.arm, e.type) for e in s.plan.events if e.object == name] == sync


def test_a_release_waits_for_the_grasp_that_frees_its_spot(ctx: WorldContext) -> None:
    """D5: two swaps. Each swap's release depends on the other arm's grasp of the object
    resting at its goal, and the timelines keep that order."""
    instance, plan = _solved(ctx, "D5")
    after = dependencies(plan, instance, WorldSweep(instance, ctx.scene, 0.005))
    swaps = {i: js for i, js in after.items() if js}
    assert len(swaps) >= 4
    for i, js in swaps.items():
        e = plan.events[i]
        assert e.type == "release"
        for j in js:
            g = plan.events[j]
            assert g.type == "grasp" and g.object != e.object and g.t < e.t
            objects = {o.name: o for o in instance.objects}
            goal, start = objects[e.object].goal, objects[g.object].start
            assert math.dist((goal.x, goal.y), (start.x, start.y)) < 0.1
    s = schedule_timelines(plan, instance, ctx.scene, execution_options(ctx.scene))
    assert validate_plan(instance, s.plan, ctx.scene).ok
    if s.asynchronous:
        when = {(e.arm, e.type, e.object): e.t for e in s.plan.events}
        for i, js in swaps.items():
            e = plan.events[i]
            for j in js:
                g = plan.events[j]
                assert when[(g.arm, g.type, g.object)] <= when[(e.arm, e.type, e.object)]


class _Blind(WorldSweep):
    """A mutant of the scheduler's replay that sees no conflict."""

    def run(self, k0: int, q: FloatArray, events: list[TimedEvent]) -> Conflict | None:  # type: ignore[override]
        return None


@pytest.fixture(scope="module")
def blind(ctx: WorldContext, uneven: tuple[Instance, PlanFile, Schedule]) -> PlanFile:
    """R5's timelines placed with a replay that sees no conflict."""
    instance, plan, _ = uneven
    scene = ctx.scene
    options = execution_options(scene)
    retimers = [retimer(scene, i, options) for i in range(2)]
    blocks = [arm_blocks(plan, scene, i, options.tick, True, retimers[i]) for i in range(2)]
    sweep = _Blind(instance, scene, options.max_tcp_step)
    after = dependencies(plan, instance, WorldSweep(instance, scene, options.max_tcp_step))
    return Timelines(plan, blocks, sweep, options, after, retimers, TimelineOptions()).run()


def test_without_the_sweep_the_timelines_collide_and_with_it_they_wait(
    ctx: WorldContext, uneven: tuple[Instance, PlanFile, Schedule], blind: PlanFile
) -> None:
    """A blind replay lets the arms start as soon as their dependencies allow (and shortcut
    through anything): the validator rejects that plan. The real sweep inserts waits."""
    instance, _, s = uneven
    report = validate_plan(instance, blind, ctx.scene)
    assert not report.ok and report.violation is not None
    assert report.violation.kind == "collision"
    assert blind.duration < s.plan.duration  # what the waits and the detours cost
    assert dict(s.figures)["wait_other_arms"] > 0.0


def test_a_timelines_schedule_that_collides_falls_back(
    ctx: WorldContext,
    uneven: tuple[Instance, PlanFile, Schedule],
    blind: PlanFile,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A timelines result that collides: the application replays it, drops it and keeps the
    step re-timing (valid), never the colliding plan."""
    instance, plan, s = uneven
    bad = dataclasses.replace(s, plan=blind, async_duration=blind.duration)

    def broken(*args: object, **kwargs: object) -> Schedule:
        return bad

    monkeypatch.setattr("sdar_tamp.app.execution.schedule_timelines", broken)
    kept = schedule_plan(plan, instance, ctx.scene, scheduler="timelines")
    assert kept.plan is not blind and kept.order != "timelines"
    assert kept.plan.duration <= plan.duration
    assert validate_plan(instance, kept.plan, ctx.scene).ok


def test_timelines_keep_the_shorter_of_the_two_schedules(
    ctx: WorldContext, uneven: tuple[Instance, PlanFile, Schedule]
) -> None:
    instance, plan, s = uneven
    retimed = schedule_plan(plan, instance, ctx.scene)
    both = schedule_plan(plan, instance, ctx.scene, scheduler="timelines")
    assert both.plan.duration == pytest.approx(min(retimed.plan.duration, s.plan.duration))
    assert validate_plan(instance, both.plan, ctx.scene).ok


def test_past_the_budget_no_timelines_schedule_is_returned(
    ctx: WorldContext, uneven: tuple[Instance, PlanFile, Schedule]
) -> None:
    instance, plan, _ = uneven
    options = execution_options(ctx.scene)
    s = schedule_timelines(plan, instance, ctx.scene, options, TimelineOptions(max_checks=1))
    assert not s.asynchronous and s.plan is plan and s.async_duration is None
    assert "out of collision checks" in s.reason


def test_options_are_checked(ctx: WorldContext) -> None:
    for bad in ({"tries": -1}, {"tries": True}, {"lift": math.nan}, {"lift": -0.1},
                {"max_checks": 0}):  # fmt: skip
        with pytest.raises(ParameterError, match=next(iter(bad))):
            TimelineOptions(**bad)  # type: ignore[arg-type]
    instance, plan = _solved(ctx, "R5")
    with pytest.raises(ParameterError, match="scheduler must be one of retime, timelines"):
        schedule_plan(plan, instance, ctx.scene, scheduler="fast")
