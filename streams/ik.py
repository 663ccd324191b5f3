"""Batched inverse kinematics for grasp candidates, filtered by collision and ranked.

For many ``(arm, object pose, grasp)`` requests at once: the IK of the grasp pose and of its
pre-grasp (``lift`` back along the approach) for every branch (closed form or numeric, see
:meth:`sdar_tamp.world.kinematics.ArmKinematics.ik_tcp_pair`); a branch survives if
both are real and within the joint limits, the pre-grasp lies on the same branch (joint
distance below ``max_branch_jump``), and neither configuration, nor the straight approach
between them (checked every 1.5 cm), collides with the table, the other resting objects,
itself or the other arm (held at ``other_q``, default its home pose).
The gripper may touch the object being grasped (the fingers close on it); every other
contact counts. Survivors are ranked by the joint distance of their pre-grasp from the arm's
current configuration. :func:`compatible_tuples` then combines candidates of several arms (one
per arm) whose configurations are collision-free together, cheapest total first
(:func:`compatible_pairs` for two arms: the sub-task instantiation of SDAR-M).

The closed-form part does not depend on the other objects: :class:`GraspIK` computes it once
for every grasp of an object at a pose, and :func:`collision_free_candidates` filters it for
an arrangement (the IK stream keeps one table per pose).

Values holding arrays (:class:`IKRequest`, :class:`IKCandidate`) compare by identity.
"""

from __future__ import annotations

import heapq
from collections import OrderedDict
from collections.abc import Callable, Hashable, Iterator, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.collision import CollisionWorld, ObjectBox
from sdar_tamp.world.transforms import FloatArray
from streams.context import WorldContext
from streams.grasps import Grasp, pregrasp_offset
from streams.motion.cartesian import straight_tool_move, straight_tool_moves


@dataclass(frozen=True, eq=False)
class IKRequest:
    """Grasp ``obj`` (a box at its pose, start or goal) with ``arm`` using any of ``grasps``."""

    arm: str
    obj: str
    box: ObjectBox
    grasps: tuple[Grasp, ...]


@dataclass(frozen=True, eq=False)
class IKCandidate:
    """One collision-free IK branch: grasp and pre-grasp configurations ``(dof,)`` [rad]."""

    arm: str
    obj: str
    grasp: Grasp
    branch: int
    q: FloatArray
    q_pre: FloatArray
    cost: float  # joint distance of q_pre from the arm's current configuration [rad]


class GraspIK:
    """The closed-form IK of one arm for grasps of one object at one pose, computed at once
    and kept: the branches whose grasp and pre-grasp (``lift`` [m] back along the approach)
    are both real, within the joint limits and on one branch (joint distance below
    ``max_branch_jump`` [rad]), and, on first use, the straight approach between them. None
    of it depends on the other objects, so one table serves every arrangement; collision
    checks are :func:`collision_free_candidates`' job.
    """

    def __init__(
        self,
        ctx: WorldContext,
        arm: str,
        obj: str,
        box: ObjectBox,
        grasps: Sequence[Grasp],
        lift: float = 0.08,
        max_branch_jump: float = 1.0,
    ) -> None:
        self.arm, self.obj, self.box, self.lift = arm, obj, box, lift
        self.grasps = tuple(grasps)
        self._kin = ctx.kinematics[arm]
        n = len(self.grasps)
        if n == 0:
            self.q = self.q_pre = np.zeros((0, self._kin.branches, self._kin.dof))
            self.ok = np.zeros((0, self._kin.branches), dtype=np.bool_)
        else:
            T_tcp = box.T_world_obj @ np.stack([g.T_object_tcp for g in self.grasps])
            grasp, pre = self._kin.ik_tcp_pair(T_tcp, pregrasp_offset(T_tcp, lift))
            self.q, self.q_pre = grasp.q, pre.q
            ok = grasp.valid & pre.valid
            self.ok = ok & (np.abs(self.q - self.q_pre).max(axis=-1) < max_branch_jump)
        self._sweeps: dict[tuple[int, int], FloatArray | None] = {}

    def sweep(self, gi: int, b: int) -> FloatArray | None:
        """Configurations ``(k, dof)`` of the straight approach of grasp ``gi`` on branch ``b``,
        from the grasp back to the pre-grasp (None: unreachable)."""
        key = (gi, b)
        if key not in self._sweeps and not self._kin.closed_form:
            # the numeric IK: every branch's approach in one batch (its cost is per call)
            todo = [(int(g), int(c)) for g, c in zip(*np.nonzero(self.ok), strict=True)]
            todo = [k for k in todo if k not in self._sweeps] or [key]
            moves = straight_tool_moves(
                self._kin, np.stack([self.q[k] for k in todo]), -self.lift, step=SWEEP_STEP
            )
            self._sweeps.update(zip(todo, moves, strict=True))
        if key not in self._sweeps:
            self._sweeps[key] = straight_tool_move(
                self._kin, self.q[gi, b], -self.lift, step=SWEEP_STEP
            )
        return self._sweeps[key]


