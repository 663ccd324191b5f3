"""The stream map of ``domains/dual_arm_rearrangement/stream.pddl``: name -> plain callable.

Generators (``sample-grasp``, ``inverse-kinematics``, ``sample-buffer``, ``combine-confs``,
``plan-dual-motion``) yield one output tuple per call of ``next``; tests (``test-overlap``,
``test-cfree``, ``test-blocks-grasps``, ``test-grasp-cfree``) return a bool; the functions
``Duration``, ``Distance``, ``ArmDistance`` and ``NextMotion`` return a number [s].
:data:`STREAM_KINDS` says which is which, so the wiring layer can wrap them (e.g.
``from_gen_fn`` / ``from_test`` / ``from_fn``). Replace any entry of the returned dict by
another callable with the same signature to swap a stream.

Values: objects are names (str); poses are :class:`sdar_tamp.world.instance.Pose2D`; grasps
are :class:`streams.grasps.Grasp`; arm configurations :class:`ArmConf`; dual-arm
configurations :class:`CellConf`; trajectories :class:`streams.motion.MotionResult`.
Fluent facts (``atpose ?o ?p``, ``holding ?a ?o ?g``) arrive as tuples in ``fluents=``.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.logs import get_logger
from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.footprint import corners, overlap_matrix
from sdar_tamp.world.instance import Pose2D
from sdar_tamp.world.transforms import FloatArray, inverse, pose_xyz_yaw
from streams.buffers import GRASP_CORRIDOR, BufferPool
from streams.context import WorldContext
from streams.finger_blocking import GraspBlocking, gripper_boxes
from streams.grasps import DEFAULT_GRASPS, Grasp, GraspOptions, half_turn_twins, sample_grasps
from streams.ik import GraspIK, SceneCache, collision_free_candidates
from streams.motion.exact_check import HeldObject
from streams.motion.ladder import default_strategies, plan_dual_motion
from streams.motion.planner import MotionPlanner
from streams.motion.records import MotionRequest, MotionResult
from streams.motion.sampling import (
    OmplUnavailableError,
    SamplingOptions,
    ompl_available,
    warm_started_strategies,
)
from streams.motion.strategies import TransferStrategy

LOG = get_logger(__name__)
Size = tuple[float, float, float]

#: Kind of every stream of the file: "gen" (generator of output tuples), "test" or "function".
STREAM_KINDS: Mapping[str, str] = MappingProxyType(
    {
        "sample-grasp": "gen",
        "inverse-kinematics": "gen",
        "sample-buffer": "gen",
        "combine-confs": "gen",
        "plan-dual-motion": "gen",
        "plan-dual-motion-quick": "gen",
        "test-overlap": "test",
        "test-cfree": "test",
        "test-blocks-grasps": "test",
        "test-grasp-cfree": "test",
        "Duration": "function",
        "Distance": "function",
        "ArmDistance": "function",
        "NextMotion": "function",
    }
)


@dataclass(frozen=True)
class ArmConf:
    """A configuration of one arm [rad]; ``grasp`` and ``pre`` are set for grasp poses."""

    arm: str
    q: tuple[float, ...]
    pre: tuple[float, ...] | None = None  # the pre-grasp configuration, if any


@dataclass(frozen=True, init=False)
class CellConf:
    """A configuration of every arm, in the scene's arm order: ``CellConf(first, second)``."""

    arms: tuple[ArmConf, ...]

    def __init__(self, *arms: ArmConf) -> None:
        if not arms:
            raise ParameterError("CellConf: expected one ArmConf per arm, got none")
        object.__setattr__(self, "arms", tuple(arms))

    @property
    def q(self) -> FloatArray:
        """Every arm's joints ``(dof,)`` [rad], in the scene's layout."""
        return np.concatenate([np.asarray(a.q, dtype=np.float64) for a in self.arms])

    def arm(self, name: str) -> ArmConf:
        """The configuration of arm ``name``."""
        for a in self.arms:
            if a.arm == name:
                return a
        raise ParameterError(f"arm must be one of {[a.arm for a in self.arms]}; got {name!r}")


