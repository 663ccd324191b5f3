"""Makers' robot descriptions from ``example-robot-data`` (BSD-3-Clause; optional: about
130 MB to download, 415 MB installed). The tests skip when it is not installed; the
environment variable ``EXAMPLE_ROBOT_DATA_SHARE`` may name its ``share`` directory."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.world._pin import PinRobot
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.urdf import example_robot_data_share
from streams._pin_geometry import arm_primitives

SHARE = example_robot_data_share()
pytestmark = pytest.mark.skipif(SHARE is None, reason="example-robot-data is not installed")

ARMS = {
    "ur_description/urdf/ur10_robot.urdf": 6,
    "ur_description/urdf/ur5_robot.urdf": 6,
    "panda_description/urdf/panda.urdf": 9,
    "xarm_description/urdf/xarm7.urdf": 7,
}


@pytest.mark.parametrize("relative", sorted(ARMS))
def test_maker_arms_load_with_their_meshes(relative: str) -> None:
    assert SHARE is not None
    robots = SHARE / "example-robot-data" / "robots"
    urdf = robots / relative
    robot = PinRobot.load(urdf, (robots, SHARE))
    assert robot.nq == ARMS[relative]
    kinds = {type(o.geometry).__name__ for o in robot.geometry.geometryObjects}
    assert any(k.startswith("BVHModel") for k in kinds)
    prims = arm_primitives(urdf, (robots, SHARE))
    assert len(prims) == len(robot.geometry.geometryObjects)
    assert all(p.kind == "box" and min(p.half) >= 0.0 for p in prims)


def test_without_package_directories_the_missing_mesh_is_located() -> None:
    assert SHARE is not None
    urdf = SHARE / "example-robot-data" / "robots" / "panda_description" / "urdf" / "panda.urdf"
    with pytest.raises(SceneError, match=r"panda\.urdf:\d+:\d+: mesh 'package://"):
        PinRobot.load(urdf)


@pytest.mark.parametrize(
    ("relative", "frame", "dof"),
    [
        ("panda_description/urdf/panda.urdf", "panda_hand_tcp", 7),
        ("ur_description/urdf/ur10_robot.urdf", "tool0", 6),
        ("xarm_description/urdf/xarm7.urdf", "link_eef", 7),
    ],
)
def test_maker_chains_match_pinocchio(relative: str, frame: str, dof: int) -> None:
    from sdar_tamp.world._pin import chain_to
    from streams.motion._casadi import to_array
    from streams.motion.fk_chain import chain_pose_function

    assert SHARE is not None
    robots = SHARE / "example-robot-data" / "robots"
    robot = PinRobot.load(robots / relative, (robots, SHARE))
    chain = chain_to(robot, frame)
    assert chain.dof == dof
    fk = chain_pose_function(chain, np.eye(4))
    rng = np.random.default_rng(2)
    lo, hi = robot.model.lowerPositionLimit, robot.model.upperPositionLimit
    for _ in range(30):
        q = rng.uniform(np.maximum(lo, -np.pi), np.minimum(hi, np.pi))
        expected = robot.frame_pose(q, robot.frame_id(frame))
        got = to_array(fk(np.array([q[j.q_index] for j in chain.joints])))
        assert np.abs(got - expected).max() < 1e-9


#: The makers' published DH lengths (d1, a2, a3, d4, d5, d6) [m] of the CB3 arms.
PUBLISHED = {
    "ur3_robot": (0.1519, -0.24365, -0.21325, 0.11235, 0.08535, 0.0819),
    "ur5_robot": (0.089159, -0.425, -0.39225, 0.10915, 0.09465, 0.0823),
    "ur10_robot": (0.1273, -0.612, -0.5723, 0.163941, 0.1157, 0.0922),
}


@pytest.mark.parametrize("name", sorted(PUBLISHED))
def test_ur_parameters_read_from_maker_urdfs(name: str) -> None:
    from sdar_tamp.world.ur_identify import ur_parameters

    assert SHARE is not None
    robots = SHARE / "example-robot-data" / "robots"
    urdf = robots / f"ur_description/urdf/{name}.urdf"
    found = ur_parameters(PinRobot.load(urdf, (robots, SHARE)))
    assert found is not None
    assert tuple(vars(found[0]).values()) == PUBLISHED[name]


def test_the_panda_is_not_ur() -> None:
    from sdar_tamp.world.ur_identify import ur_parameters

    assert SHARE is not None
    robots = SHARE / "example-robot-data" / "robots"
    urdf = robots / "panda_description/urdf/panda.urdf"
    assert ur_parameters(PinRobot.load(urdf, (robots, SHARE)), flange="panda_hand_tcp") is None


def test_a_cell_of_maker_arms_without_gripper_or_tcp_frame() -> None:
    """A maker's description as it ships (meshes, no gripper, no ``tcp`` frame): the cell
    declares the finger box; the closed form is found from the URDF, the grasp-blocking boxes
    come from the declared fingers."""
    from sdar_tamp.world.kinematics import ArmKinematics
    from sdar_tamp.world.scene import load_scene
    from streams.finger_blocking import cell_gripper_boxes, declared_finger_boxes

    assert SHARE is not None
    path = Path(__file__).with_name("data") / "maker_ur10_pair.yaml"
    scene = load_scene(path, environ={"ROS_PACKAGE_PATH": str(SHARE)})
    assert scene.arms[0].urdf.name == "ur10_robot.urdf" and scene.arms[0].dof == 6
    kin = ArmKinematics.from_scene(scene, "left")
    assert kin.closed_form and kin.params is not None
    assert kin.params.a2 == pytest.approx(-0.612)
    q = np.array(scene.arms[0].home)
    reached = kin.ik_tcp(kin.fk_tcp(q)[None])
    assert reached.valid.any()
    boxes = cell_gripper_boxes(scene)
    expected = declared_finger_boxes(scene.arms[0].gripper)
    assert len(boxes) == 2 and boxes[0].half == expected[0].half


def test_a_cell_of_seven_joint_maker_arms() -> None:
    """The xArm7 as ``example-robot-data`` ships it (not a shipped robot): the numeric IK
    reaches its home's TCP and both arms grasp every point of the cell's workspace."""
    from sdar_tamp.world.cell_reach import unreached_points
    from sdar_tamp.world.kinematics import ArmKinematics
    from sdar_tamp.world.scene import load_scene

    assert SHARE is not None
    path = Path(__file__).with_name("data") / "maker_xarm7_pair.yaml"
    scene = load_scene(path, environ={"ROS_PACKAGE_PATH": str(SHARE)})
    assert scene.arms[0].urdf.name == "xarm7.urdf" and scene.arms[0].dof == 7
    kin = ArmKinematics.from_scene(scene, "left")
    assert not kin.closed_form and kin.tool_frame == "link_eef"
    T = kin.fk_tcp(np.array(scene.arms[0].home))
    np.testing.assert_allclose(T[:3, 3], [-0.13, 0.0, 0.3], atol=1e-3)
    assert T[2, 2] == pytest.approx(-1.0)  # top-down
    sol = kin.ik_tcp(T[None])
    assert sol.valid.any()
    missed = unreached_points(scene, 0.1)
    assert sorted(missed) == ["left", "right"]
    assert all(len(m) == 0 for m in missed.values())
