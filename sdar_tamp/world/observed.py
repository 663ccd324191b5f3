"""Observed states: what a camera sees on the table while a plan runs, as a YAML file.

File shape (every key optional; metres and radians, world frame)::

    poses:                       # objects of the instance seen at another pose
      - {name: o3, pose: [0.112, -0.041, 0.35]}          # [x, y, yaw]
    removed: [o4]                # objects no longer on the table
    added:                       # objects the instance does not know
      - {name: box1, size: [0.06, 0.04, 0.05], pose: [0.0, 0.1, 0.0]}

Objects not named rest where the plan says. :func:`load_observed` checks the shape (every error
``file:line:col: key.path: expected ...``) and that no name appears twice; a name YAML 1.1
reads as a boolean (``on``, ``off``, ``yes``, ``no``) is refused with the advice to quote it.
:func:`observed_arrangement` applies the observation to the arrangement the plan predicts and
refuses, at the entry of the file at fault, an observed world that cannot be: an unknown
object, an object held by an arm, footprints leaving the workspace or overlapping (named, with
the overlap depth). :func:`check_clear_of_arms` refuses an object inside an arm at the arms'
configuration of the time reached.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sdar_tamp.errors import SourceLocation
from sdar_tamp.world._yaml import Node, parse_yaml, read_yaml
from sdar_tamp.world.collision import CollisionWorld, ObjectBox
from sdar_tamp.world.errors import ObservedStateError
from sdar_tamp.world.footprint import corners, inside_rectangle
from sdar_tamp.world.instance import Pose2D
from sdar_tamp.world.scene import Scene, Workspace
from sdar_tamp.world.transforms import FloatArray, pose_xyz_yaw

_NAME = re.compile(r"[A-Za-z0-9_.\-]+")
Size = tuple[float, float, float]


@dataclass(frozen=True)
class AddedObject:
    """An object the instance does not know: side lengths [m] and pose on the table."""

    name: str
    size: Size
    pose: Pose2D


@dataclass(frozen=True)
class ObservedState:
    """Objects seen at new poses, objects gone, objects added; ``locations``: the file entry
    of each name (for located errors)."""

    poses: Mapping[str, Pose2D] = field(default_factory=dict)
    removed: tuple[str, ...] = ()
    added: tuple[AddedObject, ...] = ()
    source: str = "<observed>"
    locations: Mapping[str, SourceLocation] = field(default_factory=dict)

    def where(self, name: str) -> SourceLocation:
        return self.locations.get(name, SourceLocation(self.source, 1, 1))


@dataclass(frozen=True)
class Resting:
    """An object resting on the table: side lengths [m] and planar pose."""

    size: Size
    pose: Pose2D


def load_observed(path: Path) -> ObservedState:
    """Read an observed-state file (see the module docstring)."""
    return _from_node(read_yaml(Path(path), ObservedStateError))


def parse_observed(text: str, name: str = "<observed>") -> ObservedState:
    """Parse observed-state YAML text; ``name`` is used in messages."""
    return _from_node(parse_yaml(text, name, ObservedStateError))


def _pose(node: Node) -> Pose2D:
    x, y, yaw = node.as_floats(3, "[x, y, yaw] in [m, m, rad]")
    return Pose2D(x, y, yaw)


def _name(node: Node, seen: dict[str, SourceLocation]) -> str:
    name = node.as_name()
    if not _NAME.fullmatch(name):
        raise node.error("a name of letters, digits, '_', '-' or '.'")
    if name in seen:
        raise ObservedStateError(
            f"{node.path}: {name!r} is already named at line {seen[name].line}; an object is "
            "either moved, removed or added, once",
            node.location,
        )
    seen[name] = node.location
    return name


def _from_node(root: Node) -> ObservedState:
    if root.value is None:
        return ObservedState(source=root.file)
    keys = root.mapping([], ["poses", "removed", "added"])
    seen: dict[str, SourceLocation] = {}
    poses: dict[str, Pose2D] = {}
    for node in keys["poses"].items() if "poses" in keys else []:
        k = node.mapping(["name", "pose"])
        poses[_name(k["name"], seen)] = _pose(k["pose"])
    removed = tuple(_name(n, seen) for n in (keys["removed"].items() if "removed" in keys else []))
    added: list[AddedObject] = []
    for node in keys["added"].items() if "added" in keys else []:
        k = node.mapping(["name", "size", "pose"])
        name = _name(k["name"], seen)
        lx, ly, lz = k["size"].as_floats(3, "[lx, ly, lz] in m, each > 0", positive=True)
        added.append(AddedObject(name, (lx, ly, lz), _pose(k["pose"])))
    return ObservedState(poses, removed, tuple(added), root.file, seen)


def observed_arrangement(
    observed: ObservedState,
    resting: Mapping[str, Resting],
    held: Mapping[str, str],
    known: tuple[str, ...],
    workspace: Workspace,
) -> dict[str, Resting]:
    """The resting objects once ``observed`` replaces the predicted arrangement ``resting``.

    ``held``: object -> the arm holding it at that time; ``known``: every object of the
    instance (those placed before, held, or resting). Raises :class:`ObservedStateError` at
    the file's entry for an unknown or held object, an added name already in use, a footprint
    leaving ``workspace`` or two overlapping footprints (with the overlap depth [m])."""
    out = dict(resting)
    for name in (*observed.poses, *observed.removed):
        where = observed.where(name)
        if name in held:
            raise ObservedStateError(
                f"{name!r} is held by arm {held[name]!r} at that time; an observation names "
                "resting objects only",
                where,
            )
        if name not in resting:
            gone = name in known
            raise ObservedStateError(
                f"unknown object {name!r}: "
                + ("it was removed before" if gone else f"the instance has {sorted(known)}"),
                where,
            )
    for name, pose in observed.poses.items():
        out[name] = Resting(resting[name].size, pose)
    for name in observed.removed:
        del out[name]
    for obj in observed.added:
        if obj.name in known or obj.name in resting:
            raise ObservedStateError(
                f"added object {obj.name!r}: the name is the instance's object; a moved object "
                "goes under 'poses'",
                observed.where(obj.name),
            )
        out[obj.name] = Resting(obj.size, obj.pose)
    check_arrangement(out, workspace, observed)
    return out


def check_arrangement(
    arrangement: Mapping[str, Resting], workspace: Workspace, observed: ObservedState
) -> None:
    """Footprints inside ``workspace`` and pairwise clear (touching allowed); errors at the
    observed file's entry of the first object named."""
    names = sorted(arrangement)
    if not names:
        return
    rect = corners(
        np.array([arrangement[n].pose.as_tuple() for n in names]),
        np.array([arrangement[n].size[:2] for n in names]),
    )
    inside = inside_rectangle(rect, workspace.x, workspace.y)
    changed = set(observed.poses) | {o.name for o in observed.added}
    for k in np.flatnonzero(~inside):
        name = names[int(k)]
        p = arrangement[name].pose
        raise ObservedStateError(
            f"object {name!r} at ({p.x:.3f}, {p.y:.3f}) m: its footprint leaves the workspace "
            f"x {list(workspace.x)}, y {list(workspace.y)} (off the table or out of reach)",
            observed.where(name),
        )
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            depth = overlap_depth(rect[i], rect[j])
            if depth > 1e-9:
                a, b = names[i], names[j]
                first = a if a in changed or b not in changed else b
                raise ObservedStateError(
                    f"objects {a!r} and {b!r} overlap by {depth * 1e3:.1f} mm",
                    observed.where(first),
                )


