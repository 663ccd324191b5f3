"""Replaying a stretch of a timeline against the world, as the plan validator does.

:class:`WorldSweep` checks configurations ``(m, dof)`` one tick apart, with the gripper events
inside the stretch, against the collision world in the state the earlier events left it: the
same points as the replay of :mod:`sdar_tamp.replay` (its subdivision of every interval, which
depends only on the interval's ends), the same contact rule at grasps and releases, and the
rule that a released object lands on a free spot. A stretch that passes here passes there.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Hashable, Sequence
from dataclasses import dataclass

import numpy as np

from sdar_tamp.plan_file import PlanEvent
from sdar_tamp.plan_rules import STILL_TOL
from sdar_tamp.replay_sampling import interval_subdivisions
from sdar_tamp.replay_walk import POS_TOL, contact_allowed, describe_contacts
from sdar_tamp.world.collision import CollisionPair, CollisionWorld, ObjectBox
from sdar_tamp.world.footprint import corners, overlap_matrix
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray, inverse, pose_xyz_yaw

#: Arrangements whose collision geometry the sweep keeps: placing a block replays the
#: events before it again and again, so the same arrangements come back.
SWEEP_GEOMETRIES = 16
#: Arrangements whose collision answers the sweep remembers (by configuration): each placement
#: attempt replays the same stretches, so about three checks in four repeat an earlier one.
SWEEP_MEMOS = 32
#: Intervals whose replay subdivision the sweep remembers (by their two ends; about 0.3 kB
#: each): the stretches replayed again share most of their intervals.
SWEEP_INTERVALS = 50_000


@dataclass(frozen=True, eq=False)
class TimedEvent:
    """A gripper event at tick ``tick``, the arm at ``q_arm`` ``(k,)`` [rad] (its
    ``k`` joints)."""

    tick: int
    event: PlanEvent
    q_arm: FloatArray


@dataclass(frozen=True)
class Conflict:
    """The first broken rule of a stretch: at tick ``tick``, ``kind`` (collision, grasp,
    release) and what; ``arms``: the arms in contact with another arm (a collision between
    arms or their held objects), in scene order, else empty."""

    tick: int
    kind: str
    message: str
    arms: tuple[str, ...] = ()


#: what :meth:`WorldSweep.reset` remembers: the events' key, the resting boxes, the held
#: objects' grasps, the resting poses, the held objects and the contacts exempt
_After = tuple[
    Hashable,
    dict[str, ObjectBox],
    dict[str, tuple[str, FloatArray, tuple[float, float, float]]],
    dict[str, tuple[float, float, float]],
    dict[str, tuple[str, FloatArray]],
    dict[str, tuple[str, FloatArray]],
]


class WorldSweep:
    """The world of one instance; :meth:`run` checks a stretch of a timeline."""

    def __init__(self, instance: Instance, scene: Scene, max_tcp_step: float) -> None:
        self.scene, self.step = scene, max_tcp_step
        self.names = scene.arm_names
        self.scene_layout = scene.layout
        self.kins = {a: ArmKinematics.from_scene(scene, a) for a in self.names}
        self.sizes = {o.name: o.size for o in instance.objects}
        self.start = {o.name: o.start.as_tuple() for o in instance.objects}
        self.world = CollisionWorld(scene, keep=SWEEP_GEOMETRIES)
        self.rest: dict[str, tuple[float, float, float]] = {}
        self.held: dict[str, tuple[str, FloatArray]] = {}  # arm -> (object, T_tcp_object)
        self.exempt: dict[str, tuple[str, FloatArray]] = {}  # arm -> (object, q_arm)
        self.checks = 0
        #: the checks the collision world answered (the others were remembered answers)
        self.queries = 0
        self._columns = {a: scene.layout.slice(a) for a in self.names}
        self._intervals: dict[bytes, int] = {}
        self._memos: OrderedDict[Hashable, dict[bytes, bool]] = OrderedDict()
        self._memo: dict[bytes, bool] | None = None  # the current arrangement's; None: unknown
        #: arm -> the object it holds, the configuration it grasped it at, its pose before
        self._grasped: dict[str, tuple[str, FloatArray, tuple[float, float, float]]] = {}
        #: the world after the last events :meth:`reset` replayed, by those events
        self._after: _After | None = None

    def box(self, name: str, pose: tuple[float, float, float]) -> ObjectBox:
        size = self.sizes[name]
        return ObjectBox(pose_xyz_yaw(pose[0], pose[1], size[2] / 2.0, pose[2]), size)

    def reset(self, before: Sequence[TimedEvent]) -> None:
        """The world after the events ``before`` (in time order; assumed valid). The world
        after the last ``before`` replayed is remembered: the same events again (a start
        search resets to them once per start it tries) set it at once, the same resting
        boxes in the same order and each held object grasped at the same configuration."""
        for arm in self.names:
            if self.world.held_by(arm) is not None:
                self.world.detach(arm)
        self._memo = None
        key = tuple(
            (e.tick, e.event.arm, e.event.type, e.event.object, e.q_arm.tobytes()) for e in before
        )
        if self._after is not None and self._after[0] == key:
            _, boxes, grasped, rest, held, exempt = self._after
            self.world.set_objects({**boxes, **{n: self.box(n, p) for n, _, p in grasped.values()}})
            for arm, (name, q_arm, _) in grasped.items():
                self.world.attach(arm, name, q_arm)
            self.rest, self.held, self.exempt = dict(rest), dict(held), dict(exempt)
            self._grasped = dict(grasped)
            return
        self.rest = dict(self.start)
        self.held, self.exempt, self._grasped = {}, {}, {}
        self.world.set_objects({n: self.box(n, p) for n, p in self.rest.items()})
        for e in before:
            self.apply(e, check=False)
            self.exempt[e.event.arm] = (e.event.object, e.q_arm)
        boxes = self.world.objects
        self._after = (key, boxes, dict(self._grasped), dict(self.rest), dict(self.held),
                       dict(self.exempt))  # fmt: skip

    def run(self, k0: int, q: FloatArray, events: Sequence[TimedEvent]) -> Conflict | None:
        """Check the configurations ``q`` ``(m, dof)`` at ticks ``k0 .. k0 + m - 1`` and the
        ``events`` among them (in time order); the first conflict, or None."""
        counts = self.subdivisions(q) if len(q) > 1 else None
        pending = list(events)
        for k in range(len(q)):
            group = [e for e in pending if e.tick <= k0 + k]
            pending = pending[len(group) :]
            for e in group:
                self.exempt[e.event.arm] = (e.event.object, e.q_arm)
            found = self.collide(q[k], k0 + k)
            for e in group:
                found = found or self.apply(e)
            if group and found is None:
                found = self.collide(q[k], k0 + k)
            if found is not None:
                return found
            if counts is not None and k + 1 < len(q):
                n = counts[k]
                for s in range(1, n):
                    found = self.collide(q[k] + (q[k + 1] - q[k]) * (s / n), k0 + k)
                    if found is not None:
                        return found
        return None

    def subdivisions(self, q: FloatArray) -> list[int]:
        """The replay's subdivision of every interval of ``q`` ``(m, dof)``
        (:func:`~sdar_tamp.replay_sampling.tcp_subdivisions`), remembered by interval."""
        q = np.ascontiguousarray(q, dtype=np.float64)
        width = q.shape[1] * q.itemsize
        raw = q.tobytes()
        keys = [raw[k * width : (k + 2) * width] for k in range(len(q) - 1)]
        known = self._intervals
        missing = [k for k, key in enumerate(keys) if key not in known]
        if missing:
            if len(known) + len(missing) > SWEEP_INTERVALS:
                known.clear()
                missing = list(range(len(keys)))
            rows = np.array(missing)
            counts = interval_subdivisions(
                q[rows], q[rows + 1], self.kins, self.scene_layout, self.step
            )
            known.update(zip((keys[k] for k in missing), counts.tolist(), strict=True))
        return [known[key] for key in keys]

    def collide(self, q: FloatArray, tick: int) -> Conflict | None:
        self.checks += 1
        if self.exempt:
            for arm, (_, q_event) in list(self.exempt.items()):
                if np.abs(q[self._columns[arm]] - q_event).max() > STILL_TOL:
                    del self.exempt[arm]
        if not self._in_collision(q):
            return None
        pairs = [p for p in self.world.report(q) if not self.allowed(p)]
        if not pairs:
            return None
        owners = [(self.world.owner(p.first), self.world.owner(p.second)) for p in pairs]
        between = {a for pair in owners if None not in pair and pair[0] != pair[1] for a in pair}
        arms = tuple(a for a in self.names if a in between)
        message = describe_contacts(pairs, self.world, len(pairs))
        return Conflict(tick, "collision", message, arms)

    def _in_collision(self, q: FloatArray) -> bool:
        """``world.in_collision(q)``, remembered per arrangement and configuration."""
        if self._memo is None:
            key = self.world.arrangement_key()
            memo = self._memos.get(key)
            if memo is None:
                memo = self._memos[key] = {}
                if len(self._memos) > SWEEP_MEMOS:
                    self._memos.popitem(last=False)
            else:
                self._memos.move_to_end(key)
            self._memo = memo
        k = np.ascontiguousarray(q, dtype=np.float64).tobytes()
        hit = self._memo.get(k)
        if hit is None:
            self.queries += 1
            hit = self._memo[k] = self.world.in_collision(q)
        return hit

    def allowed(self, p: CollisionPair) -> bool:
        return contact_allowed(p, self.exempt)

    def apply(self, timed: TimedEvent, check: bool = True) -> Conflict | None:
        """Perform one event: a grasp of a resting object, a release onto a free spot
        (``check=False``: an event already known to be valid, whose spot is not tested again)."""
        e, tick = timed.event, timed.tick
        T_world_tcp = self.kins[e.arm].fk_tcp(timed.q_arm)
        if e.type == "grasp":
            if e.arm in self.held or e.object not in self.rest:
                return Conflict(tick, "grasp", f"{e.arm} grasps {e.object}, which is not free")
            pose = self.rest.pop(e.object)
            T_obj = self.box(e.object, pose).T_world_obj
            self.held[e.arm] = (e.object, inverse(T_world_tcp) @ T_obj)
            self._grasped[e.arm] = (e.object, timed.q_arm, pose)
            self.world.attach(e.arm, e.object, timed.q_arm)
            self._memo = None
            return None
        holding = self.held.get(e.arm)
        if holding is None or holding[0] != e.object:
            return Conflict(tick, "release", f"{e.arm} releases {e.object}, which it does not hold")
        T = T_world_tcp @ holding[1]
        pose = (float(T[0, 3]), float(T[1, 3]), math.atan2(T[1, 0], T[0, 0]))
        size = np.array(self.sizes[e.object][:2])
        shrunk = corners(np.array([pose]), size - 2.0 * POS_TOL)
        for other, p in self.rest.items() if check else ():
            if overlap_matrix(shrunk, corners(np.array([p]), np.array(self.sizes[other][:2])))[
                0, 0
            ]:
                return Conflict(tick, "release", f"{e.object} released onto {other}")
        del self.held[e.arm]
        self._grasped.pop(e.arm, None)
        self.world.detach(e.arm, timed.q_arm)
        self.world.set_object(e.object, self.box(e.object, pose))
        self.rest[e.object] = pose
        self._memo = None
        return None
