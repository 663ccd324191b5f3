"""A small two-arm plan for the export tests: rest-to-rest motions sampled at several spacings
(0.02 s, 0.013 s and 0.05 s, the last resampled by the plan builder), gripper events of both
arms at one instant and a release."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.plan_building import GripperEvent, MotionSegment, build_plan_file
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_writing import save_plan
from sdar_tamp.world.scene import load_scene
from sdar_tamp.world.transforms import FloatArray, pose_xyz_yaw

STARTS = {"o1": (-0.1, 0.1, 0.3), "o2": (0.1, 0.0, 0.0)}
SIZES = {"o1": (0.08, 0.04, 0.05), "o2": (0.08, 0.04, 0.05)}
T_TCP_OBJ = pose_xyz_yaw(0.0, 0.0, 0.01, 0.4)


def _move(q0: FloatArray, delta: FloatArray, duration: float, dt: float) -> MotionSegment:
    t = np.linspace(0.0, duration, round(duration / dt) + 1)
    s = 0.5 - 0.5 * np.cos(np.pi * t / duration)  # rest to rest
    return MotionSegment(t, q0 + s[:, None] * delta, "plain", ("o1",), "move")


def build_export_plan() -> PlanFile:
    scene = load_scene()
    home = np.concatenate([np.array(a.home) for a in scene.arms])
    left = np.zeros(12)
    left[:6] = [0.3, -0.2, 0.25, 0.1, -0.15, 0.4]
    both = np.linspace(-0.2, 0.2, 12)
    a = _move(home, left, 0.8, 0.02)
    b = _move(a.q[-1], both, 0.65, 0.013)
    c = _move(b.q[-1], -both - left, 1.2, 0.05)
    items = [
        a,
        GripperEvent("left", "grasp", "o1", T_TCP_OBJ),
        GripperEvent("right", "grasp", "o2", T_TCP_OBJ),
        b,
        GripperEvent("left", "release", "o1", T_TCP_OBJ),
        c,
        GripperEvent("right", "release", "o2", T_TCP_OBJ),
    ]
    return build_plan_file(scene, "E2", STARTS, SIZES, items, {"planning_time": 0.5})


@pytest.fixture(scope="session")
def plan_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return save_plan(build_export_plan(), tmp_path_factory.mktemp("export") / "E2.plan.json")


@pytest.fixture(scope="session")
def plan(plan_path: Path) -> PlanFile:
    return load_plan(plan_path)