def overlap_depth(a: FloatArray, b: FloatArray) -> float:
    """Penetration depth [m] of two rectangles ``(4, 2)``: the least overlap of their
    projections on the four edge normals (<= 0: apart or touching)."""
    depth = float("inf")
    for rect in (a, b):
        for edge in (rect[1] - rect[0], rect[2] - rect[1]):
            axis = edge / np.linalg.norm(edge)
            pa, pb = a @ axis, b @ axis
            depth = min(depth, float(min(pa.max(), pb.max()) - max(pa.min(), pb.min())))
    return depth


def check_clear_of_arms(
    arrangement: Mapping[str, Resting],
    scene: Scene,
    q: FloatArray,
    t: float,
    observed: ObservedState,
    world: CollisionWorld | None = None,
    held: Mapping[str, tuple[str, ObjectBox]] | None = None,
) -> None:
    """No resting object inside an arm at configuration ``q`` ``(dof,)`` (the arms at time
    ``t`` [s]); raises :class:`ObservedStateError` naming the object, the arm's shapes and
    the configuration. ``world``: a collision world of ``scene`` to reuse (its objects are
    replaced); ``held``: arm -> (name, box in the world frame) of what each arm holds."""
    world = world or CollisionWorld(scene)
    boxes = {
        name: ObjectBox(pose_xyz_yaw(r.pose.x, r.pose.y, r.size[2] / 2.0, r.pose.yaw), r.size)
        for name, r in arrangement.items()
    }
    for arm in scene.arm_names:
        if world.held_by(arm) is not None:
            world.detach(arm)
    world.set_objects(boxes)
    for arm, (name, box) in (held or {}).items():  # what the arms hold, in their grippers
        world.set_object(name, box)
        world.attach(arm, name, scene.layout.part(q, arm))
    for pair in world.report(q) if world.in_collision(q) else ():
        names = [s[len("object:") :] for s in (pair.first, pair.second) if s.startswith("object:")]
        owners = [world.owner(s) for s in (pair.first, pair.second)]
        owner = next((a for a in owners if a is not None), None)
        if len(names) == 1 and owner is not None:
            conf = ", ".join(f"{v:.3f}" for v in scene.layout.part(q, owner))
            raise ObservedStateError(
                f"object {names[0]!r} is inside arm {owner!r} ({pair.first} with {pair.second}) "
                f"at t = {t:.3f} s, the arm at [{conf}] rad",
                observed.where(names[0]),
            )
