"""Braking along the running motion (``sdar_tamp.app.braking``) on D5's stored plan: the arms
come to rest on the plan's path within the validator's limits (what they hold held on), or
there is no braking."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.app.braking import brake, still_until_dwells_end
from sdar_tamp.plan_file import GRIPPER_DWELL, MAX_DT, PlanFile
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_rules import check_timeline
from sdar_tamp.plan_state import prefix_plan
from sdar_tamp.world.scene import Scene, load_scene

SOLVED = Path(__file__).parents[1] / "plan" / "solved"


@pytest.fixture(scope="module")
def d5() -> PlanFile:
    return load_plan(SOLVED / "D5.plan.json")


@pytest.fixture(scope="module")
def scene() -> Scene:
    return load_scene()


def _limits(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    return scene.joint_array("velocity_limit"), scene.joint_array("acceleration_limit")


@pytest.mark.parametrize("at", [4.3, 4.5, 4.9, 5.2, 8.6, 9.0])  # both arms moving, empty
def test_braking_keeps_the_limits_and_the_path(d5: PlanFile, scene: Scene, at: float) -> None:
    stop = brake(d5, at, *_limits(scene))
    assert stop is not None
    plan = prefix_plan(stop.plan, stop.cut)  # and a still hold after it
    assert check_timeline(plan, scene) is None  # velocity, acceleration, dwell
    k = int(np.searchsorted(d5.t, at - 1e-9))
    np.testing.assert_array_equal(plan.q[: k + 1], d5.q[: k + 1])  # the plan up to there
    end = stop.cut.t
    assert end < d5.t[k] + 1.0  # at rest within a second
    q_end = stop.plan.q[-1]
    # the arms stand where the plan passes: at a plan time between `at` and the stop time
    dense = np.linspace(d5.t[k], end, 5000)
    path = np.stack([np.interp(dense, d5.t, d5.q[:, j]) for j in range(d5.q.shape[1])], 1)
    assert np.linalg.norm(path - q_end, axis=1).min() < 1e-3
    assert np.abs(np.diff(stop.plan.q[k:], axis=0)).max() > 0.0  # it did move on


def test_arms_at_rest_stop_at_once(d5: PlanFile, scene: Scene) -> None:
    """At 8.2 s both arms stand still in the dwell of their releases at 7.8 s."""
    stop = brake(d5, 8.2, *_limits(scene))
    assert stop is not None
    k = int(np.searchsorted(d5.t, 8.2 - 1e-9))
    assert stop.cut.index == k and stop.cut.t == d5.t[k]
    assert stop.cut.events == sum(e.t < 8.2 for e in d5.events)


@pytest.mark.parametrize("at", [2.5, 10.8])  # both arms carry (o3, o0); the left carries o2
def test_braking_with_an_object_in_hand(d5: PlanFile, scene: Scene, at: float) -> None:
    """The held objects stay held (no event on the braked stretch); the stop keeps the limits
    once the dwells are over."""
    stop = brake(d5, at, *_limits(scene))
    assert stop is not None and stop.cut.t < at + 1.0
    assert stop.plan.events == tuple(e for e in d5.events if e.t < at)
    assert check_timeline(still_until_dwells_end(stop.plan), scene) is None


def test_still_until_the_dwells_end(d5: PlanFile, scene: Scene) -> None:
    """Braked at 1.5 s, in the dwell of the grasps of 1.386 s (the arms still): the plan is
    held still to 1.886 s, samples at most MAX_DT apart; a plan past its dwells is kept."""
    stop = brake(d5, 1.5, *_limits(scene))
    assert stop is not None and stop.cut.t < 1.886
    held = still_until_dwells_end(stop.plan)
    assert held.t[-1] == pytest.approx(1.386 + GRIPPER_DWELL, abs=1e-3)
    assert np.diff(held.t).max() <= MAX_DT + 1e-9
    assert np.abs(held.q[len(stop.plan.t) - 1 :] - stop.plan.q[-1]).max() == 0.0
    assert still_until_dwells_end(held) is held


def test_no_braking_through_a_gripper_event(d5: PlanFile, scene: Scene) -> None:
    """Just before the grasps of 5.71 s the arms cannot stop before the grippers act."""
    assert brake(d5, 5.70, *_limits(scene)) is None
