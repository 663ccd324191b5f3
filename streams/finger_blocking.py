"""Grasp blocking: whether a neighbouring object leaves a grasp (or every grasp) of an object.

A grasp of an object is impossible when a gripper shape at that grasp intersects a neighbour:
a finger needs room beside the object on the closing axis (about 2.2 cm for the shipped
gripper: 1 cm from the open pad to the object, then the 1.2 cm finger), and a tilted grasp
swings the gripper body over the neighbours along the other axis. These tests are cheap
(oriented box against oriented box, no kinematics): they are necessary conditions for the IK
stream, so "blocks every grasp" is a proof that no arm can grasp the object there while the
neighbour rests where it does.

Gripper shapes are the collision boxes fixed to the tool centre point's link in the robot
description (:func:`gripper_boxes`); the neighbour's box is grown by ``margin`` [m] on every
face (the clearance the IK stream asks for).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sdar_tamp.world._pin import PinRobot, se3_to_array
from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.gripper import Gripper
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import BoolArray, FloatArray, inverse, translation
from streams._pin_geometry import arm_primitives
from streams.grasps import Grasp


@dataclass(frozen=True)
class GripperBox:
    """One box of the gripper: its centre in the TCP frame ``(4, 4)`` and half sides [m]."""

    T_tcp_box: FloatArray
    half: tuple[float, float, float]


def gripper_boxes(
    urdf: Path, tcp_frame: str = "tcp", package_dirs: tuple[Path, ...] = ()
) -> tuple[GripperBox, ...]:
    """The collision boxes of the link carrying ``tcp_frame`` (fingers and gripper body)."""
    robot = PinRobot.load(urdf, package_dirs)
    frame = robot.model.frames[robot.frame_id(tcp_frame)]
    T_tcp_joint = inverse(se3_to_array(frame.placement))
    joint = int(frame.parentJoint)
    return tuple(
        GripperBox(T_tcp_joint @ p.T_joint_shape, p.half)
        for p in arm_primitives(urdf, package_dirs)
        if p.joint == joint and p.kind == "box"
    )


def declared_finger_boxes(gripper: Gripper) -> tuple[GripperBox, GripperBox]:
    """The two finger boxes of a gripper known by its measures (a cell's ``finger_box``, or a
    description without a ``tcp`` frame): either side of the closing axis (y) from the
    pre-grasp opening out to the envelope, over the envelope's extent along x and z."""
    env = gripper.envelope
    lo, hi = env.min(axis=0), env.max(axis=0)
    inner = gripper.max_opening / 2.0
    boxes = []
    for y0, y1 in ((float(lo[1]), -inner), (inner, float(hi[1]))):
        if y1 <= y0:
            raise SceneError(
                f"gripper: the fingers' envelope ({lo[1]:.4f} .. {hi[1]:.4f} m across the "
                f"closing axis) does not reach beyond the opening {gripper.max_opening} m"
            )
        T = translation((lo[0] + hi[0]) / 2.0, (y0 + y1) / 2.0, (lo[2] + hi[2]) / 2.0)
        half = ((hi[0] - lo[0]) / 2.0, (y1 - y0) / 2.0, (hi[2] - lo[2]) / 2.0)
        boxes.append(GripperBox(T, (float(half[0]), float(half[1]), float(half[2]))))
    return boxes[0], boxes[1]


def cell_gripper_boxes(scene: Scene) -> tuple[GripperBox, ...]:
    """The gripper boxes of every arm of the cell (an arm's robot description's boxes on its
    ``tcp`` frame's link where it has that frame and boxes there, else its gripper's declared
    finger boxes); arms of one description and gripper count once."""
    out: list[GripperBox] = []
    seen: set[tuple[Path, Gripper]] = set()
    for arm in scene.arms:
        if (arm.urdf, arm.gripper) in seen:
            continue
        seen.add((arm.urdf, arm.gripper))
        robot = PinRobot.load(arm.urdf, scene.package_dirs)
        found: tuple[GripperBox, ...] = ()
        if robot.model.existFrame("tcp"):
            found = gripper_boxes(arm.urdf, "tcp", scene.package_dirs)
        out.extend(found or declared_finger_boxes(arm.gripper))
    return tuple(out)


