"""Motions placed in time against the other arms' committed, time-parameterised trajectories
(:meth:`sdar_tamp.schedule.scheduler.Placement.place`, which the assignment of moves commits
every reach and carry with): in the four-arm test cell the west arm reaches over the middle of
the table and goes back home; the east arm, whose tool ends where the west arm's was, passes
behind it without waiting when it gets there after the west arm has left, and waits (the
sweep naming both arms) when it would get there first."""

from __future__ import annotations

import math

import numpy as np
import pytest
from karm_cells import build, relay, tool_at

from sdar_tamp.plan_file import PlanFile
from sdar_tamp.replay import validate_plan
from sdar_tamp.schedule.pieces import Block
from sdar_tamp.schedule.scheduler import Entry, Placement, ScheduleOptions
from sdar_tamp.schedule.sweep import WorldSweep
from sdar_tamp.world.collision import CollisionWorld
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray

HIGH = 0.15  #: [m] the tools' height over the middle of the table


def _profile(q0: FloatArray, q1: FloatArray, n: int) -> FloatArray:
    """``q0 -> q1`` on a cosine profile of ``n`` ticks, ``(n + 1, k)``."""
    s = 0.5 - 0.5 * np.cos(np.pi * np.arange(n + 1) / n)
    return q0 + s[:, None] * (q1 - q0)


def _ticks(q0: FloatArray, q1: FloatArray, seconds_per_rad: float = 1.2) -> int:
    return max(25, math.ceil(float(np.abs(q1 - q0).max()) * seconds_per_rad / 0.02))


def _entry(arm: int, q: FloatArray) -> Entry:
    return Entry(arm, Block(arm, q, q, None, 0.0, 0.0, 0, None), q, 0)


@pytest.fixture(scope="module")
def middle(cells: dict[int, Scene]) -> tuple[Scene, Instance, PlanFile, dict[str, FloatArray]]:
    """The four-arm cell, the relay instance (one object, away from the middle), a plan file
    of it (its arms and layout) and the west and east arms' configurations with the tool
    over the middle of the table."""
    scene = cells[4]
    instance, phases = relay(scene)
    plan = build(scene, instance, phases)
    over = {
        arm: tool_at(scene, arm, (0.0, 0.0, 0.0), HIGH, np.array(scene.arm(arm).home))
        for arm in ("west", "east")
    }
    return scene, instance, plan, over


def _placement(scene: Scene, instance: Instance, plan: PlanFile) -> Placement:
    sweep = WorldSweep(instance, scene, 0.005)
    return Placement(plan, [[] for _ in plan.arms], sweep, ScheduleOptions(), "objects")


def _west_there_and_back(
    p: Placement, scene: Scene, over: dict[str, FloatArray]
) -> tuple[int, int]:
    """Place the west arm's reach over the middle and back home from tick 0; its arm index
    and the tick it is over the middle."""
    west = scene.arm_names.index("west")
    home = np.array(scene.arm("west").home)
    n = _ticks(home, over["west"])
    q = np.concatenate([_profile(home, over["west"], n), _profile(over["west"], home, n)[1:]])
    p.place([_entry(west, q)])
    assert p.horizon(west) == 2 * n
    return west, n


def test_a_motion_passes_behind_another_moving_arm_without_waiting(
    middle: tuple[Scene, Instance, PlanFile, dict[str, FloatArray]],
) -> None:
    scene, instance, plan, over = middle
    p = _placement(scene, instance, plan)
    _, n = _west_there_and_back(p, scene, over)
    east = scene.arm_names.index("east")
    # against a static snapshot of the west arm (over the middle) the east arm's end collides
    world = CollisionWorld(scene)
    q = scene.home.copy()
    q[scene.layout.slice("west")] = over["west"]
    q[scene.layout.slice("east")] = over["east"]
    assert world.in_collision(q)
    # in time it gets there after the west arm has left: placed at its earliest start
    home = np.array(scene.arm("east").home)
    slow = _profile(home, over["east"], 2 * n + 20)
    p.place([_entry(east, slow)])
    assert p.delay == 0 and p.delayed_by is None
    assert p.horizon(east) == len(slow) - 1
    # both arms move at once: the east arm leaves home before the west one is back
    moving_east = np.flatnonzero(np.abs(np.diff(slow, axis=0)).max(axis=1) > 1e-6)
    assert moving_east[0] < 2 * n
    report = validate_plan(instance, p.assemble(), scene)
    # nothing is carried: the object stays off its goal, and there is no contact
    assert report.violation is None or report.violation.kind == "goal", report.violation


def test_a_motion_that_would_get_there_first_waits_and_names_the_arms(
    middle: tuple[Scene, Instance, PlanFile, dict[str, FloatArray]],
) -> None:
    scene, instance, plan, over = middle
    p = _placement(scene, instance, plan)
    _, n = _west_there_and_back(p, scene, over)
    east = scene.arm_names.index("east")
    home = np.array(scene.arm("east").home)
    fast = _profile(home, over["east"], n)
    p.place([_entry(east, fast)])
    assert p.delay > 0  # it waited for the west arm
    c = p.delayed_by
    assert c is not None and c.kind == "collision" and c.arms == ("west", "east"), c
    assert c.message.startswith("arms west and east in contact")
    report = validate_plan(instance, p.assemble(), scene)
    assert report.violation is None or report.violation.kind == "goal", report.violation
