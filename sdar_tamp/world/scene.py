"""The dual-arm scene: table, arms (two, for now), workspace, default object, gripper.

Loaded from ``scene.yaml`` (the shipped one lives in ``domains/dual_arm_rearrangement``) into
frozen dataclasses. World frame: table centre at the origin, z up, table top at z = 0.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from importlib.resources import files
from pathlib import Path

import numpy as np

from sdar_tamp.world._yaml import Node, read_yaml
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.layout import ArmLayout
from sdar_tamp.world.robot_check import JointRequest, check_robot
from sdar_tamp.world.transforms import BoolArray, FloatArray, pose_xyz_yaw
from sdar_tamp.world.urdf import package_dirs_from_env, resolve_uri

#: Joint keys of ``joint_limits`` in the scene file, in joint order.
JOINT_KEYS = ("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3")
Vec6 = tuple[float, float, float, float, float, float]
#: Default ``velocity_safety``: the full limits (the time parameterisation slows a profile
#: whose samples would break them, so the validator's numerical tolerance suffices).
DEFAULT_VELOCITY_SAFETY = 1.0


def domain_path(name: str) -> Path:
    """Path of a data file shipped in ``domains/dual_arm_rearrangement`` (installed or not)."""
    return Path(str(files("domains") / "dual_arm_rearrangement" / name))


def default_scene_path() -> Path:
    return domain_path("scene.yaml")


@dataclass(frozen=True)
class Table:
    """A box whose top face is the plane z = 0, centred on the origin."""

    size: tuple[float, float, float]  # x, y extent and thickness [m]


@dataclass(frozen=True)
class Workspace:
    """The axis-aligned rectangle of the table where objects may rest [m]."""

    x: tuple[float, float]
    y: tuple[float, float]

    @property
    def area(self) -> float:
        return (self.x[1] - self.x[0]) * (self.y[1] - self.y[0])

    def contains(self, points: FloatArray, tol: float = 1e-12) -> BoolArray:
        """Mask ``(n,)`` of which points ``(n, 2)`` lie in the rectangle."""
        p = np.asarray(points, dtype=np.float64)
        return (
            (p[:, 0] >= self.x[0] - tol)
            & (p[:, 0] <= self.x[1] + tol)
            & (p[:, 1] >= self.y[0] - tol)
            & (p[:, 1] <= self.y[1] + tol)
        )


@dataclass(frozen=True)
class Gripper:
    """Two-finger gripper: opening between the pads and TCP offset along tool0 z [m]."""

    max_opening: float
    tcp_offset: float
    grasp_margin: float  # the grasped side must be <= max_opening - grasp_margin [m]

    @property
    def max_graspable_width(self) -> float:
        return self.max_opening - self.grasp_margin


@dataclass(frozen=True)
class ArmSpec:
    """One arm: name, base pose in the world, joint limits and home configuration."""

    name: str
    base_xyz: tuple[float, float, float]  # [m]
    base_yaw: float  # [rad]
    lower: Vec6  # [rad]
    upper: Vec6  # [rad]
    velocity_limit: Vec6  # [rad/s]
    acceleration_limit: Vec6  # [rad/s^2]
    home: Vec6  # [rad]

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


@dataclass(frozen=True)
class Scene:
    """Everything static about the dual-arm world."""

    file: str
    robot_urdf: Path
    table: Table
    workspace: Workspace
    object_size: tuple[float, float, float]  # default cuboid lx, ly, lz [m]
    gripper: Gripper
    arms: tuple[ArmSpec, ...]
    #: Fraction in (0, 1] of the velocity and acceleration limits a trajectory's time-optimal
    #: profile may use (the sampled trajectory keeps the full limits in any case).
    velocity_safety: float = DEFAULT_VELOCITY_SAFETY
    #: Where the robot description's ``package://`` URIs are looked up: the scene's
    #: ``packages`` (relative to the scene file), then ``ROS_PACKAGE_PATH``.
    package_dirs: tuple[Path, ...] = ()

    @property
    def arm_names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.arms)

    @property
    def layout(self) -> ArmLayout:
        """The arms' joints in a configuration vector, in the scene's arm order."""
        return ArmLayout(self.arm_names, tuple(len(a.home) for a in self.arms))

    @property
    def home(self) -> FloatArray:
        """Every arm at its home configuration ``(layout.dof,)`` [rad]."""
        return self.layout.join([a.home for a in self.arms])

    def joint_array(self, field: str) -> FloatArray:
        """A per-joint property of every arm (``lower``, ``upper``, ``velocity_limit``,
        ``acceleration_limit`` or ``home``) as one vector ``(layout.dof,)``."""
        if field not in _JOINT_FIELDS:
            raise SceneError(f"field must be one of {', '.join(_JOINT_FIELDS)}; got {field!r}")
        return self.layout.join([getattr(a, field) for a in self.arms])

    def arm(self, name: str) -> ArmSpec:
        for a in self.arms:
            if a.name == name:
                return a
        raise SceneError(f"unknown arm {name!r}; the scene has {list(self.arm_names)}")


_JOINT_FIELDS = ("lower", "upper", "velocity_limit", "acceleration_limit", "home")


def load_scene(path: Path | None = None, environ: Mapping[str, str] | None = None) -> Scene:
    """Load a scene file (default: the shipped ``scene.yaml``).

    ``robot`` is a path relative to the scene file or a ``package://`` URI, looked up in the
    scene's ``packages`` directories, then in ``ROS_PACKAGE_PATH`` of ``environ`` (default
    ``os.environ``). The robot description is loaded and checked against the arms: every
    joint and frame the scene uses exists, and the scene's joint limits lie within the URDF's.
    """
    path = default_scene_path() if path is None else Path(path)
    root = read_yaml(path, SceneError)
    keys = root.mapping(
        ["robot", "table", "workspace", "object_size", "gripper", "arms"],
        ["velocity_safety", "packages"],
    )
    packages: tuple[Path, ...] = ()
    if "packages" in keys:
        packages = tuple(path.parent / node.as_str() for node in keys["packages"].items())
        for node, directory in zip(keys["packages"].items(), packages, strict=True):
            if not directory.is_dir():
                raise node.error("a package directory (relative to the scene file)")
    package_dirs = packages + package_dirs_from_env(environ)
    robot_path, how = resolve_uri(keys["robot"].as_str(), path.parent, package_dirs)
    if robot_path is None:
        raise keys["robot"].error(f"a robot description file ({how})")
    robot = robot_path
    tx, ty, tz = (
        keys["table"].mapping(["size"])["size"].as_floats(3, "[x, y, thickness]", positive=True)
    )
    table = Table((tx, ty, tz))
    ws = keys["workspace"].mapping(["x", "y"])
    workspace = Workspace(ws["x"].as_interval(), ws["y"].as_interval())
    size = keys["object_size"].as_floats(3, "[lx, ly, lz]", positive=True)
    g = keys["gripper"].mapping(["max_opening", "tcp_offset", "grasp_margin"])
    gripper = Gripper(
        g["max_opening"].as_float(positive=True),
        g["tcp_offset"].as_float(positive=True),
        g["grasp_margin"].as_float(),
    )
    arm_nodes = keys["arms"].items()
    if len(arm_nodes) != 2:
        raise keys["arms"].error("a list of exactly two arms", show_value=False)
    arms = tuple(_arm(node) for node in arm_nodes)
    if arms[0].name == arms[1].name:
        raise arm_nodes[1].mapping(_ARM_KEYS)["name"].error("a name different from arms[0].name")
    safety = DEFAULT_VELOCITY_SAFETY
    if "velocity_safety" in keys:
        node = keys["velocity_safety"]
        safety = node.as_float()
        if not 0.0 < safety <= 1.0:
            raise node.error("a number in (0, 1], the share of the joint limits a motion uses")
    scene = Scene(str(path), robot, table, workspace, size, gripper, arms,  # type: ignore[arg-type]
                  safety, package_dirs)  # fmt: skip
    check_robot(robot, package_dirs, keys["robot"], _joint_requests(arms, arm_nodes), FRAMES)
    return scene


#: The frames of the robot description the planner uses: the flange and the tool centre point.
FRAMES = ("tool0", "tcp")


def _joint_requests(arms: tuple[ArmSpec, ...], nodes: list[Node]) -> list[JointRequest]:
    out: list[JointRequest] = []
    for arm, node in zip(arms, nodes, strict=True):
        limits = node.mapping(_ARM_KEYS)["joint_limits"].mapping(list(JOINT_KEYS))
        for i, key in enumerate(JOINT_KEYS):
            out.append(JointRequest(f"{key}_joint", arm.lower[i], arm.upper[i], limits[key]))
    return out


_ARM_KEYS = ["name", "base", "joint_limits", "velocity_limit", "acceleration_limit", "home"]


def _per_joint(node: Node) -> Vec6:
    """A positive scalar for every joint, or a list of six positive numbers."""
    if isinstance(node.value, list):
        return node.as_floats(6, "a number > 0 or a list of six", positive=True)  # type: ignore[return-value]
    v = node.as_float(positive=True)
    return (v, v, v, v, v, v)


def _arm(node: Node) -> ArmSpec:
    k = node.mapping(_ARM_KEYS)
    base = k["base"].mapping(["xyz", "yaw"])
    limits = k["joint_limits"].mapping(list(JOINT_KEYS))
    intervals = [limits[j].as_interval() for j in JOINT_KEYS]
    lower = tuple(lo for lo, _ in intervals)
    upper = tuple(hi for _, hi in intervals)
    home = k["home"].as_floats(6, "a list of six joint angles [rad]")
    for i, (v, lo, hi) in enumerate(zip(home, lower, upper, strict=True)):
        if not lo <= v <= hi:
            raise k["home"].items()[i].error(f"{JOINT_KEYS[i]} within [{lo}, {hi}]")
    return ArmSpec(
        name=k["name"].as_str(),
        base_xyz=base["xyz"].as_floats(3, "[x, y, z]"),  # type: ignore[arg-type]
        base_yaw=base["yaw"].as_float(),
        lower=lower,  # type: ignore[arg-type]
        upper=upper,  # type: ignore[arg-type]
        velocity_limit=_per_joint(k["velocity_limit"]),
        acceleration_limit=_per_joint(k["acceleration_limit"]),
        home=home,  # type: ignore[arg-type]
    )
