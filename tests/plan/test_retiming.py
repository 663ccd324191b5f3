"""Re-timing one arm's share of a synchronous motion for that arm alone: faster along the same
path, within the arm's limits as the plan rules measure them, and with the tool slow near a
gripper event."""

from __future__ import annotations

import numpy as np
import pytest

from sdar_tamp.app.execution import path_timer
from sdar_tamp.errors import ParameterError
from sdar_tamp.schedule.retiming import ArmRetimer, PathTimer, thin
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene, load_scene
from sdar_tamp.world.transforms import FloatArray

TICK = 0.02


@pytest.fixture(scope="module")
def scene() -> Scene:
    return load_scene()


def _retimer(scene: Scene, timer: PathTimer | None, grasp_speed: float = 0.1) -> ArmRetimer:
    spec = scene.arms[0]
    return ArmRetimer(
        ArmKinematics.from_scene(scene, spec.name),
        np.array(spec.velocity_limit),
        np.array(spec.acceleration_limit),
        TICK,
        timer,
        grasp_speed=grasp_speed,
    )


def _slow_motion(scene: Scene) -> tuple[FloatArray, FloatArray]:
    """A rest-to-rest motion of the first arm from home, 3 s long (a smooth ramp): as in a
    synchronous motion whose other arm had the longer path."""
    home = np.array(scene.arms[0].home)
    goal = home + np.array([0.6, 0.3, -0.4, 0.2, 0.0, 1.2])
    t = np.linspace(0.0, 3.0, 151)
    s = 0.5 * (1.0 - np.cos(np.pi * t / 3.0))
    return t, home + s[:, None] * (goal - home)


def _rates(q: FloatArray, tick: float) -> tuple[FloatArray, FloatArray]:
    """Velocities and accelerations as the plan rules measure them (at rest outside)."""
    vel = np.diff(q, axis=0) / tick
    rest = np.zeros((1, q.shape[1]))
    return vel, np.diff(np.concatenate([rest, vel, rest]), axis=0) / tick


def test_thin_keeps_both_ends_and_the_spacing() -> None:
    q = np.cumsum(np.full((50, 2), 0.001), axis=0)
    out = thin(q, 0.01)
    assert np.array_equal(out[0], q[0]) and np.array_equal(out[-1], q[-1])
    assert np.all(np.linalg.norm(np.diff(out, axis=0), axis=1) >= 0.01 - 1e-12)
    assert len(out) < len(q)
    assert len(thin(q[:1], 0.01)) == 1


def test_the_arm_alone_moves_faster_within_its_limits(scene: Scene) -> None:
    t, q = _slow_motion(scene)
    retimer = _retimer(scene, path_timer(1.0))
    out = retimer.retime(t, q, slow_start=False, slow_end=False)
    assert np.array_equal(out[0], q[0]) and np.array_equal(out[-1], q[-1])
    assert (len(out) - 1) * TICK < 0.7 * 3.0  # much faster than the synchronous 3 s
    vel, acc = _rates(out, TICK)
    spec = scene.arms[0]
    assert np.all(np.abs(vel) <= np.array(spec.velocity_limit) * (1 + 1e-6))
    assert np.all(np.abs(acc) <= np.array(spec.acceleration_limit) * (1 + 1e-6))
    # the same path: every sample lies close to the original polyline
    gaps = [np.linalg.norm(q - x, axis=1).min() for x in out]
    assert max(gaps) < 0.02
    # the uniform re-timing cannot change the shape of the profile, so it is slower
    uniform = _retimer(scene, None).retime(t, q, slow_start=False, slow_end=False)
    assert len(out) < len(uniform) <= len(q)


def test_the_tool_is_slow_near_a_gripper_event(scene: Scene) -> None:
    t, q = _slow_motion(scene)
    retimer = _retimer(scene, path_timer(1.0))
    kin = retimer.kinematics
    free = retimer.retime(t, q, slow_start=False, slow_end=False)
    slow = retimer.retime(t, q, slow_start=True, slow_end=True)
    assert len(slow) > len(free)  # the slow ends cost time
    for out, capped in ((slow, True), (free, False)):
        p = (kin.fk_batch(out) @ kin.T_tool0_tcp)[:, :3, 3]
        step = np.linalg.norm(np.diff(p, axis=0), axis=1)
        travel = np.concatenate([[0.0], np.cumsum(step)])
        near = (travel[1:] <= retimer.straight) | (travel[-1] - travel[:-1] <= retimer.straight)
        speed = step[near] / TICK
        if capped:
            assert speed.max() <= retimer.grasp_speed * 1.05
        else:
            assert speed.max() > retimer.grasp_speed * 1.05


def test_a_slower_timing_keeps_the_synchronous_pace(scene: Scene) -> None:
    t, q = _slow_motion(scene)

    def crawl(
        path: FloatArray, v: FloatArray, a: FloatArray, caps: FloatArray | None, dt: float
    ) -> tuple[FloatArray, FloatArray]:
        n = 1000
        x = np.linspace(0.0, 1.0, n + 1)
        return x * n * dt, path[0] + x[:, None] * (path[-1] - path[0])

    out = _retimer(scene, crawl).retime(t, q, slow_start=False, slow_end=False)
    assert np.array_equal(out, q)  # samples 0.02 s apart already: the original


def test_bad_retimer_settings_are_rejected(scene: Scene) -> None:
    base = _retimer(scene, None)
    for name in ("tick", "straight", "grasp_speed", "spacing"):
        for value in (0.0, -1.0, float("nan")):
            with pytest.raises(ParameterError, match=name):
                ArmRetimer(base.kinematics, base.v_max, base.a_max, **{"tick": TICK, name: value})
