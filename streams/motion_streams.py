"""The motion streams of ``domains/dual_arm_rearrangement/stream.pddl``: ``plan-dual-motion``
(SDAR-M's ladder, plain optimisation, one arm at a time or OMPL), its quick variant (the
ladder's first rung alone), and the functions that estimate motion durations for the task
planner (``Duration``, ``Distance``, ``ArmDistance``, ``NextMotion``)."""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterator, Sequence
from typing import Any

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.logs import get_logger
from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.instance import Pose2D
from sdar_tamp.world.transforms import FloatArray, inverse
from streams.context import WorldContext
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
from streams.stream_types import ArmConf, CellConf

LOG = get_logger(__name__)
Size = tuple[float, float, float]

#: Motion planners of ``plan-dual-motion``: SDAR-M's ladder, plain optimisation, one arm at a
#: time, and OMPL's RRTConnect (optional extra ``sdar-tamp[ompl]``, :mod:`streams.motion.sampling`).
MOTION_PLANNERS = ("sdar", "plain", "sequential", "ompl")


class MotionStreams:
    """The motion streams of one problem, sharing ``planner``.

    ``size``: object name -> its size (lx, ly, lz) [m]; ``box``: an object at a pose as a
    box; ``motion``: one of :data:`MOTION_PLANNERS`; ``sampling``: SDAR-M's first rung also
    warm-starts the optimiser from a sampled path (default: where OMPL is installed;
    :func:`streams.motion.sampling.warm_started_strategies`); ``half_turns``: the grasps'
    half-turn twins are offered (:meth:`next_motion` assumes both variants)."""

    def __init__(
        self,
        ctx: WorldContext,
        size: Callable[[str], Size],
        box: Callable[[str, Pose2D], ObjectBox],
        seed: int = 0,
        planner: MotionPlanner | None = None,
        motion: str = "sdar",
        sampling: bool | None = None,
        half_turns: bool = True,
    ) -> None:
        if motion not in MOTION_PLANNERS:
            raise ParameterError(
                f"motion planner must be one of {', '.join(MOTION_PLANNERS)}; got {motion!r}"
            )
        if sampling and not ompl_available():
            raise OmplUnavailableError(
                "sampling=True: the sampled warm start needs OMPL: pip install 'sdar-tamp[ompl]'"
            )
        self.sampling = ompl_available() if sampling is None else sampling
        self.ctx = ctx
        self.size = size
        self.box = box
        self.seed = seed
        # the planner's optimiser starts building in the background now, while selection runs
        self.planner = planner if planner is not None else MotionPlanner(ctx)
        self.motion = motion
        self.half_turns = half_turns
        self._plain_failed: set[Hashable] = set()  # motions the quick stream failed

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
        objects = {f[1]: self.box(f[1], f[2]) for f in fluents if f[0] == "atpose"}
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
