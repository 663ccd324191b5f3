"""What the 3-D page animates, as compact arrays: link poses per frame, who holds what, how far
each gripper is closed, the joint-space curves, the steps and events.

The page draws every mesh from one copy of its geometry (vertices in their link or object frame)
and moves it by poses given as position + quaternion ``(x, y, z, qx, qy, qz, qw)`` per link per
frame; the browser interpolates between frames.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from sdar_tamp.plan_file import GRIPPER_DWELL
from sdar_tamp.viewer._geometry import FINGER_FRAMES, ArmDrawing
from sdar_tamp.viewer._timeline import Timeline
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray, inverse, pose_xyz_yaw

#: Rate of the joint-space curves [1/s].
JOINT_RATE = 25.0


def quaternions(R: FloatArray) -> FloatArray:
    """Unit quaternions ``(..., 4)`` ``(qx, qy, qz, qw)`` of rotations ``(..., 3, 3)``.

    Consecutive entries along the first axis keep the same hemisphere (no sign flips)."""
    R = np.asarray(R, dtype=np.float64)
    m = R.reshape(-1, 3, 3)
    # the Shepperd method: the largest of the four candidates is the best conditioned
    d = np.stack(
        [
            1 + m[:, 0, 0] - m[:, 1, 1] - m[:, 2, 2],
            1 - m[:, 0, 0] + m[:, 1, 1] - m[:, 2, 2],
            1 - m[:, 0, 0] - m[:, 1, 1] + m[:, 2, 2],
            1 + m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2],
        ],
        axis=1,
    )
    best = np.argmax(d, axis=1)
    q = np.empty((len(m), 4))
    for i, k in enumerate(best):
        r = m[i]
        s = 2.0 * np.sqrt(max(d[i, k], 1e-300))
        if k == 0:
            q[i] = (
                s / 4,
                (r[0, 1] + r[1, 0]) / s,
                (r[0, 2] + r[2, 0]) / s,
                (r[2, 1] - r[1, 2]) / s,
            )
        elif k == 1:
            q[i] = (
                (r[0, 1] + r[1, 0]) / s,
                s / 4,
                (r[1, 2] + r[2, 1]) / s,
                (r[0, 2] - r[2, 0]) / s,
            )
        elif k == 2:
            q[i] = (
                (r[0, 2] + r[2, 0]) / s,
                (r[1, 2] + r[2, 1]) / s,
                s / 4,
                (r[1, 0] - r[0, 1]) / s,
            )
        else:
            q[i] = (
                (r[2, 1] - r[1, 2]) / s,
                (r[0, 2] - r[2, 0]) / s,
                (r[1, 0] - r[0, 1]) / s,
                s / 4,
            )
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    out = q.reshape(*R.shape[:-2], 4)
    if out.ndim >= 2 and len(out) > 1:  # same hemisphere as the previous entry along axis 0
        for k in range(1, len(out)):
            flip = np.sum(out[k] * out[k - 1], axis=-1) < 0
            out[k] = np.where(flip[..., None], -out[k], out[k])
    return out


def pose7(T: FloatArray) -> FloatArray:
    """Poses ``(..., 4, 4)`` as ``(..., 7)``: position [m] then quaternion (qx, qy, qz, qw)."""
    T = np.asarray(T, dtype=np.float64)
    return np.concatenate([T[..., :3, 3], quaternions(T[..., :3, :3])], axis=-1)


@dataclass(frozen=True)
class Grip:
    """How far an arm's gripper is closed over the frames: ``closure`` ``(k,)`` in [0, 1] and
    the width of what it closes on ``width`` ``(k,)`` [m]."""

    closure: FloatArray = field(repr=False)
    width: FloatArray = field(repr=False)


def grips(timeline: Timeline, times: FloatArray) -> tuple[Grip, ...]:
    """Every arm's gripper (timeline order) at ``times``: closing over :data:`GRIPPER_DWELL`
    after a grasp, opening over it after a release; the width is the grasped object's extent
    across the jaws."""
    plan = timeline.plan
    names = [a.name for a in plan.arms] if plan is not None else []
    sizes = {o.name: np.asarray(o.size, dtype=np.float64) for o in timeline.instance.objects}
    out = []
    for a in range(len(timeline.arms)):
        closure = np.zeros(len(times))
        width = np.zeros(len(times))
        events = sorted(
            (e for e in (plan.events if plan is not None else ()) if e.arm == names[a]),
            key=lambda e: float(e.t),
        )
        for e in events:
            after = times >= float(e.t)
            ramp = np.clip((times - float(e.t)) / GRIPPER_DWELL, 0.0, 1.0)
            closure[after] = ramp[after] if e.type == "grasp" else 1.0 - ramp[after]
            R = np.asarray(e.T_tcp_object, dtype=np.float64).reshape(4, 4)[:3, :3]
            width[after] = float(np.abs(R[1]) @ sizes[e.object])
        out.append(Grip(closure, width))
    return tuple(out)


def link_poses(arm: ArmDrawing, q: FloatArray, grip: Grip) -> FloatArray:
    """``T_world_link`` ``(k, L, 4, 4)`` of ``arm.links`` at ``q`` ``(k, arm.dof)``; the fingers
    slide towards each other as ``grip`` closes (on the object's width)."""
    T = arm.frame_poses(q, arm.links)
    fingers = [arm.links.index(f) for f in FINGER_FRAMES if f in arm.links]
    if not fingers:
        return T
    base = arm.frame_poses(q, ("gripper_base_link",))[:, 0]
    for j in fingers:
        shape = next(s for s in arm.shapes if s.link == arm.links[j])
        half = 0.5 * float(np.abs(shape.T_link_shape[1, :3]) @ np.asarray(shape.size))
        local = inverse(base[0]) @ T[0, j]  # the finger in the gripper's frame (fixed)
        y_open = float(local[1, 3])
        y_closed = np.sign(y_open) * np.minimum(abs(y_open), grip.width / 2 + half)
        shift = grip.closure * (y_closed - y_open)  # (k,)
        moved = np.repeat(local[None], len(q), axis=0)
        moved[:, 1, 3] += shift
        T[:, j] = base @ moved
    return T


def object_holds(timeline: Timeline) -> list[list[tuple[float, int, FloatArray]]]:
    """Per object (instance order): ``(t, arm, pose)`` from ``t`` [s] on: held by ``arm`` with
    ``pose`` = ``T_tcp_object``, or resting (``arm == -1``) at ``pose`` = ``T_world_object``;
    the first entry (``t = -inf``) is its start pose."""
    out = []
    for obj in timeline.instance.objects:
        start = pose_xyz_yaw(obj.start.x, obj.start.y, obj.size[2] / 2, obj.start.yaw)
        entries = [(-np.inf, -1, start)]
        entries += [(h.t, h.arm, h.T) for h in timeline.holds.get(obj.name, ())]
        out.append(entries)
    return out


@dataclass(frozen=True)
class JointCurves:
    """Joint-space curves at ``t`` ``(k,)`` [s]: per arm, position as a fraction of its range
    (0 lower, 1 upper limit) and velocity as a fraction of its limit (-1 to 1), ``(k, arm
    dof)``; ``joints``: per arm, its joints' names in the robot description."""

    t: FloatArray = field(repr=False)
    position: tuple[FloatArray, ...] = field(repr=False)
    velocity: tuple[FloatArray, ...] = field(repr=False)
    joints: tuple[tuple[str, ...], ...] = ()


def joint_curves(timeline: Timeline, scene: Scene, rate: float = JOINT_RATE) -> JointCurves:
    """q and q-dot of every arm against the scene's limits for the arms of the plan (by name;
    the scene's arms in order when a name is unknown)."""
    t, q = timeline.t, timeline.q
    keep = np.concatenate([[True], np.diff(t) > 1e-9])
    t_u, q_u = t[keep], q[keep]
    qd = np.gradient(q_u, t_u, axis=0) if len(t_u) > 1 else np.zeros_like(q_u)
    times = timeline.sample_times(rate)
    q_s = timeline.q_at(times)
    qd_s = (
        np.column_stack([np.interp(times, t_u, qd[:, j]) for j in range(q.shape[1])])
        if len(t_u) > 1
        else np.zeros((len(times), q.shape[1]))
    )
    positions, velocities, joints = [], [], []
    names = scene.arm_names
    for a, drawing in enumerate(timeline.arms):
        spec = scene.arm(drawing.name) if drawing.name in names else scene.arms[a]
        lower, upper = spec.lower_array, spec.upper_array
        span = np.where(upper - lower > 0, upper - lower, 1.0)
        vmax = np.asarray(spec.velocity_limit, dtype=np.float64)
        positions.append((timeline.arm_q(q_s, a) - lower) / span)
        velocities.append(timeline.arm_q(qd_s, a) / np.where(vmax > 0, vmax, 1.0))
        joints.append(spec.joint_names)
    return JointCurves(times, tuple(positions), tuple(velocities), tuple(joints))
