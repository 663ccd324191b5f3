"""Plan files of a cell with a 6-joint and a 7-joint arm: exact round trips, located errors
when the plan's vectors do not fit the cell's arms, and the validator's rules per joint."""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pytest
from mixed_cell import PANDA_JOINTS, PANDA_UPPER, PANDA_VELOCITY, mixed_plan

from sdar_tamp.plan_file import PlanFile, PlanFileError
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_rules import check_format, check_scene, check_timeline
from sdar_tamp.plan_writing import plan_to_dict, save_plan
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.scene import Scene, load_scene
from sdar_tamp.world.shipped_cell import UR_JOINT_NAMES

SOLVED = Path(__file__).parents[1] / "plan" / "solved"


def _line_of(path: Path, needle: str) -> int:
    """The first line (from 1) of ``path`` holding ``needle``."""
    lines = path.read_text().splitlines()
    return next(i for i, line in enumerate(lines, 1) if needle in line)


# -- reading and writing -------------------------------------------------------------------------
def test_round_trip_keeps_each_arms_joint_count(
    plan: PlanFile, cell: Scene, tmp_path: Path
) -> None:
    path = save_plan(plan, tmp_path / "mixed.json")
    loaded = load_plan(path, cell.layout)
    assert plan_to_dict(loaded) == plan_to_dict(plan)
    assert loaded.q.shape == (len(plan.t), 13)
    assert loaded.layout.dofs == (6, 7)
    assert [len(a.joints) for a in loaded.arms] == [6, 7]
    assert loaded.arms[1].joints == tuple(f"right_{j}" for j in PANDA_JOINTS)
    assert loaded.arms[0].joints[0] == "left_shoulder_pan_joint"
    data = json.loads(path.read_text())
    assert len(data["arms"][1]["home"]) == 7 and len(data["trajectory"]["q"][0]) == 13
    again = save_plan(loaded, tmp_path / "again.json")
    assert again.read_bytes() == path.read_bytes()


@pytest.mark.parametrize("name", ["D5", "M2", "R5"])
def test_shipped_ur5e_plans_read_and_write_byte_identical(name: str, tmp_path: Path) -> None:
    source = SOLVED / f"{name}.plan.json"
    plan = load_plan(source, load_scene().layout)
    assert plan.layout.dofs == (6, 6)
    # a version-1 file (two arms) written again as version 2: only the version differs
    text = source.read_text(encoding="utf-8")
    assert '\n  "version": 1,\n' in text
    again = save_plan(plan, tmp_path / "copy.json").read_text(encoding="utf-8")
    assert again == text.replace('\n  "version": 1,\n', '\n  "version": 2,\n', 1)


def test_a_7_joint_plan_in_a_6_joint_cell_is_a_located_error(
    plan: PlanFile, tmp_path: Path
) -> None:
    path = save_plan(plan, tmp_path / "mixed.json")
    with pytest.raises(PlanFileError) as info:
        load_plan(path, load_scene().layout)
    line = _line_of(path, '"right_panda_joint1"')  # the right arm's joint list
    assert str(info.value).startswith(f"{path}:{line}:")
    assert info.value.key == "arms[1].joints"
    assert "the cell's arm 'right' has 6 joints, the plan's arm 'right' 7" in str(info.value)
    assert "right_panda_joint7" in str(info.value)


def test_a_ur5e_plan_in_the_mixed_cell_is_a_located_error(cell: Scene) -> None:
    source = SOLVED / "D5.plan.json"
    with pytest.raises(PlanFileError) as info:
        load_plan(source, cell.layout)
    line = _line_of(source, '"right_shoulder_pan_joint"')
    assert re.match(rf"{re.escape(str(source))}:{line}:\d+: arms\[1\]\.joints: ", str(info.value))
    assert "the cell's arm 'right' has 7 joints, the plan's arm 'right' 6" in str(info.value)


def test_a_short_row_is_located_at_its_line(plan: PlanFile, tmp_path: Path) -> None:
    data = plan_to_dict(plan)
    data["trajectory"]["q"][3].pop()
    path = tmp_path / "short.json"
    path.write_text(json.dumps(data, indent=1))
    with pytest.raises(PlanFileError) as info:
        load_plan(path)
    assert info.value.key == "trajectory.q[3]"
    assert "expected 13 numbers, got 12" in str(info.value)
    line = int(str(info.value)[len(str(path)) + 1 :].split(":")[0])
    text = path.read_text().splitlines()
    # the row starts on its line: the numbers of row 3 follow
    assert (
        text[line - 1].strip() == "["
        and json.loads(text[line].strip().rstrip(",")) == (data["trajectory"]["q"][3][0])
    )


def test_a_home_of_the_other_arms_length_is_an_error(plan: PlanFile, tmp_path: Path) -> None:
    data = plan_to_dict(plan)
    data["arms"][1]["home"] = data["arms"][1]["home"][:6]
    path = tmp_path / "home.json"
    path.write_text(json.dumps(data, indent=1))
    with pytest.raises(PlanFileError, match=r"arms\[1\]\.home: expected 7 numbers, got 6"):
        load_plan(path)


def test_an_arm_without_joints_is_an_error(plan: PlanFile, tmp_path: Path) -> None:
    data = plan_to_dict(plan)
    data["arms"][0]["joints"] = []
    path = tmp_path / "none.json"
    path.write_text(json.dumps(data))
    with pytest.raises(PlanFileError, match=r":1:\d+: arms\[0\]\.joints: expected the arm's"):
        load_plan(path)


