"""Shared fixtures of the viewer tests: a hand-made two-arm plan, its files, page helpers."""

from __future__ import annotations

import base64
import dataclasses
import json
import re
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from sdar_tamp.plan_building import GripperEvent, MotionSegment, build_plan_file
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_writing import save_plan
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D, load_instance, save_instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene, load_scene
from sdar_tamp.world.transforms import FloatArray, inverse, pose_xyz_yaw, top_down_pose

CHROMIUM = Path(shutil.which("chromium") or "/usr/bin/chromium")
SIZE = (0.08, 0.04, 0.05)
#: Left arm carries o0, right arm carries o1 (both at once); o2 starts at its goal.
OBJECTS = (
    ObjectSpec("o0", SIZE, Pose2D(-0.12, 0.12, 0.0), Pose2D(-0.12, -0.15, 0.6)),
    ObjectSpec("o1", SIZE, Pose2D(0.12, -0.12, 0.0), Pose2D(0.10, 0.15, 0.0)),
    ObjectSpec("o2", SIZE, Pose2D(0.0, 0.0, 0.3), Pose2D(0.0, 0.0, 0.3)),
)


# -- a hand-made plan: two simultaneous top-down pick-and-places ---------------------------------
def _ik(kin: ArmKinematics, pose: Pose2D, z: float, q_ref: FloatArray) -> FloatArray:
    q, ok = kin.ik_tcp(top_down_pose(pose.x, pose.y, z, pose.yaw)).closest(q_ref)
    assert ok[0], "fixture pose out of reach"
    return q[0]


def _move(
    q0: FloatArray, q1: FloatArray, duration: float, kind: str, objs: tuple[str, ...]
) -> MotionSegment:
    t = np.linspace(0.0, duration, round(duration / 0.02) + 1)
    s = 0.5 - 0.5 * np.cos(np.pi * t / duration)  # rest to rest
    return MotionSegment(t, q0 + s[:, None] * (q1 - q0), "free", objs, kind)


def build_plan(scene: Scene, instance: Instance, slow: float = 1.0) -> PlanFile:
    """About ``8 * slow`` seconds: approach, descend, grasp, lift, carry, lower, release,
    retreat and go home, both arms together."""
    kins = [ArmKinematics.from_scene(scene, a.name) for a in scene.arms]
    home = np.concatenate([np.array(a.home) for a in scene.arms])
    carried = (instance.objects[0], instance.objects[1])
    hover, z_grasp = 0.15, SIZE[2] / 2

    def both(which: str, z: float) -> FloatArray:
        out = home.copy()
        for a, (kin, obj) in enumerate(zip(kins, carried, strict=True)):
            out[6 * a : 6 * a + 6] = _ik(kin, getattr(obj, which), z, home[6 * a : 6 * a + 6])
        return out

    above_start, at_start = both("start", hover), both("start", z_grasp)
    above_goal, at_goal = both("goal", hover), both("goal", z_grasp)
    names = ("o0", "o1")
    grasps, releases = [], []
    for a, obj in enumerate(carried):
        T_obj = pose_xyz_yaw(obj.start.x, obj.start.y, z_grasp, obj.start.yaw)
        T_tcp = kins[a].fk_tcp(at_start[6 * a : 6 * a + 6])
        T_tcp_obj = inverse(T_tcp) @ T_obj
        grasps.append(GripperEvent(scene.arms[a].name, "grasp", obj.name, T_tcp_obj))
        releases.append(GripperEvent(scene.arms[a].name, "release", obj.name, T_tcp_obj))
    items = [
        _move(home, above_start, 1.5 * slow, "approach", names),
        _move(above_start, at_start, 0.6 * slow, "approach", names),
        *grasps,
        _move(at_start, above_start, 0.6 * slow, "transfer", names),
        _move(above_start, above_goal, 1.5 * slow, "transfer", names),
        _move(above_goal, at_goal, 0.6 * slow, "transfer", names),
        *releases,
        _move(at_goal, above_goal, 0.6 * slow, "retreat", names),
        _move(above_goal, home, 1.5 * slow, "retreat", names),
    ]
    starts = {o.name: o.start.as_tuple() for o in instance.objects}
    sizes = {o.name: o.size for o in instance.objects}
    return build_plan_file(scene, instance.name, starts, sizes, items, {"planning_time": 0.25})


def write_fixture(folder: Path, slow: float = 1.0) -> tuple[Path, Path]:
    """Write the instance and its plan; return both paths."""
    scene = load_scene()
    instance = Instance("V3", scene.workspace, OBJECTS)
    inst_path = save_instance(instance, folder / "V3.yaml")
    plan_path = save_plan(build_plan(scene, instance, slow), folder / "V3.plan.json")
    return inst_path, plan_path


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    return write_fixture(tmp_path_factory.mktemp("viewer"), slow=1.2)  # within the limits: valid


@pytest.fixture(scope="module")
def instance(files: tuple[Path, Path]) -> Instance:
    return load_instance(files[0])


@pytest.fixture(scope="module")
def plan(files: tuple[Path, Path]) -> PlanFile:
    return load_plan(files[1])


def page_json(html: str) -> dict[str, Any]:
    """The page's data: the JSON in its ``sdar-data`` script element."""
    m = re.search(r'<script type="application/json" id="sdar-data">(.*?)</script>', html, re.S)
    assert m is not None
    data = json.loads(m.group(1))
    assert isinstance(data, dict)
    return data


def decode(spec: dict[str, str]) -> np.ndarray:
    kind = {"f4": "<f4", "i4": "<i4", "u1": "u1"}[spec["dtype"]]
    return np.frombuffer(base64.b64decode(spec["bdata"]), dtype=np.dtype(kind))


def broken(plan: PlanFile) -> tuple[PlanFile, float]:
    """``plan`` with a jump of the first arm's shoulder in the middle: too fast there."""
    k = len(plan.t) // 2
    q = np.array(plan.q)
    q[k:, 0] += 0.3
    return dataclasses.replace(plan, q=q), float(plan.t[k])
