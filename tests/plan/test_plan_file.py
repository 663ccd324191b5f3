"""The plan file: JSON round trip, one test per load error, and the timeline builder."""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_building import GripperEvent, MotionSegment, build_plan_file, resample
from sdar_tamp.plan_file import PlanFile, PlanFileError
from sdar_tamp.plan_reading import load_plan, locate_key, plan_from_dict
from sdar_tamp.plan_rules import check_timeline
from sdar_tamp.plan_writing import plan_to_dict, save_plan
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene, load_scene
from sdar_tamp.world.transforms import pose_xyz_yaw

STARTS = {"o1": (-0.1, 0.1, 0.3), "o2": (0.1, 0.0, 0.0)}
SIZES = {"o1": (0.08, 0.04, 0.05), "o2": (0.08, 0.04, 0.05)}
T_TCP_OBJ = pose_xyz_yaw(0.0, 0.0, 0.01, 0.4)


@pytest.fixture(scope="module")
def scene() -> Scene:
    return load_scene()


def _home(scene: Scene) -> np.ndarray:
    return np.concatenate([np.array(a.home) for a in scene.arms])


def _segment(q0: np.ndarray, delta: np.ndarray, times: list[float]) -> MotionSegment:
    t = np.array(times)
    return MotionSegment(t, q0 + (t / t[-1])[:, None] * delta, "plain", ("o1",), "move")


def _items(scene: Scene) -> list[MotionSegment | GripperEvent]:
    """Left arm moves (coarse 0.05 s samples), two gripper events at one instant, both arms
    move, a release, then nothing."""
    home = _home(scene)
    left = np.zeros(12)
    left[:6] = 0.1
    a = _segment(home, left, [0.0, 0.05, 0.1])
    b = _segment(a.q[-1], np.full(12, -0.05), [0.0, 0.02, 0.04, 0.06])
    return [
        a,
        GripperEvent("left", "grasp", "o1", T_TCP_OBJ),
        GripperEvent("right", "grasp", "o2", T_TCP_OBJ),
        b,
        GripperEvent("left", "release", "o1", T_TCP_OBJ),
    ]


@pytest.fixture(scope="module")
def plan(scene: Scene) -> PlanFile:
    return build_plan_file(
        scene, "T2", STARTS, SIZES, _items(scene), {"planning_time": 1.5, "actions": 99}
    )


# -- round trip --------------------------------------------------------------------------------
def test_round_trip_is_exact(plan: PlanFile, tmp_path: Path) -> None:
    path = save_plan(plan, tmp_path / "sub" / "plan.json")
    loaded = load_plan(path)
    assert plan_to_dict(loaded) == plan_to_dict(plan)
    np.testing.assert_array_equal(loaded.q, plan.q)
    assert loaded.steps == plan.steps
    data = json.loads(path.read_text())
    assert data["format"] == "sdar-plan" and data["version"] == 2
    assert data["units"] == {"length": "m", "angle": "rad", "time": "s"}
    assert data["arms"][0]["joints"][0] == "left_shoulder_pan_joint"


def test_arrays_are_read_only(plan: PlanFile) -> None:
    with pytest.raises(ValueError):
        plan.q[0, 0] = 1.0


# -- load errors (one per rule) ------------------------------------------------------------------
def _set(path: list[Any], value: Any) -> Callable[[dict[str, Any]], None]:
    def edit(data: dict[str, Any]) -> None:
        node = data
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = value

    return edit


def _drop_last_joint(data: dict[str, Any]) -> None:
    data["trajectory"]["q"][3].pop()


def _repeat_time(data: dict[str, Any]) -> None:
    data["trajectory"]["t"][2] = data["trajectory"]["t"][1]


