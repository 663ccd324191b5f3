"""Symbolic (CasADi SX) forward kinematics generated from a robot's kinematic chain.

Any serial chain of one-axis revolute and prismatic joints, as pinocchio reads it from the
URDF (:func:`sdar_tamp.world._pin.chain_to`): the frame of joint ``i`` is
``T_{i-1} @ T_parent_joint_i @ motion_i(q_i)``, with ``motion`` the rotation by ``q_i`` about
the joint's unit axis (Rodrigues' formula) or the translation by ``q_i`` along it. The UR cell's
optimiser keeps its DH form (:mod:`streams.motion.fk_casadi`); this is the form for other arms.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from sdar_tamp.world._pin import Chain, ChainJoint
from sdar_tamp.world.transforms import FloatArray
from streams.motion._casadi import ca, function, sx_sym


def _skew(a: FloatArray) -> FloatArray:
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def joint_motion(joint: ChainJoint, q: Any) -> Any:
    """The SX ``4x4`` motion of ``joint`` by the scalar ``q`` (rotation [rad] or slide [m])."""
    axis = np.asarray(joint.axis, dtype=np.float64)
    axis = axis / np.linalg.norm(axis)
    T: Any = ca.SX.eye(4)
    if joint.kind == "prismatic":
        for k in range(3):
            T[k, 3] = q * axis[k]
        return T
    K = _skew(axis)
    R = ca.SX(np.eye(3)) + ca.sin(q) * ca.SX(K) + (1.0 - ca.cos(q)) * ca.SX(K @ K)
    T[:3, :3] = R
    return T


def chain_frames(chain: Chain, q: Any, T_world_root: FloatArray) -> list[Any]:
    """World poses (SX ``4x4``) of every joint frame of ``chain`` for the SX vector ``q``
    ``(chain.dof,)``, the chain's root at ``T_world_root`` ``(4, 4)``."""
    T: Any = ca.SX(np.asarray(T_world_root, dtype=np.float64))
    frames: list[Any] = []
    for i, joint in enumerate(chain.joints):
        T = T @ ca.SX(joint.T_parent_joint) @ joint_motion(joint, q[i])
        frames.append(T)
    return frames


def chain_pose(chain: Chain, q: Any, T_world_root: FloatArray) -> Any:
    """World pose (SX ``4x4``) of the chain's end frame."""
    frames = chain_frames(chain, q, T_world_root)
    last: Any = frames[-1] if frames else ca.SX(np.asarray(T_world_root, dtype=np.float64))
    return last @ ca.SX(chain.T_joint_frame)


def chain_pose_function(chain: Chain, T_world_root: FloatArray) -> Any:
    """A casadi ``Function`` ``q (dof,) -> T_world_frame (4x4)`` (fully expanded SX)."""
    q = sx_sym("q", chain.dof)
    return function(f"fk_{chain.frame}", [q], [chain_pose(chain, q, T_world_root)])
