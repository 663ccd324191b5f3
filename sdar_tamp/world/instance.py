"""Rearrangement instances: objects with start and goal poses on the workspace, as YAML files.

File shape::

    name: S8
    workspace: {x: [xmin, xmax], y: [ymin, ymax]}   # world frame [m]
    objects:
      - {name: o0, size: [lx, ly, lz], start: [x, y, yaw], goal: [x, y, yaw]}  # [m], [rad]
    scene: scene.yaml        # optional, relative to the instance file (default: shipped scene)
    family: S                # optional metadata written by the generators
    seed: 7                  # optional

Rules checked by :func:`validate_instance` (each error names the object): unique names, a
graspable size (a horizontal side the fingers close on and a height they can hold above the
table, :mod:`sdar_tamp.world.graspability`), footprints inside the workspace, and no two
overlapping footprints at start or at goal (touching is allowed).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from sdar_tamp.errors import SourceLocation
from sdar_tamp.world._yaml import Node, parse_yaml, read_yaml, yaml_name
from sdar_tamp.world.errors import InstanceError
from sdar_tamp.world.footprint import corners, inside_rectangle, overlap_matrix
from sdar_tamp.world.graspability import GraspLimits, grasp_problem
from sdar_tamp.world.scene import Workspace
from sdar_tamp.world.shipped_cell import SHIPPED_GRASP
from sdar_tamp.world.transforms import FloatArray

_NAME = re.compile(r"[A-Za-z0-9_.\-]+")


@dataclass(frozen=True)
class Pose2D:
    """A planar pose on the table: position [m] and yaw about z [rad]."""

    x: float
    y: float
    yaw: float

    def as_tuple(self) -> tuple[float, float, float]:
        return (self.x, self.y, self.yaw)


@dataclass(frozen=True)
class ObjectSpec:
    """One cuboid to rearrange."""

    name: str
    size: tuple[float, float, float]  # lx, ly, lz [m]
    start: Pose2D
    goal: Pose2D


@dataclass(frozen=True)
class Instance:
    """A rearrangement problem: workspace and objects with start and goal poses."""

    name: str
    workspace: Workspace
    objects: tuple[ObjectSpec, ...]
    scene: str | None = None  # scene file as written (relative to the instance file)
    family: str | None = None
    seed: int | None = None
    #: the file the instance was read from (None: built in memory); not part of its value
    source: Path | None = field(default=None, compare=False, repr=False)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(o.name for o in self.objects)

    def start_poses(self) -> FloatArray:
        """``(n, 3)``: x, y, yaw of every start."""
        return np.array([o.start.as_tuple() for o in self.objects]).reshape(-1, 3)

    def goal_poses(self) -> FloatArray:
        """``(n, 3)``: x, y, yaw of every goal."""
        return np.array([o.goal.as_tuple() for o in self.objects]).reshape(-1, 3)

    def sizes(self) -> FloatArray:
        """``(n, 3)`` side lengths."""
        return np.array([o.size for o in self.objects]).reshape(-1, 3)

    def scene_path(self, instance_file: Path | None = None) -> Path | None:
        """The scene file, resolved against the folder of ``instance_file`` (default: the file
        the instance was read from; relative to the working folder for an instance built in
        memory); None: the default scene."""
        if self.scene is None:
            return None
        p = Path(self.scene)
        folder_of = instance_file if instance_file is not None else self.source
        return p if p.is_absolute() or folder_of is None else folder_of.parent / p


def validate_instance(
    instance: Instance,
    grasp: GraspLimits | None = SHIPPED_GRASP,
    locations: dict[str, SourceLocation] | None = None,
) -> None:
    """Raise :class:`InstanceError` naming the first object that breaks a rule. ``grasp``:
    the gripper the objects must suit (default: the shipped cell's; None: not checked, for a
    caller that checks against its cell once it knows it)."""
    loc = locations or {}
    seen: set[str] = set()
    for o in instance.objects:
        if not _NAME.fullmatch(o.name):
            raise InstanceError(
                f"object {o.name!r}: expected a name of letters, digits, '_', '-' or '.'",
                loc.get(o.name),
            )
        if o.name in seen:
            raise InstanceError(f"object {o.name!r}: duplicate name", loc.get(o.name))
        seen.add(o.name)
        problem = None if grasp is None else grasp_problem(o.size, grasp)
        if problem is not None:
            raise InstanceError(
                f"object {o.name!r}: size {list(o.size)} cannot be grasped: {problem}",
                loc.get(o.name),
            )
    ws = instance.workspace
    sizes = instance.sizes()[:, :2]
    for label, poses in (("start", instance.start_poses()), ("goal", instance.goal_poses())):
        rect = corners(poses, sizes)
        inside = inside_rectangle(rect, ws.x, ws.y)
        for i in np.flatnonzero(~inside):
            o = instance.objects[int(i)]
            raise InstanceError(
                f"object {o.name!r}: {label} footprint leaves the workspace "
                f"x {list(ws.x)}, y {list(ws.y)}",
                loc.get(o.name),
            )
        over = np.triu(overlap_matrix(rect, rect), k=1)
        if over.any():
            first = np.argwhere(over)[0]
            a, b = instance.objects[int(first[0])].name, instance.objects[int(first[1])].name
            raise InstanceError(
                f"object {a!r}: {label} footprint overlaps the {label} footprint of {b!r}",
                loc.get(a),
            )


def load_instance(path: Path, grasp: GraspLimits | None = SHIPPED_GRASP) -> Instance:
    """Read and validate an instance file."""
    instance = _from_node(read_yaml(Path(path), InstanceError), grasp)
    return replace(instance, source=Path(path))


def parse_instance(
    text: str, name: str = "<string>", grasp: GraspLimits | None = SHIPPED_GRASP
) -> Instance:
    """Parse and validate instance YAML text; ``name`` is used in messages."""
    return _from_node(parse_yaml(text, name, InstanceError), grasp)


def _pose(node: Node) -> Pose2D:
    x, y, yaw = node.as_floats(3, "[x, y, yaw] in [m, m, rad]")
    return Pose2D(x, y, yaw)


def _from_node(root: Node, grasp: GraspLimits | None) -> Instance:
    keys = root.mapping(["name", "workspace", "objects"], ["scene", "family", "seed"])
    ws = keys["workspace"].mapping(["x", "y"])
    objects: list[ObjectSpec] = []
    locations: dict[str, SourceLocation] = {}
    for node in keys["objects"].items():
        k = node.mapping(["name", "size", "start", "goal"])
        name = k["name"].as_name()
        size = k["size"].as_floats(3, "[lx, ly, lz] in m, each > 0", positive=True)
        objects.append(ObjectSpec(name, size, _pose(k["start"]), _pose(k["goal"])))  # type: ignore[arg-type]
        locations.setdefault(name, node.location)
    seed = keys.get("seed")
    if seed is not None and (not isinstance(seed.value, int) or isinstance(seed.value, bool)):
        raise seed.error("an integer")
    instance = Instance(
        name=keys["name"].as_str(),
        workspace=Workspace(ws["x"].as_interval(), ws["y"].as_interval()),
        objects=tuple(objects),
        scene=keys["scene"].as_str() if "scene" in keys else None,
        family=keys["family"].as_str() if "family" in keys else None,
        seed=int(seed.value) if seed is not None else None,  # type: ignore[call-overload]
    )
    validate_instance(instance, grasp, locations)
    return instance


def dump_instance(instance: Instance) -> str:
    """YAML text of ``instance``; floats are written exactly (``repr``), so loading the text
    gives an equal instance."""
    ws = instance.workspace
    lines = [f"name: {yaml_name(instance.name)}"]
    if instance.family is not None:
        lines.append(f"family: {instance.family}")
    if instance.seed is not None:
        lines.append(f"seed: {instance.seed}")
    if instance.scene is not None:
        lines.append(f"scene: {instance.scene}")
    lines.append(f"workspace: {{x: {_f(ws.x)}, y: {_f(ws.y)}}}  # [m]")
    lines.append("objects:  # size [m]; start, goal: [x, y, yaw] in [m, m, rad]")
    for o in instance.objects:
        lines.append(
            f"  - {{name: {yaml_name(o.name)}, size: {_f(o.size)}, "
            f"start: {_f(o.start.as_tuple())}, goal: {_f(o.goal.as_tuple())}}}"
        )
    return "\n".join(lines) + "\n"


def save_instance(instance: Instance, path: Path) -> Path:
    """Write ``instance`` to ``path`` (parent folders are created)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(dump_instance(instance), encoding="utf-8")
    return path


def _f(values: tuple[float, ...]) -> str:
    return "[" + ", ".join(_float(v) for v in values) + "]"


def _float(v: float) -> str:
    """Exact text of a float that YAML 1.1 reads as a float (``1e-17`` -> ``1.0e-17``)."""
    text = repr(float(v))
    if "e" in text and "." not in text:
        text = text.replace("e", ".0e")
    return text
