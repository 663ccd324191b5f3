"""Stopping the arms along their current motion (:func:`brake`): when the running plan would
meet the observed world before its next cut point, the arms are brought to rest on the plan's
own path as fast as the acceleration limits allow, and re-planning starts from there
(:func:`sdar_tamp.app.replanning.replan`).

The braking follows the plan's samples (linear between them, as the executor and the
validator read them) at a slowing pace: the plan time ``p`` reached advances by at most one
sample spacing per spacing, so every configuration is one the plan passes through, no joint
moves faster than in the plan, and an arm the plan keeps still (a gripper's dwell) stays still
at least as long. Sample after sample, ``p`` advances the least that keeps every joint's
second divided difference within its limit, until the arms can stand still (the last velocity
within the rule of a plan's end, half the limit over one spacing: any still hold may follow).
A path that turns too sharply to follow at the speed reached gives no braking. An object held
moves with its tool along the braked path, as it would along the plan's.

A continuation starts with empty grippers (SDAR's start state holds arm configurations only,
every object resting), so an arm braked with an object in hand puts it down first
(:func:`put_down`): one motion, planned among the objects resting where the arms stopped and
carrying what they hold, to where the plan would have released it (or, failing that, back to
where it was grasped, or straight down below where it is), and the release there.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Iterator, Mapping

import numpy as np

from sdar_tamp.plan_building import GripperEvent, MotionSegment, build_plan_file
from sdar_tamp.plan_file import GRIPPER_DWELL, MAX_DT, PlanFile
from sdar_tamp.plan_rules import LIMIT_RTOL, TIME_TOL
from sdar_tamp.plan_state import Cut, configuration_at
from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.transforms import FloatArray, inverse, pose_xyz_yaw
from streams.motion.exact_check import HeldObject
from streams.motion.ladder import plan_dual_motion
from streams.motion.planner import MotionPlanner
from streams.motion.records import MotionRequest

Pose3 = tuple[float, float, float]

#: Candidate advances of the plan time per sample, as shares of the spacing (the least that
#: keeps the limits is taken).
_SHARES = np.linspace(0.0, 1.0, 401)
#: Share of each acceleration limit the braking's steps use: all of it (less rounding), since
#: the plan itself may be at its limit where braking begins, following its path at full speed.
_MARGIN = 1.0 - 1e-9
#: Share of half the limit within which the last velocity must lie to stand still.
_STOP_MARGIN = 0.98


@dataclasses.dataclass(frozen=True)
class Braking:
    """``plan`` up to the first sample at or after the time reached, then the braking samples,
    ending at rest; ``cut``: its last sample (where re-planning starts)."""

    plan: PlanFile
    cut: Cut


def brake(plan: PlanFile, at: float, v_max: FloatArray, a_max: FloatArray) -> Braking | None:
    """The arms of ``plan`` brought to rest along its path from time ``at`` [s] within
    ``v_max`` [rad/s] and ``a_max`` [rad/s^2] ``(dof,)`` (see the module docstring), what
    they hold held on; None when a gripper acts before the arms are at rest, or when the path
    cannot be followed."""
    t, q = plan.t, plan.q
    i0 = min(int(np.searchsorted(t, at - TIME_TOL)), len(t) - 1)
    if i0 == 0:
        return None
    h = float(t[i0] - t[i0 - 1])
    v = (q[i0] - q[i0 - 1]) / h
    p, ts, qs = float(t[i0]), [float(t[i0])], [q[i0]]
    limit = _MARGIN * a_max * h
    while np.any(np.abs(v) > 0.5 * _STOP_MARGIN * a_max * h):  # to stand still after any spacing
        if len(ts) > len(t):
            return None
        cand = p + _SHARES * h
        q_c = np.stack([np.interp(cand, t, q[:, j]) for j in range(q.shape[1])], axis=1)
        dv = (q_c - qs[-1]) / h - v
        ok = np.all(np.abs(dv) <= limit, axis=1)
        if not ok.any():
            return None
        k = int(np.argmax(ok))
        v = (q_c[k] - qs[-1]) / h
        p = float(cand[k])
        ts.append(ts[-1] + h)
        qs.append(q_c[k])
    if any(float(t[i0]) - TIME_TOL <= e.t <= p + TIME_TOL for e in plan.events):
        return None  # a gripper acts on the way
    bt, bq = np.array(ts), np.stack(qs)
    if np.any(np.abs(np.diff(bq, axis=0)) / h > v_max * (1.0 + LIMIT_RTOL)):
        return None
    events = sum(e.t < float(t[i0]) - TIME_TOL for e in plan.events)
    braked = dataclasses.replace(
        plan,
        t=np.concatenate([t[:i0], bt]),
        q=np.concatenate([q[:i0], bq]),
        events=plan.events[:events],
    )
    return Braking(braked, Cut(len(braked.t) - 1, float(braked.t[-1]), events))


def still_until_dwells_end(plan: PlanFile, dwell: float = GRIPPER_DWELL) -> PlanFile:
    """``plan`` (ending at rest) held still after its end until the dwell of every gripper
    event is over (samples at most :data:`~sdar_tamp.plan_file.MAX_DT` apart), so that a
    motion may follow at once."""
    end = max((e.t + dwell for e in plan.events), default=0.0)
    t_end = float(plan.t[-1])
    if end <= t_end + TIME_TOL:
        return plan
    n = max(1, math.ceil((end - t_end) / MAX_DT - 1e-9))
    hold = np.linspace(t_end, end, n + 1)[1:]
    q = np.concatenate([plan.q, np.repeat(plan.q[-1][None], n, 0)])
    return dataclasses.replace(plan, t=np.concatenate([plan.t, hold]), q=q)


def put_down(
    planner: MotionPlanner,
    running: PlanFile,
    at: float,
    q_stop: FloatArray,
    held: Mapping[str, str],
    grips: Mapping[str, FloatArray],
    resting: Mapping[str, Pose3],
    sizes: Mapping[str, tuple[float, float, float]],
    gripper_time: float = GRIPPER_DWELL,
) -> Iterator[PlanFile]:
    """The ways of putting down what the arms stopped at ``q_stop`` ``(dof,)`` [rad]
    (``running`` braked from ``at`` [s]) hold: arm -> object ``held``, at ``grips`` (arm ->
    ``T_tcp_object`` ``(4, 4)``), in order of preference per arm: where ``running``
    releases its object next, back where it was grasped, or straight down on the table below
    where it is (:func:`_below`), the choices of the arms together ranked by the sum of their
    ranks. Each is a plan piece from ``t = 0`` at
    ``q_stop``: one motion among the objects ``resting`` (name -> ``(x, y, yaw)`` [m, m,
    rad]) with the held ones carried (the arms without an object keep where they stopped),
    every held object released at its end, and the dwell. Each motion is planned when the
    next piece is asked for (none where no motion is found); the caller replays each piece
    in the observed world."""
    scene = planner.ctx.scene
    q0 = np.asarray(q_stop)
    layout = scene.layout
    kins = planner.ctx.kinematics
    options: dict[str, list[FloatArray]] = {}
    for arm in held:
        ahead = _event(running, arm, "release", at, after=True)
        behind = _event(running, arm, "grasp", at, after=False)
        here = layout.part(q0, arm)
        below = _below(kins[arm], here, grips[arm], sizes[held[arm]])
        times = [w for w in (ahead, behind) if w is not None]
        options[arm] = [layout.part(configuration_at(running, w), arm) for w in times]
        options[arm] += [below] if below is not None else []
    boxes = {n: _box(p, sizes[n]) for n, p in resting.items()}
    carried = {a: HeldObject(o, sizes[o], kins[a].T_tool0_tcp @ grips[a]) for a, o in held.items()}
    starts = {**resting, **{o: (0.0, 0.0, 0.0) for o in held.values()}}  # placed at release
    arms = sorted(held, key=scene.arm_names.index)
    ranks = sorted(itertools.product(*(range(len(options[a])) for a in arms)), key=sum)
    for rank in ranks:
        q_goal = q0.copy()
        for arm, k in zip(arms, rank, strict=True):
            q_goal[layout.slice(arm)] = options[arm][k]
        request = MotionRequest(
            q0, q_goal, boxes, carried, tuple(False for _ in scene.arm_names),
            tuple(a in held for a in scene.arm_names),
        )  # fmt: skip
        result = plan_dual_motion(planner, request)
        if not result.success or result.trajectory is None:
            continue
        traj = result.trajectory
        seg = MotionSegment(traj.t, traj.q, result.level or "", tuple(held.values()), "put-down")
        items: list[MotionSegment | GripperEvent] = [seg]
        items += [GripperEvent(a, "release", o, grips[a]) for a, o in held.items()]
        yield build_plan_file(
            scene, running.instance, starts, {n: sizes[n] for n in starts}, items, {},
            gripper_time=gripper_time, q_start=q0,
        )  # fmt: skip


def _below(
    kin: ArmKinematics, q_arm: FloatArray, T_tcp_object: FloatArray,
    size: tuple[float, float, float],
) -> FloatArray | None:  # fmt: skip
    """The arm's configuration ``(dof,)`` [rad] that sets the object it holds at
    ``T_tcp_object`` down on the table straight below where it is at ``q_arm`` (its yaw
    kept; the IK branch nearest ``q_arm``), or None out of reach."""
    T = kin.fk_tcp(q_arm) @ T_tcp_object
    yaw = math.atan2(T[1, 0], T[0, 0])
    T_place = pose_xyz_yaw(float(T[0, 3]), float(T[1, 3]), size[2] / 2.0, yaw)
    sol = kin.ik_tcp_from((T_place @ inverse(T_tcp_object))[None], q_arm[None, None])
    if not bool(np.asarray(sol.valid).reshape(-1)[0]):
        return None
    q: FloatArray = np.asarray(sol.q, dtype=np.float64).reshape(-1, len(q_arm))[0]
    return q


def _event(plan: PlanFile, arm: str, kind: str, at: float, after: bool) -> float | None:
    """The time [s] of ``arm``'s first ``kind`` event of ``plan`` after ``at`` (``after``), or
    of its last one before."""
    times = [e.t for e in plan.events if e.arm == arm and e.type == kind]
    if after:
        return next((t for t in times if t >= at - TIME_TOL), None)
    return next((t for t in reversed(times) if t < at), None)


def _box(p: Pose3, size: tuple[float, float, float]) -> ObjectBox:
    return ObjectBox(pose_xyz_yaw(p[0], p[1], size[2] / 2.0, p[2]), size)
