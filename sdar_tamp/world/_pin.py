"""Typed adapter over pinocchio: load a robot description, query frame poses and Jacobians.

pinocchio ships without type stubs; this module is the only place (with :mod:`._coal` and
:mod:`.collision_model`) that touches its objects directly.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from sdar_tamp.errors import SourceLocation
from sdar_tamp.world import _coal
from sdar_tamp.world.errors import KinematicsError, SceneError
from sdar_tamp.world.transforms import BoolArray, FloatArray
from sdar_tamp.world.urdf import read_urdf


def build_model(urdf_path: Path, text: str) -> tuple[Any, Any]:
    """The pinocchio model and collision geometry of the URDF ``text`` read from
    ``urdf_path`` (its mesh paths absolute); pinocchio's errors become located ones."""
    try:
        model = pin.buildModelFromXML(text)
        geometry = pin.buildGeomFromUrdfString(model, text, pin.COLLISION)
    except (RuntimeError, ValueError) as error:
        detail = " ".join(str(error).split())
        raise SceneError(
            f"the robot description does not load: {detail}", SourceLocation(str(urdf_path), 1, 1)
        ) from None
    return model, geometry


def se3_to_array(M: Any) -> FloatArray:
    """A ``pin.SE3`` as a ``(4, 4)`` array."""
    return np.asarray(M.homogeneous, dtype=np.float64)


def array_to_se3(T: FloatArray) -> Any:
    """A ``(4, 4)`` array as a ``pin.SE3``."""
    return pin.SE3(np.ascontiguousarray(T[:3, :3]), np.ascontiguousarray(T[:3, 3]))


