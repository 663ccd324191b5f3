"""The stream map of ``domains/dual_arm_rearrangement/stream.pddl``: name -> plain callable.

Generators (``sample-grasp``, ``inverse-kinematics``, ``sample-buffer``, ``combine-confs``,
``plan-dual-motion``) yield one output tuple per call of ``next``; tests (``test-overlap``,
``test-cfree-conf-pose``) return a bool. :data:`STREAM_KINDS` says which is which, so the
wiring layer can wrap them (e.g. ``from_gen_fn`` / ``from_test``). Replace any entry of the
returned dict by another callable with the same signature to swap a stream.

Values: objects are names (str); poses are :class:`sdar_tamp.world.instance.Pose2D`; grasps
are :class:`streams.grasps.Grasp`; arm configurations :class:`ArmConf`; dual-arm
configurations :class:`DualConf`; trajectories :class:`streams.motion.MotionResult`.
Fluent facts (``atpose ?o ?p``, ``holding ?a ?o ?g``) arrive as tuples in ``fluents=``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.footprint import corners, overlap_matrix
from sdar_tamp.world.instance import Pose2D
from sdar_tamp.world.transforms import FloatArray, inverse, pose_xyz_yaw
from streams.buffers import sample_buffers
from streams.context import WorldContext
from streams.grasps import Grasp, sample_grasps
from streams.ik import IKRequest, solve_ik_candidates
from streams.motion import DualMotionPlanner, MotionRequest, MotionResult, plan_dual_motion
from streams.validate import HeldObject

Size = tuple[float, float, float]

#: Kind of every stream of the file: "gen" (generator of output tuples) or "test".
STREAM_KINDS: Mapping[str, str] = MappingProxyType(
    {
        "sample-grasp": "gen",
        "inverse-kinematics": "gen",
        "sample-buffer": "gen",
        "combine-confs": "gen",
        "plan-dual-motion": "gen",
        "test-overlap": "test",
        "test-cfree-conf-pose": "test",
    }
)


@dataclass(frozen=True)
class ArmConf:
    """A configuration of one arm [rad]; ``grasp`` and ``pre`` are set for grasp poses."""

    arm: str
    q: tuple[float, ...]
    pre: tuple[float, ...] | None = None  # the pre-grasp configuration, if any


@dataclass(frozen=True)
class DualConf:
    """Both arms, scene order."""

    left: ArmConf
    right: ArmConf

    @property
    def q(self) -> FloatArray:
        return np.array(self.left.q + self.right.q)


class DualArmStreams:
    """The streams of one problem: sizes of the objects, a seed, and a shared planner."""

    def __init__(
        self,
        ctx: WorldContext,
        sizes: Mapping[str, Size],
        seed: int = 0,
        planner: DualMotionPlanner | None = None,
    ) -> None:
        self.ctx = ctx
        self.sizes = dict(sizes)
        self.seed = seed
        self.world = ctx.new_world()
        self._planner = planner
        self._grasps: dict[str, tuple[Grasp, ...]] = {}
        self._buffer_calls = 0

    @property
    def planner(self) -> DualMotionPlanner:
        if self._planner is None:  # built on first use (about 3 s)
            self._planner = DualMotionPlanner(self.ctx)
        return self._planner

    def size(self, obj: str) -> Size:
        return self.sizes.get(obj, self.ctx.scene.object_size)

    def box(self, obj: str, p: Pose2D) -> ObjectBox:
        s = self.size(obj)
        return ObjectBox(pose_xyz_yaw(p.x, p.y, s[2] / 2.0, p.yaw), s)

    def grasps(self, obj: str) -> tuple[Grasp, ...]:
        if obj not in self._grasps:
            self._grasps[obj] = sample_grasps(
                self.size(obj), self.ctx.scene.gripper.max_graspable_width
            )
        return self._grasps[obj]

    def resting(self, fluents: Sequence[tuple[Any, ...]]) -> dict[str, ObjectBox]:
        return {f[1]: self.box(f[1], f[2]) for f in fluents if f[0] == "atpose"}

    # -- streams -----------------------------------------------------------------------------
    def sample_grasp(self, obj: str) -> Iterator[tuple[Grasp]]:
        for g in self.grasps(obj):
            yield (g,)

    def inverse_kinematics(
        self, arm: str, obj: str, p: Pose2D, g: Grasp, fluents: Sequence[tuple[Any, ...]] = ()
    ) -> Iterator[tuple[ArmConf]]:
        objects = self.resting(fluents)
        objects[obj] = self.box(obj, p)
        request = IKRequest(arm, obj, objects[obj], (g,))
        home = {a: self.ctx.home(a) for a in self.ctx.arm_names}
        for c in solve_ik_candidates(self.ctx, self.world, objects, [request], home):
            yield (ArmConf(arm, tuple(map(float, c.q)), tuple(map(float, c.q_pre))),)

    def sample_buffer(
        self, obj: str, fluents: Sequence[tuple[Any, ...]] = ()
    ) -> Iterator[tuple[Pose2D]]:
        size = self.size(obj)
        taken = [
            corners(np.array([f[2].as_tuple()]), np.array([self.size(f[1])[:2]]))
            for f in fluents
            if f[0] == "atpose" and f[1] != obj
        ]
        occupied = np.concatenate(taken) if taken else np.zeros((0, 4, 2))
        self._buffer_calls += 1
        seed = self.seed * 100_003 + self._buffer_calls
        for arm in self.ctx.arm_names:
            for p in sample_buffers(self.ctx, arm, size, occupied, 4, seed):
                yield (p,)

    def combine_confs(
        self, a1: str, q1: ArmConf, a2: str, q2: ArmConf
    ) -> Iterator[tuple[DualConf]]:
        left = self.ctx.arm_names[0]
        if a1 == a2:
            return
        yield (DualConf(q1, q2) if a1 == left else DualConf(q2, q1),)

    def plan_dual_motion(
        self, q1: DualConf, q2: DualConf, fluents: Sequence[tuple[Any, ...]] = ()
    ) -> Iterator[tuple[MotionResult]]:
        objects = self.resting(fluents)
        held: dict[str, HeldObject] = {}
        for f in fluents:
            if f[0] == "holding":
                arm, obj, g = f[1], f[2], f[3]
                T_tool0_tcp = self.ctx.kinematics[arm].T_tool0_tcp
                T_tool0_obj = T_tool0_tcp @ inverse(g.T_object_tcp)
                held[arm] = HeldObject(obj, self.size(obj), T_tool0_obj)
        retreat = (q1.left.pre is not None, q1.right.pre is not None)
        approach = (q2.left.pre is not None, q2.right.pre is not None)
        request = MotionRequest(q1.q, q2.q, objects, held, retreat, approach)
        result = plan_dual_motion(self.planner, request)
        if result.success:
            yield (result,)

    def test_overlap(self, o: str, p: Pose2D, o2: str, p2: Pose2D) -> bool:
        """Footprints of ``o`` at ``p`` and ``o2`` at ``p2`` overlap (dependency graph)."""
        if o == o2:
            return False
        a = corners(np.array([p.as_tuple()]), np.array([self.size(o)[:2]]))
        b = corners(np.array([p2.as_tuple()]), np.array([self.size(o2)[:2]]))
        return bool(overlap_matrix(a, b)[0, 0])

    def test_cfree_conf_pose(self, arm: str, q: ArmConf, o: str, p: Pose2D) -> bool:
        """The arm at ``q`` (other arm at home) does not touch ``o`` resting at ``p``."""
        world = self.world
        world.set_objects({o: self.box(o, p)})
        qs = {a: self.ctx.home(a) for a in self.ctx.arm_names}
        qs[arm] = np.array(q.q)
        left, right = self.ctx.arm_names
        return not world.in_collision(qs[left], qs[right])


def make_stream_map(
    world_context: WorldContext,
    sizes: Mapping[str, Size] | None = None,
    seed: int = 0,
    planner: DualMotionPlanner | None = None,
) -> dict[str, Callable[..., Any]]:
    """Bind every stream of ``stream.pddl`` by name (see the module docstring).

    ``sizes``: object name -> (lx, ly, lz) [m] (default: the scene's object size);
    ``planner``: a motion planner to share (default: one built on first use, about 3 s).
    """
    s = DualArmStreams(world_context, sizes or {}, seed, planner)
    return {
        "sample-grasp": s.sample_grasp,
        "inverse-kinematics": s.inverse_kinematics,
        "sample-buffer": s.sample_buffer,
        "combine-confs": s.combine_confs,
        "plan-dual-motion": s.plan_dual_motion,
        "test-overlap": s.test_overlap,
        "test-cfree-conf-pose": s.test_cfree_conf_pose,
    }