BAD: dict[str, tuple[Callable[[dict[str, Any]], object], str]] = {
    "missing format": (lambda d: d.pop("format"), ": missing key 'format'"),
    "missing key": (lambda d: d.pop("events"), ": missing key 'events'"),
    "not a list": (_set(["events"], {}), ": events: expected a list of events, got {}"),
    "unexpected key": (_set(["extra"], 1), ": extra: unexpected key"),
    "format": (_set(["format"], "other"), ": format: expected 'sdar-plan'"),
    "version": (_set(["version"], 3), ": version: expected one of [1, 2] (this reader), got 3"),
    "version type": (_set(["version"], True), ": version: expected one of [1, 2]"),
    "units": (_set(["units", "length"], "mm"), ": units: expected"),
    "arm count": (
        lambda d: (d.update(version=1), d["arms"].pop()),
        ": arms: expected 2 arms (a version-1 file), got 1",
    ),
    "no arms": (_set(["arms"], []), ": arms: expected at least 1 arm (a version-2 file), got 0"),
    "arms not a list": (_set(["arms"], {}), ": arms: expected a list of arms, got {}"),
    "arm names": (_set(["arms", 1, "name"], "left"), ": arms[1].name: expected a name"),
    "joints": (_set(["arms", 0, "joints"], []), ": arms[0].joints: expected the arm's joint"),
    "joints and home": (_set(["arms", 0, "joints"], ["a"]), ": arms[0].home: expected 1 numbers"),
    "rigid": (_set(["arms", 0, "T_world_base", 0, 0], 2.0), ": arms[0].T_world_base: expected"),
    "home": (_set(["arms", 1, "home"], [0.0] * 5), ": arms[1].home: expected 6 numbers, got 5"),
    "row length": (_drop_last_joint, ": trajectory.q[3]: expected 12 numbers, got 11"),
    "row count": (lambda d: d["trajectory"]["q"].pop(), ": trajectory.q: expected"),
    "number": (_set(["trajectory", "q", 2, 0], "x"), ": trajectory.q[2][0]: expected a finite"),
    "nan": (_set(["trajectory", "q", 2, 1], math.nan), ": trajectory.q[2][1]: expected a finite"),
    "t0": (_set(["trajectory", "t", 0], 0.001), ": trajectory.t[0]: expected 0"),
    "increasing": (_repeat_time, ": trajectory.t[2]: expected a time >"),
    "spacing": (
        _set(["trajectory", "t", 1], 0.0201),
        ": trajectory.t[1]: expected at most 0.02 s after trajectory.t[0], got 0.0201 s",
    ),
    "empty": (_set(["trajectory"], {"t": [], "q": []}), ": trajectory.t: expected at least one"),
    "unsorted": (_set(["events", 2, "t"], 0.05), ": events[2].t: expected a time >= events[1].t"),
    "event time": (_set(["events", 2, "t"], 99.0), ": events[2].t: expected a time within"),
    "event arm": (_set(["events", 0, "arm"], "middle"), ": events[0].arm: expected one of"),
    "event type": (_set(["events", 0, "type"], "push"), ": events[0].type: expected one of"),
    "event pose": (_set(["events", 0, "T_tcp_object"], [[1]]), ": events[0].T_tcp_object: exp"),
    "final pose": (_set(["final_poses", "o1"], [0.0, 0.0]), ": final_poses.o1: expected 3 num"),
    "metric": (_set(["metrics", "steps"], True), ": metrics.steps: expected a finite number"),
    "step": (_set(["steps", 0, "objects"], "o1"), ": steps[0].objects: expected a list"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_each_load_error_names_file_and_key(plan: PlanFile, tmp_path: Path, case: str) -> None:
    edit, expected = BAD[case]
    data = plan_to_dict(plan)
    edit(data)
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(data, indent=1))
    with pytest.raises(PlanFileError) as info:
        load_plan(path)
    err = info.value
    if err.key and locate_key(path.read_text(), err.key) is not None:  # located at the value
        line, column = locate_key(path.read_text(), err.key) or (0, 0)
        assert str(err).startswith(f"{path}:{line}:{column}: {err.key}: ")
    else:  # a missing key: the file
        assert str(err).startswith(f"{path}: ")
    assert expected in str(err)


def test_exact_message_of_a_short_row(plan: PlanFile) -> None:
    data = plan_to_dict(plan)
    _drop_last_joint(data)
    with pytest.raises(PlanFileError) as info:
        plan_from_dict(data, "plan.json")
    assert str(info.value) == "plan.json: trajectory.q[3]: expected 12 numbers, got 11"
    assert info.value.key == "trajectory.q[3]"


def test_missing_file_and_bad_json(tmp_path: Path) -> None:
    with pytest.raises(PlanFileError, match="cannot read file"):
        load_plan(tmp_path / "none.json")
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "sdar-plan",\n  "version": }')
    with pytest.raises(PlanFileError, match=r"bad.json:2:14: invalid JSON"):
        load_plan(bad)
    bad.write_text("[1, 2]")
    with pytest.raises(PlanFileError, match=r"bad.json: expected an object with keys"):
        load_plan(bad)


