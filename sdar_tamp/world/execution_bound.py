"""A lower bound on the execution time of any plan of a rearrangement instance in a cell.

For each object ``i`` not at its goal, ``c_i`` is the least time some arm must spend on it:

    c_i = min( min over arms a of ( 2 d + T_a,i ),  4 d )

where ``d`` [s] is the gripper dwell (the still time after a gripper event) and ``T_a,i`` [s]
the shortest rest-to-rest motion of arm ``a`` from a grasp configuration of ``i`` at its start
to a grasp configuration at its goal, with the same grasp at both ends (the object does not
slip in the gripper), minimised over the grasp set, the IK branches at both ends, the goal's
yaw and its half turn (the goal holds modulo pi), and the joint values that differ by 2 pi
within the limits; collisions are ignored. A rest-to-rest motion of one joint over ``D``
[rad] under velocity ``v`` and acceleration ``a`` limits takes at least ``2 sqrt(D / a)``
when ``D <= v^2 / a`` (triangular profile) and ``D / v + v / a`` otherwise (trapezoidal); a
motion takes at least the longest of its joints. ``v`` and ``a`` are the arm's limits times
the scene's ``velocity_safety``, as the planner's time parameterisation uses them. The bound
over ``k`` arms is

    B = max( sum_i c_i / k,  max_i c_i ).

Why it is a lower bound on the makespan ``E`` of every plan. Follow object ``i`` through a
plan: it is grasped at its start, released, maybe grasped again and released again, the last
release at its goal. Call the time from a grasp event of ``i`` to the end of the dwell after
the following release of ``i`` a *holding interval* of ``i``; during it the arm holding ``i``
holds nothing else. (1) If ``i`` is carried in one holding interval, one arm grasps it at its
start (its configuration then is one of the grasp configurations above, at rest: the arm is
still through the dwell), stays still for ``d``, moves, holding the same grasp, to a
configuration releasing ``i`` at its goal, at rest, and stays still for ``d`` after the
release: at least ``2 d + T_a,i``. (2) If it needs two or more (a buffer, or a relay by
another arm), those intervals hold at least four dwells: ``4 d``. So the holding intervals of
``i`` last ``c_i`` or more in total. They do not overlap one another (``i`` must rest between
them), so ``E >= max_i c_i``. An arm holds one object at a time, so the holding intervals of
one arm do not overlap either, and each lies within ``[0, E]``: the ``k`` arms together give
at most ``k E`` of them, hence ``E >= sum_i c_i / k``.

Scope: the minimum over IK branches is exact for arms with the closed-form IK (every branch
of a UR-family arm is enumerated, each joint value also a turn away where the limits allow).
A UR arm has a continuum of solutions only at singular poses: the wrist one (joints 4 and 6
parallel) needs the tool's approach horizontal, which no grasp of the planner's set has
(its tilts are below 90 degrees); the shoulder one needs the wrist above the base's axis, far
from any workspace. For other arms (numeric IK) the minimum runs over the branches the
numeric IK finds, and :attr:`ExecutionBound.proven` is false. Goals are taken as given: the
validator's 1 mm / 1 degree tolerance on a goal is not subtracted. No approach term is added:
the motion from an arm's home to its first grasp bounds that arm's first holding interval,
but its first grasp may be of an object another arm left in a buffer anywhere on the table,
so no positive time can be charged to it without bounding the buffers; the bound leaves it
out. The grasp set is the caller's (the application passes the planner's,
:func:`streams.grasps.sample_grasps`: this layer may not import the streams).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray, pose_xyz_yaw

#: An object at its start within these of its goal needs no motion (the validator's goal
#: tolerances: 1 mm, 1 degree, yaw modulo pi).
AT_GOAL_DISTANCE = 1e-3  # [m]
AT_GOAL_YAW = math.radians(1.0)  # [rad]
#: Joint values that differ by this many turns either way are tried (within the limits).
_TURNS = np.arange(-2, 3) * 2.0 * np.pi


@dataclass(frozen=True)
class ObjectBound:
    """The least time [s] some arm must spend on one object (``cost``, ``c_i``): its shortest
    rest-to-rest ``motion`` [s] (``inf`` when no arm grasps it at both ends with one grasp),
    the ``arm`` that achieves it (``None`` then), and whether the relay term ``4 d`` is the
    smaller (``relay``)."""

    name: str
    cost: float
    motion: float
    arm: str | None
    relay: bool


@dataclass(frozen=True)
class ExecutionBound:
    """The lower bound on execution time (see the module docstring): per object not at its
    goal its :class:`ObjectBound`; ``arms`` (``k``), ``dwell`` [s]; ``proven``: every arm's IK
    branches were all enumerated."""

    arms: int
    dwell: float
    objects: tuple[ObjectBound, ...]
    proven: bool = True

    def __post_init__(self) -> None:
        if self.arms < 1:
            raise ParameterError(f"arms: expected at least one arm, got {self.arms}")

    @property
    def total(self) -> float:
        """``sum_i c_i`` [s]."""
        return float(sum(o.cost for o in self.objects))

    @property
    def longest(self) -> float:
        """``max_i c_i`` [s] (0 with no object to move)."""
        return max((o.cost for o in self.objects), default=0.0)

    @property
    def seconds(self) -> float:
        """The bound ``max(sum_i c_i / k, max_i c_i)`` [s]."""
        return max(self.total / self.arms, self.longest)

    def ratio(self, execution_time: float) -> float | None:
        """``execution_time`` [s] over the bound, or ``None`` when the bound is 0."""
        bound = self.seconds
        return execution_time / bound if bound > 0.0 else None


def rest_to_rest_time(
    displacement: FloatArray, velocity: FloatArray, acceleration: FloatArray
) -> FloatArray:
    """The shortest rest-to-rest time [s] of motions ``(..., dof)`` of joint displacements
    [rad] under per-joint ``velocity`` [rad/s] and ``acceleration`` [rad/s^2] limits
    ``(dof,)``: the longest joint's time-optimal (triangular or trapezoidal) profile;
    shape ``(...)``."""
    d = np.abs(np.asarray(displacement, dtype=np.float64))
    v = np.asarray(velocity, dtype=np.float64)
    a = np.asarray(acceleration, dtype=np.float64)
    if np.any(v <= 0.0) or np.any(a <= 0.0):
        raise ParameterError("velocity and acceleration limits must be > 0")
    triangular = 2.0 * np.sqrt(d / a)
    trapezoidal = d / v + v / a
    t = np.where(d <= v * v / a, triangular, trapezoidal)
    return np.asarray(t.max(axis=-1), dtype=np.float64)


def joint_displacement(
    q_from: FloatArray, q_to: FloatArray, lower: FloatArray, upper: FloatArray
) -> FloatArray:
    """The least joint displacements ``(..., dof)`` [rad] between configurations ``q_from``
    and ``q_to`` (broadcast, ``(..., dof)``), each joint value taken also a whole number of
    turns away where that stays within ``lower``/``upper`` ``(dof,)`` (a revolute joint whose
    limits span more than one turn reaches one pose with several values)."""
    a = np.asarray(q_from, dtype=np.float64)[..., None] + _TURNS  # (..., dof, 5)
    b = np.asarray(q_to, dtype=np.float64)[..., None] + _TURNS
    lo = np.asarray(lower, dtype=np.float64)[:, None] - 1e-9
    hi = np.asarray(upper, dtype=np.float64)[:, None] + 1e-9
    a = np.where((a >= lo) & (a <= hi), a, np.nan)
    b = np.where((b >= lo) & (b <= hi), b, np.nan)
    diff = np.abs(a[..., :, None] - b[..., None, :])  # (..., dof, 5, 5)
    diff = np.where(np.isnan(diff), np.inf, diff)
    return np.asarray(diff.min(axis=(-2, -1)), dtype=np.float64)


def at_goal(obj: ObjectSpec) -> bool:
    """Whether ``obj`` rests at its goal already (the validator's tolerances)."""
    s, g = obj.start, obj.goal
    turn = (s.yaw - g.yaw) % np.pi
    return bool(
        math.hypot(s.x - g.x, s.y - g.y) <= AT_GOAL_DISTANCE
        and min(turn, np.pi - turn) <= AT_GOAL_YAW
    )


def shortest_motion(
    kin: ArmKinematics,
    velocity: FloatArray,
    acceleration: FloatArray,
    obj: ObjectSpec,
    grasps: Sequence[FloatArray],
) -> float:
    """``T_a,i`` [s] of the module docstring for the arm ``kin`` and ``obj``, with the grasps
    ``T_object_tcp`` ``(4, 4)`` of ``grasps``; ``inf`` when no grasp has an IK solution at
    both ends."""
    if not grasps:
        return math.inf
    G = np.stack([np.asarray(g, dtype=np.float64) for g in grasps])  # (g, 4, 4)
    z = obj.size[2] / 2.0

    def tcp(p: Pose2D, yaw: float) -> FloatArray:
        return np.asarray(pose_xyz_yaw(p.x, p.y, z, yaw) @ G, dtype=np.float64)

    start = kin.ik_tcp(tcp(obj.start, obj.start.yaw))  # (g, b, dof)
    goals = [kin.ik_tcp(tcp(obj.goal, obj.goal.yaw + turn)) for turn in (0.0, np.pi)]
    q_goal = np.concatenate([s.q for s in goals], axis=1)  # (g, 2 b, dof)
    ok_goal = np.concatenate([s.valid for s in goals], axis=1)
    lo, hi = kin.spec.lower_array, kin.spec.upper_array
    d = joint_displacement(start.q[:, :, None], q_goal[:, None], lo, hi)  # (g, b, 2b, dof)
    t = rest_to_rest_time(d, velocity, acceleration)
    t = np.where(start.valid[:, :, None] & ok_goal[:, None, :], t, np.inf)
    return float(t.min()) if t.size else math.inf


def execution_bound(
    scene: Scene,
    instance: Instance,
    grasps: Mapping[str, Sequence[FloatArray]],
    dwell: float,
    kinematics: Mapping[str, ArmKinematics] | None = None,
) -> ExecutionBound:
    """The lower bound of the module docstring for ``instance`` in ``scene``: ``grasps`` per
    object name, its grasp set as ``T_object_tcp`` ``(4, 4)`` poses; ``dwell`` [s] the
    plans' gripper dwell; ``kinematics``: the arms' (default: loaded from the scene)."""
    if not dwell >= 0.0:
        raise ParameterError(f"dwell: expected >= 0 [s], got {dwell}")
    missing = [o.name for o in instance.objects if o.name not in grasps]
    if missing:
        raise ParameterError(f"grasps: no grasp set for the objects {missing}")
    given = kinematics or {}
    kins = {a: given.get(a) or ArmKinematics.from_scene(scene, a) for a in scene.arm_names}
    share = scene.velocity_safety
    limits = {
        a: (
            np.asarray(scene.arm(a).velocity_limit, dtype=np.float64) * share,
            np.asarray(scene.arm(a).acceleration_limit, dtype=np.float64) * share,
        )
        for a in kins
    }
    out: list[ObjectBound] = []
    for obj in instance.objects:
        if at_goal(obj):
            continue
        times = {a: shortest_motion(k, *limits[a], obj, grasps[obj.name]) for a, k in kins.items()}
        arm = min(times, key=lambda a: times[a])
        motion = times[arm]
        direct = 2.0 * dwell + motion
        relay = 4.0 * dwell
        out.append(
            ObjectBound(
                obj.name,
                min(direct, relay),
                motion,
                arm if math.isfinite(motion) else None,
                relay < direct,
            )
        )
    proven = all(k.closed_form for k in kins.values())
    return ExecutionBound(len(kins), float(dwell), tuple(out), proven)
