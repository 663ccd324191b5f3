"""The world state of a plan at any time: arm configurations, held and resting objects.

An object rests at its start pose until grasped; while held it moves rigidly with the arm's tool
centre point (``T_world_obj = T_world_tcp(q(t)) @ T_tcp_object``); at release it rests where it
was released. Configurations between plan samples are linearly interpolated.
"""

from __future__ import annotations

import itertools
import logging
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sdar_tamp.errors import ParameterError
from sdar_tamp.viewer._geometry import ArmDrawing
from sdar_tamp.viewer._plan import PlanLike, StepLike
from sdar_tamp.world._pin import PinRobot
from sdar_tamp.world.errors import ArmLayoutError
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.layout import ArmLayout
from sdar_tamp.world.scene import ArmSpec, Scene
from sdar_tamp.world.transforms import FloatArray, pose_xyz_yaw

IntArray = NDArray[np.int64]
_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Segment:
    """A time span of the plan shown as one storyboard panel [s]."""

    index: int
    t_start: float
    t_end: float
    label: str


@dataclass(frozen=True)
class _Hold:
    """One event of one object: from ``t`` on it is held by ``arm`` with ``T`` = ``T_tcp_object``,
    or (``arm == -1``) it rests at ``T`` = ``T_world_object``."""

    t: float
    arm: int
    T: FloatArray = field(repr=False)


@dataclass(frozen=True)
class Timeline:
    """A plan (or, without one, the arms at home) replayable at any time."""

    instance: Instance
    arms: tuple[ArmDrawing, ...]
    layout: ArmLayout  # the arms' joints in q
    t: FloatArray  # (n,) [s]
    q: FloatArray  # (n, layout.dof) [rad]
    plan: PlanLike | None = field(default=None, repr=False)
    holds: dict[str, tuple[_Hold, ...]] = field(default_factory=dict, repr=False)

    @staticmethod
    def build(instance: Instance, plan: PlanLike | None, scene: Scene) -> Timeline:
        """The plan on ``instance`` in ``scene`` (without a plan: the arms at home). Every arm
        is drawn from its own robot description with its own joints (the scene's arm of the
        plan arm's name, else the scene's arm in its place)."""
        robots: dict[Path, PinRobot] = {}  # one load per robot description
        if plan is None:
            drawings = tuple(
                _drawing(scene, a, a.name, a.T_world_base, None, robots) for a in scene.arms
            )
            return Timeline(instance, drawings, scene.layout, np.zeros(1), scene.home[None])
        if plan.instance != instance.name:
            _log.warning("plan for instance %r drawn on instance %r", plan.instance, instance.name)
        if len(plan.arms) != len(scene.arms):
            raise ParameterError(
                f"plan.arms: expected {len(scene.arms)} arms (the scene's), got {len(plan.arms)}"
            )
        names = scene.arm_names
        specs = [scene.arm(a.name) if a.name in names else scene.arms[i]
                 for i, a in enumerate(plan.arms)]  # fmt: skip
        try:
            layout = ArmLayout(tuple(a.name for a in plan.arms), tuple(len(s.home) for s in specs))
        except ArmLayoutError as e:
            raise ParameterError(f"plan.arms: {e}") from None
        drawings = tuple(
            _drawing(
                scene,
                spec,
                a.name,
                np.asarray(a.T_world_base, dtype=np.float64),
                np.asarray(a.T_tool0_tcp, dtype=np.float64),
                robots,
            )
            for a, spec in zip(plan.arms, specs, strict=True)
        )
        t = np.asarray(plan.t, dtype=np.float64).reshape(-1)
        q = np.asarray(plan.q, dtype=np.float64)
        if len(t) == 0 or q.shape != (len(t), layout.dof) or np.any(np.diff(t) < 0):
            raise ParameterError(
                f"plan: expected increasing times (n,) and configurations (n, {layout.dof}) "
                f"(joints per arm: {dict(zip(layout.names, layout.dofs, strict=True))}), "
                f"got t {t.shape} and q {q.shape}"
            )
        timeline = Timeline(instance, drawings, layout, t, q, plan)
        return Timeline(instance, drawings, layout, t, q, plan, timeline._holds(plan))

    # -- sampling ------------------------------------------------------------------------------
    @property
    def t_start(self) -> float:
        return float(self.t[0])

    @property
    def t_end(self) -> float:
        return float(self.t[-1])

    def sample_times(self, fps: float) -> FloatArray:
        """Times [s] from start to end every ``1 / fps`` s, the end time included."""
        if not fps > 0:
            raise ParameterError(f"fps must be > 0 frames per second, got {fps}")
        n = int(np.floor((self.t_end - self.t_start) * fps + 1e-9))
        times = self.t_start + np.arange(n + 1) / fps
        if times[-1] < self.t_end - 1e-9:
            times = np.append(times, self.t_end)
        return times

    def q_at(self, times: FloatArray) -> FloatArray:
        """Configurations ``(k, layout.dof)`` [rad] at ``times`` ``(k,)``, linearly interpolated."""
        ts = np.atleast_1d(np.asarray(times, dtype=np.float64))
        if len(self.t) == 1:
            return np.repeat(self.q, len(ts), axis=0)
        columns = range(self.layout.dof)
        return np.column_stack([np.interp(ts, self.t, self.q[:, j]) for j in columns])

    def arm_q(self, q: FloatArray, arm: int) -> FloatArray:
        """The joints ``(k, arm dof)`` of arm number ``arm`` in ``q`` ``(k, layout.dof)``."""
        return self.layout.part(q, arm)

    def object_poses(self, times: FloatArray) -> tuple[FloatArray, IntArray]:
        """World poses ``(k, n_obj, 4, 4)`` of every object at ``times`` ``(k,)``, and who holds
        it ``(k, n_obj)``: the arm index, or -1 when it rests."""
        ts = np.atleast_1d(np.asarray(times, dtype=np.float64))
        q = self.q_at(ts)
        tcp = [self.arms[a].tcp_poses(self.arm_q(q, a)) for a in range(len(self.arms))]
        n_obj = len(self.instance.objects)
        poses = np.empty((len(ts), n_obj, 4, 4))
        holder = np.full((len(ts), n_obj), -1, dtype=np.int64)
        for i, obj in enumerate(self.instance.objects):
            poses[:, i] = pose_xyz_yaw(obj.start.x, obj.start.y, obj.size[2] / 2, obj.start.yaw)
            holds = self.holds.get(obj.name, ())
            for k, hold in enumerate(holds):
                end = holds[k + 1].t if k + 1 < len(holds) else np.inf
                mask = (ts >= hold.t) & (ts < end)
                if hold.arm >= 0:
                    poses[mask, i] = tcp[hold.arm][mask] @ hold.T
                    holder[mask, i] = hold.arm
                else:
                    poses[mask, i] = hold.T
        return poses, holder

    # -- panels --------------------------------------------------------------------------------
    def segments(self) -> tuple[Segment, ...]:
        """The plan's steps, or (when it records none) spans split at every release."""
        plan = self.plan
        if plan is not None and len(plan.steps) > 0:
            return tuple(
                Segment(k, float(s.t_start), float(s.t_end), _step_label(s))
                for k, s in enumerate(plan.steps)
            )
        releases = sorted(
            {float(e.t) for e in (plan.events if plan is not None else ()) if e.type == "release"}
        )
        cuts = [self.t_start]
        for r in releases:
            if r > cuts[-1] + 1e-6:
                cuts.append(r)
        if self.t_end > cuts[-1] + 1e-6 or len(cuts) == 1:
            cuts.append(self.t_end)
        return tuple(
            Segment(k, a, b, "until a release" if k < len(releases) else "to the end")
            for k, (a, b) in enumerate(itertools.pairwise(cuts))
        )

    def snapshot_time(self, segment: Segment) -> float:
        """A telling moment of ``segment``: midway through carrying, else its middle [s]."""
        events = [] if self.plan is None else list(self.plan.events)
        inside = [e for e in events if segment.t_start - 1e-9 <= float(e.t) <= segment.t_end]
        grasps = [float(e.t) for e in inside if e.type == "grasp"]
        if grasps:
            g = max(grasps)
            after = [float(e.t) for e in inside if e.type == "release" and float(e.t) > g]
            return (g + (min(after) if after else segment.t_end)) / 2
        return (segment.t_start + segment.t_end) / 2

    # -- events --------------------------------------------------------------------------------
    def _holds(self, plan: PlanLike) -> dict[str, tuple[_Hold, ...]]:
        names = [a.name for a in plan.arms]
        known = set(self.instance.names)
        out: dict[str, list[_Hold]] = {}
        order = sorted(range(len(plan.events)), key=lambda k: (float(plan.events[k].t), k))
        for k in order:
            e = plan.events[k]
            if e.arm not in names:
                raise ParameterError(f"plan.events[{k}].arm must be one of {names}, got {e.arm!r}")
            if e.object not in known:
                raise ParameterError(
                    f"plan.events[{k}].object {e.object!r} is not an object of instance "
                    f"{self.instance.name!r}"
                )
            if e.type not in ("grasp", "release"):
                raise ParameterError(
                    f"plan.events[{k}].type must be 'grasp' or 'release', got {e.type!r}"
                )
            arm = names.index(e.arm)
            T = np.asarray(e.T_tcp_object, dtype=np.float64).reshape(4, 4)
            if e.type == "grasp":
                out.setdefault(e.object, []).append(_Hold(float(e.t), arm, T))
            else:
                qa = self.arm_q(self.q_at(np.array([float(e.t)])), arm)
                rest = self.arms[arm].tcp_poses(qa)[0] @ T
                out.setdefault(e.object, []).append(_Hold(float(e.t), -1, rest))
        return {name: tuple(h) for name, h in out.items()}