# -- the builder ---------------------------------------------------------------------------------
def test_timeline_dwell_and_resampling(plan: PlanFile, scene: Scene) -> None:
    t, q = plan.t, plan.q
    assert t[0] == 0.0 and np.all(np.diff(t) > 0) and np.diff(t).max() <= 0.02 + 1e-12
    # segment a: 0.1 s; two events at the same instant; one dwell of 0.5 s; segment b: 0.06 s
    assert [e.t for e in plan.events] == pytest.approx([0.1, 0.1, 0.66])
    assert plan.duration == pytest.approx(0.1 + 0.5 + 0.06 + 0.5)
    dwell = (t >= 0.1 - 1e-12) & (t <= 0.6 + 1e-12)
    assert dwell.sum() >= 26 and np.ptp(q[dwell], axis=0).max() == 0.0
    # resampled linearly: the coarse first segment is a straight line in joint space
    first = t <= 0.1 + 1e-12
    home = _home(scene)
    np.testing.assert_allclose(q[first, 0], home[0] + t[first], atol=1e-12)
    bounds = [x for s in plan.steps for x in (s.t_start, s.t_end)]
    assert bounds == pytest.approx([0.0, 0.1, 0.6, 0.66])
    assert plan.steps[0].level == "plain" and plan.steps[0].objects == ("o1",)


def test_a_second_event_of_one_arm_waits_for_the_dwell_of_its_first(scene: Scene) -> None:
    """A release and a grasp of one arm with no motion between them (an arm that puts an
    object down and takes it up again): the grasp comes one dwell after the release."""
    items: list[MotionSegment | GripperEvent] = [
        GripperEvent("left", "grasp", "o1", T_TCP_OBJ),
        GripperEvent("right", "grasp", "o2", T_TCP_OBJ),
        GripperEvent("left", "release", "o1", T_TCP_OBJ),
        GripperEvent("left", "grasp", "o1", T_TCP_OBJ),
    ]
    plan = build_plan_file(scene, "T2", STARTS, SIZES, items, {})
    assert [e.t for e in plan.events] == pytest.approx([0.0, 0.0, 0.5, 1.0])
    assert plan.duration == pytest.approx(3 * 0.5)
    assert check_timeline(plan, scene) is None
    # without the wait the timeline breaks the dwell rule the validator enforces
    squeezed = dataclasses.replace(
        plan, events=tuple(dataclasses.replace(e, t=min(e.t, 0.5)) for e in plan.events)
    )
    limit = check_timeline(squeezed, scene)
    assert limit is not None and limit.kind == "dwell"


def test_metrics_and_final_poses(plan: PlanFile, scene: Scene) -> None:
    m = plan.metrics
    assert m.actions == 1  # o1 placed; o2 still held; the passed 99 is replaced
    assert m.steps == 2 and m.dual_arm_steps == 1
    assert m.execution_time == pytest.approx(plan.duration)
    assert m.planning_time == 1.5
    assert plan.final_poses["o2"] == STARTS["o2"]
    q_left = plan.q[np.searchsorted(plan.t, plan.events[2].t), :6]
    T = ArmKinematics.from_scene(scene, "left").fk_tcp(q_left) @ T_TCP_OBJ
    x, y, yaw = plan.final_poses["o1"]
    assert (x, y) == pytest.approx((T[0, 3], T[1, 3]))
    assert yaw == pytest.approx(math.atan2(T[1, 0], T[0, 0]))
    assert [a.name for a in plan.arms] == list(scene.arm_names)
    np.testing.assert_allclose(plan.arms[1].T_world_base, scene.arms[1].T_world_base)


def test_builder_rejects_a_segment_that_does_not_connect(scene: Scene) -> None:
    items = _items(scene)
    seg = items[3]
    assert isinstance(seg, MotionSegment)
    items[3] = MotionSegment(seg.t, seg.q + 0.01)
    with pytest.raises(ParameterError, match=r"items\[3\]: the segment starts"):
        build_plan_file(scene, "T2", STARTS, SIZES, items, {})
    with pytest.raises(ParameterError, match="known object"):
        build_plan_file(
            scene, "T2", STARTS, SIZES, [GripperEvent("left", "grasp", "o9", T_TCP_OBJ)], {}
        )


def test_resample_inserts_linear_samples() -> None:
    t, q = resample(np.array([0.0, 0.05, 0.06]), np.array([[0.0], [1.0], [3.0]]), 0.02)
    np.testing.assert_allclose(t, [0.0, 0.05 / 3, 0.1 / 3, 0.05, 0.06])
    np.testing.assert_allclose(q[:, 0], [0.0, 1 / 3, 2 / 3, 1.0, 3.0])


def test_the_plan_layout_follows_its_arms(plan: PlanFile, scene: Scene) -> None:
    assert plan.layout == scene.layout
    assert plan.q.shape[1] == plan.layout.dof


def test_repeated_arm_names_in_memory_are_a_format_violation(plan: PlanFile) -> None:
    import dataclasses

    from sdar_tamp.plan_rules import check_format

    twins = dataclasses.replace(plan, arms=(plan.arms[0], plan.arms[0]))
    found = check_format(twins)
    assert found is not None and found.kind == "format"
    assert found.message == "arms: arm layout: arm names must differ, got ['left'] twice"
    assert check_format(plan) is None
