"""Symbolic (CasADi SX) forward kinematics of an arm of the scene, and its sphere centres.

A non-UR arm's frames come from its kinematic chain (:mod:`streams.motion.fk_chain`). For a
UR-family arm, frames follow :mod:`sdar_tamp.world.kinematics`: ``world -> base_link`` (the
arm's base pose), ``base_link -> DH base`` (pi about z), then the standard DH chain
``A_i = Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``. The frame of joint ``i`` (where the URDF hangs
link ``i``'s collision shapes) is ``A_1 ... A_{i-1} Rz(q_i) Tz(d_i)``; joint 6's frame is
``tool0``; the tool centre point is ``tcp_offset`` further along tool0 z.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sdar_tamp.world._pin import Chain
from sdar_tamp.world.errors import KinematicsError
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray, translation
from sdar_tamp.world.ur_ik import URParameters
from streams.motion._casadi import ca, function, sx_sym, to_array
from streams.motion.fk_chain import chain_frames
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
    """Symbolic FK of one arm: ``tcp(q)`` ``4x4`` and sphere centres ``(n, 3)`` as functions.

    A UR-family arm keeps the DH form of :func:`joint_frames` (``params`` set, six frames, the
    last one tool0); any other arm's FK is generated from its chain
    (:mod:`streams.motion.fk_chain`, ``chain`` set): its ``dof`` joint frames, then the tool
    frame. Spheres hang on the joint frames (``spheres.joint`` 1..dof); a held object's on
    :attr:`held_frame`.
    """

    T_world_base: FloatArray
    tcp_offset: float
    params: URParameters | None  # read from the URDF (UR family)
    T_base_dh: FloatArray  # (4, 4) the DH base in the arm's base frame
    spheres: ArmSpheres
    coarse: ArmSpheres  # fewer, larger spheres (arm-arm pairs of the optimiser)
    tcp_fn: Any  # casadi Function q(dof) -> 4x4
    tool0_fn: Any  # casadi Function q(dof) -> 4x4
    centres_fn: Any  # casadi Function q(dof) -> (n, 3)
    coarse_fn: Any  # casadi Function q(dof) -> (n_coarse, 3)
    chain: Chain | None = None  # the chain to the tool frame of a non-UR arm

    @staticmethod
    def from_scene(scene: Scene, arm: str) -> ArmFK:
        """The arm's symbolic FK, its spheres from :func:`.spheres.arm_spheres`."""
        return ArmFK.from_kinematics(ArmKinematics.from_scene(scene, arm), scene.package_dirs)

    @staticmethod
    def from_kinematics(kin: ArmKinematics, package_dirs: tuple[Path, ...] = ()) -> ArmFK:
        """The symbolic FK of the arm of ``kin``, its spheres from its robot description.

        Raises:
            KinematicsError: a collision shape hangs on a joint outside the arm's chain.
        """
        urdf = kin.robot.urdf_path
        spheres = _on_chain(kin, arm_spheres(urdf, package_dirs=package_dirs))
        coarse = _on_chain(kin, arm_spheres(urdf, coarse=True, package_dirs=package_dirs))
        chain = None if kin.params is not None else kin.chain
        q = sx_sym("q", kin.dof)
        frames = _frames(q, kin.T_world_base, kin.params, kin.T_base_dh, chain)
        tool0 = frames[-1] if chain is None else frames[-1] @ ca.SX(chain.T_joint_frame)
        tcp = tool0 @ ca.SX(translation(0.0, 0.0, kin.tcp_offset))
        return ArmFK(
            kin.T_world_base,
            kin.tcp_offset,
            kin.params,
            kin.T_base_dh,
            spheres,
            coarse,
            function("tcp", [q], [tcp]),
            function("tool0", [q], [tool0]),
            function("centres", [q], [sphere_centres(frames, spheres)]),
            function("coarse", [q], [sphere_centres(frames, coarse)]),
            chain,
        )

    @property
    def dof(self) -> int:
        return 6 if self.chain is None else self.chain.dof

    @property
    def n_frames(self) -> int:
        """Frames a sphere may hang on: six for the DH form (tool0 is joint 6's frame), else
        the ``dof`` joint frames and the tool frame."""
        return 6 if self.chain is None else self.chain.dof + 1

    @property
    def held_frame(self) -> int:
        """Index of the tool frame among :meth:`frames` (a held object's spheres hang on it)."""
        return self.n_frames - 1

    def frames(self, q: Any) -> list[Any]:
        """The world poses (SX ``4x4``) of the :attr:`n_frames` frames for the SX ``q``."""
        frames = self.joint_frames(q)
        if self.chain is not None:
            frames.append(frames[-1] @ ca.SX(self.chain.T_joint_frame))
        return frames

    def joint_frames(self, q: Any) -> list[Any]:
        """The world poses (SX ``4x4``) of the :attr:`dof` joint frames for the SX ``q``: the
        frames every sphere hangs on (a held object's on the last one, :attr:`T_last_tool`);
        the optimiser's slots choose among these (a slot's cost grows with their number)."""
        return _frames(q, self.T_world_base, self.params, self.T_base_dh, self.chain)

    @property
    def T_last_tool(self) -> FloatArray | None:
        """The tool frame in the last joint frame ``(4, 4)``, or None where they are one frame
        (the DH form: joint 6's frame is tool0)."""
        return None if self.chain is None else np.asarray(self.chain.T_joint_frame)

    def recipe(self) -> str:
        """The kinematic data the symbolic functions are made of (a cache key)."""
        if self.chain is None:
            return repr(self.params) + np.asarray(self.T_base_dh).tobytes().hex()
        parts = [self.chain.frame, np.asarray(self.chain.T_joint_frame).tobytes().hex()]
        for j in self.chain.joints:
            parts.append(f"{j.name}:{j.kind}:{np.asarray(j.axis).tobytes().hex()}")
            parts.append(np.asarray(j.T_parent_joint).tobytes().hex())
        return "|".join(parts)

    def tcp(self, q: FloatArray) -> FloatArray:
        return to_array(self.tcp_fn(np.asarray(q, dtype=np.float64)))

    def tool0(self, q: FloatArray) -> FloatArray:
        return to_array(self.tool0_fn(np.asarray(q, dtype=np.float64)))

    def centres(self, q: FloatArray, coarse: bool = False) -> FloatArray:
        """Sphere centres ``(m, n, 3)`` [m] for configurations ``q`` ``(m, dof)``."""
        qa = np.atleast_2d(np.asarray(q, dtype=np.float64))
        n = len(self.coarse if coarse else self.spheres)
        fn = self.coarse_fn if coarse else self.centres_fn
        out = to_array(fn.map(len(qa))(qa.T))  # (n, 3m)
        return out.reshape(n, len(qa), 3).transpose(1, 0, 2)

    def tcp_positions(self, q: FloatArray) -> FloatArray:
        """TCP positions ``(m, 3)`` for ``q`` ``(m, dof)``."""
        qa = np.atleast_2d(np.asarray(q, dtype=np.float64))
        T = to_array(self.tcp_fn.map(len(qa))(qa.T))  # (4, 4m)
        return T.reshape(4, len(qa), 4)[:3, :, 3].T

    def tool0_batch(self, q: FloatArray) -> FloatArray:
        qa = np.atleast_2d(np.asarray(q, dtype=np.float64))
        T = to_array(self.tool0_fn.map(len(qa))(qa.T))
        return T.reshape(4, len(qa), 4).transpose(1, 0, 2)


