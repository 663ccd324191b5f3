"""Typed adapter reading the arm's collision primitives from its pinocchio geometry model."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sdar_tamp.world._pin import PinRobot, se3_to_array
from sdar_tamp.world.transforms import FloatArray


@dataclass(frozen=True)
class Primitive:
    """A cylinder (axis along local z) or a box of one arm link, in its joint frame."""

    name: str
    joint: int  # 0 base (fixed), 1 shoulder_pan ... 6 wrist_3 (gripper and tool0 included)
    T_joint_shape: FloatArray  # (4, 4)
    kind: str  # "cylinder" or "box"
    half: tuple[float, float, float]  # cylinder: (radius, radius, half length); box: half sides


def arm_primitives(urdf: Path) -> tuple[Primitive, ...]:
    """Every collision primitive of one arm of the URDF (single-arm model)."""
    robot = PinRobot.load(urdf)
    out: list[Primitive] = []
    for obj in robot.geometry.geometryObjects:
        geom = obj.geometry
        kind = type(geom).__name__.lower()
        if kind == "cylinder":
            r, h = float(geom.radius), float(geom.halfLength)
            half = (r, r, h)
        elif kind == "box":
            hs = np.asarray(geom.halfSide, dtype=np.float64)
            half = (float(hs[0]), float(hs[1]), float(hs[2]))
        else:  # pragma: no cover - the shipped URDF has cylinders and boxes only
            raise ValueError(f"unsupported collision shape {kind!r} of {obj.name}")
        out.append(
            Primitive(str(obj.name), int(obj.parentJoint), se3_to_array(obj.placement), kind, half)
        )
    return tuple(out)
