"""Typed adapter reading the arm's collision primitives from its pinocchio geometry model.

Cylinders and boxes are read as they are. A mesh (the collision geometry makers ship) and a
sphere become the box that bounds them in their own frame: a conservative stand-in, while the
validator keeps checking the exact shapes with coal. A mesh also keeps its triangles (in the
joint frame), from which :mod:`streams.motion.sphere_fit` fits the optimiser's spheres.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sdar_tamp.world._pin import PinRobot, se3_to_array
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.transforms import FloatArray


@dataclass(frozen=True)
class Primitive:
    """A cylinder (axis along local z) or a box of one arm link, in its joint frame (a mesh
    or sphere of the URDF is its bounding box)."""

    name: str
    joint: int  # 0 base (fixed), 1 shoulder_pan ... 6 wrist_3 (gripper and tool0 included)
    T_joint_shape: FloatArray  # (4, 4)
    kind: str  # "cylinder" or "box"
    half: tuple[float, float, float]  # cylinder: (radius, radius, half length); box: half sides
    link: str = ""  # the URDF link holding the shape
    #: the link hangs from its joint through fixed joints (a tool, a gripper, a flange), rather
    #: than being the child link of the joint itself
    fixed_to_joint: bool = False
    triangles: FloatArray | None = None  # a mesh's triangles (m, 3, 3) in the joint frame


def arm_primitives(urdf: Path, package_dirs: tuple[Path, ...] = ()) -> tuple[Primitive, ...]:
    """Every collision primitive of one arm of the URDF (single-arm model).

    Raises:
        SceneError: the URDF does not load, or a collision shape is none of box, cylinder,
            sphere and mesh (naming the shape and the URDF).
    """
    robot = PinRobot.load(urdf, package_dirs)
    model = robot.model
    out: list[Primitive] = []
    for obj in robot.geometry.geometryObjects:
        geom = obj.geometry
        kind = type(geom).__name__.lower()
        T = se3_to_array(obj.placement)
        frame = model.frames[int(obj.parentFrame)]
        previous = model.frames[int(frame.parentFrame)]
        fixed = int(obj.parentJoint) != 0 and str(previous.type.name) != "JOINT"
        triangles = None
        if kind == "cylinder":
            r, h = float(geom.radius), float(geom.halfLength)
            half = (r, r, h)
        elif kind == "box":
            half = _triple(np.asarray(geom.halfSide, dtype=np.float64))
        elif kind == "sphere":
            r = float(geom.radius)
            kind, half = "box", (r, r, r)
        elif kind.startswith("bvhmodel") or kind == "convex":
            points = _vertices(geom, obj.name, urdf)
            if kind.startswith("bvhmodel"):
                triangles = _triangles(geom, points) @ T[:3, :3].T + T[:3, 3]
            kind, T, half = "box", *_bounding_box(T, points)
        else:  # pragma: no cover - read_urdf lets only box, cylinder, sphere and mesh through
            raise SceneError(
                f"{urdf}: collision shape {str(obj.name)!r} is a {kind}; the supported shapes "
                "are box, cylinder, sphere and mesh"
            )
        out.append(
            Primitive(
                str(obj.name),
                int(obj.parentJoint),
                T,
                kind,
                half,
                str(frame.name),
                fixed,
                triangles,
            )
        )
    return tuple(out)


def _triple(v: FloatArray) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


def _vertices(geom: Any, name: str, urdf: Path) -> FloatArray:
    """The vertices ``(n, 3)`` of a mesh geometry, in its own frame [m] (scale applied)."""
    points = np.asarray(geom.vertices(), dtype=np.float64).reshape(-1, 3)
    if len(points) == 0:
        raise SceneError(f"{urdf}: collision mesh {name!r} has no vertices")
    return points


def _triangles(geom: Any, points: FloatArray) -> FloatArray:
    """The triangles ``(m, 3, 3)`` of a coal mesh whose vertices are ``points``."""
    index = np.array(
        [[int(t[0]), int(t[1]), int(t[2])] for t in map(geom.tri_indices, range(geom.num_tris))],
        dtype=np.int64,
    ).reshape(-1, 3)
    return points[index]


def _bounding_box(
    T_joint_mesh: FloatArray, points: FloatArray
) -> tuple[FloatArray, tuple[float, float, float]]:
    """The axis-aligned box (in the mesh frame) around ``points`` ``(n, 3)``: its centre's pose
    in the joint frame ``(4, 4)`` and its half sides [m]."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre = np.eye(4)
    centre[:3, 3] = (lo + hi) / 2.0
    return T_joint_mesh @ centre, _triple((hi - lo) / 2.0)
