"""Quick proofs that a rearrangement instance cannot be solved.

Picking an object needs a grasp of the grasp set whose configuration, and the pre-grasp
backed off along the approach, puts the arm clear of the table, of itself and of every other
resting object, within the joint limits (the gripper may touch the object it grasps; the other
arms, however many the cell has, are left out, so nothing they could do makes an object
pickable). Each arm of the cell is tried for every grasp: an object is pickable when any arm
has such a grasp. Releasing an object at its goal and retreating needs the same of its goal
pose.

*First picks.* With every object at its start, repeatedly take away every object that has
such a grasp; taking objects away only frees grasps. Call the rest ``S``. In a plan, the first
object of ``S`` to be picked is picked while all of ``S`` still rests at its start and the
objects outside ``S`` at most are absent; so if any object of ``S`` must move (its goal is not
its start), no plan exists.

*Last placements.* The same with every object at its goal: the last object of the remainder
to be placed is released while the rest of the remainder already rests at its goals.

Both tests are necessary conditions only: an instance that passes them may still be
unsolvable. ``margin`` [m] is the clearance asked between the arm and the other objects:
with :data:`VALIDATOR_MARGIN` (objects shrunk by 1 mm, as the replay validator checks) a
rejected instance has no valid plan at all with the grasp set; with the IK streams'
:data:`~streams.stream_map.IK_MARGIN` (3 mm) it has none the planner can find, since every
pick and place it plans passes through those IK checks.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from sdar_tamp.world.collision import CollisionWorld, ObjectBox
from sdar_tamp.world.instance import Instance, Pose2D
from sdar_tamp.world.transforms import FloatArray, pose_xyz_yaw
from streams.context import WorldContext
from streams.grasps import DEFAULT_GRASPS, Grasp, GraspOptions, pregrasp_offset, sample_grasps
from streams.stream_map import IK_MARGIN

#: Pre-grasp distance along the approach [m] (as the IK stream's).
PREGRASP_LIFT = 0.08
#: Clearance [m] of the replay validator (negative: objects shrunk by 1 mm per face).
VALIDATOR_MARGIN = -1e-3
#: Clearance [m] of the planner's IK checks.
PLANNER_MARGIN = IK_MARGIN
_OBJECT = "object:"


@dataclass(frozen=True)
class StuckObject:
    """An object of the remainder: which other objects its grasps hit (``neighbours``), and
    whether grasps also hit the table or the arm itself or fall outside the arms' reach."""

    name: str
    neighbours: tuple[str, ...]
    table: bool
    self_collision: bool
    reachable: bool  # some grasp has an IK solution within the joint limits

    def reason(self) -> str:
        if not self.reachable:
            return f"{self.name}: no grasp within reach of any arm"
        hits = [*self.neighbours]
        if self.table:
            hits.append("the table")
        if self.self_collision:
            hits.append("the arm itself")
        return f"{self.name}: no grasp clear of {', '.join(hits) or 'obstacles'}"


@dataclass(frozen=True)
class InfeasibilityProof:
    """Why an instance is unsolvable: in arrangement ``phase`` (``start``: none of ``stuck``
    can be picked first; ``goal``: none can be placed last)."""

    phase: str
    stuck: tuple[StuckObject, ...]
    margin: float = VALIDATOR_MARGIN  # [m], see the module docstring

    @property
    def objects(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.stuck)

    def summary(self) -> str:
        what = "picked first" if self.phase == "start" else "placed last"
        scope = (
            ""
            if self.margin <= VALIDATOR_MARGIN
            else f" with the planner's {self.margin * 1000:g} mm grasp clearance"
        )
        return (
            f"infeasible: with every object at its {self.phase}, none of "
            f"{', '.join(self.objects)} can ever be {what}{scope}"
        )

    def lines(self) -> tuple[str, ...]:
        """The summary, then one line per stuck object."""
        return (self.summary(), *(s.reason() for s in self.stuck))


