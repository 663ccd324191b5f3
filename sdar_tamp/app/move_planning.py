"""The streams behind the assignment of moves to arms
(:class:`sdar_tamp.schedule.assignment.MovePlanner`): grasps, closed-form inverse kinematics
and the motion planner of ``plan-dual-motion``, for one arm at a time.

A move by an arm is possible with a grasp of the object that the arm reaches, collision-free, at
both the move's start and end poses (one grasp: the object lands as the synchronous plan put
it). :meth:`StreamMovePlanner.estimate` ranks the pairs of inverse-kinematics branches of every
grasp by the rest-to-rest times (each joint at its velocity and acceleration limits) from where
the arm stands to the grasp and on to the release, collisions ignored; :meth:`~.plan` checks the
best pairs against the resting objects and the other arms and plans the two motions (retreat,
transfer, approach) with the motion planner (its first rung, then its whole ladder), first with
the other arms standing where the caller says (where their committed timelines end, or where
the scheduler's sweep met one), then with them at home (on the way home, :meth:`~.park`, where
they stand). A planned move tells the way back out of its release (:func:`approach_back`: its
approach backwards), which the scheduler's short retreat follows.
:meth:`~.buffer` is the buffer stream's first pose clear of every pose the plan's moves use.
"""

from __future__ import annotations

from collections.abc import Hashable, Iterator, Mapping, Sequence
from typing import Any

import numpy as np

from sdar_tamp.schedule.assignment import PlannedMove, Stand
from sdar_tamp.schedule.moves import Move, Pose
from sdar_tamp.world.instance import Instance, Pose2D
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray, inverse
from streams.context import WorldContext
from streams.grasps import Grasp
from streams.ik import GraspIK, SceneCache, collision_free_candidates
from streams.stream_map import IK_MARGIN, RearrangementStreams
from streams.stream_types import ArmConf, CellConf

#: grasp pairs planned per move (best estimate first)
PAIRS = 2


