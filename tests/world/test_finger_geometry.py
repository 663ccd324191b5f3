"""Finger measures read from the URDF: the shipped gripper gives back today's constants."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.world._pin import PinRobot
from sdar_tamp.world.errors import KinematicsError
from sdar_tamp.world.finger_geometry import finger_geometry
from sdar_tamp.world.scene import domain_path, load_scene

URDF = domain_path("robots/ur5e_2f85.urdf")
FINGERS = ("gripper_left_finger", "gripper_right_finger")
#: The constants the planner used before the cell described its gripper: fingertips 0.017 m
#: beyond the TCP, 0.022 m wide; pads 0.036 m either side of the TCP, 0.065 m long.
FINGER_DEPTH, FINGER_WIDTH = 0.017, 0.022
FINGER_ENVELOPE = np.array(
    [[x, y, z] for x in (-0.011, 0.011) for y in (-0.042, 0.042) for z in (-0.048, 0.017)]
)


def test_the_shipped_gripper_reads_back_exactly() -> None:
    g = finger_geometry(PinRobot.load(URDF), FINGERS)
    assert g.depth == FINGER_DEPTH and g.width == FINGER_WIDTH
    assert g.opening == load_scene().gripper.max_opening
    np.testing.assert_array_equal(g.envelope, FINGER_ENVELOPE)
    # measured from the flange with the cell's TCP offset: the same
    flange = finger_geometry(PinRobot.load(URDF), FINGERS, "tool0", tcp_offset=0.178)
    assert (flange.depth, flange.width, flange.opening) == (g.depth, g.width, g.opening)
    np.testing.assert_array_equal(flange.envelope, FINGER_ENVELOPE)
    gripper = load_scene().arm("right").gripper
    assert (gripper.finger_depth, gripper.finger_width) == (FINGER_DEPTH, FINGER_WIDTH)
    np.testing.assert_array_equal(gripper.envelope, FINGER_ENVELOPE)


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