@dataclass(frozen=True)
class _Candidate:
    arm: str
    q: FloatArray  # (dof,)
    q_pre: FloatArray  # (dof,)


class _Checker:
    """Grasp configurations of each object at one arrangement, checked against the resting
    objects of a shrinking set."""

    def __init__(
        self,
        ctx: WorldContext,
        boxes: Mapping[str, ObjectBox],
        grasps: Mapping[str, tuple[Grasp, ...]],
        lift: float,
        margin: float,
    ) -> None:
        self.ctx = ctx
        self.boxes = dict(boxes)
        self.world = CollisionWorld(ctx.scene, tolerance=-margin)
        self.home = {a: ctx.home(a) for a in ctx.arm_names}
        self.candidates = self._candidates(grasps, lift)

    def _candidates(
        self, grasps: Mapping[str, tuple[Grasp, ...]], lift: float
    ) -> dict[str, list[_Candidate]]:
        """Per object, its grasp configurations: the IK of every object's grasps in one batch
        per arm (the numeric IK's cost is mostly per call, not per pose)."""
        out: dict[str, list[_Candidate]] = {o: [] for o in self.boxes}
        named = [(o, g) for o in self.boxes for g in grasps[o]]
        if not named:
            return out
        T_tcp = np.concatenate(
            [
                self.boxes[o].T_world_obj @ np.stack([g.T_object_tcp for g in grasps[o]])
                for o in self.boxes
                if grasps[o]
            ]
        )
        for arm in self.ctx.arm_names:
            grasp, pre = self.ctx.kinematics[arm].ik_tcp_pair(T_tcp, pregrasp_offset(T_tcp, lift))
            rows, branches = np.nonzero(grasp.valid & pre.valid)
            for gi, b in zip(rows, branches, strict=True):
                out[named[gi][0]].append(_Candidate(arm, grasp.q[gi, b], pre.q[gi, b]))
        return out

    def rest(self, names: Iterable[str]) -> None:
        self.world.set_objects({n: self.boxes[n] for n in names})

    def hits(self, obj: str, c: _Candidate, q: FloatArray) -> set[str]:
        """What the arm hits at ``q`` (object names, ``table``, ``self``); empty when clear
        (the other arms wait at home; what they touch is not counted)."""
        full = self.ctx.layout.join({**self.home, c.arm: q})
        if not self.world.in_collision(full):
            return set()
        found: set[str] = set()
        owner = self.world.owner
        for p in self.world.report():
            a, b = (p.first, p.second) if owner(p.first) == c.arm else (p.second, p.first)
            if owner(a) != c.arm:
                continue  # pairs of the other arms only: left out
            if owner(b) == c.arm:
                found.add("self")
            elif b == "table":
                found.add("table")
            elif b.startswith(_OBJECT) and b != f"{_OBJECT}{obj}":
                found.add(b[len(_OBJECT) :])
            elif b == f"{_OBJECT}{obj}" and "gripper" not in a:
                found.add("self")  # the wrist or forearm on the object it grasps
        return found

    def graspable(self, obj: str) -> bool:
        return any(
            not self.hits(obj, c, c.q) and not self.hits(obj, c, c.q_pre)
            for c in self.candidates[obj]
        )

    def explain(self, obj: str) -> StuckObject:
        hit: set[str] = set()
        for c in self.candidates[obj]:
            hit |= self.hits(obj, c, c.q) | self.hits(obj, c, c.q_pre)
        others = tuple(sorted(h for h in hit if h not in ("table", "self")))
        return StuckObject(obj, others, "table" in hit, "self" in hit, bool(self.candidates[obj]))


@dataclass(frozen=True)
class Removal:
    """The outcome of taking objects away: the objects taken away in each round (every one
    with a clear grasp at once), and those that remain with what their grasps hit."""

    rounds: tuple[tuple[str, ...], ...]
    stuck: tuple[StuckObject, ...]


