"""Checking a scene's arms against their robot description.

Every joint the scene names exists in the URDF, is a single-axis joint, and the scene's limits
lie within the URDF's; every frame the planner uses exists. Errors are located in the scene
file, at the key that names the joint or the robot.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from sdar_tamp.world._pin import PinRobot
from sdar_tamp.world._yaml import Node

#: Tolerance on the scene's limits against the URDF's [rad] (decimal rounding of pi).
LIMIT_TOLERANCE = 1e-9


@dataclass(frozen=True)
class JointRequest:
    """A joint the scene uses: its URDF name and limits [rad], and the scene key naming it."""

    urdf_name: str
    lower: float
    upper: float
    node: Node


def check_robot(
    urdf: Path,
    package_dirs: tuple[Path, ...],
    robot_node: Node,
    joints: Sequence[JointRequest],
    frames: Sequence[str],
) -> PinRobot:
    """Load the URDF and check ``joints`` and ``frames`` against it; returns the loaded robot.

    Raises:
        SceneError: the URDF does not load (located in the URDF), a joint or frame is missing,
            or a scene limit lies outside the URDF's (located in the scene file).
    """
    robot = PinRobot.load(urdf, package_dirs)
    model = robot.model
    for frame in frames:
        if not model.existFrame(frame):
            raise robot_node.error(
                f"a robot description with a frame {frame!r} ({urdf.name} has none)",
                show_value=False,
            )
    for request in joints:
        if not model.existJointName(request.urdf_name):
            raise request.node.error(
                f"a joint {request.urdf_name!r} in {urdf.name}; it has {list(robot.joint_names)}",
                show_value=False,
            )
        jid = int(model.getJointId(request.urdf_name))
        if int(model.nqs[jid]) != 1:
            raise request.node.error(
                f"{request.urdf_name!r} to be a one-axis joint in {urdf.name}", show_value=False
            )
        index = int(model.idx_qs[jid])
        lo = float(model.lowerPositionLimit[index])
        hi = float(model.upperPositionLimit[index])
        if request.lower < lo - LIMIT_TOLERANCE or request.upper > hi + LIMIT_TOLERANCE:
            raise request.node.error(
                f"limits within the URDF's [{lo}, {hi}] of {request.urdf_name} "
                f"({urdf.name}), got [{request.lower}, {request.upper}]",
                show_value=False,
            )
    return robot
