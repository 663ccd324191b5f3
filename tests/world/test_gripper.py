"""The gripper of a cell: read from the scene file, fingers measured or declared."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from sdar_tamp.plan_file import GRIPPER_DWELL
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.graspability import GraspLimits
from sdar_tamp.world.gripper import DEFAULT_DWELL, box_envelope
from sdar_tamp.world.scene import default_scene_path, domain_path, load_scene
from sdar_tamp.world.shipped_cell import SHIPPED_GRASP


def _data() -> dict[str, Any]:
    data: dict[str, Any] = yaml.safe_load(default_scene_path().read_text())
    data["robot"] = str(domain_path("robots/ur5e_2f85.urdf"))
    return data


def _load(tmp_path: Path, data: dict[str, Any]) -> Any:
    path = tmp_path / "cell.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return load_scene(path)


def _error(tmp_path: Path, data: dict[str, Any]) -> str:
    with pytest.raises(SceneError) as info:
        _load(tmp_path, data)
    assert "cell.yaml:" in str(info.value)
    return str(info.value)


def test_the_shipped_gripper_and_its_defaults() -> None:
    g = load_scene().gripper
    assert (g.max_opening, g.stroke, g.tcp_offset, g.grasp_margin) == (0.06, 0.085, 0.178, 0.01)
    assert g.finger_links == ("gripper_left_finger", "gripper_right_finger")
    assert g.max_graspable_width == pytest.approx(0.05)
    assert g.limits == GraspLimits(0.06 - 0.01, 0.017, 0.022)
    assert DEFAULT_DWELL == GRIPPER_DWELL == g.dwell
    # the instance loader's default is the shipped cell's gripper
    assert dataclasses.astuple(SHIPPED_GRASP) == pytest.approx(dataclasses.astuple(g.limits))


def test_a_declared_finger_box(tmp_path: Path) -> None:
    data = _data()
    del data["gripper"]["fingers"]
    data["gripper"]["finger_box"] = {
        "depth": 0.02,
        "width": 0.03,
        "length": 0.05,
        "thickness": 0.01,
    }
    g = _load(tmp_path, data).gripper
    assert (g.finger_depth, g.finger_width, g.finger_links) == (0.02, 0.03, ())
    np.testing.assert_allclose(g.envelope.min(axis=0), [-0.015, -0.04, -0.03])
    np.testing.assert_allclose(g.envelope.max(axis=0), [0.015, 0.04, 0.02])
    assert box_envelope((0, 1), (0, 1), (0, 1))[1] == (0, 0, 1)


def test_a_per_arm_gripper_and_the_shared_grasp_limits(tmp_path: Path) -> None:
    data = _data()
    wide = dict(data["gripper"], max_opening=0.08, stroke=0.085, dwell=0.3)
    data["arms"][1]["gripper"] = wide
    scene = _load(tmp_path, data)
    left, right = (scene.arm(n).gripper for n in ("left", "right"))
    assert (left.max_opening, right.max_opening, right.dwell) == (0.06, 0.08, 0.3)
    assert scene.grasp_limits == GraspLimits.shared([left.limits, right.limits])
    assert scene.grasp_limits.max_width == left.max_graspable_width
    with pytest.raises(ValueError, match="at least one"):
        GraspLimits.shared([])


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda g: g.update(stroke=0.05), "gripper.stroke: expected a stroke >= max_opening"),
        (lambda g: g.update(grasp_margin=0.07), "gripper.grasp_margin: expected a margin in [0"),
        (lambda g: g.update(dwell=-1), "gripper.dwell: expected a time >= 0"),
        (
            lambda g: g.update(finger_box={"depth": 1, "width": 1, "length": 1, "thickness": 1}),
            "gripper.finger_box: expected either fingers or finger_box, not both",
        ),
        (
            lambda g: g.update(fingers=["gripper_left_finger", "tool0"]),
            "gripper.fingers: expected finger links that can be measured: finger link 'tool0'",
        ),
        (lambda g: g.update(fingers="pads"), "gripper.fingers: expected a list"),
        (
            lambda g: g.update(tcp_offset=0.17),
            "gripper.tcp_offset: expected the offset of the description's 'tcp' frame from "
            "'tool0' (0.0000, 0.0000, 0.1780) m, unturned (it differs by 0.008), got 0.17",
        ),
        (
            lambda g: g.update(max_opening=0.04, stroke=0.085),
            "gripper: expected a gripper that holds the default object [0.08, 0.04, 0.05]: "
            "both horizontal sides",
        ),
    ],
)
def test_bad_grippers_are_located(tmp_path: Path, edit: Any, message: str) -> None:
    data = _data()
    edit(data["gripper"])
    assert message in _error(tmp_path, data)


def test_a_gripper_needs_fingers_when_the_urdf_has_no_shipped_ones(tmp_path: Path) -> None:
    text = domain_path("robots/ur5e_2f85.urdf").read_text(encoding="utf-8")
    (tmp_path / "robot.urdf").write_text(text.replace("gripper_left_finger", "pad_l"))
    data = _data()
    data["robot"] = "robot.urdf"
    del data["gripper"]["fingers"]
    assert "gripper: expected key 'fingers' (two URDF links) or 'finger_box'" in _error(
        tmp_path, data
    )
    data["gripper"]["fingers"] = ["pad_l", "gripper_right_finger"]
    assert _load(tmp_path, data).gripper.finger_depth == 0.017


def test_a_per_arm_gripper_that_cannot_hold_the_object_is_located(tmp_path: Path) -> None:
    data = _data()
    data["arms"][1]["gripper"] = dict(data["gripper"], max_opening=0.045)
    msg = _error(tmp_path, data)
    assert "arms[1].gripper: expected a gripper that holds the default object" in msg