def remove_graspable(
    ctx: WorldContext,
    boxes: Mapping[str, ObjectBox],
    grasps: Mapping[str, tuple[Grasp, ...]],
    lift: float = PREGRASP_LIFT,
    margin: float = VALIDATOR_MARGIN,
) -> Removal:
    """Repeatedly take away every object of ``boxes`` (resting, name -> box) that has a clear
    grasp of ``grasps`` (name -> grasp set) with clearance ``margin`` [m], see the module
    docstring."""
    checker = _Checker(ctx, boxes, grasps, lift, margin)
    remaining = list(boxes)
    rounds: list[tuple[str, ...]] = []
    while remaining:
        checker.rest(remaining)
        free = tuple(o for o in remaining if checker.graspable(o))
        if not free:
            break
        rounds.append(free)
        remaining = [o for o in remaining if o not in free]
    if remaining:
        checker.rest(remaining)
    return Removal(tuple(rounds), tuple(checker.explain(o) for o in remaining))


def _box(pose: Pose2D, size: tuple[float, float, float]) -> ObjectBox:
    return ObjectBox(pose_xyz_yaw(pose.x, pose.y, size[2] / 2.0, pose.yaw), size)


def _stays(start: Pose2D, goal: Pose2D) -> bool:
    """The object may never need to move (its goal is its start, up to 1 um and 1 urad)."""
    turn = math.remainder(goal.yaw - start.yaw, 2.0 * math.pi)
    return math.hypot(goal.x - start.x, goal.y - start.y) < 1e-6 and abs(turn) < 1e-6


def prove_infeasible(
    ctx: WorldContext,
    instance: Instance,
    grasps: GraspOptions = DEFAULT_GRASPS,
    lift: float = PREGRASP_LIFT,
    margin: float = VALIDATOR_MARGIN,
) -> InfeasibilityProof | None:
    """A proof that ``instance`` cannot be solved with the grasp set ``grasps`` and the
    clearance ``margin`` [m] (first picks, then last placements), or ``None`` when these
    tests find none."""
    limits = ctx.scene.grasp_limits
    sets = {
        o.name: sample_grasps(o.size, limits, grasps.tilts, grasps.symmetric)
        for o in instance.objects
    }
    moving = {o.name for o in instance.objects if not _stays(o.start, o.goal)}
    for phase in ("start", "goal"):
        boxes = {
            o.name: _box(o.start if phase == "start" else o.goal, o.size) for o in instance.objects
        }
        stuck = remove_graspable(ctx, boxes, sets, lift, margin).stuck
        if any(s.name in moving for s in stuck):
            return InfeasibilityProof(phase, stuck, margin)
    return None


def prove_unplannable(
    ctx: WorldContext, instance: Instance, grasps: GraspOptions = DEFAULT_GRASPS
) -> InfeasibilityProof | None:
    """A proof that the planner cannot solve ``instance`` (its IK clearance,
    :data:`PLANNER_MARGIN`); when one is found, the stronger proof that no valid plan exists
    (:data:`VALIDATOR_MARGIN`) is returned instead if it holds too."""
    proof = prove_infeasible(ctx, instance, grasps, margin=PLANNER_MARGIN)
    if proof is None:
        return None
    return prove_infeasible(ctx, instance, grasps, margin=VALIDATOR_MARGIN) or proof


class ProofCheck:
    """The generators' acceptance test (:data:`sdar_tamp.world.generators.Acceptance`): the
    reason an instance is proven unsolvable by the planner (:func:`prove_unplannable`), or
    ``None``. The world (default: the shipped
    scene) is loaded on first use."""

    def __init__(self, ctx: WorldContext | None = None, grasps: GraspOptions = DEFAULT_GRASPS):
        self._ctx = ctx
        self.grasps = grasps

    def __call__(self, instance: Instance) -> str | None:
        if self._ctx is None:
            self._ctx = WorldContext.load()
        proof = prove_unplannable(self._ctx, instance, self.grasps)
        return None if proof is None else "; ".join(proof.lines())
