"""One arm's share of a synchronous plan: its motions from rest to rest and its gripper events.

An arm's timeline in a plan is cut where that arm stands still for a whole sampling interval
and, inside a run of motion, where the sampling step changes: the motion planner times every
part of a motion (retreat, transfer, approach) from rest to rest on its own uniform grid, so a
change of step marks a rest point. Each rest-to-rest part becomes a :class:`Block`; the block
that ends where the arm's gripper acts carries that event, so the gripper closes the moment the
arm arrives.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import PlanEvent, PlanFile, StepRecord
from sdar_tamp.plan_rules import STILL_TOL
from sdar_tamp.schedule.retiming import ArmRetimer, on_ticks
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray

STEP_TOL = 1e-9  #: [s] two sampling steps closer than this belong to one uniform grid


def arm_columns(plan: PlanFile, arm: int) -> slice:
    """The columns of arm ``arm`` (plan order) in the plan's ``q`` (its layout: every arm with
    its own number of joints)."""
    if isinstance(arm, bool) or not isinstance(arm, int) or not 0 <= arm < len(plan.arms):
        raise ParameterError(f"arm: expected an index in [0, {len(plan.arms)}), got {arm!r}")
    return plan.layout.slice(arm)


@dataclass(frozen=True, eq=False)
class Block:
    """One arm's rest-to-rest motion, then optionally its gripper event.

    ``q`` ``(n + 1, k)`` [rad] (``k``: the arm's joints): the motion sampled every tick (one
    row: no motion);
    ``q_sync``: the same motion at its synchronous pace (:func:`on_ticks`); ``event``: the
    event at its end (its ``t`` is the synchronous plan's); ``sync_start`` and ``sync_end``
    [s]: when the motion ran in the synchronous plan, from its sample ``sync_index``;
    ``step``: its label there.
    """

    arm: int
    q: FloatArray
    q_sync: FloatArray
    event: PlanEvent | None
    sync_start: float
    sync_end: float
    sync_index: int
    step: StepRecord | None

    @property
    def motion_ticks(self) -> int:
        return len(self.q) - 1

    @property
    def sync_key(self) -> float:
        """When the block was done in the synchronous plan (its event, else its motion's end)."""
        return self.event.t if self.event is not None else self.sync_end


def _step_at(plan: PlanFile, t: float) -> StepRecord | None:
    return next((s for s in plan.steps if s.t_start - 1e-9 <= t <= s.t_end + 1e-9), None)


def _runs(moving: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """Maximal runs ``[i, j)`` of True in ``moving`` (intervals of the timeline)."""
    edges = np.diff(np.concatenate([[0], moving.astype(int), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True))


def _rest_points(t: FloatArray, i: int, j: int) -> list[int]:
    """Sample indices in ``(i, j)`` where the sampling step changes (rest points)."""
    h = np.diff(t[i : j + 1])
    change = np.flatnonzero(np.abs(np.diff(h)) > STEP_TOL) + 1  # sample i + k: h[k-1] != h[k]
    return [i + int(k) for k in change]


def arm_blocks(
    plan: PlanFile,
    scene: Scene,
    arm: int,
    tick: float,
    retimed: bool = True,
    retimer: ArmRetimer | None = None,
) -> list[Block]:
    """The blocks of arm ``arm`` in order, every motion on a grid of ``tick`` [s]: at its
    synchronous pace (see :func:`on_ticks`) or, with ``retimed``, re-timed for the arm alone
    by ``retimer`` (default: uniformly faster, :class:`ArmRetimer` without a path timer) when
    that is shorter."""
    spec = scene.arms[arm]
    v, a = np.array(spec.velocity_limit), np.array(spec.acceleration_limit)
    if retimer is None and retimed:
        retimer = ArmRetimer(ArmKinematics.from_scene(scene, spec.name), v, a, tick)
    t, q = plan.t, plan.q[:, arm_columns(plan, arm)]
    if q.shape[1] != len(v):
        raise ParameterError(
            f"arm {spec.name!r}: the plan holds {q.shape[1]} joints, the scene's arm {len(v)}"
        )
    moving = np.any(np.abs(np.diff(q, axis=0)) > STILL_TOL, axis=1)
    cuts: list[tuple[int, int]] = []
    for i, j in _runs(moving):
        bounds = [i, *_rest_points(t, i, j), j]
        cuts.extend(itertools.pairwise(bounds))
    ends = np.array([t[j] for _, j in cuts])
    attached: dict[int, PlanEvent] = {}
    after: dict[int, list[PlanEvent]] = {}  # events of no motion, after cut k (-1: first)
    for e in plan.events:
        if e.arm != spec.name:
            continue
        k = int(np.searchsorted(ends, e.t + 1e-12, side="right")) - 1  # last motion before it
        if k >= 0 and k not in attached and not after.get(k):
            attached[k] = e
        else:
            after.setdefault(k, []).append(e)
    blocks = [_still(arm, q[0], e, t) for e in after.get(-1, [])]
    for k, (i, j) in enumerate(cuts):
        sync = on_ticks(t[i : j + 1], q[i : j + 1], tick, v, a)
        samples = sync
        if retimer is not None and retimed:
            slow_start = bool(after.get(k - 1)) or (k - 1) in attached
            slow_end = k in attached
            samples = retimer.retime(t[i : j + 1], q[i : j + 1], slow_start, slow_end)
        step = _step_at(plan, 0.5 * (t[i] + t[j]))
        event = attached.get(k)
        blocks.append(Block(arm, samples, sync, event, float(t[i]), float(t[j]), i, step))
        blocks.extend(_still(arm, q[j], e, t) for e in after.get(k, []))
    return blocks


def _still(arm: int, q_arm: FloatArray, e: PlanEvent, t: FloatArray) -> Block:
    """An event without a motion before it (the arm stands where it is)."""
    row = np.array(q_arm)[None]
    return Block(arm, row, row, e, e.t, e.t, int(np.searchsorted(t, e.t)), None)
