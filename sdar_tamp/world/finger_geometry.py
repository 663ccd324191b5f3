"""The fingers of a parallel gripper, measured from the robot description.

A gripper is described by the URDF links of its fingers: their collision shapes, fixed
relative to the tool centre point (TCP), give the box that encloses the fingers in the TCP
frame (z the approach, y the closing axis). From it: how far the fingertips reach beyond the
TCP (``depth``), the fingers' extent across the closing axis (``width``), the gap between the
pads (``opening``) and the enclosing box's corners (``envelope``). Lengths are rounded to
:data:`DECIMALS` decimals [m], so a URDF written in millimetres reads back exact decimals.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass

import numpy as np

from sdar_tamp.world._pin import PinRobot, se3_to_array
from sdar_tamp.world.errors import KinematicsError
from sdar_tamp.world.transforms import FloatArray, inverse, translation

#: Decimals [m] the measured lengths are rounded to (1 um: mesh vertices are often stored in
#: single precision, about 1e-8 m at these sizes).
DECIMALS = 6


@dataclass(frozen=True)
class FingerGeometry:
    """Finger measures in the TCP frame [m]."""

    depth: float  # the fingertips' reach beyond the TCP along the approach (+z)
    width: float  # the fingers' extent along x (across the closing axis, across the approach)
    opening: float  # the gap between the pads' inner faces along y
    envelope: FloatArray  # (8, 3) corners of the box enclosing the fingers (x, then y, then z)


def _box_corners(half: FloatArray) -> FloatArray:
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    out: FloatArray = signs * half
    return out


def _finger_corners(
    robot: PinRobot, link: str, T_tcp_root: FloatArray, joint: int, locked: Collection[str]
) -> FloatArray:
    """Corners ``(8 k, 3)`` of the collision shapes of ``link`` in the TCP frame."""
    fid = robot.frame_id(link)
    frame = robot.model.frames[fid]
    j = int(frame.parentJoint)
    while j != joint:  # only locked joints may lie between the TCP's link and the finger
        if j == 0 or str(robot.model.names[j]) not in locked:
            raise KinematicsError(
                f"finger link {link!r} of {robot.urdf_path.name} moves relative to the tool "
                "centre point; the fingers must be fixed to the link that carries it (or hang "
                "on joints the arm holds locked)"
            )
        j = int(robot.model.parents[j])
    corners = []
    for obj in robot.geometry.geometryObjects:
        if int(obj.parentFrame) != fid:
            continue
        kind = type(obj.geometry).__name__.lower()
        if kind == "box":
            local = _box_corners(np.asarray(obj.geometry.halfSide, dtype=np.float64))
        elif kind.startswith("bvhmodel"):
            local = np.asarray(obj.geometry.vertices(), dtype=np.float64).reshape(-1, 3)
        else:
            raise KinematicsError(
                f"finger link {link!r} of {robot.urdf_path.name} has a {kind} collision shape; "
                "fingers are boxes or meshes"
            )
        T_root_joint = se3_to_array(robot.data.oMi[int(obj.parentJoint)])  # shapes hang on joints
        T = T_tcp_root @ T_root_joint @ se3_to_array(obj.placement)
        corners.append(local @ T[:3, :3].T + T[:3, 3])
    if not corners:
        raise KinematicsError(
            f"finger link {link!r} of {robot.urdf_path.name} has no collision shape"
        )
    return np.concatenate(corners)


def finger_geometry(
    robot: PinRobot,
    finger_links: Sequence[str],
    tcp_frame: str = "tcp",
    tcp_offset: float = 0.0,
    q: FloatArray | None = None,
    locked: Collection[str] = (),
) -> FingerGeometry:
    """The measures of the fingers ``finger_links`` (two: one either side of the TCP on y).
    The TCP is ``tcp_offset`` [m] along the z axis of the frame ``tcp_frame``; the fingers
    are measured at the configuration ``q`` ``(nq,)`` (default: neutral), and may hang on
    the joints ``locked`` (held at their value in ``q``, such as a gripper's slides).

    Raises:
        KinematicsError: not two fingers, an unknown link or frame, a finger without a box or
            mesh collision shape, fingers not fixed to the TCP's link, or fingers on one side.
    """
    if len(finger_links) != 2:
        raise KinematicsError(f"expected two finger links, got {list(finger_links)}")
    tcp = robot.frame_id(tcp_frame)
    robot.frame_pose(robot.neutral() if q is None else q, tcp)  # places every frame
    T_tcp_root = inverse(se3_to_array(robot.data.oMf[tcp]) @ translation(0.0, 0.0, tcp_offset))
    joint = int(robot.model.frames[tcp].parentJoint)
    fingers = [_finger_corners(robot, link, T_tcp_root, joint, locked) for link in finger_links]
    allp = np.concatenate(fingers)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    left, right = sorted(fingers, key=lambda c: float(c[:, 1].mean()))
    opening = float(right[:, 1].min() - left[:, 1].max())
    if opening <= 0.0:
        raise KinematicsError(
            f"fingers {list(finger_links)} of {robot.urdf_path.name} do not face each other "
            "across the tool centre point's y axis"
        )

    def r(v: float) -> float:
        return round(float(v), DECIMALS)

    envelope = np.array(
        [[r(x), r(y), r(z)] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )
    return FingerGeometry(r(hi[2]), r(hi[0] - lo[0]), r(opening), envelope)