def _step_label(step: StepLike) -> str:
    parts = [str(step.kind)] if step.kind else []
    parts += [f"level {step.level}"] if step.level != "" else []
    parts += [", ".join(step.objects)] if len(step.objects) > 0 else []
    return ", ".join(parts)


def _drawing(
    scene: Scene,
    spec: ArmSpec,
    name: str,
    T_world_base: FloatArray,
    T_tool0_tcp: FloatArray | None,
    robots: dict[Path, PinRobot],
) -> ArmDrawing:
    """Arm ``name`` drawn from ``spec``'s robot description (loaded into ``robots`` once) and
    joints; ``T_tool0_tcp`` default: the arm's gripper's."""
    path = spec.urdf
    robot = robots.get(path)
    if robot is None:
        robot = robots[path] = PinRobot.load(path, scene.package_dirs)
    if T_tool0_tcp is None:
        T_tool0_tcp = np.eye(4)
        T_tool0_tcp[2, 3] = spec.gripper.tcp_offset
    return ArmDrawing.build(name, robot, T_world_base, T_tool0_tcp, joints=spec.joint_names)


def yaw_of(T: FloatArray) -> FloatArray:
    """Yaw [rad] of poses ``(..., 4, 4)`` (rotation about world z of their x axis)."""
    out: FloatArray = np.arctan2(T[..., 1, 0], T[..., 0, 0])
    return out
