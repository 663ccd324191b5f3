"""The URScript export: the servoj stream read back matches the plan at the controller period,
gripper calls come at the event times in order, the header states the base-to-base transform."""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.export import ServoSettings, urscript_programs, write_urscript
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.world.transforms import inverse, pose_xyz_yaw

NUMBER = r"-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?"
SERVOJ = re.compile(
    rf"^  servoj\(\[({NUMBER}(?:, {NUMBER}){{5}})\], 0, 0, servo_t, servo_lookahead, servo_gain\)$"
)
GRIPPER = re.compile(r'^  sdar_gripper_(close|open)\("([^"]+)"\)$')
SETTING = re.compile(rf"^  (servo_t|servo_lookahead|servo_gain) = ({NUMBER})  #")


def _stream(
    text: str, period: float
) -> tuple[np.ndarray, np.ndarray, list[tuple[float, str, str]]]:
    """Targets (m, 6), their times (k * period, k = 1..m) and the gripper calls with the time
    of the target just before them (0 before the first)."""
    targets, calls = [], []
    for line in text.splitlines():
        if m := SERVOJ.match(line):
            targets.append([float(x) for x in m.group(1).split(", ")])
        elif m := GRIPPER.match(line):
            calls.append((len(targets) * period, m.group(1), m.group(2)))
    return np.array(targets), period * np.arange(1, len(targets) + 1), calls


def _matrix_after(text: str, title: str) -> np.ndarray:
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(title)) + 1
    rows = [re.findall(NUMBER, lines[start + r]) for r in range(4)]
    return np.array(rows, dtype=float)


@pytest.mark.parametrize("period", [0.008, 0.002, 0.03])
def test_servoj_stream_matches_the_plan(plan: PlanFile, period: float) -> None:
    programs = urscript_programs(plan, ServoSettings(period=period))
    assert list(programs) == ["left", "right"]
    for index, text in enumerate(programs.values()):
        targets, times, _ = _stream(text, period)
        assert len(targets) == math.ceil(plan.duration / period - 1e-9)
        assert times[-1] >= plan.duration - 1e-12 and times[-1] < plan.duration + period
        cols = slice(6 * index, 6 * index + 6)
        expected = np.stack([np.interp(times, plan.t, plan.q[:, j]) for j in range(12)], 1)
        np.testing.assert_allclose(targets, expected[:, cols], rtol=0, atol=1e-9)
        movej = re.search(r"movej\(\[([^\]]+)\]", text)
        assert movej is not None
        np.testing.assert_allclose([float(x) for x in movej.group(1).split(", ")], plan.q[0, cols])


def test_gripper_calls_at_the_event_times_in_order(plan: PlanFile) -> None:
    period = 0.008
    for arm, text in urscript_programs(plan, ServoSettings(period=period)).items():
        _, _, calls = _stream(text, period)
        events = [e for e in plan.events if e.arm == arm]
        kinds = {"grasp": "close", "release": "open"}
        assert [(c[1], c[2]) for c in calls] == [(kinds[e.type], e.object) for e in events]
        for (t_call, _, _), e in zip(calls, events, strict=True):
            assert e.t - 1e-9 <= t_call < e.t + period  # the first target at or after it


def test_event_at_the_start_comes_before_the_stream(plan: PlanFile) -> None:
    early = dataclasses.replace(plan.events[0], t=0.0)
    moved = dataclasses.replace(plan, events=(early, *plan.events[1:]))
    text = urscript_programs(moved)["left"]
    lines = text.splitlines()
    call = lines.index('  sdar_gripper_close("o1")')
    assert lines[call - 1] == "  sdar_wait_for_start()"
    assert SERVOJ.match(lines[call + 1])


def test_settings_are_stated(plan: PlanFile) -> None:
    text = urscript_programs(plan, ServoSettings(period=0.004, lookahead=0.05, gain=500))["left"]
    values = {m.group(1): float(m.group(2)) for m in map(SETTING.match, text.splitlines()) if m}
    assert values == {"servo_t": 0.004, "servo_lookahead": 0.05, "servo_gain": 500.0}
    assert "one every servo_t = 0.004 s" in text and "lookahead_time 0.05 s, gain 500" in text


def test_header_states_the_base_to_base_transform(plan: PlanFile) -> None:
    programs = urscript_programs(plan)
    T_left_right = inverse(plan.arms[0].T_world_base) @ plan.arms[1].T_world_base
    left, right = programs["left"], programs["right"]
    np.testing.assert_allclose(_matrix_after(left, "# T_left_right"), T_left_right, atol=1e-6)
    np.testing.assert_allclose(
        _matrix_after(right, "# T_right_left"), inverse(T_left_right), atol=1e-6
    )
    np.testing.assert_allclose(
        _matrix_after(left, "# T_world_base of left"), plan.arms[0].T_world_base, atol=1e-6
    )
    flip = pose_xyz_yaw(0.0, 0.0, 0.0, math.pi)  # controller Base in base_link
    np.testing.assert_allclose(
        _matrix_after(left, "# The same between the controllers' Base frames"),
        inverse(flip) @ T_left_right @ flip,
        atol=1e-6,
    )
    assert "# Units: m, rad, s." in left
    assert np.allclose(T_left_right[:3, 3], [1.1, 0.0, 0.0])  # the shipped scene's bases


def test_program_structure(plan: PlanFile, tmp_path: Path) -> None:
    paths = write_urscript(plan, tmp_path / "scripts")
    assert [p.name for p in paths] == ["left.script", "right.script"]
    for path in paths:
        lines = path.read_text(encoding="utf-8").splitlines()
        code = [line for line in lines if line.strip() and not line.startswith("#")]
        assert code[0] == f"def sdar_{path.stem}():" and code[-1] == "end"
        opened = sum(line.strip().startswith("def ") for line in code)
        assert opened == 4 == sum(line.strip() == "end" for line in code)
        assert code[-2] == "  stopj(start_acceleration)"


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("period", 0.0),
        ("period", 0.001),
        ("lookahead", 0.5),
        ("gain", 50.0),
        ("gain", float("nan")),
        ("start_speed", 0.0),
        ("start_acceleration", True),
    ],
)
def test_bad_settings_name_the_parameter(field: str, value: float) -> None:
    with pytest.raises(ParameterError, match=rf"^{field} must be a number in \["):
        ServoSettings(**{field: value})


def test_names_that_cannot_be_written_are_refused(plan: PlanFile) -> None:
    bad = dataclasses.replace(plan.events[0], object='o1"); popup("x')
    with pytest.raises(ParameterError, match="object name"):
        urscript_programs(dataclasses.replace(plan, events=(bad, *plan.events[1:])))
