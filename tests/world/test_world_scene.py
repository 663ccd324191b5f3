from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from sdar_tamp.errors import SdarError
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.scene import Scene, default_scene_path, domain_path, load_scene

PI = 3.141592653589793
#: The values the paper cell loaded to before cells named their robot fully (recorded from
#: ``load_scene()`` of the first scene file form), field by field.
PAPER_LIMITS = ((-1.57, -PI, 0.0, -PI, -PI, -PI), (1.57, PI, PI, 0.0, PI, PI))
UR_JOINTS = tuple(
    f"{j}_joint"
    for j in ("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3")
)


def _check_paper_cell(scene: Scene) -> None:
    assert scene.table.size == (1.4, 0.8, 0.05)
    assert scene.workspace.x == (-0.25, 0.25) and scene.workspace.y == (-0.3, 0.3)
    assert scene.object_size == (0.08, 0.04, 0.05)
    assert scene.velocity_safety == 1.0 and scene.package_dirs == ()
    assert scene.arm_names == ("left", "right")
    for arm, xyz, yaw in zip(
        scene.arms, ((-0.55, 0.0, 0.0), (0.55, 0.0, 0.0)), (0.0, PI), strict=True
    ):
        assert arm.base_xyz == xyz and arm.base_yaw == yaw
        assert arm.urdf == domain_path("robots/ur5e_2f85.urdf").resolve()
        assert (arm.base_frame, arm.tool_frame, arm.joint_names) == (
            "base_link",
            "tool0",
            UR_JOINTS,
        )
        assert (arm.lower, arm.upper) == PAPER_LIMITS and arm.dof == 6
        assert arm.velocity_limit == (PI,) * 6 and arm.acceleration_limit == (5.0,) * 6
        assert arm.home == (0.0, -2.2, 1.9, -1.383, -1.57, 0.0)
        g = arm.gripper
        assert (g.max_opening, g.tcp_offset, g.grasp_margin, g.dwell) == (0.06, 0.178, 0.01, 0.5)
        assert (g.finger_depth, g.finger_width) == (0.017, 0.022)
    assert scene.robot_urdf == scene.arms[0].urdf and scene.gripper == scene.arms[0].gripper
    np.testing.assert_allclose(scene.arms[1].T_world_base[:2, :2], [[-1, 0], [0, -1]], atol=1e-12)


def test_shipped_scene_matches_the_paper_setup() -> None:
    scene = load_scene()
    _check_paper_cell(scene)
    assert scene.gripper.stroke == 0.085
    assert default_scene_path() == domain_path("cells/ur5e_facing.yaml")


def test_the_first_scene_form_loads_to_the_same_values() -> None:
    """Top-level robot and gripper, short joint keys, no fingers: the same cell."""
    old = load_scene(Path(__file__).parent / "data" / "scene_v1.yaml")
    _check_paper_cell(old)
    new = load_scene()
    assert old.arms[0].gripper.stroke == 0.06  # the first form names no stroke
    strokes = [
        dataclasses.replace(a, gripper=dataclasses.replace(a.gripper, stroke=0.0)) for a in new.arms
    ]
    olds = [
        dataclasses.replace(a, gripper=dataclasses.replace(a.gripper, stroke=0.0)) for a in old.arms
    ]
    assert strokes == olds
    assert dataclasses.replace(old, file="", arms=()) == dataclasses.replace(new, file="", arms=())


def _write(tmp_path: Path, data: dict[str, Any]) -> Path:
    data["robot"] = str(domain_path("robots/ur5e_2f85.urdf"))
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


def _data() -> dict[str, Any]:
    data: dict[str, Any] = yaml.safe_load(default_scene_path().read_text())
    return data


def _error(tmp_path: Path, data: dict[str, Any]) -> str:
    with pytest.raises(SceneError) as info:
        load_scene(_write(tmp_path, data))
    assert isinstance(info.value, SdarError)
    assert "scene.yaml:" in str(info.value)
    return str(info.value)


def test_bad_interval_names_the_yaml_path(tmp_path: Path) -> None:
    data = _data()
    data["arms"][1]["joint_limits"] = dict(data["arms"][1]["joint_limits"], elbow=[2.0, 1.0])
    msg = _error(tmp_path, data)
    assert "arms[1].joint_limits.elbow: expected [lower, upper] with lower < upper" in msg
    assert "[2.0, 1.0]" in msg


