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

from sdar_tamp.textfile import read_text
from sdar_tamp.world._yaml import file_error
from sdar_tamp.world.errors import KinematicsError, SceneError
from sdar_tamp.world.transforms import FloatArray


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
    def load(urdf_path: Path) -> PinRobot:
        """Parse a URDF file (collision geometry included)."""
        text = read_text(urdf_path, file_error(SceneError))
        model = pin.buildModelFromXML(text)
        geometry = pin.buildGeomFromUrdfString(model, text, pin.COLLISION)
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