@dataclass(frozen=True)
class PinRobot:
    """A pinocchio kinematic model with its collision geometry, in the robot's base frame."""

    urdf_path: Path
    model: Any
    geometry: Any
    data: Any = field(repr=False)

    @staticmethod
    def load(urdf_path: Path, package_dirs: tuple[Path, ...] = ()) -> PinRobot:
        """Parse a URDF file (collision geometry included, meshes too), its ``package://``
        URIs looked up in ``package_dirs`` (:func:`sdar_tamp.world.urdf.read_urdf`).

        Raises:
            SceneError: the file cannot be read or parsed, a mesh is missing, or pinocchio
                rejects the description (located at the file).
        """
        model, geometry = build_model(urdf_path, read_urdf(urdf_path, package_dirs))
        return PinRobot(urdf_path, model, geometry, model.createData())

    @property
    def nq(self) -> int:
        return int(self.model.nq)

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(str(self.model.names[i]) for i in range(1, self.model.njoints))

    def neutral(self) -> FloatArray:
        """The description's neutral configuration ``(nq,)`` (zero angles)."""
        return np.asarray(pin.neutral(self.model), dtype=np.float64)

    def frame_id(self, name: str) -> int:
        if not self.model.existFrame(name):
            raise KinematicsError(f"unknown frame {name!r} in {self.urdf_path.name}")
        return int(self.model.getFrameId(name))

    def frame_pose(self, q: FloatArray, frame: int) -> FloatArray:
        """``T_base_frame`` ``(4, 4)`` at joint configuration ``q`` ``(nq,)`` [rad]."""
        pin.framesForwardKinematics(self.model, self.data, q)
        return se3_to_array(self.data.oMf[frame])

    def frame_poses(self, q: FloatArray, frames: tuple[int, ...]) -> FloatArray:
        """Poses ``(len(frames), 4, 4)`` of several frames at one configuration."""
        pin.framesForwardKinematics(self.model, self.data, q)
        return np.stack([se3_to_array(self.data.oMf[f]) for f in frames])

    def local_error_and_jacobian(
        self, q: FloatArray, frame: int, T_base_target: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Pose error ``log6(T_frame_target)`` ``(6,)`` and its Jacobian in q ``(6, nq)``."""
        pin.framesForwardKinematics(self.model, self.data, q)
        current = self.data.oMf[frame]
        iMd = current.actInv(array_to_se3(T_base_target))
        err = np.asarray(pin.log6(iMd).vector, dtype=np.float64)
        J = pin.computeFrameJacobian(self.model, self.data, q, frame, pin.LOCAL)
        jac = -np.asarray(pin.Jlog6(iMd.inverse()), dtype=np.float64) @ J
        return err, jac

    def integrate(self, q: FloatArray, v: FloatArray) -> FloatArray:
        return np.asarray(pin.integrate(self.model, q, v), dtype=np.float64)


@dataclass(frozen=True)
class ChainJoint:
    """One actuated joint of a serial chain, as pinocchio reads it from the URDF.

    The joint's frame is ``T_parent_joint @ motion(q)``, where ``motion`` turns by ``q`` [rad]
    about ``axis`` (``revolute``) or slides by ``q`` [m] along it (``prismatic``).
    """

    name: str
    T_parent_joint: FloatArray  # (4, 4): the joint frame at q = 0 in the previous joint's frame
    axis: FloatArray  # (3,) unit vector in the joint frame
    kind: str  # "revolute" or "prismatic"
    q_index: int  # index of the joint's coordinate in the robot's configuration vector


@dataclass(frozen=True)
class Chain:
    """The serial chain from the robot's root to one frame: joints in order, then the frame's
    fixed placement ``T_joint_frame`` ``(4, 4)`` in the last joint's frame."""

    joints: tuple[ChainJoint, ...]
    T_joint_frame: FloatArray
    frame: str

    @property
    def dof(self) -> int:
        return len(self.joints)


_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


def _joint_kind_axis(joint: Any) -> tuple[str, FloatArray] | None:
    """``(kind, axis)`` of a one-coordinate revolute or prismatic pinocchio joint, else None."""
    short = str(joint.shortname())
    for prefix, kind in (("JointModelR", "revolute"), ("JointModelP", "prismatic")):
        if short in (f"{prefix}X", f"{prefix}Y", f"{prefix}Z"):
            return kind, np.array(_AXES[short[-1]])
        if short.startswith(prefix) and short.endswith("Unaligned"):
            return kind, np.asarray(joint.extract().axis, dtype=np.float64).copy()
    return None


def chain_to(robot: PinRobot, frame: str) -> Chain:
    """The chain of ``robot`` from its root to ``frame``.

    Raises:
        KinematicsError: unknown frame, or a joint on the way that is neither a one-axis
            revolute nor a prismatic joint (continuous and floating joints included).
    """
    model = robot.model
    f = model.frames[robot.frame_id(frame)]
    ids: list[int] = []
    j = int(f.parentJoint)
    while j != 0:
        ids.append(j)
        j = int(model.parents[j])
    joints: list[ChainJoint] = []
    for j in reversed(ids):
        kind_axis = _joint_kind_axis(model.joints[j])
        if kind_axis is None:
            raise KinematicsError(
                f"joint {model.names[j]!r} of {robot.urdf_path.name} is a "
                f"{model.joints[j].shortname()}; a chain takes one-axis revolute or prismatic "
                "joints"
            )
        kind, axis = kind_axis
        joints.append(
            ChainJoint(
                str(model.names[j]),
                se3_to_array(model.jointPlacements[j]),
                axis,
                kind,
                int(model.joints[j].idx_q),
            )
        )
    return Chain(tuple(joints), se3_to_array(f.placement), frame)


def colliding_configurations(robot: PinRobot, q: FloatArray, table_top: float) -> BoolArray:
    """``(n,)``: which configurations ``q`` ``(n, nq)`` put two collision shapes of the robot
    at least two joints apart in contact, or a shape of a link past the first moving one
    below the plane ``z = table_top`` [m] of the robot's base frame (a table top)."""
    geometry = robot.geometry.copy()
    model = robot.model
    table = pin.GeometryObject(
        "table", 0, pin.SE3(np.eye(3), np.array([0.0, 0.0, table_top - 0.5])), _coal.box((4, 4, 1))
    )
    table_id = geometry.addGeometryObject(table)

    def depth(joint: int) -> int:
        n = 0
        while joint != 0:
            joint, n = int(model.parents[joint]), n + 1
        return n

    objects = list(geometry.geometryObjects)
    for a in range(len(objects)):
        ja = int(objects[a].parentJoint)
        if a != table_id and depth(ja) >= 2:
            geometry.addCollisionPair(pin.CollisionPair(a, table_id))
        for b in range(a + 1, len(objects)):
            jb = int(objects[b].parentJoint)
            if table_id not in (a, b) and abs(depth(ja) - depth(jb)) >= 2:
                geometry.addCollisionPair(pin.CollisionPair(a, b))
    gdata = geometry.createData()
    data = model.createData()
    out = np.zeros(len(q), dtype=np.bool_)
    for i, row in enumerate(np.asarray(q, dtype=np.float64)):
        out[i] = bool(pin.computeCollisions(model, data, geometry, gdata, row, True))
    return out
