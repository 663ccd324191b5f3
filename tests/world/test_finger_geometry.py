"""Finger measures read from the URDF: the shipped gripper gives back today's constants."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.world._pin import PinRobot
from sdar_tamp.world.errors import KinematicsError
from sdar_tamp.world.finger_geometry import finger_geometry
from sdar_tamp.world.graspability import FINGER_DEPTH, FINGER_WIDTH
from sdar_tamp.world.scene import domain_path, load_scene
from streams.motion.shape import FINGER_ENVELOPE

URDF = domain_path("ur5e_2f85.urdf")
FINGERS = ("gripper_left_finger", "gripper_right_finger")


def test_the_shipped_gripper_reads_back_exactly() -> None:
    g = finger_geometry(PinRobot.load(URDF), FINGERS)
    assert g.depth == FINGER_DEPTH and g.width == FINGER_WIDTH
    assert g.opening == load_scene().gripper.max_opening
    np.testing.assert_array_equal(g.envelope, FINGER_ENVELOPE)


def _variant(tmp_path: Path, old: str, new: str) -> PinRobot:
    text = URDF.read_text(encoding="utf-8")
    assert old in text
    path = tmp_path / "robot.urdf"
    path.write_text(text.replace(old, new), encoding="utf-8")
    return PinRobot.load(path)


def test_mesh_fingers_measure_like_boxes(tmp_path: Path) -> None:
    corners = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    lines = [f"v {x * 0.011} {y * 0.006} {z * 0.0325}" for x, y, z in corners]
    quads = ((1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4))
    lines += [f"f {a} {b} {c} {d}" for a, b, c, d in quads]
    (tmp_path / "finger.obj").write_text("\n".join(lines) + "\n", encoding="utf-8")
    box = '<geometry><box size="0.022 0.012 0.065"/></geometry>'
    robot = _variant(tmp_path, box, '<geometry><mesh filename="finger.obj"/></geometry>')
    g = finger_geometry(robot, FINGERS)
    assert (g.depth, g.width, g.opening) == (FINGER_DEPTH, FINGER_WIDTH, 0.06)


def test_bad_fingers_are_named(tmp_path: Path) -> None:
    robot = PinRobot.load(URDF)
    with pytest.raises(KinematicsError, match=r"expected two finger links"):
        finger_geometry(robot, FINGERS[:1])
    with pytest.raises(KinematicsError, match=r"unknown frame 'thumb'"):
        finger_geometry(robot, ("thumb", FINGERS[1]))
    with pytest.raises(KinematicsError, match=r"'tool0' of ur5e_2f85\.urdf has no collision"):
        finger_geometry(robot, ("tool0", FINGERS[1]))
    with pytest.raises(KinematicsError, match=r"'gripper_base_link' .* has a cylinder"):
        finger_geometry(robot, ("gripper_base_link", FINGERS[1]))
    with pytest.raises(KinematicsError, match=r"do not face each other"):
        finger_geometry(robot, (FINGERS[0], FINGERS[0]))


def test_a_moving_finger_is_refused(tmp_path: Path) -> None:
    robot = _variant(
        tmp_path,
        '<joint name="gripper_left_finger_joint" type="fixed">',
        '<joint name="gripper_left_finger_joint" type="prismatic"><axis xyz="0 1 0"/>'
        '<limit lower="0" upper="0.04" effort="1" velocity="1"/>',
    )
    with pytest.raises(KinematicsError, match=r"'gripper_left_finger' .* moves relative"):
        finger_geometry(robot, FINGERS)
