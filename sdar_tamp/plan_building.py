"""Building a plan file: motion segments and gripper events concatenated into one timeline."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import (
    EVENT_TYPES,
    GRIPPER_DWELL,
    MAX_DT,
    ArmInfo,
    PlanEvent,
    PlanFile,
    StepRecord,
    plan_joint_names,
)
from sdar_tamp.plan_metrics import MetricValue, PlanMetrics
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray


@dataclass(frozen=True, eq=False)
class MotionSegment:
    """One synchronous motion: samples ``q`` ``(m, dof)`` [rad] (every arm, in the scene's
    layout) at ``t`` ``(m,)`` [s] from 0."""

    t: FloatArray
    q: FloatArray
    level: str = ""
    objects: tuple[str, ...] = ()
    kind: str = ""


@dataclass(frozen=True, eq=False)
class GripperEvent:
    """``arm`` closes on (``grasp``) or opens from (``release``) ``object``, held at
    ``T_tcp_object`` ``(4, 4)`` in the tool-centre-point frame."""

    arm: str
    type: str
    object: str
    T_tcp_object: FloatArray


#: Metrics computed by :func:`build_plan_file` (they replace values passed under these keys):
#: gripper actions completed (a grasp and its release), motion segments, the segments in which
#: two arms or more move at once (``dual_arm_steps``: for two arms, both; the key keeps its
#: name so that two-arm plans read as before), and the duration [s].
COMPUTED_METRICS = ("actions", "steps", "dual_arm_steps", "execution_time")
Pose3 = tuple[float, float, float]


def build_plan_file(
    scene: Scene,
    instance_name: str,
    start_poses: Mapping[str, Pose3],
    sizes: Mapping[str, tuple[float, float, float]],
    items: Sequence[MotionSegment | GripperEvent],
    metrics: Mapping[str, MetricValue],
    gripper_time: float = GRIPPER_DWELL,
    dt: float = MAX_DT,
    q_start: FloatArray | None = None,
) -> PlanFile:
    """Concatenate ``items`` into one timeline (the scene's arms, one or more, in scene order).

    Each segment must start where the timeline stands. Consecutive gripper events (no motion
    between them) of different arms happen at the same instant, followed by one dwell of
    ``gripper_time`` [s] with the robot still: any subset of the arms may act at once (a
    two-gripper action, or several one-gripper actions at one configuration); a second event
    of one arm waits for the dwell of its first. The timeline is resampled linearly wherever
    the spacing exceeds ``dt`` [s]. ``final_poses``: start poses ``(x, y, yaw)`` [m, m, rad]
    of the objects in ``start_poses`` (``sizes`` must name the same objects), updated at every
    release from the tool pose (``T_world_tcp @ T_tcp_object`` projected on the table). Metrics: see
    :data:`COMPUTED_METRICS`; other entries of ``metrics`` are passed through. The timeline
    starts at ``q_start`` ``(dof,)``, else at the first segment's start, else at home.
    """
    from sdar_tamp.world.kinematics import ArmKinematics  # pinocchio: imported on use

    if set(sizes) != set(start_poses):
        raise ParameterError(
            f"sizes: expected the objects {sorted(start_poses)}, got {sorted(sizes)}"
        )
    if gripper_time < 0.0 or dt <= 0.0:
        raise ParameterError(f"gripper_time >= 0 and dt > 0 expected [s], got {gripper_time}, {dt}")
    layout = scene.layout
    names = layout.names
    kins = {a: ArmKinematics.from_scene(scene, a) for a in names}
    first = next((i for i in items if isinstance(i, MotionSegment)), None)
    home = scene.home
    q_now = np.array(q_start if q_start is not None else first.q[0] if first else home, float)
    ts: list[FloatArray] = [np.zeros(1)]
    qs: list[FloatArray] = [q_now[None]]
    now, dwell = 0.0, False
    acting: set[str] = set()  # arms whose gripper acts at ``now`` (their dwell not yet over)
    events: list[PlanEvent] = []
    steps: list[StepRecord] = []
    final: dict[str, Pose3] = {
        k: (float(v[0]), float(v[1]), float(v[2])) for k, v in start_poses.items()
    }
    held: dict[str, str] = {}
    actions = dual = 0
    for n, item in enumerate(items):
        if isinstance(item, GripperEvent):
            if item.arm not in names or item.type not in EVENT_TYPES or item.object not in final:
                raise ParameterError(
                    f"items[{n}]: expected an arm of {list(names)}, a type of "
                    f"{list(EVENT_TYPES)} and a known object, got {item}"
                )
            if item.arm in acting and gripper_time > 0.0:  # the arm's previous dwell first
                now += gripper_time
                ts.append(np.array([now]))
                qs.append(q_now[None])
                acting.clear()
            events.append(PlanEvent(now, item.arm, item.type, item.object, item.T_tcp_object))
            acting.add(item.arm)
            dwell = True
            if item.type == "grasp":
                held[item.arm] = item.object
                continue
            actions += held.pop(item.arm, None) == item.object
            q_arm = layout.part(q_now, item.arm)
            T = kins[item.arm].fk_tcp(q_arm) @ np.asarray(item.T_tcp_object)
            final[item.object] = (float(T[0, 3]), float(T[1, 3]), math.atan2(T[1, 0], T[0, 0]))
            continue
        if dwell and gripper_time > 0.0:
            now += gripper_time
            ts.append(np.array([now]))
            qs.append(q_now[None])
        dwell = False
        acting.clear()
        t, q = np.asarray(item.t, dtype=np.float64), np.asarray(item.q, dtype=np.float64)
        if t.ndim != 1 or q.shape != (len(t), layout.dof) or len(t) == 0 or t[0] != 0.0:
            raise ParameterError(
                f"items[{n}]: expected t (m,) from 0 and q (m, {layout.dof}), got {t.shape} and "
                f"{q.shape}"
            )
        if np.any(np.diff(t) <= 0.0):
            raise ParameterError(f"items[{n}].t: expected strictly increasing times")
        jump = float(np.abs(q[0] - q_now).max())
        if jump > 1e-6:
            raise ParameterError(
                f"items[{n}]: the segment starts {jump:.3g} rad away from where the timeline stands"
            )
        moving = np.abs(np.diff(q, axis=0)) > 1e-9
        arms_moving = np.stack([moving[:, s].any(axis=1) for s in layout.slices], axis=1)
        dual += bool(np.any(arms_moving.sum(axis=1) >= 2))  # two arms or more at once
        steps.append(StepRecord(now, now + float(t[-1]), item.level, item.objects, item.kind))
        ts.append(now + t[1:])
        qs.append(q[1:])
        now += float(t[-1])
        q_now = q[-1].copy()
    if dwell and gripper_time > 0.0:
        ts.append(np.array([now + gripper_time]))
        qs.append(q_now[None])
    t_all, q_all = resample(np.concatenate(ts), np.concatenate(qs), dt)
    out = PlanMetrics.from_mapping(metrics).updated(
        {
            "actions": actions,
            "steps": len(steps),
            "dual_arm_steps": dual,
            "execution_time": float(t_all[-1]),
        }
    )
    arms = tuple(
        ArmInfo(
            a.name,
            plan_joint_names(a.name, a.joint_names),
            a.T_world_base,
            kins[a.name].T_tool0_tcp,
            np.array(a.home),
        )
        for a in scene.arms
    )
    return PlanFile(instance_name, arms, t_all, q_all, tuple(events), final, out, tuple(steps))


def resample(t: FloatArray, q: FloatArray, dt: float) -> tuple[FloatArray, FloatArray]:
    """Insert linearly interpolated samples where the spacing of ``t`` ``(n,)`` exceeds
    ``dt`` [s]; ``q`` is ``(n, k)``."""
    if len(t) < 2:
        return t, q
    h = np.diff(t)
    n = np.maximum(1, np.ceil(h / dt - 1e-9)).astype(int)
    idx = np.repeat(np.arange(len(h)), n)
    frac = (np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)) / np.repeat(n, n)
    t_new = np.append(t[idx] + frac * h[idx], t[-1])
    q_new = np.concatenate([q[idx] + frac[:, None] * (q[idx + 1] - q[idx]), q[-1:]])
    return t_new, q_new
