"""Grasp blocking: box-box tests, the gripper's boxes and the blocking streams on hand-built
scenes (two objects side by side on the closing axis, beside each other on the other axis,
far apart)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.instance import Pose2D
from sdar_tamp.world.scene import load_scene
from sdar_tamp.world.transforms import pose_xyz_yaw
from streams.context import WorldContext
from streams.finger_blocking import (
    GraspBlocking,
    GripperBox,
    boxes_overlap,
    cell_gripper_boxes,
    declared_finger_boxes,
    gripper_boxes,
)
from streams.stream_map import RearrangementStreams

BAR = (0.08, 0.04, 0.05)  # graspable across y only
CUBE = (0.04, 0.04, 0.05)  # graspable across both sides


def _overlap(Ta: np.ndarray, ha: tuple[float, ...], Tb: np.ndarray, hb: tuple[float, ...]) -> bool:
    return bool(boxes_overlap(Ta[None], np.array([ha]), Tb[None], np.array([hb]))[0])


def test_boxes_overlap_face_and_edge_cases() -> None:
    eye = np.eye(4)
    unit = (0.5, 0.5, 0.5)
    assert _overlap(eye, unit, pose_xyz_yaw(0.9, 0.0, 0.0, 0.0), unit)
    assert not _overlap(eye, unit, pose_xyz_yaw(1.1, 0.0, 0.0, 0.0), unit)
    # turned by 45 degrees: its corner reaches 0.5 * sqrt(2) ~ 0.707 towards the other box
    assert _overlap(eye, unit, pose_xyz_yaw(1.15, 0.0, 0.0, np.pi / 4), unit)
    assert not _overlap(eye, unit, pose_xyz_yaw(1.25, 0.0, 0.0, np.pi / 4), unit)
    # two boxes tilted about different axes, separated only by an edge-edge axis
    Ta = np.eye(4)
    c, s = np.cos(np.pi / 4), np.sin(np.pi / 4)
    Ta[:3, :3] = [[1, 0, 0], [0, c, -s], [0, s, c]]
    Tb = np.eye(4)
    Tb[:3, :3] = [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    Tb[:3, 3] = [0.0, 0.0, 1.3]
    thin = (0.5, 0.05, 0.05)
    assert not _overlap(Ta, thin, Tb, (0.05, 0.5, 0.05))
    Tb[:3, 3] = [0.0, 0.0, 0.05]
    assert _overlap(Ta, thin, Tb, (0.05, 0.5, 0.05))


def test_boxes_overlap_agrees_with_sampled_points() -> None:
    rng = np.random.default_rng(3)
    for _ in range(200):
        Ta = pose_xyz_yaw(*rng.uniform(-0.3, 0.3, 3), rng.uniform(-np.pi, np.pi))
        Tb = pose_xyz_yaw(*rng.uniform(-0.3, 0.3, 3), rng.uniform(-np.pi, np.pi))
        ha, hb = rng.uniform(0.05, 0.25, 3), rng.uniform(0.05, 0.25, 3)
        pts = Ta[:3, :3] @ (rng.uniform(-1, 1, (2000, 3)) * ha).T + Ta[:3, 3:4]
        local = Tb[:3, :3].T @ (pts - Tb[:3, 3:4])
        common = bool((np.abs(local) <= hb[:, None]).all(axis=0).any())
        got = _overlap(Ta, tuple(ha), Tb, tuple(hb))
        assert got or not common  # a shared point proves an overlap


def test_gripper_boxes_of_the_shipped_gripper(ctx: WorldContext) -> None:
    boxes = gripper_boxes(ctx.scene.robot_urdf)
    fingers = [b for b in boxes if abs(b.T_tcp_box[1, 3]) > 0.03]
    assert len(boxes) == 3 and len(fingers) == 2
    for b in fingers:  # beside the TCP on the closing axis, tips just below it
        assert abs(b.T_tcp_box[1, 3]) == pytest.approx(0.036)
        assert b.T_tcp_box[2, 3] + b.half[2] == pytest.approx(0.017)


def test_grasp_blocking_checks_its_values() -> None:
    with pytest.raises(ValueError, match="at least one gripper box"):
        GraspBlocking(())
    with pytest.raises(ValueError, match="margin"):
        GraspBlocking((GripperBox(np.eye(4), (0.01, 0.01, 0.01)),), margin=-0.1)


@pytest.fixture(scope="module")
def streams(ctx: WorldContext) -> RearrangementStreams:
    sizes = {"a": BAR, "b": BAR, "c": CUBE, "d": CUBE}
    return RearrangementStreams(ctx, sizes)


def test_neighbour_on_the_closing_axis_blocks_every_grasp(streams: RearrangementStreams) -> None:
    here = Pose2D(0.0, 0.1, 0.0)
    beside = Pose2D(0.0, 0.1 + 0.045, 0.0)  # 5 mm gap across the bar's 4 cm side
    assert streams.test_blocks_grasps("b", beside, "a", here)
    # rotated bars: the closing axis turns with the object
    turned, turned_beside = Pose2D(0.0, 0.1, np.pi / 2), Pose2D(0.045, 0.1, np.pi / 2)
    assert streams.test_blocks_grasps("b", turned_beside, "a", turned)


def test_far_or_off_axis_neighbours_leave_a_grasp(streams: RearrangementStreams) -> None:
    here = Pose2D(0.0, 0.1, 0.0)
    assert not streams.test_blocks_grasps("b", Pose2D(0.0, 0.3, 0.0), "a", here)
    assert not streams.test_blocks_grasps("b", Pose2D(0.0, 0.1 + 0.07, 0.0), "a", here)
    # end to end on the long axis: top-down fingers stay clear (tilted ones may not)
    assert not streams.test_blocks_grasps("b", Pose2D(0.085, 0.1, 0.0), "a", here)
    # a cube keeps the grasps across the free axis
    assert not streams.test_blocks_grasps("d", Pose2D(0.0, 0.145, 0.0), "c", Pose2D(0, 0.1, 0))
    assert not streams.test_blocks_grasps("a", here, "a", here)


def test_grasp_cfree_tells_grasps_apart(streams: RearrangementStreams) -> None:
    here = Pose2D(0.0, 0.1, 0.0)
    grasps = streams.grasps("c")
    across_x = [g for g in grasps if g.closing_axis == 0 and g.is_top_down]
    across_y = [g for g in grasps if g.closing_axis == 1 and g.is_top_down]
    neighbour = Pose2D(0.045, 0.1, 0.0)  # beside the cube on its x axis
    assert not any(streams.test_grasp_cfree("c", here, g, "d", neighbour) for g in across_x)
    assert all(streams.test_grasp_cfree("c", here, g, "d", neighbour) for g in across_y)
    assert not streams.test_grasp_cfree("c", here, across_y[0], "c", here)


# -- the cell's gripper boxes --------------------------------------------------------------------
def test_the_shipped_cell_keeps_its_descriptions_boxes() -> None:
    scene = load_scene()
    boxes = cell_gripper_boxes(scene)  # both arms: one description, one gripper
    own = gripper_boxes(scene.arms[0].urdf, package_dirs=scene.package_dirs)
    assert len(boxes) == len(own) > 0
    for a, b in zip(boxes, own, strict=True):
        np.testing.assert_array_equal(a.T_tcp_box, b.T_tcp_box)
        assert a.half == b.half


def test_declared_finger_boxes_fill_the_envelope_beside_the_opening() -> None:
    gripper = load_scene().arms[0].gripper
    left, right = declared_finger_boxes(gripper)
    lo, hi = gripper.envelope.min(axis=0), gripper.envelope.max(axis=0)
    for box, sign in ((left, -1.0), (right, 1.0)):
        centre, half = box.T_tcp_box[:3, 3], np.array(box.half)
        assert sign * (centre[1] - sign * half[1]) == pytest.approx(gripper.max_opening / 2)
        np.testing.assert_allclose(centre[[0, 2]] - half[[0, 2]], lo[[0, 2]])
        np.testing.assert_allclose(centre[[0, 2]] + half[[0, 2]], hi[[0, 2]])
    assert right.T_tcp_box[1, 3] + right.half[1] == pytest.approx(hi[1])
    assert left.T_tcp_box[1, 3] - left.half[1] == pytest.approx(lo[1])


def test_a_description_without_a_tcp_frame_uses_the_declared_fingers(tmp_path: Path) -> None:
    scene = load_scene()
    text = scene.arms[0].urdf.read_text(encoding="utf-8")
    renamed = tmp_path / "no_tcp.urdf"
    renamed.write_text(text.replace('"tcp"', '"tool_centre"'), encoding="utf-8")
    arms = tuple(replace(a, urdf=renamed) for a in scene.arms)
    boxes = cell_gripper_boxes(replace(scene, arms=arms))
    expected = declared_finger_boxes(scene.arms[0].gripper)
    assert len(boxes) == 2
    for a, b in zip(boxes, expected, strict=True):
        np.testing.assert_array_equal(a.T_tcp_box, b.T_tcp_box)


def test_fingers_inside_the_opening_are_an_error() -> None:
    gripper = load_scene().arms[0].gripper
    narrow = replace(gripper, max_opening=0.2, stroke=0.2)
    with pytest.raises(SceneError, match=r"does not reach beyond the opening 0\.2 m"):
        declared_finger_boxes(narrow)
