"""Drawing a plan of a 6-joint and a 7-joint arm: each arm from its own robot description, its
joint curves against its own limits and names, the page and the storyboard."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mixed_cell import PANDA_JOINTS

from sdar_tamp.errors import SdarError
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.viewer import write_html, write_storyboard
from sdar_tamp.viewer._geometry import ArmDrawing
from sdar_tamp.viewer._joints import joint_figure
from sdar_tamp.viewer._story import grips, joint_curves
from sdar_tamp.viewer._timeline import Timeline
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene


@pytest.fixture(scope="module")
def timeline(instance: Instance, plan: PlanFile, cell: Scene) -> Timeline:
    return Timeline.build(instance, plan, cell)


def test_each_arm_is_drawn_from_its_own_robot(timeline: Timeline, plan: PlanFile) -> None:
    left, right = timeline.arms
    assert (left.dof, right.dof) == (6, 7)
    assert right.robot.urdf_path.name == "panda_arm.urdf"
    assert right.chain_frames() == ("universe", *PANDA_JOINTS, "tool0")
    assert left.chain_frames()[1:3] == ("shoulder_pan_joint", "shoulder_lift_joint")
    q = timeline.q_at(np.array([0.0, 2.0]))
    assert q.shape == (2, 13)
    points = right.chain_points(timeline.arm_q(q, 1))
    assert points.shape == (2, 7 + 3, 3)  # root, 7 joints, tool0, tcp
    tcp = right.tcp_poses(timeline.arm_q(q, 1))[:, :3, 3]
    np.testing.assert_allclose(points[:, -1], tcp, atol=1e-12)
    np.testing.assert_allclose(points[:, 0], plan.arms[1].T_world_base[:3, 3][None].repeat(2, 0))
    assert right.static_links() == ("panda_link0",) and left.static_links() == ("base_link",)


def test_joint_curves_per_arm(timeline: Timeline, cell: Scene) -> None:
    curves = joint_curves(timeline, cell)
    assert [p.shape[1] for p in curves.position] == [6, 7]
    assert curves.joints[1] == PANDA_JOINTS
    assert np.all((curves.position[1] >= 0.0) & (curves.position[1] <= 1.0))
    figure = joint_figure(curves, ["left", "right"], [(0.0, 1.4)], None)
    names = [trace["name"] for trace in figure["data"]]
    assert len(names) == 2 * (6 + 7)
    assert names[:6] == ["shoulder pan", "shoulder lift", "elbow", "wrist 1", "wrist 2", "wrist 3"]
    assert names[12:19] == [f"panda joint{i}" for i in range(1, 8)]
    shown = [t["name"] for t in figure["data"] if t["showlegend"]]
    assert len(shown) == len(set(shown)) == 13  # every joint once in the legend
    assert len(grips(timeline, np.array([0.0, 1.6]))) == 2


def test_page_and_storyboard(
    instance: Instance, plan: PlanFile, cell: Scene, tmp_path: Path
) -> None:
    page = write_html(instance, plan, tmp_path / "mixed.html", cell, fps=5.0, validate=False)
    text = page.read_text()
    assert "panda joint7" in text
    board = write_storyboard(instance, plan, tmp_path / "mixed.png", cell)
    assert board.stat().st_size > 0


def test_an_arm_of_some_of_the_robots_joints(timeline: Timeline) -> None:
    """The arm's joints placed into the robot's configuration by name (here the UR5e's in
    reverse order: the same poses as in order)."""
    left = timeline.arms[0]
    names = left.robot.joint_names
    backwards = ArmDrawing.build("b", left.robot, left.T_world_base, left.T_tool0_tcp,
                                 joints=tuple(reversed(names)))  # fmt: skip
    assert backwards.q_index == (5, 4, 3, 2, 1, 0) and backwards.dof == 6
    q = np.linspace(-0.5, 0.5, 6)[None]
    np.testing.assert_allclose(backwards.tcp_poses(q[:, ::-1]), left.tcp_poses(q), atol=1e-12)
    with pytest.raises(SdarError, match="no joint named 'finger_joint'"):
        ArmDrawing.build("b", left.robot, left.T_world_base, left.T_tool0_tcp,
                         joints=("finger_joint",))  # fmt: skip