def collision_free_candidates(
    ctx: WorldContext,
    world: CollisionWorld,
    objects: Mapping[str, ObjectBox],
    table: GraspIK,
    q_current: Mapping[str, FloatArray],
    indices: Sequence[int] | None = None,
    other_q: Mapping[str, FloatArray] | None = None,
) -> list[IKCandidate]:
    """The branches of ``table`` (grasps ``indices``, default all) whose grasp, pre-grasp and
    approach are collision-free among ``objects`` (see the module docstring), cheapest first."""
    return list(
        iter_collision_free_candidates(
            ctx, lambda: world, objects, table, q_current, indices, other_q
        )
    )


def iter_collision_free_candidates(
    ctx: WorldContext,
    world_of: Callable[[], CollisionWorld],
    objects: Mapping[str, ObjectBox],
    table: GraspIK,
    q_current: Mapping[str, FloatArray],
    indices: Sequence[int] | None = None,
    other_q: Mapping[str, FloatArray] | None = None,
) -> Iterator[IKCandidate]:
    """:func:`collision_free_candidates` one at a time, cheapest first: the branches are
    ordered by cost (which needs no collision check) and checked in that order, so a caller
    that takes the first candidates checks only as many branches as it needs. ``world_of``
    gives the world to check in at each branch (a caller's scratch world may serve other
    arrangements between two candidates); it is given exactly ``objects`` first."""
    park = {a: ctx.home(a) for a in ctx.arm_names}
    if other_q is not None:
        park.update({a: np.asarray(q, dtype=np.float64) for a, q in other_q.items()})
    arm, obj = table.arm, table.obj
    ref = np.asarray(q_current[arm], dtype=np.float64)
    wanted = range(len(table.grasps)) if indices is None else indices
    ranked = [
        (float(np.linalg.norm(table.q_pre[gi, b] - ref)), gi, int(b))
        for gi in wanted
        for b in np.flatnonzero(table.ok[gi])
    ]
    ranked.sort(key=lambda item: item[0])  # stable: equal costs keep grasp, branch order
    for cost, gi, b in ranked:
        world = world_of()
        ensure_objects(world, objects)
        q, q_pre = table.q[gi, b], table.q_pre[gi, b]
        if _collides(ctx, world, park, arm, obj, q) or _collides(ctx, world, park, arm, obj, q_pre):
            continue
        sweep = table.sweep(gi, b)
        if sweep is None or any(_collides(ctx, world, park, arm, obj, qs) for qs in sweep[1:-1]):
            continue  # the straight approach between them is blocked or unreachable
        yield IKCandidate(arm, obj, table.grasps[gi], b, q.copy(), q_pre.copy(), cost)


def solve_ik_candidates(
    ctx: WorldContext,
    world: CollisionWorld,
    objects: Mapping[str, ObjectBox],
    requests: Sequence[IKRequest],
    q_current: Mapping[str, FloatArray],
    lift: float = 0.08,
    other_q: Mapping[str, FloatArray] | None = None,
    max_branch_jump: float = 1.0,
) -> list[IKCandidate]:
    """All collision-free candidates of every request, cheapest first.

    ``world`` is used as scratch space (its resting objects are replaced); ``objects`` are the
    resting objects of the current arrangement, name -> box.
    """
    out: list[IKCandidate] = []
    for r in requests:
        if not r.grasps:
            continue
        table = GraspIK(ctx, r.arm, r.obj, r.box, r.grasps, lift, max_branch_jump)
        out += collision_free_candidates(ctx, world, objects, table, q_current, None, other_q)
    out.sort(key=lambda c: c.cost)
    return out


def _collides(
    ctx: WorldContext,
    world: CollisionWorld,
    park: dict[str, FloatArray],
    arm: str,
    obj: str,
    q: FloatArray,
) -> bool:
    """Collision of ``arm`` at ``q``, except its gripper touching the object it grasps."""
    if not world.in_collision(ctx.layout.join({**park, arm: q})):
        return False
    target = f"object:{obj}"
    return any(not _is_gripper_contact(p.first, p.second, arm, target) for p in world.report())


def _is_gripper_contact(a: str, b: str, arm: str, target: str) -> bool:
    shape = a if b == target else b if a == target else None
    return shape is not None and shape.startswith(f"{arm}_") and _GRIPPER in shape


_GRIPPER = "gripper"
#: Spacing [m] of the checks along the straight approach between pre-grasp and grasp.
SWEEP_STEP = 0.015


def ensure_objects(world: CollisionWorld, objects: Mapping[str, ObjectBox]) -> None:
    """Give ``world`` exactly these resting objects, rebuilding its geometry only on change."""
    current = world.objects
    same = current.keys() == objects.keys() and all(
        np.array_equal(current[k].T_world_obj, v.T_world_obj) and current[k].size == v.size
        for k, v in objects.items()
    )
    if not same:
        world.set_objects(objects)


