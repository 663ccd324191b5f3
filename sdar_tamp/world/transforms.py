"""Homogeneous transforms as numpy arrays, single ``(4, 4)`` or batched ``(..., 4, 4)``.

``T_a_b`` is the pose of frame b in frame a, so ``T_a_c = T_a_b @ T_b_c``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def rot_z(yaw: ArrayLike) -> FloatArray:
    """Rotation matrices about z, shape ``(..., 3, 3)`` for yaw of shape ``(...)`` [rad]."""
    yaw_a = np.asarray(yaw, dtype=np.float64)
    c, s = np.cos(yaw_a), np.sin(yaw_a)
    out = np.zeros((*yaw_a.shape, 3, 3))
    out[..., 0, 0] = c
    out[..., 0, 1] = -s
    out[..., 1, 0] = s
    out[..., 1, 1] = c
    out[..., 2, 2] = 1.0
    return out


def pose_xyz_yaw(x: ArrayLike, y: ArrayLike, z: ArrayLike, yaw: ArrayLike) -> FloatArray:
    """Poses ``(..., 4, 4)`` from a position [m] and a rotation ``yaw`` about z [rad]."""
    xa, ya, za, yawa = np.broadcast_arrays(
        *(np.asarray(v, dtype=np.float64) for v in (x, y, z, yaw))
    )
    out = np.zeros((*xa.shape, 4, 4))
    out[..., :3, :3] = rot_z(yawa)
    out[..., 0, 3] = xa
    out[..., 1, 3] = ya
    out[..., 2, 3] = za
    out[..., 3, 3] = 1.0
    return out


def translation(x: float, y: float, z: float) -> FloatArray:
    """A pure translation ``(4, 4)`` [m]."""
    out = np.eye(4)
    out[:3, 3] = (x, y, z)
    return out


def inverse(T: FloatArray) -> FloatArray:
    """Inverse of rigid transforms ``(..., 4, 4)``."""
    out = np.zeros_like(T)
    rt = np.swapaxes(T[..., :3, :3], -1, -2)
    out[..., :3, :3] = rt
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", rt, T[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def top_down_pose(x: ArrayLike, y: ArrayLike, z: ArrayLike, yaw: ArrayLike) -> FloatArray:
    """Tool poses ``(..., 4, 4)`` pointing straight down (tool z = -world z) at ``(x, y, z)``.

    ``yaw`` [rad] is the direction of the tool x axis in the table plane; the gripper closes
    along the tool y axis, i.e. along world direction ``yaw + pi/2``.
    """
    T = pose_xyz_yaw(x, y, z, yaw)
    flip = np.diag([1.0, -1.0, -1.0])  # rotation of pi about x: z down, y mirrored
    T[..., :3, :3] = T[..., :3, :3] @ flip
    return T
