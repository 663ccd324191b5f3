"""Building a plan file: motion segments and gripper events concatenated into one timeline."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

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

if TYPE_CHECKING:
    from sdar_tamp.world.kinematics import ArmKinematics


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


@dataclass(frozen=True, eq=False)
class PlanPart:
    """What a :class:`PlanBuilder` fixed since its last :meth:`~PlanBuilder.take`: samples
    ``q`` ``(n, dof)`` [rad] at absolute times ``t`` ``(n,)`` [s] (already resampled; the
    first part starts with the sample at ``t = 0``), the gripper events and the motion
    segments. The parts of one builder, concatenated, are the plan file's trajectory, events
    and steps."""

    t: FloatArray
    q: FloatArray
    events: tuple[PlanEvent, ...]
    steps: tuple[StepRecord, ...]


class PlanBuilder:
    """Concatenates motion segments and gripper events into one timeline, item by item (the
    rules: :func:`build_plan_file`). :meth:`take` returns what is fixed so far: every sample
    up to where the timeline stands (the dwell after the last gripper events comes with the
    next motion or at the end, since more events may join them at that instant)."""

    def __init__(
        self,
        scene: Scene,
        start_poses: Mapping[str, Pose3],
        sizes: Mapping[str, tuple[float, float, float]],
        q_start: FloatArray,
        gripper_time: float = GRIPPER_DWELL,
        dt: float = MAX_DT,
    ) -> None:
        from sdar_tamp.world.kinematics import ArmKinematics  # pinocchio: imported on use

        if set(sizes) != set(start_poses):
            raise ParameterError(
                f"sizes: expected the objects {sorted(start_poses)}, got {sorted(sizes)}"
            )
        if gripper_time < 0.0 or dt <= 0.0:
            raise ParameterError(
                f"gripper_time >= 0 and dt > 0 expected [s], got {gripper_time}, {dt}"
            )
        self.scene, self.gripper_time, self.dt = scene, gripper_time, dt
        self.layout = scene.layout
        self.kins = {a: ArmKinematics.from_scene(scene, a) for a in self.layout.names}
        self.q_now = np.array(q_start, dtype=np.float64)
        self.now, self.dwell = 0.0, False
        self.acting: set[str] = set()  # arms whose gripper acts at ``now`` (dwell not over)
        self.final: dict[str, Pose3] = {
            k: (float(v[0]), float(v[1]), float(v[2])) for k, v in start_poses.items()
        }
        self.held: dict[str, str] = {}
        self.actions = self.dual = self.items = 0
        self._ts: list[FloatArray] = [np.zeros(1)]  # raw samples not taken yet
        self._qs: list[FloatArray] = [self.q_now[None]]
        self._events: list[PlanEvent] = []
        self._steps: list[StepRecord] = []
        self._last: tuple[FloatArray, FloatArray] | None = None  # the last sample taken
        self._parts: list[PlanPart] = []

    def add(self, item: MotionSegment | GripperEvent) -> None:
        """Append one motion segment or gripper event (see :func:`build_plan_file`).

        Raises:
            ParameterError: an unknown arm, type or object; a segment of the wrong shape,
                with times not increasing from 0, or not starting where the timeline stands.
        """
        n = self.items
        self.items += 1
        if isinstance(item, GripperEvent):
            self._event(n, item)
            return
        layout = self.layout
        t, q = np.asarray(item.t, dtype=np.float64), np.asarray(item.q, dtype=np.float64)
        if t.ndim != 1 or q.shape != (len(t), layout.dof) or len(t) == 0 or t[0] != 0.0:
            raise ParameterError(
                f"items[{n}]: expected t (m,) from 0 and q (m, {layout.dof}), got {t.shape} and "
                f"{q.shape}"
            )
        if np.any(np.diff(t) <= 0.0):
            raise ParameterError(f"items[{n}].t: expected strictly increasing times")
        jump = float(np.abs(q[0] - self.q_now).max())
        if jump > 1e-6:
            raise ParameterError(
                f"items[{n}]: the segment starts {jump:.3g} rad away from where the timeline stands"
            )
        self._close_dwell()
        moving = np.abs(np.diff(q, axis=0)) > 1e-9
        arms_moving = np.stack([moving[:, s].any(axis=1) for s in layout.slices], axis=1)
        self.dual += bool(np.any(arms_moving.sum(axis=1) >= 2))  # two arms or more at once
        now = self.now
        self._steps.append(StepRecord(now, now + float(t[-1]), item.level, item.objects, item.kind))
        self._ts.append(now + t[1:])
        self._qs.append(q[1:])
        self.now = now + float(t[-1])
        self.q_now = q[-1].copy()

    def _event(self, n: int, item: GripperEvent) -> None:
        if (
            item.arm not in self.layout.names
            or item.type not in EVENT_TYPES
            or item.object not in self.final
        ):
            raise ParameterError(
                f"items[{n}]: expected an arm of {list(self.layout.names)}, a type of "
                f"{list(EVENT_TYPES)} and a known object, got {item}"
            )
        if item.arm in self.acting and self.gripper_time > 0.0:  # the arm's previous dwell
            self.now += self.gripper_time
            self._ts.append(np.array([self.now]))
            self._qs.append(self.q_now[None])
            self.acting.clear()
        self._events.append(
            PlanEvent(self.now, item.arm, item.type, item.object, item.T_tcp_object)
        )
        self.acting.add(item.arm)
        self.dwell = True
        if item.type == "grasp":
            self.held[item.arm] = item.object
            return
        self.actions += self.held.pop(item.arm, None) == item.object
        q_arm = self.layout.part(self.q_now, item.arm)
        T = self.kins[item.arm].fk_tcp(q_arm) @ np.asarray(item.T_tcp_object)
        self.final[item.object] = (float(T[0, 3]), float(T[1, 3]), math.atan2(T[1, 0], T[0, 0]))

    def _close_dwell(self) -> None:
        """The dwell after the last gripper events: the timeline stands still."""
        if self.dwell and self.gripper_time > 0.0:
            self.now += self.gripper_time
            self._ts.append(np.array([self.now]))
            self._qs.append(self.q_now[None])
        self.dwell = False
        self.acting.clear()

    def take(self) -> PlanPart:
        """The samples, events and segments fixed since the last call (samples resampled
        where their spacing exceeds ``dt``)."""
        t, q = np.concatenate(self._ts), np.concatenate(self._qs)
        if self._last is not None and len(t):
            t, q = resample(np.append(self._last[0], t), np.vstack([self._last[1], q]), self.dt)
            t, q = t[1:], q[1:]
        else:
            t, q = resample(t, q, self.dt)
        if len(t):
            self._last = (t[-1:], q[-1:])
        part = PlanPart(t, q, tuple(self._events), tuple(self._steps))
        self._ts, self._qs, self._events, self._steps = [], [], [], []
        self._parts.append(part)
        return part

    @property
    def parts(self) -> tuple[PlanPart, ...]:
        """Every part taken so far, in order."""
        return tuple(self._parts)

    def finish(self, instance_name: str, metrics: Mapping[str, MetricValue]) -> PlanFile:
        """The plan file: the timeline ends with the dwell of its last gripper events; the
        metrics of :data:`COMPUTED_METRICS` replace those in ``metrics``. No item may be
        added after it."""
        if self.dwell and self.gripper_time > 0.0:
            self._ts.append(np.array([self.now + self.gripper_time]))
            self._qs.append(self.q_now[None])
            self.dwell = False
        self.take()
        parts = self._parts
        t_all = np.concatenate([p.t for p in parts])
        q_all = np.concatenate([p.q for p in parts])
        events = tuple(e for p in parts for e in p.events)
        steps = tuple(s for p in parts for s in p.steps)
        out = PlanMetrics.from_mapping(metrics).updated(
            {
                "actions": self.actions,
                "steps": len(steps),
                "dual_arm_steps": self.dual,
                "execution_time": float(t_all[-1]),
            }
        )
        arms = plan_arms(self.scene, self.kins)
        return PlanFile(instance_name, arms, t_all, q_all, events, dict(self.final), out, steps)


def plan_arms(scene: Scene, kins: Mapping[str, ArmKinematics] | None = None) -> tuple[ArmInfo, ...]:
    """The plan file's ``arms`` of ``scene`` (``kins``: the arms' kinematics, when built)."""
    from sdar_tamp.world.kinematics import ArmKinematics  # pinocchio: imported on use

    kins = kins or {a: ArmKinematics.from_scene(scene, a) for a in scene.arm_names}
    return tuple(
        ArmInfo(
            a.name,
            plan_joint_names(a.name, a.joint_names),
            a.T_world_base,
            kins[a.name].T_tool0_tcp,
            np.array(a.home),
        )
        for a in scene.arms
    )


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
    :class:`PlanBuilder` does the same item by item.
    """
    first = next((i for i in items if isinstance(i, MotionSegment)), None)
    q_now = q_start if q_start is not None else first.q[0] if first else scene.home
    builder = PlanBuilder(scene, start_poses, sizes, np.asarray(q_now), gripper_time, dt)
    for item in items:
        builder.add(item)
    return builder.finish(instance_name, metrics)


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