def test_unknown_key(tmp_path: Path) -> None:
    data = _data()
    data["tabel"] = {}
    assert "unknown key 'tabel'" in _error(tmp_path, data)


def test_missing_key(tmp_path: Path) -> None:
    data = _data()
    del data["arms"][0]["home"]
    assert "arms[0]: expected key 'home'" in _error(tmp_path, data)


def test_wrong_type(tmp_path: Path) -> None:
    data = _data()
    data["arms"][0]["acceleration_limit"] = "fast"
    assert "arms[0].acceleration_limit: expected a finite number > 0" in _error(tmp_path, data)


def test_wrong_length(tmp_path: Path) -> None:
    data = _data()
    data["object_size"] = [0.08, 0.04]
    assert "object_size: expected [lx, ly, lz]" in _error(tmp_path, data)


def test_non_positive(tmp_path: Path) -> None:
    data = _data()
    data["table"]["size"] = [1.4, -0.8, 0.05]
    assert "table.size[1]: expected a number > 0" in _error(tmp_path, data)


def test_home_outside_limits(tmp_path: Path) -> None:
    data = _data()
    data["arms"][0]["home"] = [0.0, -2.2, -1.0, -1.383, -1.57, 0.0]
    assert "arms[0].home[2]: expected elbow_joint within [0.0," in _error(tmp_path, data)


def test_no_arms(tmp_path: Path) -> None:
    data = _data()
    data["arms"] = []
    assert "arms: expected a non-empty list of arms" in _error(tmp_path, data)


def test_any_number_of_arms(tmp_path: Path) -> None:
    for count in (1, 3):
        data = _data()
        arms = [dict(data["arms"][k % 2], name=f"arm{k}") for k in range(count)]
        data["arms"] = arms
        scene = load_scene(_write(tmp_path, data))
        assert scene.arm_names == tuple(f"arm{k}" for k in range(count))
        assert scene.layout.dof == 6 * count


def test_duplicate_arm_names(tmp_path: Path) -> None:
    data = _data()
    data["arms"][1]["name"] = "left"
    assert "arms[1].name: expected a name different" in _error(tmp_path, data)


def test_missing_robot_file(tmp_path: Path) -> None:
    path = _write(tmp_path, _data())
    text = path.read_text().replace(str(domain_path("robots/ur5e_2f85.urdf")), "nope.urdf")
    path.write_text(text)
    with pytest.raises(SceneError, match="robot: expected a robot description file"):
        load_scene(path)


def test_yaml_syntax_error_has_line_and_column(tmp_path: Path) -> None:
    path = tmp_path / "scene.yaml"
    path.write_text("table: {size: [1, 2\narms: x\n")
    with pytest.raises(SceneError, match=r"scene.yaml:\d+:\d+: invalid YAML"):
        load_scene(path)


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(SceneError, match="cannot read file"):
        load_scene(tmp_path / "absent.yaml")


def test_error_location_points_at_the_line(tmp_path: Path) -> None:
    text = default_scene_path().read_text().replace("elbow_joint: [0.0,", "elbow_joint: [4.0,")
    text = text.replace(
        "robot: ../robots/ur5e_2f85.urdf", f"robot: {domain_path('robots/ur5e_2f85.urdf')}"
    )
    path = tmp_path / "scene.yaml"
    path.write_text(text)
    line = next(i for i, s in enumerate(text.splitlines(), 1) if "elbow_joint: [4.0," in s)
    with pytest.raises(SceneError, match=rf"scene.yaml:{line}:\d+: arms\[0\]\.joint_limits\.elbow"):
        load_scene(path)


def test_unknown_arm(scene: object) -> None:
    with pytest.raises(SceneError, match="unknown arm 'middle'"):
        load_scene().arm("middle")


def _robot_variant(tmp_path: Path, old: str, new: str) -> Path:
    """A scene whose robot is the shipped URDF with ``old`` replaced by ``new``."""
    text = domain_path("robots/ur5e_2f85.urdf").read_text(encoding="utf-8")
    assert old in text
    (tmp_path / "robot.urdf").write_text(text.replace(old, new), encoding="utf-8")
    data = _data()
    data["robot"] = "robot.urdf"
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def test_limits_outside_the_urdf_are_located(tmp_path: Path) -> None:
    data = _data()
    data["arms"][0]["joint_limits"] = dict(data["arms"][0]["joint_limits"], elbow=[0.0, 3.5])
    data["arms"][0]["home"][2] = 3.2
    msg = _error(tmp_path, data)
    assert "arms[0].joint_limits.elbow: expected limits within the URDF's" in msg
    assert "[-3.141592653589793, 3.141592653589793] of elbow_joint" in msg


