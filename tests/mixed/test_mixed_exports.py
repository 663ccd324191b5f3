"""Exporting a plan of a 6-joint and a 7-joint arm: each arm's joint trajectory holds its own
joints under its robot's joint names, the CSV table one column per joint, and URScript refuses
the arm that is not a UR arm (naming it, and its robot file when the cell is given)."""

from __future__ import annotations

import csv
import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from mixed_cell import PANDA_JOINTS, PANDA_URDF

from sdar_tamp.cli import main
from sdar_tamp.errors import ParameterError
from sdar_tamp.export import export_plan, export_plan_file, joint_trajectory_document
from sdar_tamp.export.table import csv_header
from sdar_tamp.export.timeline import gripper_states, positions_at
from sdar_tamp.export.urscript import check_ur_arms, urscript_programs
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_writing import save_plan
from sdar_tamp.world.scene import Scene, load_scene


def test_joint_trajectories_of_each_arms_size(plan: PlanFile) -> None:
    doc = joint_trajectory_document(plan)
    left, right = (a["joint_trajectory"] for a in doc["arms"])
    assert left["joint_names"][0] == "left_shoulder_pan_joint" and len(left["joint_names"]) == 6
    assert right["joint_names"] == [f"right_{j}" for j in PANDA_JOINTS]
    for message, k, cols in ((left, 6, slice(0, 6)), (right, 7, slice(6, 13))):
        points = message["points"]
        assert len(points) == len(plan.t)
        assert all(len(p[key]) == k for p in points for key in ("positions", "velocities"))
        np.testing.assert_array_equal(
            np.array([p["positions"] for p in points]), np.asarray(plan.q[:, cols])
        )


def test_csv_has_a_column_per_joint(plan: PlanFile, tmp_path: Path) -> None:
    header = csv_header(plan)
    assert len(header) == 1 + 13 + 2 + 2
    assert header[7:14] == [f"right_{j}" for j in PANDA_JOINTS]
    (path,) = export_plan(plan, "csv", tmp_path / "mixed.csv")
    with path.open() as stream:
        rows = list(csv.reader(stream))
    assert rows[0] == header and all(len(r) == len(header) for r in rows)
    last = np.array([float(x) for x in rows[-1][1:14]])
    np.testing.assert_allclose(last, plan.q[-1])
    assert rows[-1][14:] == ["1", "1", "o1", "o2"]


def test_timeline_helpers_take_every_arm(plan: PlanFile) -> None:
    times = np.array([0.0, 1.2, 1.5])
    assert positions_at(plan, times).shape == (3, 13)
    state = gripper_states(plan, times)
    assert state.closed.tolist() == [[False, False], [True, False], [True, True]]
    assert state.held == (("", ""), ("o1", ""), ("o1", "o2"))


def test_urscript_refuses_the_7_joint_arm_by_its_joints(plan: PlanFile, tmp_path: Path) -> None:
    with pytest.raises(ParameterError) as info:
        export_plan(plan, "urscript", tmp_path / "scripts")
    text = str(info.value)
    assert "arm 'right' is not a Universal Robots arm" in text
    assert "right_panda_joint1" in text and "joint-trajectory or csv" in text
    assert not (tmp_path / "scripts").exists()  # nothing written


def test_urscript_names_the_robot_file_given_the_cell(plan: PlanFile, cell: Scene) -> None:
    with pytest.raises(ParameterError) as info:
        urscript_programs(plan, scene=cell)
    text = str(info.value)
    assert "arm 'right' is not a Universal Robots arm" in text
    assert str(PANDA_URDF) in text and "no UR-family chain to tool0" in text


def test_urscript_accepts_ur_arms_by_their_robot(plan: PlanFile, cell: Scene) -> None:
    ur_cell = load_scene()
    check_ur_arms(dataclasses.replace(plan, arms=plan.arms[:1]), cell)  # the left UR5e alone
    check_ur_arms(dataclasses.replace(plan, arms=plan.arms[:1]), ur_cell)


def test_export_command_checks_the_cell(
    plan: PlanFile, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = save_plan(plan, tmp_path / "mixed.json")
    code = main(["export", str(path), "--format", "urscript", "-o", str(tmp_path / "s")])
    err = capsys.readouterr().err
    assert code == 2 and "arm 'right' is not a Universal Robots arm" in err
    code = main(["export", str(path), "--format", "csv", "--scene", str(_ur_scene_file())])
    err = capsys.readouterr().err
    assert code == 2 and "arms[1].joints: the cell's arm 'right' has 6 joints" in err
    assert main(["export", str(path), "--format", "joint-trajectory"]) == 0
    doc = json.loads((tmp_path / "mixed.trajectory.json").read_text())
    assert len(doc["arms"][1]["joint_trajectory"]["points"][0]["positions"]) == 7


def test_export_plan_file_with_the_ur_cell(tmp_path: Path) -> None:
    source = Path(__file__).parents[1] / "plan" / "solved" / "M2.plan.json"
    paths = export_plan_file(source, "urscript", tmp_path / "ur", scene=load_scene())
    assert sorted(p.name for p in paths) == ["left.script", "right.script"]


def _ur_scene_file() -> Path:
    from sdar_tamp.world.scene import default_scene_path

    return default_scene_path()
