from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from sdar_tamp.errors import SdarError
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.scene import default_scene_path, domain_path, load_scene


def test_shipped_scene_matches_the_paper_setup() -> None:
    scene = load_scene()
    left, right = scene.arms
    assert scene.arm_names == ("left", "right")
    np.testing.assert_allclose(left.T_world_base[:3, 3], [-0.55, 0, 0])
    np.testing.assert_allclose(right.T_world_base[:2, :2], [[-1, 0], [0, -1]], atol=1e-12)
    assert left.lower[0] == -1.57 and left.upper[2] == pytest.approx(np.pi)
    assert left.home == (0.0, -2.2, 1.9, -1.383, -1.57, 0.0)
    assert left.velocity_limit == (pytest.approx(np.pi),) * 6
    assert left.acceleration_limit == (5.0,) * 6
    assert scene.object_size == (0.08, 0.04, 0.05)
    assert scene.gripper.max_opening == 0.060 and scene.gripper.tcp_offset == 0.178
    assert scene.robot_urdf.is_file()
    assert default_scene_path() == domain_path("scene.yaml")


def _write(tmp_path: Path, data: dict[str, Any]) -> Path:
    data["robot"] = str(domain_path("ur5e_2f85.urdf"))
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
    assert "arms[0].home[2]: expected elbow within [0.0," in _error(tmp_path, data)


def test_number_of_arms(tmp_path: Path) -> None:
    data = _data()
    data["arms"] = data["arms"][:1]
    assert "arms: expected a list of exactly two arms" in _error(tmp_path, data)


def test_duplicate_arm_names(tmp_path: Path) -> None:
    data = _data()
    data["arms"][1]["name"] = "left"
    assert "arms[1].name: expected a name different" in _error(tmp_path, data)


def test_missing_robot_file(tmp_path: Path) -> None:
    path = _write(tmp_path, _data())
    text = path.read_text().replace(str(domain_path("ur5e_2f85.urdf")), "nope.urdf")
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
    text = default_scene_path().read_text().replace("elbow: [0.0,", "elbow: [4.0,")
    text = text.replace("robot: ur5e_2f85.urdf", f"robot: {domain_path('ur5e_2f85.urdf')}")
    path = tmp_path / "scene.yaml"
    path.write_text(text)
    line = next(i for i, s in enumerate(text.splitlines(), 1) if "elbow: [4.0," in s)
    with pytest.raises(SceneError, match=rf"scene.yaml:{line}:\d+: arms\[0\]\.joint_limits\.elbow"):
        load_scene(path)


def test_unknown_arm(scene: object) -> None:
    with pytest.raises(SceneError, match="unknown arm 'middle'"):
        load_scene().arm("middle")


def _robot_variant(tmp_path: Path, old: str, new: str) -> Path:
    """A scene whose robot is the shipped URDF with ``old`` replaced by ``new``."""
    text = domain_path("ur5e_2f85.urdf").read_text(encoding="utf-8")
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
    assert "scene.yaml:" in message and "arms[0].joint_limits.wrist_2: expected a joint" in message
    assert "'wrist_2_joint' in robot.urdf" in message


def test_a_missing_frame_is_located(tmp_path: Path) -> None:
    path = _robot_variant(tmp_path, '<child link="tcp"/>', '<child link="tip"/>')
    path.parent.joinpath("robot.urdf").write_text(
        path.parent.joinpath("robot.urdf")
        .read_text()
        .replace('<link name="tcp"/>', '<link name="tip"/>')
    )
    with pytest.raises(
        SceneError,
        match=r"scene\.yaml:1:\d+: robot: expected a robot description "
        r"with a frame 'tcp'",
    ):
        load_scene(path)


def test_a_robot_that_does_not_load_is_located(tmp_path: Path) -> None:
    path = _robot_variant(tmp_path, "</robot>", "")
    with pytest.raises(SceneError, match=r"robot\.urdf:\d+:\d+: not a well-formed"):
        load_scene(path)
