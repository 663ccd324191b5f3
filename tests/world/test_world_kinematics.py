from __future__ import annotations

import numpy as np
import pytest

from sdar_tamp.world.errors import KinematicsError
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import inverse, top_down_pose
from sdar_tamp.world.ur_ik import UR5E, ur_fk, ur_ik, wrap_into_limits, wrap_pi


@pytest.fixture(scope="module", params=["left", "right"])
def kin(request: pytest.FixtureRequest, scene: Scene) -> ArmKinematics:
    return ArmKinematics.from_scene(scene, request.param)


def _random_q(kin: ArmKinematics, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.uniform(kin.spec.lower_array, kin.spec.upper_array, (n, 6))


def test_urdf_matches_the_dh_table(kin: ArmKinematics) -> None:
    for q in _random_q(kin, 50, 0):
        np.testing.assert_allclose(kin.fk_tool0(q), kin.fk_batch(q[None])[0], atol=1e-12)


def test_zero_configuration_in_the_dh_base_frame() -> None:
    # arm stretched along -x of the DH base, flange at (a2 + a3, -(d4 + d6), d1 - d5)
    T = ur_fk(UR5E, np.zeros(6))
    np.testing.assert_allclose(T[:3, 3], [-0.8172, -0.2329, 0.0628], atol=1e-12)


def test_tcp_is_offset_along_tool0_z(kin: ArmKinematics) -> None:
    q = np.array(kin.spec.home)
    T = inverse(kin.fk_tool0(q)) @ kin.fk_tcp(q)
    np.testing.assert_allclose(T[:3, 3], [0, 0, 0.178], atol=1e-12)
    np.testing.assert_allclose(T[:3, :3], np.eye(3), atol=1e-12)


def test_ik_agrees_with_pinocchio_fk(kin: ArmKinematics) -> None:
    q_true = _random_q(kin, 200, 1)
    targets = np.stack([kin.fk_tool0(q) for q in q_true])
    sol = kin.ik_tool0(targets)
    assert sol.q.shape == (200, 8, 6) and sol.valid.shape == (200, 8)
    assert sol.valid.any(axis=1).all()
    lo, hi = kin.spec.lower_array, kin.spec.upper_array
    for i in range(0, 200, 5):
        for b in np.flatnonzero(sol.valid[i]):
            q = sol.q[i, b]
            assert np.all(q >= lo - 1e-12) and np.all(q <= hi + 1e-12)
            np.testing.assert_allclose(kin.fk_tool0(q), targets[i], atol=1e-9)
    found = np.abs(sol.q - q_true[:, None]).max(axis=-1)
    found = np.where(sol.valid, found, np.inf).min(axis=1)
    assert np.all(found < 1e-7)  # the configuration that made the pose is among the branches


def test_closed_form_yields_up_to_eight_distinct_branches() -> None:
    q = np.random.default_rng(2).uniform(-np.pi, np.pi, (300, 6))
    sol, valid = ur_ik(UR5E, ur_fk(UR5E, q))
    err = np.abs(ur_fk(UR5E, sol) - ur_fk(UR5E, q)[:, None]).max(axis=(-1, -2))
    assert np.all(err[valid] < 1e-9)
    assert (valid.sum(axis=1) == 8).mean() > 0.5
    assert len(np.unique(np.round(sol[0], 6), axis=0)) == 8


def test_unreachable_target_has_no_valid_branch(kin: ArmKinematics) -> None:
    far = top_down_pose(5.0, 0.0, 0.1, 0.0)
    assert not kin.ik_tcp(far).valid.any()


def test_wrap_into_limits() -> None:
    lower = np.array([-1.57, -np.pi, 0.0, -np.pi, -np.pi, -np.pi])
    upper = np.array([1.57, np.pi, np.pi, 0.0, np.pi, np.pi])
    q = np.array([[0.5, 0.1, 1.0, 2.0 * np.pi - 1.0, 0.2, 0.0], [2.0, 0, 1, -1, 0, 0]])
    shifted, ok = wrap_into_limits(q, lower, upper)
    assert ok.tolist() == [True, False]
    assert shifted[0, 3] == pytest.approx(-1.0)
    assert np.allclose(wrap_pi(np.array([3 * np.pi, -np.pi])), [np.pi, np.pi])


def test_closest_branch(kin: ArmKinematics) -> None:
    home = np.array(kin.spec.home)
    q, ok = kin.ik_tool0(kin.fk_tool0(home)[None]).closest(home)
    assert ok[0] and np.allclose(q[0], home, atol=1e-9)


def test_workspace_is_reachable_top_down_by_both_arms(scene: Scene) -> None:
    ws = scene.workspace
    xs = np.linspace(*ws.x, 11)
    ys = np.linspace(*ws.y, 13)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    z = scene.object_size[2] / 2
    for arm in scene.arm_names:
        kin = ArmKinematics.from_scene(scene, arm)
        for yaw in (0.0, np.pi / 4, np.pi / 2, -np.pi / 4, np.pi):
            sol = kin.ik_tcp(top_down_pose(X.ravel(), Y.ravel(), z, yaw))
            assert sol.valid.any(axis=1).all(), (arm, yaw)


def test_damped_least_squares_ik(kin: ArmKinematics) -> None:
    rng = np.random.default_rng(3)
    home = np.array(kin.spec.home)
    for _ in range(5):
        q_goal = np.clip(home + rng.normal(0.0, 0.3, 6), kin.spec.lower_array, kin.spec.upper_array)
        target = kin.fk_tcp(q_goal)
        res = kin.ik_dls(target, home, frame="tcp")
        assert res.success, res
        np.testing.assert_allclose(kin.fk_tcp(res.q), target, atol=1e-9)


def test_bad_shapes_raise(kin: ArmKinematics) -> None:
    with pytest.raises(KinematicsError):
        kin.fk_tool0(np.zeros(5))
    with pytest.raises(KinematicsError):
        kin.ik_tool0(np.zeros((3, 3)))
    with pytest.raises(KinematicsError, match="unknown frame"):
        kin.fk(np.zeros(6), "nose")
