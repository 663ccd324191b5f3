"""The state of the world at a time of a plan, and where a running plan can be cut.

:func:`state_at` follows a plan file's events (and observations) to time ``t``: every arm's
configuration, what each arm holds and where every other object rests. It shares no code with
the planner: releases are placed by the arm's forward kinematics, as the validator does.

:func:`cut_point` finds where a running plan can hand over to a new one (re-planning from an
observed state, :mod:`sdar_tamp.app.replanning`): the first sample at or after ``t`` at which

* every arm is at rest (the interval before the sample or the one after it is still for every
  joint, so stopping there keeps the plan within its acceleration limits), and
* no arm holds an object (the new plan starts with empty grippers);

the events at that very instant are left to the new plan. :func:`prefix_plan` is the old plan
up to the cut, followed by a still hold of at least one sample spacing and until every gripper
dwell begun before the cut is over, so that any plan starting at rest can follow it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import (
    GRIPPER_DWELL,
    MAX_DT,
    PlanEvent,
    PlanFile,
    PlanObservation,
    StepRecord,
)
from sdar_tamp.plan_rules import STILL_TOL, TIME_TOL
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray

Pose3 = tuple[float, float, float]


@dataclass(frozen=True, eq=False)
class PlanState:
    """The world at time ``t`` [s]: configuration ``q`` ``(dof,)`` [rad], arm -> held object,
    resting object -> ``(x, y, yaw)`` [m, m, rad], and the objects gone (removed by an
    observation)."""

    t: float
    q: FloatArray
    held: Mapping[str, str]
    resting: Mapping[str, Pose3]
    gone: frozenset[str] = frozenset()

    @property
    def holder(self) -> dict[str, str]:
        """Held object -> its arm."""
        return {o: a for a, o in self.held.items()}


@dataclass(frozen=True)
class Cut:
    """Where a plan hands over: the sample ``index`` at time ``t`` [s]; ``events``: how many
    of the plan's events come before it."""

    index: int
    t: float
    events: int


def configuration_at(plan: PlanFile, t: float) -> FloatArray:
    """``(dof,)`` [rad] at time ``t`` [s], linear between samples."""
    return np.array([np.interp(t, plan.t, plan.q[:, j]) for j in range(plan.q.shape[1])])


def state_at(
    plan: PlanFile,
    start: Mapping[str, Pose3],
    scene: Scene,
    t: float,
    kins: Mapping[str, ArmKinematics] | None = None,
) -> PlanState:
    """The state at ``t`` [s] after the events and observations before ``t`` (strictly),
    from the objects' ``start`` poses. Raises :class:`ParameterError` for a time outside the
    plan."""
    if not (math.isfinite(t) and 0.0 <= t <= plan.duration):
        raise ParameterError(
            f"at: expected a time within the plan [0, {plan.duration:.3f}] s, got {t!r}"
        )
    kins = kins or {a: ArmKinematics.from_scene(scene, a) for a in scene.arm_names}
    resting = dict(start)
    held: dict[str, str] = {}
    gone: set[str] = set()
    moments: list[tuple[float, int, PlanEvent | PlanObservation]] = [
        (e.t, 1, e) for e in plan.events
    ]
    moments += [(o.t, 0, o) for o in plan.observations]  # before the events of its instant
    for when, _, item in sorted(moments, key=lambda m: (m[0], m[1])):
        if when >= t - TIME_TOL:
            break
        if isinstance(item, PlanObservation):
            gone |= set(resting) - set(item.resting)
            resting = {n: _pose3(p) for n, p in item.resting.items()}
            continue
        if item.type == "grasp":
            resting.pop(item.object, None)
            held[item.arm] = item.object
            continue
        q_arm = scene.layout.part(configuration_at(plan, item.t), item.arm)
        T = kins[item.arm].fk_tcp(q_arm) @ item.T_tcp_object
        resting[item.object] = (float(T[0, 3]), float(T[1, 3]), math.atan2(T[1, 0], T[0, 0]))
        held.pop(item.arm, None)
    return PlanState(t, configuration_at(plan, t), held, resting, frozenset(gone - set(resting)))


def _pose3(p: tuple[float, ...]) -> Pose3:
    return (float(p[0]), float(p[1]), float(p[2]))


def cut_point(plan: PlanFile, t: float) -> Cut:
    """The first sample at or after ``t`` [s] where every arm is at rest and holds nothing
    (see the module docstring); the plan's last sample at the latest (a valid plan ends at
    rest with empty grippers)."""
    times, q = plan.t, plan.q
    still = np.all(np.abs(np.diff(q, axis=0)) <= STILL_TOL, axis=1)  # (n - 1,) intervals
    holding: dict[str, str] = {}
    k = 0
    n = len(times)
    for i in range(int(np.searchsorted(times, t - TIME_TOL)), n):
        while k < len(plan.events) and plan.events[k].t < times[i] - TIME_TOL:
            e = plan.events[k]
            if e.type == "grasp":
                holding[e.arm] = e.object
            else:
                holding.pop(e.arm, None)
            k += 1
        if not holding:
            at_rest = i == n - 1 or still[i] or (i > 0 and still[i - 1])
            if at_rest:
                return Cut(i, float(times[i]), k)
    return Cut(n - 1, float(times[-1]), len(plan.events))


def _held_before(plan: PlanFile, t: float) -> dict[str, str]:
    held: dict[str, str] = {}
    for e in plan.events:
        if e.t >= t - TIME_TOL:
            break
        if e.type == "grasp":
            held[e.arm] = e.object
        else:
            held.pop(e.arm, None)
    return held


def prefix_plan(plan: PlanFile, cut: Cut, dwell: float = GRIPPER_DWELL) -> PlanFile:
    """The plan up to ``cut`` and a still hold after it (see the module docstring); its
    events are those before the cut, its steps are cut at it. ``final_poses`` and metrics are
    left as they are (the caller completes the plan)."""
    if _held_before(plan, cut.t):
        raise ParameterError(f"cut at t = {cut.t:.3f} s: an arm holds an object there")
    events = plan.events[: cut.events]
    pending = max((e.t + dwell for e in events), default=0.0)
    end = max(cut.t + MAX_DT, pending)
    hold = np.linspace(cut.t, end, max(2, math.ceil((end - cut.t) / MAX_DT - 1e-9) + 1))[1:]
    t = np.concatenate([plan.t[: cut.index + 1], hold])
    q = np.concatenate([plan.q[: cut.index + 1], np.repeat(plan.q[cut.index][None], len(hold), 0)])
    steps = tuple(
        replace(s, t_end=min(s.t_end, cut.t)) for s in plan.steps if s.t_start < cut.t - TIME_TOL
    )
    seen = tuple(o for o in plan.observations if o.t <= cut.t)
    return PlanFile(
        plan.instance, plan.arms, t, q, events, dict(plan.final_poses), plan.metrics, steps, seen
    )


def shift_steps(steps: tuple[StepRecord, ...], dt: float) -> tuple[StepRecord, ...]:
    """``steps`` moved ``dt`` [s] later."""
    return tuple(replace(s, t_start=s.t_start + dt, t_end=s.t_end + dt) for s in steps)
