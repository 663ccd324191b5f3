"""CasADi forward kinematics generated from the URDF's chain, against pinocchio."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.world._pin import PinRobot, chain_to
from sdar_tamp.world.errors import KinematicsError
from sdar_tamp.world.scene import domain_path
from sdar_tamp.world.transforms import pose_xyz_yaw
from streams.motion._casadi import ca, function, sx_sym, to_array
from streams.motion.fk_chain import chain_pose, chain_pose_function

_JOINT = """  <joint name="j{i}" type="{kind}">
    <parent link="l{p}"/><child link="l{i}"/>
    <origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="{axis}"/>
    <limit lower="-2.5" upper="2.5" effort="1" velocity="1"/>
  </joint>
  <link name="l{i}"/>
"""

#: A 7-DoF arm with every kind of axis pinocchio distinguishes (X, Y, Z, unaligned, negative)
#: and placements with rotations; then a fixed tool frame.
SEVEN = [
    ("revolute", "0 0 0.333", "0 0 0", "0 0 1"),
    ("revolute", "0 0 0", "-1.5708 0 0", "0 0 1"),
    ("revolute", "0 -0.316 0", "1.5708 0 0", "1 0 0"),
    ("revolute", "0.0825 0 0", "1.5708 0.2 0", "0 1 0"),
    ("revolute", "-0.0825 0.384 0", "-1.5708 0 0.3", "0.6 0 0.8"),
    ("revolute", "0 0 0", "1.5708 0 0", "0 0 -1"),
    ("revolute", "0.088 0 0", "1.5708 0 0", "0.267261 0.534522 0.801784"),
]


def write_chain(path: Path, joints: list[tuple[str, str, str, str]]) -> Path:
    body = "".join(
        _JOINT.format(i=i + 1, p=i, kind=k, xyz=x, rpy=r, axis=a)
        for i, (k, x, r, a) in enumerate(joints)
    )
    n = len(joints)
    tool = (
        f'  <link name="tool"/><joint name="tool_fixed" type="fixed"><parent link="l{n}"/>'
        '<child link="tool"/><origin xyz="0.01 0.02 0.107" rpy="0 0 -0.785"/></joint>\n'
    )
    path.write_text(f'<robot name="chain">\n  <link name="l0"/>\n{body}{tool}</robot>\n', "utf-8")
    return path


def _check_against_pinocchio(robot: PinRobot, frame: str, samples: int = 50) -> float:
    chain = chain_to(robot, frame)
    T_world_root = pose_xyz_yaw(0.3, -0.2, 0.05, 0.7)
    fk = chain_pose_function(chain, T_world_root)
    rng = np.random.default_rng(0)
    lo = robot.model.lowerPositionLimit
    hi = robot.model.upperPositionLimit
    fid = robot.frame_id(frame)
    worst = 0.0
    for _ in range(samples):
        q_full = rng.uniform(np.maximum(lo, -np.pi), np.minimum(hi, np.pi))
        q_chain = np.array([q_full[j.q_index] for j in chain.joints])
        expected = T_world_root @ robot.frame_pose(q_full, fid)
        worst = max(worst, float(np.abs(to_array(fk(q_chain)) - expected).max()))
    return worst


def test_ur5e_chain_matches_pinocchio() -> None:
    robot = PinRobot.load(domain_path("robots/ur5e_2f85.urdf"))
    assert chain_to(robot, "tcp").dof == 6
    assert _check_against_pinocchio(robot, "tcp") < 1e-9
    assert _check_against_pinocchio(robot, "tool0") < 1e-9


def test_seven_dof_chain_matches_pinocchio(tmp_path: Path) -> None:
    robot = PinRobot.load(write_chain(tmp_path / "seven.urdf", SEVEN))
    chain = chain_to(robot, "tool")
    assert chain.dof == 7
    kinds = {str(robot.model.joints[i].shortname()) for i in range(1, 8)}
    assert {"JointModelRZ", "JointModelRX", "JointModelRY"} <= kinds
    assert "JointModelRevoluteUnaligned" in kinds
    assert _check_against_pinocchio(robot, "tool") < 1e-9


def test_prismatic_joints_match_pinocchio(tmp_path: Path) -> None:
    joints = [
        ("prismatic", "0 0 0.1", "0 0 0", "0 0 1"),
        ("revolute", "0.2 0 0", "0.3 0 0", "0 1 0"),
        ("prismatic", "0 0.1 0", "0 0.4 0", "0.6 0.8 0"),
    ]
    robot = PinRobot.load(write_chain(tmp_path / "slide.urdf", joints))
    assert chain_to(robot, "tool").dof == 3
    assert _check_against_pinocchio(robot, "tool") < 1e-9


def test_derivatives_match_finite_differences(tmp_path: Path) -> None:
    robot = PinRobot.load(write_chain(tmp_path / "seven.urdf", SEVEN))
    chain = chain_to(robot, "tool")
    q = sx_sym("q", 7)
    T = chain_pose(chain, q, np.eye(4))
    flat = ca.reshape(T[:3, :], 12, 1)
    jac = function("tool_jacobian", [q], [ca.jacobian(flat, q)])
    value = function("value", [q], [flat])
    rng = np.random.default_rng(1)
    h = 1e-6
    for _ in range(10):
        q0 = rng.uniform(-2.0, 2.0, 7)
        numeric = np.stack(
            [
                (to_array(value(q0 + h * e)) - to_array(value(q0 - h * e))).ravel() / (2 * h)
                for e in np.eye(7)
            ],
            axis=1,
        )
        np.testing.assert_allclose(to_array(jac(q0)), numeric, atol=1e-8)


def test_joints_a_chain_cannot_take_are_named(tmp_path: Path) -> None:
    joints = [
        ("revolute", "0 0 0.1", "0 0 0", "0 0 1"),
        ("continuous", "0 0 0.1", "0 0 0", "1 0 0"),
    ]
    robot = PinRobot.load(write_chain(tmp_path / "spin.urdf", joints))
    with pytest.raises(KinematicsError, match=r"joint 'j2' of spin\.urdf is a JointModelRUBX"):
        chain_to(robot, "tool")
    with pytest.raises(KinematicsError, match="unknown frame 'hand'"):
        chain_to(robot, "hand")
