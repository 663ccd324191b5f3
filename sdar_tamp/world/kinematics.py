"""World-frame kinematics of one arm of the scene: pinocchio FK, batched closed-form IK.

Frames: ``world`` -> ``base_link`` (arm base pose from the scene) -> DH base (pi about z)
-> ``tool0`` (the flange) -> ``tcp`` (``tcp_offset`` along tool0 z, between the finger pads).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from sdar_tamp.world._pin import PinRobot
from sdar_tamp.world.dls_ik import DlsOptions, DlsResult, dls_ik
from sdar_tamp.world.errors import KinematicsError
from sdar_tamp.world.scene import ArmSpec, Scene
from sdar_tamp.world.transforms import BoolArray, FloatArray, inverse, rot_z, translation
from sdar_tamp.world.ur_identify import ur_parameters
from sdar_tamp.world.ur_ik import URParameters, ur_fk, ur_ik, wrap_into_limits

#: ``T_base_link_dh0``: the DH base frame is the ROS base_link turned by pi about z.
T_BASE_DH = np.eye(4)
T_BASE_DH[:3, :3] = rot_z(np.pi)


@dataclass(frozen=True)
class IKSolutions:
    """All IK branches for ``n`` targets: ``q`` ``(n, 8, 6)`` [rad], ``valid`` ``(n, 8)``.

    A branch is valid when it is a real solution and every joint fits the arm's limits
    (after shifting by a multiple of 2 pi).
    """

    q: FloatArray
    valid: BoolArray

    def closest(self, q_ref: FloatArray) -> tuple[FloatArray, BoolArray]:
        """Per target, the valid branch nearest to ``q_ref`` ``(6,)``: ``(n, 6)``, ``(n,)``."""
        dist = np.linalg.norm(self.q - q_ref, axis=-1)
        dist = np.where(self.valid, dist, np.inf)
        best = np.argmin(dist, axis=1)
        q: FloatArray = self.q[np.arange(len(best)), best]
        ok: BoolArray = np.asarray(self.valid.any(axis=1), dtype=np.bool_)
        return q, ok


@dataclass(frozen=True)
class ArmKinematics:
    """Forward and inverse kinematics of one arm, in the world frame."""

    spec: ArmSpec
    robot: PinRobot
    tcp_offset: float  # [m]
    params: URParameters  # read from the URDF (:func:`.ur_identify.ur_parameters`)
    T_base_dh: FloatArray = field(default_factory=lambda: T_BASE_DH.copy(), compare=False)

    @staticmethod
    def from_scene(scene: Scene, arm: str) -> ArmKinematics:
        """The arm's kinematics, its UR parameters read from the scene's robot description.

        Raises:
            KinematicsError: the chain from the root to ``tool0`` is not a UR-family arm (the
                closed-form IK is the only one for now).
        """
        robot = PinRobot.load(scene.robot_urdf, scene.package_dirs)
        found = ur_parameters(robot)
        if found is None:
            raise KinematicsError(
                f"{scene.robot_urdf.name}: the chain to tool0 is not a UR-family arm "
                "(six revolute joints with the UR geometry), the only kind with inverse "
                "kinematics for now"
            )
        params, T_base_dh = found
        return ArmKinematics(scene.arm(arm), robot, scene.gripper.tcp_offset, params, T_base_dh)

    @property
    def T_world_base(self) -> FloatArray:
        return self.spec.T_world_base

    @property
    def T_tool0_tcp(self) -> FloatArray:
        return translation(0.0, 0.0, self.tcp_offset)

    # -- forward kinematics (pinocchio) --------------------------------------------------
    def fk(self, q: FloatArray, frame: str = "tool0") -> FloatArray:
        """``T_world_frame`` ``(4, 4)`` for ``q`` ``(6,)`` [rad], any frame of the URDF."""
        q = self._check_q(q)
        return self.T_world_base @ self.robot.frame_pose(q, self.robot.frame_id(frame))

    def fk_tool0(self, q: FloatArray) -> FloatArray:
        return self.fk(q, "tool0")

    def fk_tcp(self, q: FloatArray) -> FloatArray:
        return self.fk(q, "tcp")

    # -- batched closed form ---------------------------------------------------------------
    def fk_batch(self, q: FloatArray) -> FloatArray:
        """``T_world_tool0`` ``(n, 4, 4)`` for ``q`` ``(n, 6)``, closed form (numpy)."""
        return self.T_world_base @ self.T_base_dh @ ur_fk(self.params, q)

    def ik_tool0(self, T_world_tool0: FloatArray) -> IKSolutions:
        """All IK branches for flange poses ``(n, 4, 4)`` (or one ``(4, 4)``)."""
        T = np.asarray(T_world_tool0, dtype=np.float64)
        if T.shape[-2:] != (4, 4):
            raise KinematicsError(f"expected poses of shape (n, 4, 4), got {T.shape}")
        T = T.reshape(-1, 4, 4)
        T_dh = inverse(self.T_world_base @ self.T_base_dh) @ T
        q, real = ur_ik(self.params, T_dh)
        q, fits = wrap_into_limits(q, self.spec.lower_array, self.spec.upper_array)
        return IKSolutions(q, real & fits)

    def ik_tcp(self, T_world_tcp: FloatArray) -> IKSolutions:
        """All IK branches for tool-centre-point poses ``(n, 4, 4)``."""
        T = np.asarray(T_world_tcp, dtype=np.float64)
        return self.ik_tool0(T @ inverse(self.T_tool0_tcp))

    # -- numerical IK (pinocchio) ----------------------------------------------------------
    def ik_dls(
        self,
        T_world_frame: FloatArray,
        q0: FloatArray,
        frame: str = "tool0",
        options: DlsOptions | None = None,
    ) -> DlsResult:
        """Damped-least-squares IK for any frame, from the start guess ``q0`` [rad]."""
        T_base = inverse(self.T_world_base) @ np.asarray(T_world_frame, dtype=np.float64)
        return dls_ik(
            self.robot,
            self.robot.frame_id(frame),
            T_base,
            self._check_q(q0),
            self.spec.lower_array,
            self.spec.upper_array,
            options,
        )

    def _check_q(self, q: FloatArray) -> FloatArray:
        qa = np.asarray(q, dtype=np.float64)
        if qa.shape != (self.robot.nq,):
            raise KinematicsError(f"expected a configuration of shape (6,), got {qa.shape}")
        return qa
