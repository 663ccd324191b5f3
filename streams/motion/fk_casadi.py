"""Symbolic (CasADi SX) forward kinematics of a UR arm of the scene, and its sphere centres.

Frames follow :mod:`sdar_tamp.world.kinematics`: ``world -> base_link`` (the arm's base pose),
``base_link -> DH base`` (pi about z), then the standard DH chain
``A_i = Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``. The frame of joint ``i`` (where the URDF hangs
link ``i``'s collision shapes) is ``A_1 ... A_{i-1} Rz(q_i) Tz(d_i)``; joint 6's frame is
``tool0``; the tool centre point is ``tcp_offset`` further along tool0 z.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray, translation
from sdar_tamp.world.ur_ik import URParameters
from streams.motion._casadi import ca, function, sx_sym, to_array
from streams.motion.spheres import ArmSpheres, arm_spheres


def _rz_tz(q: Any, d: float) -> Any:
    c, s = ca.cos(q), ca.sin(q)
    return ca.vertcat(
        ca.horzcat(c, -s, 0, 0), ca.horzcat(s, c, 0, 0), ca.horzcat(0, 0, 1, d),
        ca.horzcat(0, 0, 0, 1),
    )  # fmt: skip


def _tx_rx(a: float, alpha: float) -> FloatArray:
    ca_, sa = np.cos(alpha), np.sin(alpha)
    return np.array([[1, 0, 0, a], [0, ca_, -sa, 0], [0, sa, ca_, 0], [0, 0, 0, 1.0]])


def joint_frames(
    q: Any, T_world_base: FloatArray, params: URParameters, T_base_dh: FloatArray
) -> list[Any]:
    """World poses (SX ``4x4``) of joint frames 1..6 for the SX vector ``q`` ``(6,)``; the
    DH base at ``T_base_dh`` ``(4, 4)`` in the arm's base frame."""
    h = np.pi / 2
    rows = ((params.d1, 0.0, h), (0.0, params.a2, 0.0), (0.0, params.a3, 0.0),
            (params.d4, 0.0, h), (params.d5, 0.0, -h), (params.d6, 0.0, 0.0))  # fmt: skip
    T: Any = ca.SX(T_world_base @ T_base_dh)
    frames = []
    for i, (d, a, alpha) in enumerate(rows):
        T = T @ _rz_tz(q[i], d)
        frames.append(T)
        T = T @ ca.SX(_tx_rx(a, alpha))
    return frames


@dataclass(frozen=True)
class ArmFK:
    """Symbolic FK of one arm: ``tcp(q)`` ``4x4`` and sphere centres ``(n, 3)`` as functions."""

    T_world_base: FloatArray
    tcp_offset: float
    params: URParameters  # read from the URDF
    T_base_dh: FloatArray  # (4, 4) the DH base in the arm's base frame
    spheres: ArmSpheres
    coarse: ArmSpheres  # fewer, larger spheres (arm-arm pairs of the optimiser)
    tcp_fn: Any  # casadi Function q(6) -> 4x4
    tool0_fn: Any  # casadi Function q(6) -> 4x4
    centres_fn: Any  # casadi Function q(6) -> (n, 3)
    coarse_fn: Any  # casadi Function q(6) -> (n_coarse, 3)

    @staticmethod
    def from_scene(scene: Scene, arm: str) -> ArmFK:
        spec = scene.arm(arm)
        spheres = arm_spheres(scene.robot_urdf, package_dirs=scene.package_dirs)
        coarse = arm_spheres(scene.robot_urdf, coarse=True, package_dirs=scene.package_dirs)
        kinematics = ArmKinematics.from_scene(scene, arm)
        q = sx_sym("q", 6)
        frames = joint_frames(q, spec.T_world_base, kinematics.params, kinematics.T_base_dh)
        tool0 = frames[5]
        tcp = tool0 @ ca.SX(translation(0.0, 0.0, scene.gripper.tcp_offset))
        centres = sphere_centres(frames, spheres)
        return ArmFK(
            spec.T_world_base,
            scene.gripper.tcp_offset,
            kinematics.params,
            kinematics.T_base_dh,
            spheres,
            coarse,
            function("tcp", [q], [tcp]),
            function("tool0", [q], [tool0]),
            function("centres", [q], [centres]),
            function("coarse", [q], [sphere_centres(frames, coarse)]),
        )

    def tcp(self, q: FloatArray) -> FloatArray:
        return to_array(self.tcp_fn(np.asarray(q, dtype=np.float64)))

    def tool0(self, q: FloatArray) -> FloatArray:
        return to_array(self.tool0_fn(np.asarray(q, dtype=np.float64)))

    def centres(self, q: FloatArray, coarse: bool = False) -> FloatArray:
        """Sphere centres ``(m, n, 3)`` [m] for configurations ``q`` ``(m, 6)``."""
        qa = np.atleast_2d(np.asarray(q, dtype=np.float64))
        n = len(self.coarse if coarse else self.spheres)
        fn = self.coarse_fn if coarse else self.centres_fn
        out = to_array(fn.map(len(qa))(qa.T))  # (n, 3m)
        return out.reshape(n, len(qa), 3).transpose(1, 0, 2)

    def tcp_positions(self, q: FloatArray) -> FloatArray:
        """TCP positions ``(m, 3)`` for ``q`` ``(m, 6)``."""
        qa = np.atleast_2d(np.asarray(q, dtype=np.float64))
        T = to_array(self.tcp_fn.map(len(qa))(qa.T))  # (4, 4m)
        return T.reshape(4, len(qa), 4)[:3, :, 3].T

    def tool0_batch(self, q: FloatArray) -> FloatArray:
        qa = np.atleast_2d(np.asarray(q, dtype=np.float64))
        T = to_array(self.tool0_fn.map(len(qa))(qa.T))
        return T.reshape(4, len(qa), 4).transpose(1, 0, 2)


def sphere_centres(frames: list[Any], spheres: ArmSpheres) -> Any:
    """SX ``(n, 3)`` world centres of ``spheres`` for the joint ``frames`` (SX ``4x4`` each)."""
    rows = []
    for j, c in zip(spheres.joint, spheres.centre, strict=True):
        T = frames[int(j) - 1]
        rows.append((T[:3, :3] @ ca.SX(c) + T[:3, 3]).T)
    return ca.vertcat(*rows)