def test_a_missing_joint_is_located(tmp_path: Path) -> None:
    path = _robot_variant(tmp_path, 'joint name="wrist_2_joint"', 'joint name="wrist_2"')
    with pytest.raises(SceneError) as info:
        load_scene(path)
    message = str(info.value)
    assert "scene.yaml:" in message
    assert "arms[0].joints[4]: expected a movable joint of the chain, one of" in message
    assert "'wrist_2'" in message


def test_a_joint_limit_of_no_joint_is_located(tmp_path: Path) -> None:
    data = _data()
    data["arms"][0]["joint_limits"]["thumb"] = [0.0, 1.0]
    msg = _error(tmp_path, data)
    assert "arms[0].joint_limits.thumb: expected a joint of the arm, one of" in msg


def test_default_joints_and_limits_come_from_the_urdf(tmp_path: Path) -> None:
    data = _data()
    for arm in data["arms"]:
        for key in ("joints", "joint_limits", "base_frame", "tool_frame"):
            del arm[key]
        arm["home"][2] = -1.9  # within the URDF's limits (-pi, pi), outside the cell's
    scene = load_scene(_write(tmp_path, data))
    left = scene.arm("left")
    assert left.joint_names == UR_JOINTS and left.base_frame == "base_link"
    assert left.lower == (-2 * PI, -2 * PI, -PI, -2 * PI, -2 * PI, -2 * PI)
    assert left.upper == (2 * PI, 2 * PI, PI, 2 * PI, 2 * PI, 2 * PI)
    assert left.velocity_limit == (PI,) * 6


def test_a_shorter_chain_and_per_joint_velocities(tmp_path: Path) -> None:
    """An arm may end at another frame: its joints are those of the chain to that frame."""
    data = _data()
    arm = data["arms"][0]
    arm["tool_frame"] = "wrist_3_link"
    del arm["joints"]
    arm["velocity_limit"] = [1.0, 2.0, 3.0, 3.0, 3.0, 3.0]
    assert load_scene(_write(tmp_path, data)).arms[0].velocity_limit == (1, 2, 3, 3, 3, 3)
    arm["tool_frame"] = "forearm_link"
    assert "arms[0].joint_limits.wrist_1_joint: expected a joint of the arm" in _error(
        tmp_path, data
    )
    arm["tool_frame"] = "base_link_inertia"
    del arm["joint_limits"]
    assert "arms[0].tool_frame: expected a frame that joints move" in _error(tmp_path, data)


def test_joints_out_of_chain_order_are_located(tmp_path: Path) -> None:
    data = _data()
    joints = data["arms"][0]["joints"]
    data["arms"][0]["joints"] = [joints[1], joints[0], *joints[2:]]
    assert "arms[0].joints: expected the chain's joints in chain order" in _error(tmp_path, data)


def test_a_missing_frame_is_located(tmp_path: Path) -> None:
    path = _robot_variant(tmp_path, '<link name="tool0"/>', '<link name="flange"/>')
    text = path.parent.joinpath("robot.urdf").read_text().replace('link="tool0"', 'link="flange"')
    path.parent.joinpath("robot.urdf").write_text(text)
    with pytest.raises(SceneError, match=r"scene\.yaml:\d+:\d+: arms\[0\]\.tool_frame: expected a "
                       r"frame 'tool0' in robot\.urdf"):  # fmt: skip
        load_scene(path)
    data = _data()
    data["arms"][1]["base_frame"] = "pedestal"
    assert "arms[1].base_frame: expected a frame 'pedestal'" in _error(tmp_path, data)


def test_an_arm_without_robot_or_gripper_is_located(tmp_path: Path) -> None:
    data = _data()
    path = _write(tmp_path, data)
    data = yaml.safe_load(path.read_text())
    data["arms"][0]["robot"] = data.pop("robot")
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(SceneError, match=r"arms\[1\]: expected key 'robot' \(here or at the top"):
        load_scene(path)
    data = _data()
    del data["gripper"]
    assert "arms[0]: expected key 'gripper' (here or at the top" in _error(tmp_path, data)


def test_a_robot_that_does_not_load_is_located(tmp_path: Path) -> None:
    path = _robot_variant(tmp_path, "</robot>", "")
    with pytest.raises(SceneError, match=r"robot\.urdf:\d+:\d+: not a well-formed"):
        load_scene(path)
