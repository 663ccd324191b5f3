"""The stream map of ``domains/dual_arm_rearrangement/stream.pddl``: name -> plain callable.

Generators (``sample-grasp``, ``inverse-kinematics``, ``sample-buffer``, ``combine-confs``,
``plan-dual-motion``) yield one output tuple per call of ``next``; tests (``test-overlap``,
``test-cfree``, ``test-blocks-grasps``, ``test-grasp-cfree``) return a bool; the functions
``Duration``, ``Distance``, ``ArmDistance`` and ``NextMotion`` return a number [s].
:data:`streams.stream_types.STREAM_KINDS` says which is which, so the wiring layer can wrap
them (e.g. ``from_gen_fn`` / ``from_test`` / ``from_fn``). Replace any entry of the returned
dict by another callable with the same signature to swap a stream. The motion streams and the
duration functions are :class:`streams.motion_streams.MotionStreams`; the others are here.

Values: objects are names (str); poses are :class:`sdar_tamp.world.instance.Pose2D`; grasps
are :class:`streams.grasps.Grasp`; arm configurations :class:`~streams.stream_types.ArmConf`;
dual-arm configurations :class:`~streams.stream_types.CellConf`; trajectories
:class:`streams.motion.records.MotionResult`. Fluent facts (``atpose ?o ?p``,
``holding ?a ?o ?g``) arrive as tuples in ``fluents=``.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable, Iterator, Mapping, Sequence
from typing import Any

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.logs import get_logger
from sdar_tamp.world.collision import CollisionWorld, ObjectBox
from sdar_tamp.world.footprint import corners, overlap_matrix
from sdar_tamp.world.instance import Pose2D
from sdar_tamp.world.transforms import FloatArray, pose_xyz_yaw
from streams.buffers import GRASP_CORRIDOR, BufferPool
from streams.context import WorldContext
from streams.finger_blocking import GraspBlocking, cell_gripper_boxes
from streams.grasps import DEFAULT_GRASPS, Grasp, GraspOptions, half_turn_twins, sample_grasps
from streams.ik import (
    GraspIK,
    SceneCache,
    iter_collision_free_candidates,
)
from streams.motion.planner import MotionPlanner
from streams.motion_streams import MotionStreams
from streams.stream_types import ArmConf, CellConf

LOG = get_logger(__name__)
Size = tuple[float, float, float]

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


class RearrangementStreams:
    """The streams of one problem: sizes of the objects, a seed, and a shared planner.

    ``reserved``: object name -> pose whose footprint buffers must avoid (the goals), unless
    no buffer can be found otherwise. ``motion``: one of
    :data:`~streams.motion_streams.MOTION_PLANNERS`.
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
        #: ``plan-dual-motion`` and the duration functions (checks ``motion`` and ``sampling``)
        self.motions = MotionStreams(
            ctx, self.size, self.box, seed, planner, motion, sampling, half_turns
        )
        self.ctx = ctx
        self.sizes = dict(sizes)
        self.seed = seed
        self.world = ctx.new_world()
        self._arms_only = ctx.new_world()  # no objects: arm-arm checks of combine-confs
        self.scenes = SceneCache(ctx, IK_MARGIN, WORLD_CACHE)  # IK worlds, one per arrangement
        self.reserved = dict(reserved or {})
        self.grasp_options = grasps
        self._grasps: dict[str, tuple[Grasp, ...]] = {}
        self._set_sizes: dict[str, int] = {}
        self._boxes: dict[tuple[str, Pose2D], ObjectBox] = {}
        self._ik_tables: OrderedDict[tuple[str, str, Pose2D], GraspIK] = OrderedDict()
        self._buffer_calls = 0
        self._buffer_pools: dict[Size, BufferPool] = {}
        self._blocking: GraspBlocking | None = None
        self._twin_index: dict[str, tuple[int | None, ...]] = {}
        self.half_turns = half_turns

    @property
    def planner(self) -> MotionPlanner:
        """The motion planner the motion streams share."""
        return self.motions.planner

    @property
    def motion(self) -> str:
        """The motion planner of ``plan-dual-motion`` (see :class:`MotionStreams`)."""
        return self.motions.motion

    @property
    def sampling(self) -> bool:
        """SDAR-M's first rung also warm-starts the optimiser from a sampled path (default:
        where OMPL is installed; :func:`streams.motion.sampling.warm_started_strategies`)."""
        return self.motions.sampling

    @property
    def blocking(self) -> GraspBlocking:
        """The grasp-blocking tests of the scene's gripper (built on first use)."""
        if self._blocking is None:
            self._blocking = GraspBlocking(
                cell_gripper_boxes(self.ctx.scene),
                IK_MARGIN,
            )
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
                self.ctx.scene.grasp_limits,
                options.tilts,
                options.symmetric,
                pair_tilts=options.pair_tilts,
            )
            self._set_sizes[obj] = len(
                sample_grasps(
                    self.size(obj),
                    self.ctx.scene.grasp_limits,
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
        key = frozenset(placed.items())
        held = [self.scenes.world(key, objects)]

        def world() -> CollisionWorld:  # the arrangement's (the cache may have reused it)
            if not self.scenes.holds(key, held[0]):
                held[0] = self.scenes.world(key, objects)
            return held[0]

        wanted = [index]
        twin = self._twins(obj)[index] if table.grasps is self.grasps(obj) else None
        if twin is not None and self.half_turns and g.is_top_down:
            wanted.append(twin)  # the same hold with wrist 3 turned by pi: after g's own
        for k in wanted:  # checked as they are asked for, cheapest first
            for c in iter_collision_free_candidates(self.ctx, world, objects, table, home, (k,)):
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
                found = dict.fromkeys(  # several arms may reach one pose: once
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

    def combine_confs(self, *pairs: str | ArmConf) -> Iterator[tuple[CellConf]]:
        """The cell configuration of one (arm, configuration) pair per arm of the cell
        (``a1, q1, a2, q2, ...``: ``combine-confs`` is declared for the cell's arms), when
        the arms are clear of each other; nothing when an arm is named twice or missing.

        Raises:
            ParameterError: an odd number of values, or a configuration of another arm.
        """
        if len(pairs) % 2:
            raise ParameterError(
                f"combine-confs: expected (arm, configuration) pairs, got {len(pairs)} values"
            )
        by_arm: dict[str, ArmConf] = {}
        for arm, q in zip(pairs[::2], pairs[1::2], strict=True):
            if not isinstance(arm, str) or not isinstance(q, ArmConf) or q.arm != arm:
                raise ParameterError(
                    f"combine-confs: expected an arm and its configuration, got {arm!r}, {q!r}"
                )
            if arm in by_arm:
                return
            by_arm[arm] = q
        if set(by_arm) != set(self.ctx.arm_names):
            return
        conf = CellConf(*(by_arm[a] for a in self.ctx.arm_names))
        if not self._arms_only.in_collision(conf.q):
            yield (conf,)

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
    ``planner``: a motion planner to share (default: a new one, with its own optimiser built
    in the background);
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
        "plan-dual-motion": s.motions.plan_dual_motion,
        "plan-dual-motion-quick": s.motions.plan_dual_motion_quick,
        "test-overlap": s.test_overlap,
        "test-cfree": s.test_cfree,
        "test-blocks-grasps": s.test_blocks_grasps,
        "test-grasp-cfree": s.test_grasp_cfree,
        "Duration": s.motions.duration,
        "Distance": s.motions.distance,
        "ArmDistance": s.motions.arm_distance,
        "NextMotion": s.motions.next_motion,
    }
