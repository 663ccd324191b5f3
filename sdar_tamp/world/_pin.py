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
from sdar_tamp.world.errors import KinematicsError, SceneError
from sdar_tamp.world.transforms import FloatArray
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