def _frames(
    q: Any,
    T_world_base: FloatArray,
    params: URParameters | None,
    T_base_dh: FloatArray,
    chain: Chain | None,
) -> list[Any]:
    """Joint frames: the DH form (``params``) or the chain's."""
    if chain is None:
        assert params is not None  # an ArmFK has one or the other
        return joint_frames(q, T_world_base, params, T_base_dh)
    return chain_frames(chain, q, T_world_base)


def _on_chain(kin: ArmKinematics, spheres: ArmSpheres) -> ArmSpheres:
    """``spheres`` with their joint numbered along the arm's chain (1..dof), not the robot
    model's joint index (the same for a description holding nothing but the arm)."""
    model = kin.robot.model
    index = {int(model.getJointId(j.name)): i + 1 for i, j in enumerate(kin.chain.joints)}
    outside = sorted({int(j) for j in spheres.joint if int(j) not in index})
    if outside:
        names = [str(model.names[j]) for j in outside]
        raise KinematicsError(
            f"{kin.robot.urdf_path.name}: collision shapes hang on joints {names}, which are "
            f"not on the chain to {kin.tool_frame!r}"
        )
    joint = np.array([index[int(j)] for j in spheres.joint], dtype=np.int64)
    return ArmSpheres(joint, spheres.centre, spheres.radius)


def sphere_centres(frames: list[Any], spheres: ArmSpheres) -> Any:
    """SX ``(n, 3)`` world centres of ``spheres`` for the joint ``frames`` (SX ``4x4`` each)."""
    rows = []
    for j, c in zip(spheres.joint, spheres.centre, strict=True):
        T = frames[int(j) - 1]
        rows.append((T[:3, :3] @ ca.SX(c) + T[:3, 3]).T)
    return ca.vertcat(*rows)
