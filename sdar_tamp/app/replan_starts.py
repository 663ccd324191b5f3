"""Where a fresh continuation may start on a plan the arms execute
(:mod:`sdar_tamp.app.replan_moving`): the first point at or after a plan time at which the
arms can be handed over to another plan with empty grippers (:func:`next_start`).

Two kinds of points:

* a **clear cut**: a cut point of the plan (:func:`~sdar_tamp.plan_state.cut_point`: every
  arm at rest with an empty gripper) that is not at grasps (:func:`at_grasps`); the plan up
  to it (:func:`~sdar_tamp.app.splicing.head_at`) is the new plan's prefix;
* a **braked stop**: while every gripper is empty and the arms move (on their way to the next
  grasps, after a release), they can leave the plan anywhere: braked on its own path from
  there (:func:`~sdar_tamp.app.braking.brake`), they stand still with empty grippers a few
  samples later, and a continuation starts from that stop (the arms that moved leave
  directly, not by a lift). Clear cuts lie only at the ends of those motions; a braked stop
  lets a fresh solve that needs more time than is left before the next clear cut still start
  before the grasps the plan is heading for (R5 of the paper suite: the repair's first
  motion lasts 2.0 s, its next clear cut is 4.0 s away, and only a start before the first
  grasps can change which objects go first). Not where a moving arm's tool is lower than
  ``above`` over the table (the caller's: the tallest object and a lift): there it is
  coming down to its grasp or leaving a placement, fingers around an object, and a
  continuation from there is one from grasps (see :func:`at_grasps`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from sdar_tamp.app.braking import brake
from sdar_tamp.app.splicing import head_at
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_rules import STILL_TOL, TIME_TOL
from sdar_tamp.plan_state import Cut, cut_point, prefix_plan, state_at
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray

Pose3 = tuple[float, float, float]
SCAN = 0.05  #: [s] between the plan times tried for a braked stop


@dataclass(frozen=True, eq=False)
class Start:
    """Where a continuation may start: the arms leave the plan at plan time ``t`` [s] (a
    clear cut, or the sample where braking begins), ``prefix`` is the new plan up to the
    start (ending at rest, every gripper's dwell over), ``resting`` the objects' poses there
    (name -> ``(x, y, yaw)`` [m, m, rad]), ``free`` the arms stopped in the middle of a
    motion (they leave directly); ``braked``: a braked stop rather than a clear cut."""

    t: float
    prefix: PlanFile
    resting: Mapping[str, Pose3]
    free: frozenset[str] = frozenset()
    braked: bool = False


def next_start(
    plan: PlanFile,
    t: float,
    starts: Mapping[str, Pose3],
    scene: Scene,
    kins: Mapping[str, ArmKinematics],
    *,
    brakes: bool = True,
    above: float = 0.0,
) -> Start | None:
    """The first start of ``plan`` at or after plan time ``t`` [s] (see the module
    docstring): a clear cut, or (``brakes``) a braked stop before it, tried every
    :data:`SCAN` where the arms move with empty grippers, every moving arm's tool stopping at
    least ``above`` [m] over the table; None when there is none before the plan's end.
    ``starts``: the objects' poses at the start of the plan (its observations replace
    them)."""
    end = float(plan.t[-1])
    while t < end - 1e-9:
        cut = cut_point(plan, t)
        if brakes:  # a braked stop on the way to that cut point
            for tb in np.arange(t, cut.t - TIME_TOL, SCAN):
                if not _holding(plan, float(tb)):
                    stop = _braked(plan, float(tb), starts, scene, kins, above)
                    if stop is not None:
                        return stop
        if cut.t >= end - 1e-9:
            return None
        if not at_grasps(plan, cut):
            resting = state_at(plan, starts, scene, cut.t, kins).resting
            return Start(cut.t, head_at(plan, cut), dict(resting))
        t = cut.t + 1e-6
    return None


def at_grasps(plan: PlanFile, cut: Cut) -> bool:
    """Whether ``plan`` grasps at ``cut``'s instant: its arms stand there at their grasps,
    fingers open. A fresh solve from there does not know them: it lifts the arms and plans
    their way back to grasps of its own (seconds more than the grasps already reached), so
    a fresh continuation from such a cut is longer than the plan it should shorten."""
    return any(e.type == "grasp" and abs(e.t - cut.t) <= TIME_TOL for e in plan.events)


def _braked(
    plan: PlanFile, t: float, starts: Mapping[str, Pose3], scene: Scene,
    kins: Mapping[str, ArmKinematics], above: float,
) -> Start | None:  # fmt: skip
    """The braked stop of ``plan`` from ``t`` [s] when the arms move there with empty
    grippers, and every arm that moves stops with its tool at least ``above`` [m] over the
    table (None otherwise, or when they cannot brake before a gripper acts)."""
    i = min(int(np.searchsorted(plan.t, t - TIME_TOL)), len(plan.t) - 1)
    if i == 0 or np.abs(plan.q[i] - plan.q[i - 1]).max() <= STILL_TOL:
        return None  # at rest there: a clear cut, if any, is the start
    if _low(plan.q[i], plan.q[i - 1], scene, kins, above):
        return None  # (the braked stop is further on the path: checked there too)
    state = state_at(plan, starts, scene, float(plan.t[i]), kins)
    if state.held:
        return None
    v_max, a_max = scene.joint_array("velocity_limit"), scene.joint_array("acceleration_limit")
    stop = brake(plan, float(plan.t[i]), v_max, a_max)
    if stop is None:
        return None
    prefix = prefix_plan(stop.plan, stop.cut)
    moving = stop.plan.q[i:]
    free = frozenset(
        a for a in scene.arm_names if np.ptp(moving[:, scene.layout.slice(a)], 0).max() > 0
    )
    if _low(stop.plan.q[-1], stop.plan.q[i], scene, kins, above):
        return None  # coming down to a grasp, or leaving a placement
    return Start(float(plan.t[i]), prefix, dict(state.resting), free, braked=True)


def _holding(plan: PlanFile, t: float) -> bool:
    """Whether an arm of ``plan`` holds an object at ``t`` [s] (grasped before, not yet
    released)."""
    held: set[str] = set()
    for e in plan.events:
        if e.t >= t - TIME_TOL:
            break
        if e.type == "grasp":
            held.add(e.arm)
        else:
            held.discard(e.arm)
    return bool(held)


def _low(
    q: FloatArray, q_before: FloatArray, scene: Scene, kins: Mapping[str, ArmKinematics],
    above: float,
) -> bool:  # fmt: skip
    """Whether an arm that moves from ``q_before`` to ``q`` ``(dof,)`` [rad] has its tool
    lower than ``above`` [m] over the table at ``q``."""
    for a in scene.arm_names:
        sl = scene.layout.slice(a)
        if np.abs(q[sl] - q_before[sl]).max() > 0 and kins[a].fk_tcp(q[sl])[2, 3] < above:
            return True
    return False
