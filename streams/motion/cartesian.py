"""Straight tool moves (approach and retreat) by IK interpolation (closed form, or the
numeric IK of every step solved from the start configuration)."""

from __future__ import annotations

import numpy as np

from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.transforms import FloatArray


def _line_targets(T0: FloatArray, distance: float, step: float) -> FloatArray:
    """TCP poses ``(m, n, 4, 4)`` moving each pose of ``T0`` ``(m, 4, 4)`` by ``distance`` [m]
    along its own z axis in ``n = ceil(|distance| / step)`` (at least one) equal steps."""
    n = max(1, int(np.ceil(abs(distance) / step)))
    T = np.repeat(T0[:, None], n, axis=1)
    T[:, :, :3, 3] += (distance * np.arange(1, n + 1) / n)[None, :, None] * T0[:, None, :3, 2]
    return T


def straight_tool_move(
    kin: ArmKinematics,
    q: FloatArray,
    distance: float,
    step: float = 0.01,
    max_joint_step: float = 0.3,
) -> FloatArray | None:
    """Configurations ``(n + 1, dof)`` [rad] moving the TCP by ``distance`` [m] along its own
    z axis (negative: backwards, i.e. a retreat), orientation fixed, starting at ``q``.

    Each step takes the IK branch nearest to the previous configuration; None when a step is
    unreachable or jumps by more than ``max_joint_step`` [rad] on some joint.
    """
    q = np.asarray(q, dtype=np.float64)
    if not kin.closed_form:  # every step solved from q, its redundancy pulled toward q
        return straight_tool_moves(kin, q[None], distance, step, max_joint_step)[0]
    T = _line_targets(kin.fk_tcp(q)[None], distance, step)[0]
    out = [q]
    sol = kin.ik_tcp(T)
    for k in range(len(T)):
        d = np.where(sol.valid[k], np.abs(sol.q[k] - out[-1]).max(axis=1), np.inf)
        b = int(np.argmin(d))
        if not np.isfinite(d[b]) or d[b] > max_joint_step:
            return None
        out.append(sol.q[k, b])
    return np.stack(out)


def straight_tool_moves(
    kin: ArmKinematics,
    qs: FloatArray,
    distance: float,
    step: float = 0.01,
    max_joint_step: float = 0.3,
) -> list[FloatArray | None]:
    """:func:`straight_tool_move` from each configuration of ``qs`` ``(m, dof)``; for an arm
    without a closed form every step of every move is solved in one batch of the numeric IK
    (whose cost is mostly per call), each from its own start."""
    q_all = np.asarray(qs, dtype=np.float64).reshape(-1, kin.dof)
    if kin.closed_form or len(q_all) == 0:
        return [straight_tool_move(kin, q, distance, step, max_joint_step) for q in q_all]
    T = _line_targets(np.stack([kin.fk_tcp(q) for q in q_all]), distance, step)  # (m, n, 4, 4)
    n = T.shape[1]
    starts = np.repeat(q_all[:, None, None], n, axis=1).reshape(-1, 1, kin.dof)
    near = kin.ik_tcp_from(T.reshape(-1, 4, 4), starts)
    steps, valid = near.q[:, 0].reshape(len(q_all), n, kin.dof), near.valid[:, 0].reshape(-1, n)
    out: list[FloatArray | None] = []
    for k, q in enumerate(q_all):
        path = np.concatenate([q[None], steps[k]])
        ok = valid[k].all() and np.abs(np.diff(path, axis=0)).max() <= max_joint_step
        out.append(path if ok else None)
    return out


def tool_pose_ik(
    kin: ArmKinematics, T_world_tcp: FloatArray, q_near: FloatArray
) -> FloatArray | None:
    """The valid IK branch ``(dof,)`` for a TCP pose nearest to ``q_near``, or None. For an
    arm without a closed form, the numeric IK from ``q_near`` first (warm start: the solution
    of ``q_near``'s branch, its redundancy pulled toward ``q_near``), every branch only when
    that fails."""
    if not kin.closed_form:
        q0 = np.asarray(q_near, dtype=np.float64)
        warm = kin.ik_tcp_from(T_world_tcp[None], q0[None, None])
        if warm.valid[0, 0]:
            return np.asarray(warm.q[0, 0], dtype=np.float64)
    sol = kin.ik_tcp(T_world_tcp[None])
    if not sol.valid[0].any():
        return None
    d = np.where(sol.valid[0], np.linalg.norm(sol.q[0] - q_near, axis=1), np.inf)
    return np.asarray(sol.q[0, int(np.argmin(d))], dtype=np.float64)