class SceneCache:
    """Collision worlds for IK queries, one per object arrangement, least recently used first
    out.

    The key is the arrangement itself (the set of ``(object, pose key)`` a query places on
    the table, given by the caller), so every query of one arrangement (picks of different
    objects, grasps, arms) shares one world; a new arrangement reuses the least recently
    used world when ``capacity`` are kept. ``builds`` counts the worlds given a new object
    set (each costs a geometry rebuild of a few milliseconds); ``hits`` the queries that
    found theirs ready.
    """

    def __init__(self, ctx: WorldContext, margin: float, capacity: int = 8) -> None:
        if capacity < 1:
            raise ParameterError(f"scene cache capacity must be >= 1, got {capacity}")
        self.ctx = ctx
        self.margin = margin
        self.capacity = capacity
        self._worlds: OrderedDict[Hashable, CollisionWorld] = OrderedDict()
        self.builds = 0
        self.hits = 0

    def holds(self, key: Hashable, world: CollisionWorld) -> bool:
        """Whether ``world`` is still the one kept for the arrangement ``key``."""
        return self._worlds.get(key) is world

    def world(self, key: Hashable, objects: Mapping[str, ObjectBox]) -> CollisionWorld:
        """The world holding exactly ``objects`` (the arrangement ``key``)."""
        world = self._worlds.get(key)
        if world is not None:
            self._worlds.move_to_end(key)
            self.hits += 1
            return world
        if len(self._worlds) >= self.capacity:
            _, world = self._worlds.popitem(last=False)
        else:
            world = self.ctx.new_world(margin=self.margin)
        world.set_objects(objects)
        self.builds += 1
        self._worlds[key] = world
        return world


def compatible_pairs(
    ctx: WorldContext,
    world: CollisionWorld,
    objects: Mapping[str, ObjectBox],
    first: Sequence[IKCandidate],
    second: Sequence[IKCandidate],
    limit: int = 1,
) -> list[tuple[IKCandidate, IKCandidate]]:
    """Up to ``limit`` pairs (one candidate per arm, different objects), cheapest total cost
    first, whose grasp and pre-grasp configurations are collision-free *together*:
    :func:`compatible_tuples` of two arms.

    ``first`` must hold candidates of the scene's first arm and ``second`` of the other.
    """
    found = compatible_tuples(ctx, world, objects, (first, second), limit)
    return [(a, b) for a, b in found]


def compatible_tuples(
    ctx: WorldContext,
    world: CollisionWorld,
    objects: Mapping[str, ObjectBox],
    per_arm: Sequence[Sequence[IKCandidate]],
    limit: int = 1,
    max_checks: int = 10_000,
) -> list[tuple[IKCandidate, ...]]:
    """Up to ``limit`` tuples (one candidate of each list, each list one arm's, different
    arms and objects), cheapest total cost first (ties by list positions), whose grasp and
    pre-grasp configurations are collision-free *together*.

    Tuples are enumerated best first from the lists sorted by cost (a heap over index
    vectors: a tuple's successors raise one index), so no product of the lists is built;
    at most ``max_checks`` tuples are examined.
    """
    if limit < 1 or max_checks < 1:
        raise ParameterError(f"limit and max_checks must be >= 1, got {limit}, {max_checks}")
    lists = [sorted(c, key=lambda x: x.cost) for c in per_arm]
    if not lists or any(not c for c in lists):
        return []
    ensure_objects(world, objects)

    def total(index: tuple[int, ...]) -> float:
        return sum(lists[k][i].cost for k, i in enumerate(index))

    start = (0,) * len(lists)
    heap: list[tuple[float, tuple[int, ...]]] = [(total(start), start)]
    seen = {start}
    out: list[tuple[IKCandidate, ...]] = []
    checks = 0
    while heap and len(out) < limit and checks < max_checks:
        _, index = heapq.heappop(heap)
        for k in range(len(lists)):
            if index[k] + 1 < len(lists[k]):
                nxt = (*index[:k], index[k] + 1, *index[k + 1 :])
                if nxt not in seen:
                    seen.add(nxt)
                    heapq.heappush(heap, (total(nxt), nxt))
        combo = tuple(lists[k][i] for k, i in enumerate(index))
        if len({c.arm for c in combo}) < len(combo) or len({c.obj for c in combo}) < len(combo):
            continue
        checks += 1
        if _tuple_collides(ctx, world, combo, [c.q for c in combo]) or _tuple_collides(
            ctx, world, combo, [c.q_pre for c in combo]
        ):
            continue
        out.append(combo)
    return out


def _tuple_collides(
    ctx: WorldContext,
    world: CollisionWorld,
    combo: Sequence[IKCandidate],
    qs: Sequence[FloatArray],
) -> bool:
    """The arms at ``qs`` collide, except each gripper touching the object it grasps (the
    arms not in ``combo`` at home)."""
    parts = {a: ctx.home(a) for a in ctx.arm_names}
    parts.update({c.arm: q for c, q in zip(combo, qs, strict=True)})
    if not world.in_collision(world.layout.join(parts)):
        return False
    allowed = {(c.arm, f"object:{c.obj}") for c in combo}
    return any(
        not any(_is_gripper_contact(p.first, p.second, arm, t) for arm, t in allowed)
        for p in world.report()
    )
