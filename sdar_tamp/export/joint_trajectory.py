"""A plan as ``trajectory_msgs/JointTrajectory`` messages (one per arm) in JSON, plus the
gripper commands.

Document layout (``version`` 1; SI units)::

    {"format": "sdar-joint-trajectory", "version": 1,
     "units": {"length": "m", "angle": "rad", "time": "s"}, "instance": "M1",
     "arms": [{"name": "left", "T_world_base": 4x4, "joint_trajectory": {
                 "header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": "left_base_link"},
                 "joint_names": [k names],
                 "points": [{"positions": [k], "velocities": [k], "accelerations": [k],
                             "effort": [], "time_from_start": {"sec", "nanosec"}}, ...]}},
              ...],
     "gripper_commands": [{"time_from_start": {"sec", "nanosec"}, "t": 1.25,
                           "arm": "left", "command": "close", "object": "o3"}, ...]}

``k`` is the arm's joint count and ``joint_names`` are the plan's names of the arm's joints (the
arm's name, ``_``, the joint's name in the arm's robot description), so a 6-DoF and a 7-DoF arm
side by side get messages of their own sizes. Each message field has the name and shape of its
ROS 2 counterpart (``builtin_interfaces/
Duration`` is ``sec`` and ``nanosec``), so a node can fill a message from it key by key. The
points are the plan's own samples; velocities and accelerations as in
:mod:`sdar_tamp.export.timeline`. A zero ``stamp`` means "start when received".
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from sdar_tamp.export.timeline import arm_columns, sample_derivatives
from sdar_tamp.plan_file import UNITS, PlanFile

FORMAT = "sdar-joint-trajectory"
VERSION = 1
#: ``release`` opens the gripper, ``grasp`` closes it.
GRIPPER_COMMANDS = {"grasp": "close", "release": "open"}


def duration(seconds: float) -> dict[str, int]:
    """``builtin_interfaces/Duration`` of ``seconds`` >= 0 [s], rounded to the nanosecond."""
    total = round(seconds * 1e9)
    return {"sec": total // 1_000_000_000, "nanosec": total % 1_000_000_000}


def seconds(value: dict[str, int]) -> float:
    """The time [s] of a ``{"sec", "nanosec"}`` duration."""
    return value["sec"] + value["nanosec"] * 1e-9


def joint_trajectory_document(plan: PlanFile) -> dict[str, Any]:
    """The JSON value described in the module docstring."""
    v, a = sample_derivatives(plan.t, plan.q)
    times = [duration(float(t)) for t in plan.t]
    arms = []
    for info, cols in zip(plan.arms, arm_columns(plan), strict=True):
        q_arm, v_arm, a_arm = plan.q[:, cols], v[:, cols], a[:, cols]
        points = [
            {
                "positions": q_arm[i].tolist(),
                "velocities": v_arm[i].tolist(),
                "accelerations": a_arm[i].tolist(),
                "effort": [],
                "time_from_start": times[i],
            }
            for i in range(len(plan.t))
        ]
        message = {
            "header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": f"{info.name}_base_link"},
            "joint_names": list(info.joints),
            "points": points,
        }
        arms.append(
            {
                "name": info.name,
                "T_world_base": info.T_world_base.tolist(),
                "joint_trajectory": message,
            }
        )
    commands = [
        {
            "time_from_start": duration(e.t),
            "t": e.t,
            "arm": e.arm,
            "command": GRIPPER_COMMANDS[e.type],
            "object": e.object,
        }
        for e in plan.events
    ]
    return {
        "format": FORMAT,
        "version": VERSION,
        "units": dict(UNITS),
        "instance": plan.instance,
        "arms": arms,
        "gripper_commands": commands,
    }


def write_joint_trajectory(plan: PlanFile, path: Path) -> Path:
    """Write :func:`joint_trajectory_document` of ``plan`` to ``path`` (one point per line)."""
    document = joint_trajectory_document(plan)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(_dump(document) + "\n", encoding="utf-8")
    return path


def _dump(value: Any, indent: str = "") -> str:
    """JSON with one line per point, command and matrix row (objects with list or object
    values are spread over lines; anything else stays on one line)."""
    inner = indent + "  "
    spread = isinstance(value, dict) and any(isinstance(v, list | dict) for v in value.values())
    if spread and not _is_leaf_record(value):
        items = [f"{inner}{json.dumps(k)}: {_dump(v, inner)}" for k, v in value.items()]
        return "{\n" + ",\n".join(items) + "\n" + indent + "}"
    if isinstance(value, list) and value and isinstance(value[0], list | dict):
        return "[\n" + ",\n".join(inner + _dump(v, inner) for v in value) + "\n" + indent + "]"
    return json.dumps(value, allow_nan=False)


def _is_leaf_record(value: dict[str, Any]) -> bool:
    """A point or a gripper command (written on one line)."""
    return "time_from_start" in value or ("sec" in value and "nanosec" in value)