def boxes_overlap(
    T_a: FloatArray, half_a: FloatArray, T_b: FloatArray, half_b: FloatArray
) -> BoolArray:
    """``(n,)``: oriented boxes ``a[k]`` and ``b[k]`` intersect (separating axis test).

    ``T_a``, ``T_b`` ``(n, 4, 4)``: box centres; ``half_a``, ``half_b`` ``(n, 3)``: half sides
    [m]. Touching boxes count as intersecting.
    """
    A = T_a[:, :3, :3]
    B = T_b[:, :3, :3]
    d = T_b[:, :3, 3] - T_a[:, :3, 3]  # (n, 3)
    R = np.einsum("nji,njk->nik", A, B)  # b's axes in a's frame
    absR = np.abs(R) + 1e-9
    t = np.einsum("nji,nj->ni", A, d)  # the centre offset in a's frame
    separated = np.zeros(len(d), dtype=np.bool_)
    for i in range(3):  # a's faces
        ra = half_a[:, i]
        rb = np.einsum("nk,nk->n", half_b, absR[:, i, :])
        separated |= np.abs(t[:, i]) > ra + rb
    for k in range(3):  # b's faces
        ra = np.einsum("ni,ni->n", half_a, absR[:, :, k])
        separated |= np.abs(np.einsum("ni,ni->n", t, R[:, :, k])) > ra + half_b[:, k]
    for i in range(3):  # edge against edge
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        for k in range(3):
            k1, k2 = (k + 1) % 3, (k + 2) % 3
            ra = half_a[:, i1] * absR[:, i2, k] + half_a[:, i2] * absR[:, i1, k]
            rb = half_b[:, k1] * absR[:, i, k2] + half_b[:, k2] * absR[:, i, k1]
            dist = np.abs(t[:, i2] * R[:, i1, k] - t[:, i1] * R[:, i2, k])
            separated |= dist > ra + rb
    return ~separated


class GraspBlocking:
    """Which grasps of an object a neighbouring box leaves impossible.

    ``boxes``: the gripper's boxes (:func:`gripper_boxes`); ``margin`` [m]: the neighbour's
    box is grown by it on every face.
    """

    def __init__(self, boxes: Sequence[GripperBox], margin: float = 0.003) -> None:
        if not boxes:
            raise ValueError("GraspBlocking needs at least one gripper box")
        if margin < 0.0:
            raise ValueError(f"margin must be >= 0 [m], got {margin}")
        self.boxes = tuple(boxes)
        self.margin = margin
        self._T = np.stack([b.T_tcp_box for b in self.boxes])  # (m, 4, 4)
        self._half = np.array([b.half for b in self.boxes], dtype=np.float64)  # (m, 3)
        # the farthest any gripper box point lies from the TCP [m]
        far = np.linalg.norm(self._T[:, :3, 3], axis=1) + np.linalg.norm(self._half, axis=1)
        self.reach = float(far.max())

    def blocked(
        self, grasps: Sequence[Grasp], target: ObjectBox, neighbour: ObjectBox
    ) -> BoolArray:
        """``(len(grasps),)``: a gripper box at the grasp of ``target`` meets ``neighbour``."""
        n, m = len(grasps), len(self.boxes)
        if n == 0:
            return np.zeros(n, dtype=np.bool_)
        T_obj_tcp = np.stack([g.T_object_tcp for g in grasps])  # (n, 4, 4)
        offset = float(np.linalg.norm(T_obj_tcp[:, :3, 3], axis=1).max())
        if self._far(target, neighbour, offset):
            return np.zeros(n, dtype=np.bool_)
        T_tcp = target.T_world_obj @ T_obj_tcp
        T_a = (T_tcp[:, None] @ self._T[None]).reshape(n * m, 4, 4)
        half_a = np.broadcast_to(self._half, (n, m, 3)).reshape(n * m, 3)
        T_b = np.broadcast_to(neighbour.T_world_obj, (n * m, 4, 4))
        half_b = np.broadcast_to(np.asarray(neighbour.size) / 2.0 + self.margin, (n * m, 3))
        hit = boxes_overlap(T_a, half_a, T_b, half_b)
        return np.asarray(hit.reshape(n, m).any(axis=1), dtype=np.bool_)

    def blocks_all(self, grasps: Sequence[Grasp], target: ObjectBox, neighbour: ObjectBox) -> bool:
        """``neighbour`` leaves no grasp of ``target`` (``False`` when there are no grasps)."""
        return bool(grasps) and bool(self.blocked(grasps, target, neighbour).all())

    def _far(self, target: ObjectBox, neighbour: ObjectBox, offset: float) -> bool:
        """No gripper box can reach ``neighbour`` from a TCP at most ``offset`` [m] from the
        centre of ``target``."""
        gap = np.linalg.norm(neighbour.T_world_obj[:3, 3] - target.T_world_obj[:3, 3])
        half_n = np.linalg.norm(neighbour.size) / 2.0 + np.sqrt(3.0) * self.margin
        return bool(gap > offset + self.reach + half_n)