class StreamMovePlanner:
    """Moves of ``instance``'s objects in ``scene`` by single arms (see the module docstring);
    ``seed``: of the motion planner."""

    def __init__(self, instance: Instance, scene: Scene, seed: int = 0) -> None:
        self.ctx = WorldContext.load(scene)
        sizes = {o.name: o.size for o in instance.objects}
        goals = {o.name: o.goal for o in instance.objects}
        self.streams = RearrangementStreams(self.ctx, sizes, seed, reserved=goals, half_turns=False)
        self.names = self.ctx.arm_names
        self.scenes = SceneCache(self.ctx, IK_MARGIN, 8)
        self.tables: dict[tuple[str, str, Pose], GraspIK] = {}
        #: planned motions by their request (a failed attempt is retried at a later event)
        self.motions: dict[Hashable, tuple[FloatArray, FloatArray] | None] = {}
        v = scene.joint_array("velocity_limit") * scene.velocity_safety
        a = scene.joint_array("acceleration_limit") * scene.velocity_safety
        self.limits = {
            n: (v[self.ctx.layout.slice(n)], a[self.ctx.layout.slice(n)]) for n in self.names
        }

    def table(self, arm: str, obj: str, pose: Pose) -> GraspIK:
        key = (arm, obj, pose)
        if key not in self.tables:
            box = self.streams.box(obj, Pose2D(*pose))
            self.tables[key] = GraspIK(self.ctx, arm, obj, box, self.streams.grasps(obj))
        return self.tables[key]

    def rest_to_rest(self, arm: str, q0: FloatArray, q1: FloatArray) -> FloatArray:
        """Least times [s] ``(...)`` from ``q0`` to ``q1`` ``(..., k)``, at rest at both ends."""
        v, a = self.limits[arm]
        dq = np.abs(q1 - q0)
        t = np.where(dq * a > v * v, dq / v + v / a, 2.0 * np.sqrt(dq / a))
        return np.asarray(t.max(axis=-1))

    def estimate(self, arm: int, stand: Stand, move: Move) -> float | None:
        name = self.names[arm]
        start = self.table(name, move.obj, move.start)
        end = self.table(name, move.obj, move.end)
        best = np.inf
        for gi in range(len(start.grasps)):
            picks, places = start.q_pre[gi][start.ok[gi]], end.q_pre[gi][end.ok[gi]]
            if not len(picks) or not len(places):
                continue
            reach = self.rest_to_rest(name, stand.q, picks)
            carry = self.rest_to_rest(name, picks[:, None, :], places[None, :, :])
            best = min(best, float((reach[:, None] + carry).min()))
        return None if not np.isfinite(best) else best

    def plan(
        self,
        arm: int,
        stand: Stand,
        move: Move,
        resting: Mapping[str, Pose],
        others: Sequence[FloatArray] | None = None,
    ) -> Iterator[PlannedMove]:
        name = self.names[arm]
        home = {a: self.ctx.home(a) for a in self.names if a != name}
        wheres = [home]
        if others is not None:
            standing = {a: np.asarray(q) for a, q in zip(self.names, others, strict=True)}
            standing.pop(name)
            if any(np.abs(standing[a] - home[a]).max() > 1e-9 for a in standing):
                wheres.insert(0, standing)
        for where in wheres:
            yield from self._plan(name, stand, move, resting, where)

    def _plan(
        self,
        name: str,
        stand: Stand,
        move: Move,
        resting: Mapping[str, Pose],
        where: Mapping[str, FloatArray],
    ) -> Iterator[PlannedMove]:
        """The planned moves with the other arms standing ``where`` (arm name -> joints)."""
        boxes = {o: self.streams.box(o, Pose2D(*p)) for o, p in resting.items()}
        after = dict(resting)
        after[move.obj] = move.end
        after_boxes = {o: self.streams.box(o, Pose2D(*p)) for o, p in after.items()}
        current = {**where, name: stand.q}
        picks = collision_free_candidates(
            self.ctx,
            self.scenes.world(frozenset(resting.items()), boxes),
            boxes,
            self.table(name, move.obj, move.start),
            current,
            other_q=where,
        )
        places = collision_free_candidates(
            self.ctx,
            self.scenes.world(frozenset(after.items()), after_boxes),
            after_boxes,
            self.table(name, move.obj, move.end),
            current,
            other_q=where,
        )
        pairs = [
            (
                float(
                    self.rest_to_rest(name, stand.q, p.q_pre)
                    + self.rest_to_rest(name, p.q_pre, r.q_pre)
                ),
                k,
                p,
                r,
            )
            for k, (p, r) in enumerate((p, r) for p in picks for r in places if p.grasp is r.grasp)
        ]
        pairs.sort(key=lambda x: x[:2])
        fluents = [("atpose", o, Pose2D(*p)) for o, p in resting.items()]
        held = [f for f in fluents if f[1] != move.obj]
        for _, _, pick, place in pairs[:PAIRS]:
            grasp: Grasp = pick.grasp
            q_pick = ArmConf(name, tuple(map(float, pick.q)), tuple(map(float, pick.q_pre)))
            q_place = ArmConf(name, tuple(map(float, place.q)), tuple(map(float, place.q_pre)))
            reach = self.motion(name, self.conf(name, stand), q_pick, fluents, where)
            if reach is None:
                continue
            holding = [*held, ("holding", name, move.obj, grasp)]
            carry = self.motion(name, q_pick, q_place, holding, where)
            if carry is None:
                continue
            yield PlannedMove(
                reach,
                carry,
                inverse(grasp.T_object_tcp),
                Stand(np.array(place.q), np.array(place.q_pre), approach_back(carry, place.q_pre)),
            )

    def buffer(self, move: Move, moves: Sequence[Move]) -> Pose | None:
        """The buffer stream's first pose for the object, clear of every pose any move of
        another object starts or ends at (and of the goals)."""
        taken = {(m.obj, p) for m in moves if m.obj != move.obj for p in (m.start, m.end)}
        fluents = [("atpose", o, Pose2D(*p)) for o, p in sorted(taken)]
        found = next(self.streams.sample_buffer(move.obj, fluents), None)
        return None if found is None else found[0].as_tuple()

    def park(
        self, arm: int, stand: Stand, resting: Mapping[str, Pose], others: Sequence[FloatArray]
    ) -> tuple[FloatArray, FloatArray] | None:
        name = self.names[arm]
        home = ArmConf(name, tuple(float(x) for x in self.ctx.home(name)))
        fluents = [("atpose", o, Pose2D(*p)) for o, p in resting.items()]
        standing = {a: q for a, q in zip(self.names, others, strict=True) if a != name}
        return self.motion(name, self.conf(name, stand), home, fluents, standing)

    @staticmethod
    def conf(name: str, stand: Stand) -> ArmConf:
        pre = None if stand.pre is None else tuple(map(float, stand.pre))
        return ArmConf(name, tuple(map(float, stand.q)), pre)

    def motion(
        self,
        name: str,
        q1: ArmConf,
        q2: ArmConf,
        fluents: Sequence[tuple[Any, ...]],
        standing: Mapping[str, FloatArray] | None = None,
    ) -> tuple[FloatArray, FloatArray] | None:
        """The arm's motion ``q1 -> q2`` (times, its configurations), the other arms at home
        or where ``standing`` says."""
        where = {a: self.ctx.home(a) for a in self.names}
        where.update(standing or {})
        others = {a: ArmConf(a, tuple(float(x) for x in where[a])) for a in self.names}
        c1 = CellConf(*(q1 if a == name else others[a] for a in self.names))
        c2 = CellConf(*(q2 if a == name else others[a] for a in self.names))
        key = (c1, c2, frozenset(fluents))
        if key not in self.motions:
            motions = self.streams.motions
            result = next(motions.plan_dual_motion_quick(c1, c2, fluents), None)
            if result is None:  # the ladder's fallbacks: slower, found more often
                result = next(motions.plan_dual_motion(c1, c2, fluents), None)
            traj = None if result is None else result[0].trajectory
            self.motions[key] = (
                None
                if traj is None
                else (np.array(traj.t), np.array(traj.q[:, self.ctx.layout.slice(name)]))
            )
        return self.motions[key]


def approach_back(motion: tuple[FloatArray, FloatArray], q_pre: FloatArray) -> FloatArray:
    """The path of ``motion`` (times ``(m,)``, configurations ``(m, k)``) from its pass by
    the pre-grasp ``q_pre`` to its end, backwards: the way back out along the approach."""
    q = motion[1]
    i = int(np.argmin(np.abs(q - np.asarray(q_pre)).max(axis=1)))
    return q[min(i, len(q) - 2) :][::-1].copy()
