"""The cell: table, workspace, default object and the arms (one or more), each with its
robot description, chain, limits and gripper.

Loaded from a scene file (the shipped cells live in ``domains/dual_arm_rearrangement/cells``,
see :mod:`.cells`) into frozen dataclasses. World frame: table centre at the origin, z up,
table top at z = 0. The file form is described in ``docs/robots.md``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from importlib.resources import files
from pathlib import Path

import numpy as np

from sdar_tamp.world._pin import PinRobot
from sdar_tamp.world._yaml import Node, read_yaml
from sdar_tamp.world.arm_spec import ArmSpec, read_arm
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.graspability import GraspLimits, grasp_problem
from sdar_tamp.world.gripper import Gripper
from sdar_tamp.world.layout import ArmLayout
from sdar_tamp.world.shipped_cell import LEGACY_JOINT_KEYS
from sdar_tamp.world.transforms import BoolArray, FloatArray
from sdar_tamp.world.urdf import package_dirs_from_env, resolve_uri

__all__ = ["ArmSpec", "Gripper", "Scene", "Table", "Workspace", "load_scene"]

#: Deprecated: the short ``joint_limits`` keys of the first scene form (the shipped UR5e's
#: joints); code names an arm's joints by ``scene.arm(name).joint_names``.
JOINT_KEYS = LEGACY_JOINT_KEYS
#: Default ``velocity_safety``: the full limits (the time parameterisation slows a profile
#: whose samples would break them, so the validator's numerical tolerance suffices).
DEFAULT_VELOCITY_SAFETY = 1.0


def domain_path(name: str) -> Path:
    """Path of a data file shipped in ``domains/dual_arm_rearrangement`` (installed or not)."""
    return Path(str(files("domains") / "dual_arm_rearrangement" / name))


def default_scene_path() -> Path:
    """The shipped UR5e cell, the scene of every instance that names none."""
    return domain_path("cells/ur5e_facing.yaml")


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
class Scene:
    """Everything static about the cell: table, workspace, default object, arms."""

    file: str
    table: Table
    workspace: Workspace
    object_size: tuple[float, float, float]  # default cuboid lx, ly, lz [m]
    arms: tuple[ArmSpec, ...]
    #: Fraction in (0, 1] of the velocity and acceleration limits a trajectory's time-optimal
    #: profile may use (the sampled trajectory keeps the full limits in any case).
    velocity_safety: float = DEFAULT_VELOCITY_SAFETY
    #: Where the robot descriptions' ``package://`` URIs are looked up: the scene's
    #: ``packages`` (relative to the scene file), then ``ROS_PACKAGE_PATH``.
    package_dirs: tuple[Path, ...] = ()

    @property
    def robot_urdf(self) -> Path:
        """Deprecated: the FIRST arm's robot description (use ``arm(name).urdf``)."""
        return self.arms[0].urdf

    @property
    def gripper(self) -> Gripper:
        """Deprecated: the FIRST arm's gripper (use ``arm(name).gripper``)."""
        return self.arms[0].gripper

    @property
    def grasp_limits(self) -> GraspLimits:
        """The limits a grasp must meet for every arm's gripper (grasps are shared by the
        arms: the narrowest opening, the deepest and widest fingers)."""
        return GraspLimits.shared(a.gripper.limits for a in self.arms)

    @property
    def arm_names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.arms)

    @property
    def layout(self) -> ArmLayout:
        """The arms' joints in a configuration vector, in the scene's arm order."""
        return ArmLayout(self.arm_names, tuple(a.dof for a in self.arms))

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


def _packages(path: Path, keys: dict[str, Node]) -> tuple[Path, ...]:
    if "packages" not in keys:
        return ()
    packages = tuple(path.parent / node.as_str() for node in keys["packages"].items())
    for node, directory in zip(keys["packages"].items(), packages, strict=True):
        if not directory.is_dir():
            raise node.error("a package directory (relative to the scene file)")
    return packages


def load_scene(path: Path | None = None, environ: Mapping[str, str] | None = None) -> Scene:
    """Load a scene file (default: the shipped UR5e cell, :func:`default_scene_path`).

    A ``robot`` (top level: the default of every arm; per arm: its own) is a path relative to
    the scene file or a ``package://`` URI, looked up in the scene's ``packages``
    directories, then in ``ROS_PACKAGE_PATH`` of ``environ`` (default ``os.environ``). Each
    robot description is loaded and checked against its arms: frames and joints exist, the
    scene's joint limits lie within the URDF's, home lies within the limits, and each arm's
    gripper can hold the default object.
    """
    path = default_scene_path() if path is None else Path(path)
    root = read_yaml(path, SceneError)
    keys = root.mapping(
        ["table", "workspace", "object_size", "arms"],
        ["robot", "gripper", "velocity_safety", "packages"],
    )
    package_dirs = _packages(path, keys) + package_dirs_from_env(environ)
    tx, ty, tz = (
        keys["table"].mapping(["size"])["size"].as_floats(3, "[x, y, thickness]", positive=True)
    )
    table = Table((tx, ty, tz))
    ws = keys["workspace"].mapping(["x", "y"])
    workspace = Workspace(ws["x"].as_interval(), ws["y"].as_interval())
    sx, sy, sz = keys["object_size"].as_floats(3, "[lx, ly, lz]", positive=True)
    size = (sx, sy, sz)
    arm_nodes = keys["arms"].items()
    if not arm_nodes:
        raise keys["arms"].error("a non-empty list of arms", show_value=False)
    robots: dict[Path, PinRobot] = {}
    arms: list[ArmSpec] = []
    for node in arm_nodes:
        entry = node.value if isinstance(node.value, dict) else {}
        robot_node = node.mapping([], list(entry))["robot"] if "robot" in entry else None
        robot_node = robot_node or keys.get("robot")
        if robot_node is None:
            raise node.error("key 'robot' (here or at the top of the scene)", show_value=False)
        urdf, how = resolve_uri(robot_node.as_str(), path.parent, package_dirs)
        if urdf is None:
            raise robot_node.error(f"a robot description file ({how})")
        if urdf not in robots:
            robots[urdf] = PinRobot.load(urdf, package_dirs)
        arm = read_arm(node, urdf, robots[urdf], keys.get("gripper"))
        if arm.name in {a.name for a in arms}:
            name = node.mapping([], list(entry))["name"]
            raise name.error("a name different from the other arms'")
        problem = grasp_problem(size, arm.gripper.limits)
        if problem is not None:
            where = node.mapping([], list(entry)).get("gripper") or keys["gripper"]
            raise where.error(
                f"a gripper that holds the default object {list(size)}: {problem}",
                show_value=False,
            )
        arms.append(arm)
    safety = DEFAULT_VELOCITY_SAFETY
    if "velocity_safety" in keys:
        node = keys["velocity_safety"]
        safety = node.as_float()
        if not 0.0 < safety <= 1.0:
            raise node.error("a number in (0, 1], the share of the joint limits a motion uses")
    return Scene(str(path), table, workspace, size, tuple(arms), safety, package_dirs)
