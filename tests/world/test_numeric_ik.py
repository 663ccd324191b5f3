"""Batched numeric IK: its FK, Jacobian and rotation log against pinocchio and finite
differences; convergence, limits and redundancy on a 6- and a 7-DoF chain."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from sdar_tamp.world._pin import Chain, PinRobot, chain_to
from sdar_tamp.world.errors import KinematicsError
from sdar_tamp.world.numeric_ik import (
    NumericIKOptions,
    chain_fk,
    chain_jacobian,
    numeric_ik,
    pose_error,
    rotation_log,
)
from sdar_tamp.world.scene import domain_path, load_scene

#: Franka Emika Panda's published (modified DH) geometry as a URDF chain, limits narrowed.
PANDA_LIKE = [
    ("0 0 0.333", "0 0 0"),
    ("0 0 0", "-1.5708 0 0"),
    ("0 -0.316 0", "1.5708 0 0"),
    ("0.0825 0 0", "1.5708 0 0"),
    ("-0.0825 0.384 0", "-1.5708 0 0"),
    ("0 0 0", "1.5708 0 0"),
    ("0.088 0 0", "1.5708 0 0"),
]


def seven_dof(tmp_path: Path) -> tuple[PinRobot, Chain]:
    joints = "".join(
        f'<joint name="j{i + 1}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
        f'<origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="0 0 1"/>'
        f'<limit lower="-2.8" upper="2.8" effort="1" velocity="1"/></joint><link name="l{i + 1}"/>'
        for i, (xyz, rpy) in enumerate(PANDA_LIKE)
    )
    tool = (
        '<link name="tool"/><joint name="t" type="fixed"><parent link="l7"/><child link="tool"/>'
        '<origin xyz="0 0 0.207" rpy="0 0 -0.785"/></joint>'
    )
    path = tmp_path / "seven.urdf"
    path.write_text(f'<robot name="s"><link name="l0"/>{joints}{tool}</robot>', "utf-8")
    robot = PinRobot.load(path)
    return robot, chain_to(robot, "tool")


def test_rotation_log_matches_pinocchio() -> None:
    rng = np.random.default_rng(0)
    vectors = rng.normal(size=(200, 3))
    vectors *= rng.uniform(0.0, np.pi - 1e-6, (200, 1)) / np.linalg.norm(vectors, axis=1)[:, None]
    vectors[0] = 0.0
    vectors[1] = [np.pi, 0.0, 0.0]  # a half turn: the axis up to its sign
    R = np.stack([pin.exp3(v) for v in vectors])
    logs = rotation_log(R)
    np.testing.assert_allclose(logs[2:], vectors[2:], atol=1e-7)
    np.testing.assert_allclose(logs[0], 0.0, atol=1e-12)
    assert np.allclose(np.abs(logs[1]), [np.pi, 0.0, 0.0], atol=1e-7)


def test_chain_fk_and_jacobian_match_pinocchio_and_differences() -> None:
    robot = PinRobot.load(domain_path("robots/ur5e_2f85.urdf"))
    chain = chain_to(robot, "tcp")
    rng = np.random.default_rng(1)
    q = rng.uniform(-np.pi, np.pi, (20, 6))
    frames, end = chain_fk(chain, q)
    fid = robot.frame_id("tcp")
    expected = np.stack([robot.frame_pose(row, fid) for row in q])
    np.testing.assert_allclose(end, expected, atol=1e-12)
    J = chain_jacobian(chain, frames, end)
    h = 1e-6
    for k in range(6):
        dq = np.zeros(6)
        dq[k] = h
        _, plus = chain_fk(chain, q + dq)
        _, minus = chain_fk(chain, q - dq)
        numeric = pose_error(plus, minus) / (2 * h)  # twist (linear, angular), root frame
        np.testing.assert_allclose(J[:, :, k], numeric, atol=1e-7)


def _solve_reachable(chain: Chain, lo: np.ndarray, hi: np.ndarray) -> float:
    rng = np.random.default_rng(2)
    _, targets = chain_fk(chain, rng.uniform(lo, hi, (100, chain.dof)))
    result = numeric_ik(chain, targets, lo, hi, seed=3)
    _, reached = chain_fk(chain, result.q)
    err = pose_error(targets, reached)[result.ok]
    assert np.linalg.norm(err[:, :3], axis=1).max() < 1e-6
    assert np.linalg.norm(err[:, 3:], axis=1).max() < 1e-6
    assert np.all((result.q >= lo) & (result.q <= hi))
    return result.success_rate


def test_reachable_poses_are_solved_six_dof() -> None:
    robot = PinRobot.load(domain_path("robots/ur5e_2f85.urdf"))
    spec = load_scene().arms[0]
    rate = _solve_reachable(chain_to(robot, "tcp"), spec.lower_array, spec.upper_array)
    assert rate >= 0.97


def test_reachable_poses_are_solved_seven_dof(tmp_path: Path) -> None:
    _, chain = seven_dof(tmp_path)
    assert _solve_reachable(chain, np.full(7, -2.8), np.full(7, 2.8)) >= 0.97


def test_redundancy_goes_to_the_reference(tmp_path: Path) -> None:
    _, chain = seven_dof(tmp_path)
    lo, hi = np.full(7, -2.8), np.full(7, 2.8)
    home = np.array([0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.8])
    _, target = chain_fk(chain, home[None])
    result = numeric_ik(chain, target, lo, hi, q_ref=home)
    np.testing.assert_array_equal(result.q[0], home)  # the reference solves it: kept
    # the same pose from elsewhere in the self-motion: the null-space pull and the choice
    # among seeds bring the solution nearer the reference than where the seeds started
    rng = np.random.default_rng(4)
    far = home + rng.uniform(-0.4, 0.4, 7)
    _, target = chain_fk(chain, far[None])
    near = numeric_ik(chain, target, lo, hi, q_ref=home, options=NumericIKOptions(seeds=1))
    assert near.ok[0]
    centre = numeric_ik(chain, target, lo, hi, options=NumericIKOptions(seeds=1))
    assert np.linalg.norm(near.q[0] - home) < np.linalg.norm(centre.q[0] - home)


def test_bad_shapes_are_named(tmp_path: Path) -> None:
    _, chain = seven_dof(tmp_path)
    with pytest.raises(KinematicsError, match=r"shape \(7,\)"):
        numeric_ik(chain, np.eye(4), np.zeros(6), np.ones(6))
    with pytest.raises(KinematicsError, match="lower limits above upper"):
        numeric_ik(chain, np.eye(4), np.ones(7), np.zeros(7))


def test_a_fading_pull_converges_in_fewer_iterations(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The pull toward the reference fading out near the pose: the same poses solved, as
    near the reference, in fewer descent iterations than with a constant pull (the numpy
    descent, whose FK calls are counted)."""
    from sdar_tamp.world import numeric_ik as module

    _, chain = seven_dof(tmp_path)
    lo, hi = np.full(7, -2.8), np.full(7, 2.8)
    home = np.array([0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.8])
    rng = np.random.default_rng(5)
    _, targets = chain_fk(chain, home + rng.uniform(-0.6, 0.6, (40, 7)))
    fk = module.chain_fk
    runs = {}
    for fade in (0.0, 0.003):
        calls = [0]

        def counting(c: Chain, q: np.ndarray, calls: list[int] = calls) -> tuple:
            calls[0] += 1
            return fk(c, q)

        monkeypatch.setattr(module, "chain_fk", counting)
        opts = NumericIKOptions(
            seeds=4, iterations=100, rounds=2, null_space_fade=fade, compiled=False
        )
        result = numeric_ik(chain, targets, lo, hi, q_ref=home, options=opts)
        runs[fade] = (calls[0], result)
    (slow, constant), (fast, fading) = runs[0.0], runs[0.003]
    assert fading.ok.sum() >= constant.ok.sum() >= 38, (fading.ok.sum(), constant.ok.sum())
    assert fast < slow, (fast, slow)
    near = np.linalg.norm(fading.q - home, axis=1)[fading.ok & constant.ok]
    far = np.linalg.norm(constant.q - home, axis=1)[fading.ok & constant.ok]
    assert near.mean() < far.mean() + 0.05