# -- joint names ---------------------------------------------------------------------------------
def test_joint_names_per_arm(cell: Scene) -> None:
    assert cell.arms[0].joint_names == UR_JOINT_NAMES
    assert cell.arms[1].joint_names == PANDA_JOINTS
    with pytest.raises(SceneError, match="arm 'right': no joints"):
        dataclasses.replace(cell.arms[1], joint_names=())
    with pytest.raises(SceneError, match="lower has 7 values for 6 joints"):
        dataclasses.replace(cell.arms[1], joint_names=PANDA_JOINTS[:6])


# -- the validator's rules that need no replay ---------------------------------------------------
def test_the_plan_fits_its_cell(plan: PlanFile, cell: Scene) -> None:
    assert check_format(plan) is None
    assert check_scene(plan, cell) is None
    assert check_timeline(plan, cell) is None


def test_the_plan_does_not_fit_the_ur5e_cell(plan: PlanFile) -> None:
    v = check_scene(plan, load_scene())
    assert v is not None and v.kind == "scene"
    assert v.message.startswith("arms[1].joints: the scene's arm 'right' has 6 joints")
    assert v.message.endswith("the plan's 7")


def test_a_renamed_joint_is_named(plan: PlanFile, cell: Scene) -> None:
    right = plan.arms[1]
    joints = (*right.joints[:6], "right_joint_x")
    mutant = dataclasses.replace(
        plan, arms=(plan.arms[0], dataclasses.replace(right, joints=joints))
    )
    v = check_scene(mutant, cell)
    assert v is not None and "arms[1].joints[6]: expected 'right_panda_joint7'" in v.message


def _with(plan: PlanFile, q: np.ndarray) -> PlanFile:
    return dataclasses.replace(plan, q=q)


def test_joint_limits_per_joint(plan: PlanFile, cell: Scene) -> None:
    """The right arm's 7th joint (the plan's 13th column) and the left arm's 6th, each shifted
    to start 0.01 rad past its upper limit."""
    for column, upper, name in (
        (12, PANDA_UPPER[6], "right panda_joint7"),
        (5, None, "left wrist_3"),
    ):
        hi = cell.arms[0].upper[5] if upper is None else upper
        q = np.array(plan.q)
        q[:, column] += hi + 0.01 - q[0, column]
        v = check_timeline(_with(plan, q), cell)
        assert v is not None and v.kind == "joint limit" and v.t == 0.0, v
        assert v.message.startswith(f"{name} = {hi + 0.01:.6f} rad outside [")


def _constant_speed(plan: PlanFile, column: int, speed: float) -> np.ndarray:
    """The plan's q with ``column`` moving at ``speed`` [rad/s] over the last 0.1 s (and
    accelerations kept in bounds: the step is spread with a ramp)."""
    q = np.array(plan.q)
    n = len(q)
    ramp = np.concatenate([np.zeros(n - 6), np.arange(1, 7) * speed * 0.02])
    q[:, column] += ramp
    return q


@pytest.mark.parametrize(
    ("column", "joint", "breaks"),
    [
        (6, "panda_joint1", True),  # limit 2.175 rad/s
        (10, "panda_joint5", False),  # limit 2.61 rad/s
        (12, "panda_joint7", False),
    ],
)
def test_velocity_limits_per_joint(
    plan: PlanFile, cell: Scene, column: int, joint: str, breaks: bool
) -> None:
    speed = 2.4  # between the Panda's limits of joints 1-4 and 5-7
    assert PANDA_VELOCITY[0] < speed < PANDA_VELOCITY[4]
    mutant = _with(plan, _constant_speed(plan, column, speed))
    loose = dataclasses.replace(
        cell, arms=(cell.arms[0], dataclasses.replace(cell.arms[1], acceleration_limit=(1e3,) * 7))
    )
    v = check_timeline(mutant, loose)
    if breaks:
        assert v is not None and v.kind == "velocity", v
        assert v.message.startswith(f"right {joint} moves at 2.4 rad/s")
    else:
        assert v is None or v.kind != "velocity", v


def test_the_dwell_names_the_arms_joint(plan: PlanFile, cell: Scene) -> None:
    q = np.array(plan.q)
    k = round(1.6 / 0.02)  # inside the right arm's dwell after its grasp at 1.4 s
    q[k:, 11] += 1e-3  # right panda_joint6
    v = check_timeline(_with(plan, q), cell)
    assert v is not None and v.kind == "dwell", v
    assert v.t == pytest.approx(1.4) and "right panda_joint6 has moved 0.001 rad" in v.message


def test_mixed_plan_is_deterministic(cell: Scene) -> None:
    assert plan_to_dict(mixed_plan(cell)) == plan_to_dict(mixed_plan(cell))


def test_the_plan_schema_takes_arms_of_any_joint_count(plan: PlanFile) -> None:
    jsonschema = pytest.importorskip("jsonschema")
    from sdar_tamp.schemas import schema

    validator = jsonschema.Draft202012Validator(schema("plan"))
    document = json.loads(json.dumps(plan_to_dict(plan)))
    assert [e.message for e in validator.iter_errors(document)] == []
    document["arms"][1]["home"] = []
    assert list(validator.iter_errors(document))


def test_validate_command_locates_a_plan_of_other_arms(
    plan: PlanFile, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from sdar_tamp.cli import main
    from sdar_tamp.world.suites import shipped_suite_dir

    path = save_plan(plan, tmp_path / "mixed.json")
    code = main(["validate", str(shipped_suite_dir("paper") / "D5.yaml"), str(path)])
    err = capsys.readouterr().err
    line = _line_of(path, '"right_panda_joint1"')
    assert code == 2
    assert f"{path}:{line}:" in err and "the cell's arm 'right' has 6 joints" in err