#: Collision worlds kept for IK queries, one per object arrangement (a step of SDAR-M asks
#: for a few: the current one, and per target the one after the pick plus the object there).
WORLD_CACHE = 32
#: Poses (arm, object, pose) whose closed-form IK of every grasp is kept: the starts, goals
#: and recent buffers of a run.
IK_TABLES = 512
#: Clearance [m] IK asks of grasp, pre-grasp and approach configurations from the other
#: objects (the timed trajectory may deviate slightly from the checked configurations).
IK_MARGIN = 0.003
#: Buffers per arm and call of ``sample-buffer``, and the clearance [m] they keep from the
#: other footprints when the grasp corridor does not fit.
BUFFERS_PER_ARM = 4
BUFFER_MARGIN = 0.01

#: Motion planners of ``plan-dual-motion``: SDAR-M's ladder, plain optimisation, one arm at a
#: time, and OMPL's RRTConnect (optional extra ``sdar-tamp[ompl]``, :mod:`streams.motion.sampling`).
MOTION_PLANNERS = ("sdar", "plain", "sequential", "ompl")


class RearrangementStreams:
    """The streams of one problem: sizes of the objects, a seed, and a shared planner.

    ``reserved``: object name -> pose whose footprint buffers must avoid (the goals), unless
    no buffer can be found otherwise. ``motion``: one of :data:`MOTION_PLANNERS`.
    ``half_turns``: ``inverse-kinematics`` of a top-down grasp yields, after the grasp's own
    configurations, those of its half-turn twin (wrist 3 turned by pi; the cuboid and the
    two-finger gripper are symmetric under that turn, so they hold the object the same way):
    a placement may then end the held object's rotation either way round, and the transfer
    need not turn wrist 3 by more than about pi/2 beyond what the base turns.
    """

    def __init__(
        self,
        ctx: WorldContext,
        sizes: Mapping[str, Size],
        seed: int = 0,
        planner: MotionPlanner | None = None,
        reserved: Mapping[str, Pose2D] | None = None,
        motion: str = "sdar",
        grasps: GraspOptions = DEFAULT_GRASPS,
        half_turns: bool = True,
        sampling: bool | None = None,
    ) -> None:
        if motion not in MOTION_PLANNERS:
            raise ParameterError(
                f"motion planner must be one of {', '.join(MOTION_PLANNERS)}; got {motion!r}"
            )
        if sampling and not ompl_available():
            raise OmplUnavailableError(
                "sampling=True: the sampled warm start needs OMPL: pip install 'sdar-tamp[ompl]'"
            )
        #: SDAR-M's first rung also warm-starts the optimiser from a sampled path (default:
        #: where OMPL is installed; :func:`streams.motion.sampling.warm_started_strategies`)
        self.sampling = ompl_available() if sampling is None else sampling
        self.ctx = ctx
        self.sizes = dict(sizes)
        self.seed = seed
        self.world = ctx.new_world()
        self._arms_only = ctx.new_world()  # no objects: arm-arm checks of combine-confs
        self.scenes = SceneCache(ctx, IK_MARGIN, WORLD_CACHE)  # IK worlds, one per arrangement
        # the planner's optimiser starts building in the background now, while selection runs
        self.planner = planner if planner is not None else MotionPlanner(ctx)
        self.reserved = dict(reserved or {})
        self.motion = motion
        self.grasp_options = grasps
        self._grasps: dict[str, tuple[Grasp, ...]] = {}
        self._set_sizes: dict[str, int] = {}
        self._boxes: dict[tuple[str, Pose2D], ObjectBox] = {}
        self._ik_tables: OrderedDict[tuple[str, str, Pose2D], GraspIK] = OrderedDict()
        self._buffer_calls = 0
        self._buffer_pools: dict[Size, BufferPool] = {}
        self._plain_failed: set[Hashable] = set()  # motions the quick stream failed
        self._blocking: GraspBlocking | None = None
        self._twin_index: dict[str, tuple[int | None, ...]] = {}
        self.half_turns = half_turns

    @property
    def blocking(self) -> GraspBlocking:
        """The grasp-blocking tests of the scene's gripper (built on first use)."""
        if self._blocking is None:
            self._blocking = GraspBlocking(gripper_boxes(self.ctx.scene.robot_urdf), IK_MARGIN)
        return self._blocking

    def size(self, obj: str) -> Size:
        return self.sizes.get(obj, self.ctx.scene.object_size)

    def box(self, obj: str, p: Pose2D) -> ObjectBox:
        key = (obj, p)
        box = self._boxes.get(key)
        if box is None:
            s = self.size(obj)
            box = self._boxes[key] = ObjectBox(pose_xyz_yaw(p.x, p.y, s[2] / 2.0, p.yaw), s)
        return box

    def grasps(self, obj: str) -> tuple[Grasp, ...]:
        """The grasps ``sample-grasp`` yields for ``obj``: the grasp set proper, then the
        pair grasps (:attr:`GraspOptions.pair_tilts`)."""
        if obj not in self._grasps:
            options = self.grasp_options
            self._grasps[obj] = sample_grasps(
                self.size(obj),
                self.ctx.scene.gripper.max_graspable_width,
                options.tilts,
                options.symmetric,
                pair_tilts=options.pair_tilts,
            )
            self._set_sizes[obj] = len(
                sample_grasps(
                    self.size(obj),
                    self.ctx.scene.gripper.max_graspable_width,
                    options.tilts,
                    options.symmetric,
                )
            )
        return self._grasps[obj]

    def grasp_set(self, obj: str) -> tuple[Grasp, ...]:
        """The grasp set proper of ``obj`` (without the pair grasps): what the grasp-blocking
        test proves impossible."""
        return self.grasps(obj)[: self._set_sizes[obj]]

    def resting(self, fluents: Sequence[tuple[Any, ...]]) -> dict[str, ObjectBox]:
        return {f[1]: self.box(f[1], f[2]) for f in fluents if f[0] == "atpose"}

    # -- streams -----------------------------------------------------------------------------
    def sample_grasp(self, obj: str) -> Iterator[tuple[Grasp]]:
        for g in self.grasps(obj):
            yield (g,)

    def inverse_kinematics(
        self, arm: str, obj: str, p: Pose2D, g: Grasp, fluents: Sequence[tuple[Any, ...]] = ()
    ) -> Iterator[tuple[ArmConf]]:
        placed = {f[1]: f[2] for f in fluents if f[0] == "atpose"}
        placed[obj] = p
        objects = {o: self.box(o, q) for o, q in placed.items()}
        table = self._grasp_ik(arm, obj, p)
        index = g.index
        if not (index < len(table.grasps) and table.grasps[index] is g):
            table = GraspIK(self.ctx, arm, obj, objects[obj], (g,))  # a grasp from elsewhere
            index = 0
        home = {a: self.ctx.home(a) for a in self.ctx.arm_names}
        world = self.scenes.world(frozenset(placed.items()), objects)
        wanted = [index]
        twin = self._twins(obj)[index] if table.grasps is self.grasps(obj) else None
        if twin is not None and self.half_turns and g.is_top_down:
            wanted.append(twin)  # the same hold with wrist 3 turned by pi: after g's own
        for k in wanted:
            for c in collision_free_candidates(self.ctx, world, objects, table, home, (k,)):
                yield (ArmConf(arm, tuple(map(float, c.q)), tuple(map(float, c.q_pre))),)

    def _twins(self, obj: str) -> tuple[int | None, ...]:
        """Per grasp of ``obj``, the index of its half-turn twin (see :func:`half_turn_twins`)."""
        if obj not in self._twin_index:
            self._twin_index[obj] = half_turn_twins(self.grasps(obj))
        return self._twin_index[obj]

    def _grasp_ik(self, arm: str, obj: str, p: Pose2D) -> GraspIK:
        """The closed-form IK of every grasp of ``obj`` at ``p`` (kept for the
        :data:`IK_TABLES` poses used last)."""
        key = (arm, obj, p)
        table = self._ik_tables.get(key)
        if table is None:
            table = GraspIK(self.ctx, arm, obj, self.box(obj, p), self.grasps(obj))
            if len(self._ik_tables) >= IK_TABLES:
                self._ik_tables.popitem(last=False)
            self._ik_tables[key] = table
        else:
            self._ik_tables.move_to_end(key)
        return table

    def sample_buffer(
        self, obj: str, fluents: Sequence[tuple[Any, ...]] = ()
    ) -> Iterator[tuple[Pose2D]]:
        """Buffers of the first tier that has any, up to :data:`BUFFERS_PER_ARM` per arm:
        clear of the resting objects and the goals (:attr:`reserved`) by the grasp corridor
        (:data:`~streams.buffers.GRASP_CORRIDOR`), then by :data:`BUFFER_MARGIN` only; then
        clear of the resting objects alone, by the corridor and then by the margin. The
        corridor leaves a finger room beside the buffered object and beside its neighbours."""
        size = self.size(obj)
        resting = [(f[1], f[2]) for f in fluents if f[0] == "atpose" and f[1] != obj]
        goals = [(o, p) for o, p in self.reserved.items() if o != obj]
        self._buffer_calls += 1
        seed = self.seed * 100_003 + self._buffer_calls
        pool = self._buffer_pools.get(size)
        if pool is None:
            pool = self._buffer_pools[size] = BufferPool(self.ctx, size, self.seed)
        clear = pool.clearance(self._corners(resting))
        with_goals = np.minimum(clear, pool.clearance(self._corners(goals)))
        for avoid in (with_goals, clear):  # goals too if possible
            for margin in (GRASP_CORRIDOR, BUFFER_MARGIN):
                found = dict.fromkeys(  # both arms may reach one pose: once
                    p
                    for arm in self.ctx.arm_names
                    for p in pool.take(arm, avoid, BUFFERS_PER_ARM, seed, margin)
                )
                if found:
                    yield from ((p,) for p in found)
                    return

    def _corners(self, poses: Sequence[tuple[str, Pose2D]]) -> dict[Hashable, FloatArray]:
        """Object and pose -> the footprint's corners ``(4, 2)`` [m]."""
        rect = self._footprints(poses)
        return {key: rect[k] for k, key in enumerate(poses)}

    def _footprints(self, poses: Sequence[tuple[str, Pose2D]]) -> FloatArray:
        if not poses:
            return np.zeros((0, 4, 2))
        return corners(
            np.array([p.as_tuple() for _, p in poses]),
            np.array([self.size(o)[:2] for o, _ in poses]),
        )

    def combine_confs(
        self, a1: str, q1: ArmConf, a2: str, q2: ArmConf
    ) -> Iterator[tuple[CellConf]]:
        if a1 == a2:
            return
        by_arm = {a1: q1, a2: q2}
        conf = CellConf(*(by_arm[a] for a in self.ctx.arm_names))
        if not self._arms_only.in_collision(conf.q):
            yield (conf,)

    def plan_dual_motion(
        self, q1: CellConf, q2: CellConf, fluents: Sequence[tuple[Any, ...]] = ()
    ) -> Iterator[tuple[MotionResult]]:
        """The motion planner of this map (``motion``): SDAR-M's ladder, plain or one arm."""
        return self._motion(q1, q2, fluents, quick=False)

    def plan_dual_motion_quick(
        self, q1: CellConf, q2: CellConf, fluents: Sequence[tuple[Any, ...]] = ()
    ) -> Iterator[tuple[MotionResult]]:
        """The same motion without the fallbacks of SDAR-M's ladder (trajectory optimisation
        alone): cheap to try and to fail. With ``motion`` plain or sequential it is the same
        planner as :meth:`plan_dual_motion`."""
        return self._motion(q1, q2, fluents, quick=True)

    def _motion(
        self, q1: CellConf, q2: CellConf, fluents: Sequence[tuple[Any, ...]], quick: bool
    ) -> Iterator[tuple[MotionResult]]:
        objects = self.resting(fluents)
        held: dict[str, HeldObject] = {}
        for f in fluents:
            if f[0] == "holding":
                arm, obj, g = f[1], f[2], f[3]
                T_tool0_tcp = self.ctx.kinematics[arm].T_tool0_tcp
                T_tool0_obj = T_tool0_tcp @ inverse(g.T_object_tcp)
                held[arm] = HeldObject(obj, self.size(obj), T_tool0_obj)
        retreat = tuple(a.pre is not None for a in q1.arms)
        approach = tuple(a.pre is not None for a in q2.arms)
        request = MotionRequest(q1.q, q2.q, objects, held, retreat, approach)
        strategies: tuple[TransferStrategy, ...] | None = None
        ladder = self.motion == "sdar" and not quick
        if self.motion == "ompl":
            from streams.motion.sampling import SampledStrategy

            strategies = (SampledStrategy(options=SamplingOptions(seed=self.seed)),)
        elif self.motion == "sdar" and self.sampling:
            strategies = warm_started_strategies(ladder, SamplingOptions(seed=self.seed))
        key = _motion_key(q1, q2, fluents)
        if ladder and key in self._plain_failed:
            # the quick stream (the ladder's first rung alone, deterministic) failed on this
            # very motion: the ladder starts at its second rung
            strategies = (strategies or default_strategies())[1:]
        result = plan_dual_motion(
            self.planner,
            request,
            fallbacks=ladder,
            sequential_only=self.motion == "sequential",
            strategies=strategies,
        )
        if result.success:
            yield (result,)
        else:
            if quick and self.motion == "sdar" and result.attempts:
                self._plain_failed.add(key)
            LOG.debug("plan-dual-motion failed: %s", result.reason)

    def test_overlap(self, o: str, p: Pose2D, o2: str, p2: Pose2D) -> bool:
        """Footprints of ``o`` at ``p`` and ``o2`` at ``p2`` overlap (dependency graph)."""
        if o == o2:
            return False
        a = corners(np.array([p.as_tuple()]), np.array([self.size(o)[:2]]))
        b = corners(np.array([p2.as_tuple()]), np.array([self.size(o2)[:2]]))
        return bool(overlap_matrix(a, b)[0, 0])

    def test_cfree(self, o: str, p: Pose2D, o2: str, p2: Pose2D) -> bool:
        """Footprints of ``o`` at ``p`` and ``o2`` at ``p2`` are clear of each other."""
        return o != o2 and not self.test_overlap(o, p, o2, p2)

    def test_blocks_grasps(self, o: str, p: Pose2D, o2: str, p2: Pose2D) -> bool:
        """``o`` at ``p`` leaves no grasp of ``o2`` at ``p2`` (every grasp of the grasp set
        proper puts a gripper box into ``o``'s box): a dependency edge that footprints miss."""
        if o == o2:
            return False
        return self.blocking.blocks_all(self.grasp_set(o2), self.box(o2, p2), self.box(o, p))

    def test_grasp_cfree(self, o: str, p: Pose2D, g: Grasp, o2: str, p2: Pose2D) -> bool:
        """The gripper holding ``o`` at ``p`` with ``g`` is clear of ``o2`` at ``p2`` (two
        grippers placing two neighbouring objects at once)."""
        if o == o2:
            return False
        return not bool(self.blocking.blocked((g,), self.box(o, p), self.box(o2, p2))[0])

    @staticmethod
    def duration(t: MotionResult) -> float:
        """Execution time [s] of a planned motion."""
        assert t.trajectory is not None
        return t.trajectory.duration

    def distance(self, d1: CellConf, d2: CellConf) -> float:
        """Estimated duration [s] of the synchronous motion ``d1 -> d2``: the slowest joint's
        rest-to-rest time at its velocity and acceleration limits (no obstacles)."""
        dq = np.abs(d2.q - d1.q)
        v, a = self._limits
        t = np.where(dq * a > v * v, dq / v + v / a, 2.0 * np.sqrt(dq / a))
        return float(t.max())

    def arm_distance(self, q1: ArmConf, q2: ArmConf) -> float:
        """Estimated duration [s] of one arm's motion ``q1 -> q2`` (as :meth:`distance`)."""
        if q1.arm != q2.arm:
            raise ParameterError(
                f"ArmDistance: both configurations must be of one arm; got {q1.arm!r} and "
                f"{q2.arm!r}"
            )
        dq = np.abs(np.subtract(q2.q, q1.q))
        v, a = (x[self.ctx.layout.slice(q1.arm)] for x in self._limits)
        t = np.where(dq * a > v * v, dq / v + v / a, 2.0 * np.sqrt(dq / a))
        return float(t.max())

    def next_motion(self, q: ArmConf) -> float:
        """Expected extra duration [s] of the arm's next motion from ``q`` to a top-down
        grasp not yet known, from wrist 3 (the joint that turns most) and its limits.

        The next grasp's wrist angle is taken as uniform, offered in both half-turn
        variants (:meth:`inverse_kinematics`), of which the nearer reachable one is used:
        from an angle ``x`` within ``[-pi/2, pi/2]`` that is ``pi/4`` on average; nearer a
        limit of ``[-pi, pi]`` the far variant cannot be reached the short way round and the
        mean grows to ``(x^2 + (pi - |x|)^2) / (2 pi)``. The result is the rest-to-rest time
        of that mean less that of ``pi/4`` (0 within ``[-pi/2, pi/2]``)."""
        lower, upper = self._wrist_range(q.arm)
        if not self.half_turns or abs(upper - lower - 2.0 * np.pi) > 1e-6:
            return 0.0  # the estimate assumes both variants and exactly a full turn of range
        x = min(abs(q.q[-1] - 0.5 * (lower + upper)), np.pi)
        mean = np.pi / 4 if x <= np.pi / 2 else (x * x + (np.pi - x) ** 2) / (2.0 * np.pi)
        part = self.ctx.layout.slice(q.arm)
        v, a = (float(limit[part][-1]) for limit in self._limits)
        return _rest_to_rest(mean, v, a) - _rest_to_rest(np.pi / 4, v, a)

    def _wrist_range(self, arm: str) -> tuple[float, float]:
        scene, part = self.ctx.scene, self.ctx.layout.slice(arm)
        return float(scene.joint_array("lower")[part][-1]), float(
            scene.joint_array("upper")[part][-1]
        )

    @property
    def _limits(self) -> tuple[FloatArray, FloatArray]:
        scene = self.ctx.scene
        return scene.joint_array("velocity_limit"), scene.joint_array("acceleration_limit")


