"""The cell's collision model is built from each arm's own robot description and joints."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from sdar_tamp.world._pin import PinRobot
from sdar_tamp.world.collision import CollisionWorld, ObjectBox
from sdar_tamp.world.collision_model import build_dual_arm, prefixed_urdf, tool0_pose
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.scene import Scene, default_scene_path, domain_path, load_scene
from sdar_tamp.world.transforms import translation

DATA = Path(__file__).parent / "data"
URDF = domain_path("robots/ur5e_2f85.urdf")


def _queries(scene: Scene) -> list[Any]:
    """Closest pair and colliding pairs at 40 random configurations, four resting objects
    and one held, as ``tests/world/data/collision_ur5e_cell.json`` records them (written by
    the model built from the shared description and the UR joint names, before arms named
    their own)."""
    world = CollisionWorld(scene)
    rng = np.random.default_rng(7)
    world.set_objects(
        {
            f"o{i}": ObjectBox(
                translation(rng.uniform(-0.25, 0.25), rng.uniform(-0.3, 0.3), 0.025),
                (0.08, 0.04, 0.05),
            )
            for i in range(4)
        }
    )
    world.attach("left", "o0", scene.home[:6])
    lo, hi = scene.joint_array("lower"), scene.joint_array("upper")
    out: list[Any] = []
    for _ in range(40):
        q = rng.uniform(lo, hi)
        closest = world.min_distance(q)
        pair = [closest.pair.first, closest.pair.second] if closest.pair else None
        hits = sorted([p.first, p.second] for p in world.report(q))
        out.append([float(closest.distance), pair, hits])
    return out


def test_the_ur5e_cell_gives_the_recorded_distances_and_contacts() -> None:
    """Same pairs; distances to 1e-9 m (coal's penetration depth warm-starts from earlier
    queries of the process, which moves the last digits)."""
    recorded = json.loads((DATA / "collision_ur5e_cell.json").read_text(encoding="utf-8"))
    now = _queries(load_scene())
    assert [r[1:] for r in now] == [r[1:] for r in recorded]
    np.testing.assert_allclose([r[0] for r in now], [r[0] for r in recorded], rtol=0, atol=1e-9)


def _other_robot(tmp_path: Path) -> Path:
    """Another arm: the UR5e renamed (``b_`` joints and links), a 10 cm longer forearm, and
    a sliding left finger (a movable joint that is not one of the arm's)."""
    text = URDF.read_text(encoding="utf-8")
    text = re.sub(r'(name|link)="(?!tool0"|tcp")([a-z_0-9-]+)"', r'\1="b_\2"', text)
    text = text.replace('<origin xyz="-0.3922 0 0.1333"', '<origin xyz="-0.4922 0 0.1333"')
    slide = '<joint name="b_gripper_left_finger_joint" type="prismatic">'
    text = text.replace('<joint name="b_gripper_left_finger_joint" type="fixed">', slide)
    text = text.replace(
        '<origin xyz="0 0.036 0.1625" rpy="0 0 0"/>\n  </joint>',
        '<origin xyz="0 0.036 0.1625" rpy="0 0 0"/>\n    <axis xyz="0 1 0"/>\n'
        '    <limit lower="0" upper="0.01" effort="1" velocity="0.1"/>\n  </joint>',
    )
    path = tmp_path / "other.urdf"
    path.write_text(text, encoding="utf-8")
    return path


def _mixed_cell(tmp_path: Path) -> Path:
    other = _other_robot(tmp_path)
    data: dict[str, Any] = yaml.safe_load(default_scene_path().read_text(encoding="utf-8"))
    data["robot"] = str(URDF)
    right = data["arms"][1]
    right["robot"] = str(other)
    right["base_frame"] = "b_base_link"
    del right["joints"]
    right["joint_limits"] = {f"b_{k}": v for k, v in right["joint_limits"].items()}
    right["gripper"] = dict(
        data["gripper"], fingers=["b_gripper_left_finger", "b_gripper_right_finger"]
    )
    path = tmp_path / "mixed.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


def test_two_different_robot_descriptions_build_one_cell(tmp_path: Path) -> None:
    scene = load_scene(_mixed_cell(tmp_path))
    left, right = scene.arms
    assert left.urdf != right.urdf and right.joint_names[0] == "b_shoulder_pan_joint"
    assert right.dof == 6  # the sliding finger is not one of the arm's joints
    arms = build_dual_arm(scene)
    assert arms.model.nq == 12
    names = {s.name for s in arms.shapes if s.arm == "right"}
    assert "right_b_forearm_link_0" in names and "right_forearm_link_0" not in names
    # each arm's tool pose is its own description's forward kinematics, placed at its base
    own = PinRobot.load(right.urdf)
    flange = own.frame_id("tool0")
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = rng.uniform(scene.joint_array("lower"), scene.joint_array("upper"))
        q_right = np.zeros(own.nq)
        for k, joint in enumerate(right.joint_names):
            q_right[own.model.idx_qs[own.model.getJointId(joint)]] = q[6 + k]
        expected = right.T_world_base @ own.frame_pose(q_right, flange)
        np.testing.assert_allclose(tool0_pose(arms, q, "right"), expected, atol=1e-12)
    # the longer forearm reaches further: same joint angles, different tool positions
    q = scene.home
    mirrored = tool0_pose(arms, q, "left")[:3, 3] * np.array([-1, -1, 1])
    assert np.linalg.norm(tool0_pose(arms, q, "right")[:3, 3] - mirrored) > 0.05
    # and the world answers queries for it
    world = CollisionWorld(scene)
    assert not world.in_collision(scene.home)


def test_prefixing_renames_links_joints_and_references() -> None:
    text = (
        '<robot name="r"><link name="a"/><link name="b"/>'
        '<joint name="j" type="revolute"><parent link="a"/><child link="b"/>'
        '<mimic joint="k"/></joint></robot>'
    )
    out = prefixed_urdf(text, "x_")
    for part in ('<link name="x_a"', 'parent link="x_a"', 'child link="x_b"', 'joint="x_k"'):
        assert part in out
    assert 'name="x_j"' in out and '<robot name="r"' in out


def test_locked_joints_hold_a_sliding_finger(tmp_path: Path) -> None:
    path = _mixed_cell(tmp_path)
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    scene = load_scene(path)
    right = scene.arm("right")
    assert right.locked_joints == (("b_gripper_left_finger_joint", 0.0),)
    assert float(right.gripper.envelope[:, 1].max()) == 0.042
    data["arms"][1]["locked_joints"] = {"b_gripper_left_finger_joint": 0.01}
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    scene = load_scene(path)
    assert float(scene.arm("right").gripper.envelope[:, 1].max()) == 0.052  # opened 1 cm
    arms = build_dual_arm(scene)
    assert arms.model.nq == 12
    for bad, message in (
        ({"b_elbow_joint": 0.0}, "arms[1].locked_joints.b_elbow_joint: expected a joint that is"),
        ({"b_gripper_left_finger_joint": 0.5}, "expected a value within the URDF's [0.0, 0.01]"),
        ([0.0], "arms[1].locked_joints: expected a mapping of joint name"),
    ):
        data["arms"][1]["locked_joints"] = bad
        path.write_text(yaml.safe_dump(data), encoding="utf-8")
        with pytest.raises(SceneError) as info:
            load_scene(path)
        assert message in str(info.value) and "mixed.yaml:" in str(info.value)
