"""One arm of a cell: its robot description, base pose, chain, limits, home and gripper.

Read from an entry of the scene file's ``arms`` (see ``docs/robots.md``). The arm's joints are
the movable joints of the robot description's chain from ``base_frame`` to ``tool_frame``
(or those named by ``joints``); its joint limits default to the URDF's and may only be
narrowed; its velocity limits default to the URDF's. Every error is located in the scene file.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from sdar_tamp.world._pin import PinRobot, chain_to
from sdar_tamp.world._yaml import Node
from sdar_tamp.world.errors import KinematicsError, SceneError
from sdar_tamp.world.gripper import Gripper, read_gripper
from sdar_tamp.world.shipped_cell import LEGACY_FINGERS, LEGACY_JOINT_SUFFIX
from sdar_tamp.world.transforms import FloatArray, pose_xyz_yaw

Floats = tuple[float, ...]
#: Tolerance on the scene's limits against the URDF's [rad] (decimal rounding of pi).
LIMIT_TOLERANCE = 1e-9


@dataclass(frozen=True)
class ArmSpec:
    """One arm: robot description, base pose in the world, chain, limits, home, gripper.

    Per-joint tuples (``lower`` ... ``home``) have one value per joint of ``joint_names``
    (``dof`` of them), in chain order."""

    name: str
    urdf: Path
    base_xyz: tuple[float, float, float]  # [m]
    base_yaw: float  # [rad]
    base_frame: str
    tool_frame: str  # the flange; the TCP is gripper.tcp_offset along its z
    joint_names: tuple[str, ...]
    lower: Floats  # [rad]
    upper: Floats  # [rad]
    velocity_limit: Floats  # [rad/s]
    acceleration_limit: Floats  # [rad/s^2]
    home: Floats  # [rad]
    gripper: Gripper
    #: The description's other one-axis joints (a gripper's slides, joints before the base
    #: frame) and the value each is held at [rad or m]: default 0, or the nearest limit.
    locked_joints: tuple[tuple[str, float], ...] = ()

    def __post_init__(self) -> None:
        if not self.joint_names:
            raise SceneError(f"arm {self.name!r}: no joints; name them (arms[].joints)")
        for field_name in ("lower", "upper", "velocity_limit", "acceleration_limit", "home"):
            values = getattr(self, field_name)
            if len(values) != len(self.joint_names):
                raise SceneError(
                    f"arm {self.name!r}: {field_name} has {len(values)} values for "
                    f"{len(self.joint_names)} joints {list(self.joint_names)}"
                )

    @property
    def dof(self) -> int:
        return len(self.joint_names)

    @property
    def T_world_base(self) -> FloatArray:
        """The base pose ``(4, 4)`` in the world (a copy)."""
        return self._T_world_base.copy()

    @cached_property
    def _T_world_base(self) -> FloatArray:
        x, y, z = self.base_xyz
        return pose_xyz_yaw(x, y, z, self.base_yaw)

    @property
    def lower_array(self) -> FloatArray:
        return np.array(self.lower)

    @property
    def upper_array(self) -> FloatArray:
        return np.array(self.upper)


ARM_KEYS = ["name", "base", "acceleration_limit", "home"]
ARM_OPTIONAL = [
    "robot", "base_frame", "tool_frame", "joints", "joint_limits", "velocity_limit", "gripper",
    "locked_joints",
]  # fmt: skip
#: The flange frame an arm names no ``tool_frame``.
DEFAULT_TOOL_FRAME = "tool0"


def root_link(robot: PinRobot) -> str:
    """The robot description's root link (the first frame after pinocchio's universe)."""
    return str(robot.model.frames[1].name)


def _chain_joints(robot: PinRobot, node: Node, k: dict[str, Node]) -> tuple[str, str, list[str]]:
    """``(base_frame, tool_frame, joint names of the chain between them)``."""
    model = robot.model
    base = k["base_frame"].as_str() if "base_frame" in k else root_link(robot)
    tool = k["tool_frame"].as_str() if "tool_frame" in k else DEFAULT_TOOL_FRAME
    for key, frame in (("base_frame", base), ("tool_frame", tool)):
        if not model.existFrame(frame):
            raise k.get(key, node).error(
                f"a frame {frame!r} in {robot.urdf_path.name} (it has none)", show_value=False
            )
    try:
        chain = chain_to(robot, tool)
    except KinematicsError as error:
        raise k.get("tool_frame", node).error(f"a serial chain to {tool!r}: {error}") from None
    base_joint = int(model.frames[model.getFrameId(base)].parentJoint)
    names = [j.name for j in chain.joints]
    if base_joint != 0:
        base_name = str(model.names[base_joint])
        if base_name not in names:
            raise k["base_frame"].error(f"a frame on the chain to {tool!r}")
        names = names[names.index(base_name) + 1 :]
    if not names:
        raise k.get("tool_frame", node).error(f"a frame that joints move relative to {base!r}")
    return base, tool, names


def _joint_names(k: dict[str, Node], chain: list[str]) -> tuple[str, ...]:
    if "joints" not in k:
        return tuple(chain)
    items = k["joints"].items()
    names = tuple(item.as_str() for item in items)
    for item, name in zip(items, names, strict=True):
        if name not in chain:
            raise item.error(f"a movable joint of the chain, one of {chain}")
    if list(names) != [j for j in chain if j in names] or len(set(names)) != len(names):
        raise k["joints"].error("the chain's joints in chain order, each once")
    return names


def _urdf_limits(robot: PinRobot, joints: tuple[str, ...]) -> tuple[Floats, Floats, Floats]:
    """Lower, upper position limits and velocity limits of ``joints`` in the URDF."""
    model = robot.model
    ids = [int(model.getJointId(j)) for j in joints]
    qi = [int(model.idx_qs[j]) for j in ids]
    vi = [int(model.idx_vs[j]) for j in ids]
    return (
        tuple(float(model.lowerPositionLimit[i]) for i in qi),
        tuple(float(model.upperPositionLimit[i]) for i in qi),
        tuple(float(model.velocityLimit[i]) for i in vi),
    )


def _limits(
    k: dict[str, Node], robot: PinRobot, joints: tuple[str, ...]
) -> tuple[Floats, Floats, Floats]:
    lower, upper, velocity = (list(v) for v in _urdf_limits(robot, joints))
    if "joint_limits" in k:
        node = k["joint_limits"]
        if not isinstance(node.value, dict):
            raise node.error("a mapping of joint name to [lower, upper]")
        entries = node.mapping([], [str(key) for key in node.value])
        for key, entry in entries.items():
            name = key if key in joints else f"{key}{LEGACY_JOINT_SUFFIX}"
            if name not in joints:
                raise entry.error(f"a joint of the arm, one of {list(joints)}", show_value=False)
            i = joints.index(name)
            lo, hi = entry.as_interval()
            if lo < lower[i] - LIMIT_TOLERANCE or hi > upper[i] + LIMIT_TOLERANCE:
                raise entry.error(
                    f"limits within the URDF's [{lower[i]}, {upper[i]}] of {name} "
                    f"({robot.urdf_path.name}), got [{lo}, {hi}]",
                    show_value=False,
                )
            lower[i], upper[i] = lo, hi
    return tuple(lower), tuple(upper), tuple(velocity)


def _locked(
    k: dict[str, Node], robot: PinRobot, joints: tuple[str, ...]
) -> tuple[tuple[tuple[str, float], ...], FloatArray]:
    """The other one-axis joints with the values they are held at, and the description's
    configuration ``(nq,)`` holding them there (the arm's own joints at zero)."""
    model = robot.model
    q = robot.neutral()
    values: dict[str, float] = {}
    for j in range(1, model.njoints):
        name = str(model.names[j])
        if name in joints or int(model.nqs[j]) != 1:
            continue
        i = int(model.idx_qs[j])
        lo, hi = float(model.lowerPositionLimit[i]), float(model.upperPositionLimit[i])
        values[name] = min(max(0.0, lo), hi)
    if "locked_joints" in k:
        node = k["locked_joints"]
        if not isinstance(node.value, dict):
            raise node.error("a mapping of joint name to the value it is held at")
        for name, entry in node.mapping([], [str(key) for key in node.value]).items():
            if name not in values:
                raise entry.error(f"a joint that is not the arm's, one of {list(values)}")
            i = int(model.idx_qs[model.getJointId(name)])
            lo, hi = float(model.lowerPositionLimit[i]), float(model.upperPositionLimit[i])
            value = entry.as_float()
            if not lo - LIMIT_TOLERANCE <= value <= hi + LIMIT_TOLERANCE:
                raise entry.error(f"a value within the URDF's [{lo}, {hi}] of {name}")
            values[name] = value
    for name, value in values.items():
        q[int(model.idx_qs[model.getJointId(name)])] = value
    return tuple(values.items()), q


def _per_joint(node: Node, dof: int) -> Floats:
    """A positive scalar for every joint, or a list of one positive number per joint."""
    if isinstance(node.value, list):
        return node.as_floats(dof, f"a number > 0 or a list of {dof}", positive=True)
    v = node.as_float(positive=True)
    return (v,) * dof


def read_arm(node: Node, urdf: Path, robot: PinRobot, default_gripper: Node | None) -> ArmSpec:
    """The arm the scene entry ``node`` describes, on the loaded robot description ``robot``
    (read from ``urdf``); ``default_gripper``: the scene's top-level ``gripper``, if any."""
    k = node.mapping(ARM_KEYS, ARM_OPTIONAL)
    base = k["base"].mapping(["xyz", "yaw"])
    base_frame, tool_frame, chain = _chain_joints(robot, node, k)
    joints = _joint_names(k, chain)
    dof = len(joints)
    lower, upper, velocity = _limits(k, robot, joints)
    if "velocity_limit" in k:
        velocity = _per_joint(k["velocity_limit"], dof)
    else:
        for name, v in zip(joints, velocity, strict=True):
            if not (np.isfinite(v) and v > 0.0):
                raise node.error(
                    f"key 'velocity_limit' ({urdf.name} gives joint {name!r} none)",
                    show_value=False,
                )
    home = k["home"].as_floats(dof, f"a list of {dof} joint values, one per joint {list(joints)}")
    for i, (v, lo, hi) in enumerate(zip(home, lower, upper, strict=True)):
        if not lo <= v <= hi:
            raise k["home"].items()[i].error(f"{joints[i]} within [{lo}, {hi}]")
    gripper_node = k.get("gripper", default_gripper)
    if gripper_node is None:
        raise node.error("key 'gripper' (here or at the top of the scene)", show_value=False)
    fingers = LEGACY_FINGERS if all(robot.model.existFrame(f) for f in LEGACY_FINGERS) else ()
    locked, q_locked = _locked(k, robot, joints)
    gripper = read_gripper(gripper_node, robot, tool_frame, fingers, q_locked, dict(locked))
    return ArmSpec(
        name=k["name"].as_str(),
        urdf=urdf,
        base_xyz=base["xyz"].as_floats(3, "[x, y, z]"),  # type: ignore[arg-type]
        base_yaw=base["yaw"].as_float(),
        base_frame=base_frame,
        tool_frame=tool_frame,
        joint_names=joints,
        lower=lower,
        upper=upper,
        velocity_limit=velocity,
        acceleration_limit=_per_joint(k["acceleration_limit"], dof),
        home=home,
        gripper=gripper,
        locked_joints=locked,
    )