def _motion_key(q1: CellConf, q2: CellConf, fluents: Sequence[tuple[Any, ...]]) -> Hashable:
    """A motion request as a value: end configurations and fluent facts (grasps compare by
    identity: one object per grasp of an object, see :meth:`RearrangementStreams.grasps`)."""
    return (q1, q2, frozenset(tuple(fluents)))


def _rest_to_rest(dq: float, v: float, a: float) -> float:
    """Least time [s] to move one joint by ``dq`` [rad] from rest to rest at velocity and
    acceleration limits ``v`` [rad/s], ``a`` [rad/s^2]."""
    return dq / v + v / a if dq * a > v * v else 2.0 * float(np.sqrt(dq / a))


def make_stream_map(
    world_context: WorldContext,
    sizes: Mapping[str, Size] | None = None,
    seed: int = 0,
    planner: MotionPlanner | None = None,
    reserved: Mapping[str, Pose2D] | None = None,
    motion: str = "sdar",
    grasps: GraspOptions = DEFAULT_GRASPS,
    sampling: bool | None = None,
) -> dict[str, Callable[..., Any]]:
    """Bind every stream of ``stream.pddl`` by name (see the module docstring).

    ``sizes``: object name -> (lx, ly, lz) [m] (default: the scene's object size);
    ``planner``: a motion planner to share (default: a new one; its optimiser comes from the
    process-wide cache, built once in the background);
    ``reserved``: poses buffers keep clear of (the goals); ``motion``: ``sdar`` (optimisation,
    untangling, one arm at a time), ``plain`` (optimisation only), ``sequential`` or ``ompl``
    (RRTConnect, shortcut; needs the ``ompl`` extra); ``grasps``: the grasp set of
    ``sample-grasp``; ``sampling``: with ``sdar``, a sampled path warm-starts the optimiser
    when the straight line does not lead to a transfer (default: where OMPL is installed).
    """
    s = RearrangementStreams(
        world_context, sizes or {}, seed, planner, reserved, motion, grasps, sampling=sampling
    )
    return {
        "sample-grasp": s.sample_grasp,
        "inverse-kinematics": s.inverse_kinematics,
        "sample-buffer": s.sample_buffer,
        "combine-confs": s.combine_confs,
        "plan-dual-motion": s.plan_dual_motion,
        "plan-dual-motion-quick": s.plan_dual_motion_quick,
        "test-overlap": s.test_overlap,
        "test-cfree": s.test_cfree,
        "test-blocks-grasps": s.test_blocks_grasps,
        "test-grasp-cfree": s.test_grasp_cfree,
        "Duration": s.duration,
        "Distance": s.distance,
        "ArmDistance": s.arm_distance,
        "NextMotion": s.next_motion,
    }
