"""The joint-trajectory export: points reproduce the plan's samples, velocities and
accelerations are the derivatives of the parabola through neighbouring samples (checked with
independent polynomial fits), gripper commands follow the events."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.export import joint_trajectory_document, sample_derivatives, write_joint_trajectory
from sdar_tamp.export.joint_trajectory import duration, seconds
from sdar_tamp.plan_file import PlanFile


@pytest.fixture(scope="module")
def document(plan: PlanFile, tmp_path_factory: pytest.TempPathFactory) -> dict:
    path = write_joint_trajectory(plan, tmp_path_factory.mktemp("jt") / "plan.trajectory.json")
    return json.loads(path.read_text(encoding="utf-8"))


def _arrays(message: dict, key: str) -> np.ndarray:
    return np.array([p[key] for p in message["points"]])


def test_layout_and_names(plan: PlanFile, document: dict) -> None:
    assert document["format"] == "sdar-joint-trajectory" and document["version"] == 1
    assert document["instance"] == plan.instance
    assert [a["name"] for a in document["arms"]] == ["left", "right"]
    for arm, info in zip(document["arms"], plan.arms, strict=True):
        message = arm["joint_trajectory"]
        assert message["joint_names"] == list(info.joints)
        assert message["header"] == {
            "stamp": {"sec": 0, "nanosec": 0},
            "frame_id": f"{info.name}_base_link",
        }
        np.testing.assert_array_equal(arm["T_world_base"], info.T_world_base)
        assert len(message["points"]) == len(plan.t)
        for point in message["points"]:
            assert set(point) == {
                "positions",
                "velocities",
                "accelerations",
                "effort",
                "time_from_start",
            }
            assert 0 <= point["time_from_start"]["nanosec"] < 1_000_000_000


def test_positions_at_time_from_start_reproduce_the_plan(plan: PlanFile, document: dict) -> None:
    left, right = (a["joint_trajectory"] for a in document["arms"])
    times = np.array([seconds(p["time_from_start"]) for p in left["points"]])
    np.testing.assert_allclose(times, plan.t, rtol=0, atol=1e-9)
    assert np.all(np.diff(times) > 0)
    q = np.hstack([_arrays(left, "positions"), _arrays(right, "positions")])
    np.testing.assert_array_equal(q, plan.q)  # the plan's own samples, exactly


def test_velocities_and_accelerations_are_the_local_parabola(
    plan: PlanFile, document: dict
) -> None:
    msgs = [a["joint_trajectory"] for a in document["arms"]]
    v = np.hstack([_arrays(m, "velocities") for m in msgs])
    a = np.hstack([_arrays(m, "accelerations") for m in msgs])
    t, q = plan.t, plan.q
    assert np.all(v[0] == 0) and np.all(v[-1] == 0)  # the plan starts and ends at rest
    for i in range(1, len(t) - 1):
        s = t[i - 1 : i + 2] - t[i]
        coef = np.polyfit(s, q[i - 1 : i + 2], 2)  # exact through three points
        np.testing.assert_allclose(v[i], coef[1], atol=1e-7)
        np.testing.assert_allclose(a[i], 2 * coef[0], atol=1e-5)
    # between the neighbouring interval velocities (those the validator bounds)
    m = np.diff(q, axis=0) / np.diff(t)[:, None]
    low, high = np.minimum(m[:-1], m[1:]), np.maximum(m[:-1], m[1:])
    assert np.all((low - 1e-12 <= v[1:-1]) & (v[1:-1] <= high + 1e-12))
    # uniform stretches: the central difference
    h = np.diff(t)
    uniform = np.flatnonzero(np.abs(h[1:] - h[:-1]) < 1e-12) + 1
    assert len(uniform) > 50
    central = (q[uniform + 1] - q[uniform - 1]) / (t[uniform + 1] - t[uniform - 1])[:, None]
    np.testing.assert_allclose(v[uniform], central, atol=1e-9)
    # the ends: the validator's acceleration, the robot at rest outside the plan
    np.testing.assert_allclose(a[0], (q[1] - q[0]) / h[0] ** 2, atol=1e-9)
    np.testing.assert_allclose(a[-1], -(q[-1] - q[-2]) / h[-1] ** 2, atol=1e-9)


def test_velocities_integrate_back_to_the_positions(plan: PlanFile, document: dict) -> None:
    msgs = [a["joint_trajectory"] for a in document["arms"]]
    v = np.hstack([_arrays(m, "velocities") for m in msgs])
    steps = 0.5 * (v[1:] + v[:-1]) * np.diff(plan.t)[:, None]  # trapezoid rule
    q = plan.q[0] + np.vstack([np.zeros(12), np.cumsum(steps, axis=0)])
    assert np.abs(q - plan.q).max() < 2e-3  # [rad]; the plan moves up to 0.65 rad
    assert np.abs(plan.q - plan.q[0]).max() > 0.3


def test_gripper_commands_follow_the_events(plan: PlanFile, document: dict) -> None:
    commands = document["gripper_commands"]
    assert [(c["arm"], c["command"], c["object"]) for c in commands] == [
        ("left", "close", "o1"),
        ("right", "close", "o2"),
        ("left", "open", "o1"),
        ("right", "open", "o2"),
    ]
    for c, e in zip(commands, plan.events, strict=True):
        assert c["t"] == e.t
        assert seconds(c["time_from_start"]) == pytest.approx(e.t, abs=1e-9)


def test_duration_rounds_to_the_nanosecond() -> None:
    assert duration(0.0) == {"sec": 0, "nanosec": 0}
    assert duration(1.9500000000000002) == {"sec": 1, "nanosec": 950_000_000}
    assert duration(2.9999999999) == {"sec": 3, "nanosec": 0}
    assert seconds(duration(12.345678901)) == pytest.approx(12.345678901, abs=1e-9)


def test_derivatives_of_one_sample_are_zero() -> None:
    v, a = sample_derivatives(np.zeros(1), np.ones((1, 12)))
    assert v.shape == a.shape == (1, 12) and not v.any() and not a.any()


def test_document_is_json_of_the_plan(plan: PlanFile, tmp_path: Path) -> None:
    path = write_joint_trajectory(plan, tmp_path / "sub" / "x.json")
    assert json.loads(path.read_text(encoding="utf-8")) == joint_trajectory_document(plan)
