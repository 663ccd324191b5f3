"""Reading the DH parameters of a UR-family arm from its URDF.

With the UR convention (``alpha = (pi/2, 0, 0, pi/2, -pi/2, 0)``, see :mod:`.ur_ik`), the
rotations of the chain do not depend on the lengths and the flange position is linear in them:
``p(q) = sum_k theta_k v_k(q)`` with ``theta = (d1, a2, a3, d4, d5, d6)`` and ``v_k(q)`` the
flange position of the unit-length arm ``e_k``. :func:`ur_parameters` fits ``theta`` by least
squares to the robot's own forward kinematics (pinocchio) at sampled configurations, rounds it
to :data:`DECIMALS` decimals (makers publish at most six, so the shipped UR5e reads back as
exactly its published constants), then accepts it only if the closed form reproduces every
flange pose within :data:`POSE_TOLERANCE`. Any other arm gives ``None``.
"""

from __future__ import annotations

import numpy as np

from sdar_tamp.world._pin import PinRobot, chain_to
from sdar_tamp.world.transforms import FloatArray, inverse, rot_z
from sdar_tamp.world.ur_ik import URParameters, ur_fk

#: Decimals the fitted lengths are rounded to [m] (1e-10 m).
DECIMALS = 10
#: Largest difference between the closed form and the robot's FK for a fit to count.
POSE_TOLERANCE = 1e-9
_SAMPLES = 32


def _dh_bases() -> tuple[FloatArray, ...]:
    """Candidate ``T_root_dh0``: ROS UR descriptions turn base_link by pi about z; others don't."""
    turned = np.eye(4)
    turned[:3, :3] = rot_z(np.pi)
    return (turned, np.eye(4))


def ur_parameters(
    robot: PinRobot, flange: str = "tool0", seed: int = 0
) -> tuple[URParameters, FloatArray] | None:
    """``(parameters, T_root_dh0)`` when the chain from the root to ``flange`` is a UR-family
    arm (six revolute joints, UR zero and signs), else ``None``. Deterministic in ``seed``."""
    chain = chain_to(robot, flange)
    if chain.dof != 6 or any(j.kind != "revolute" for j in chain.joints):
        return None
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, (_SAMPLES, 6))
    full = np.zeros((_SAMPLES, robot.nq))
    full[:, [j.q_index for j in chain.joints]] = q
    fid = robot.frame_id(flange)
    T_root_flange = np.stack([robot.frame_pose(row, fid) for row in full])
    unit = np.stack(
        [ur_fk(URParameters(*np.eye(6)[k]), q)[:, :3, 3] for k in range(6)], axis=-1
    )  # (samples, 3, 6)
    for T_root_dh in _dh_bases():
        T_dh_flange = inverse(T_root_dh) @ T_root_flange
        theta, *_ = np.linalg.lstsq(unit.reshape(-1, 6), T_dh_flange[:, :3, 3].ravel())
        params = URParameters(*(round(float(t), DECIMALS) for t in theta))
        if np.abs(ur_fk(params, q) - T_dh_flange).max() < POSE_TOLERANCE:
            return params, T_root_dh
    return None
