"""SDAR-M's motion planner: what stays built between motion calls of one scene.

A :class:`MotionPlanner` owns the trajectory optimiser (from an
:class:`~streams.motion.optimiser_cache.OptimiserCache`: its own, or one its owner shares
between planners), the scratch collision worlds of the exact check, and the settings of the
direct paths and of the motion's shape. :func:`streams.motion.ladder.plan_dual_motion` plans
one segment with it; each call counts its work in its own
:class:`~streams.motion.records.MotionTally`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.transforms import FloatArray
from streams.context import WorldContext
from streams.motion.assembly import MotionAssembly
from streams.motion.exact_check import configure_world
from streams.motion.optimiser import TrajectoryOptimiser
from streams.motion.optimiser_build import OptimiserBuild
from streams.motion.optimiser_cache import OptimiserCache
from streams.motion.optimiser_records import TrajOptOptions
from streams.motion.phases import grasp_lifts, retreat_and_approach, transfer_problem
from streams.motion.records import MotionRequest, MotionTally, TransferProblem
from streams.motion.shape import ShapeOptions
from streams.motion.subsets import SubsetOptimisers
from streams.motion.transfers import DIRECT_LIFTS, REFINE_BENT, Transfers

#: Clearance [m] a transfer taken without optimisation keeps from resting and held objects
#: on the exact check (the optimiser's sphere model asks 15 mm of its spheres).
DIRECT_MARGIN = 0.005
#: [m] where the shapes of two arms come closer than this at a checked sample of a planned
#: motion, the chords to the neighbouring samples are checked finely (see
#: :func:`streams.motion.exact_check.validate_trajectory`): between samples at most 5 mm of
#: tool travel apart, two wrists passing a millimetre apart at the samples can touch.
ARM_CLEARANCE = 0.002


class MotionPlanner:
    """Owns the optimiser and scratch collision worlds. The optimiser comes from
    ``optimisers`` (built once per scene and options, in the background, so constructing a
    planner costs nothing and only the first optimisation may wait for the build; None: a
    cache of the planner's own; pass one cache to planners that should share an optimiser).
    Worlds: ``world`` for the exact validation, ``margin_world`` (objects grown by
    ``direct_margin`` [m]) for transfers taken without optimisation, ``near_world`` (arms
    closer than :data:`ARM_CLEARANCE`) for the fine check between samples.

    ``direct_lifts``: TCP lifts [m] of the bent paths tried after the straight line (empty:
    the straight line only); ``direct=False`` always optimises (the sphere model's own
    straight-line test still applies); ``refine_bent``: a bent path is handed to the optimiser
    as its warm start and the result kept when it executes faster and passes the same check
    (see :class:`~streams.motion.transfers.Transfers`); ``shape``: lift heights and blending
    (:mod:`streams.motion.shape`). Trajectories use the scene's ``velocity_safety``.
    ``defer_build``: the optimiser's build starts at :meth:`start_build` or when it is first
    needed, not now."""

    def __init__(
        self,
        ctx: WorldContext,
        options: TrajOptOptions | None = None,
        *,
        direct: bool = True,
        direct_margin: float = DIRECT_MARGIN,
        direct_lifts: Sequence[float] = DIRECT_LIFTS,
        optimisers: OptimiserCache | None = None,
        shape: ShapeOptions | None = None,
        refine_bent: bool = REFINE_BENT,
        defer_build: bool = False,
    ) -> None:
        if direct_margin < 0.0:
            raise ParameterError(f"direct_margin must be >= 0 [m], got {direct_margin}")
        self.ctx = ctx
        cache = optimisers if optimisers is not None else OptimiserCache()
        self._build = cache.get(ctx, options, start=not defer_build)
        self.subsets = SubsetOptimisers(ctx, self._build.options, cache)
        self.world = ctx.new_world()
        self.margin_world = ctx.new_world(margin=direct_margin)
        self.near_world = ctx.new_world(arm_margin=ARM_CLEARANCE)
        self.direct = direct
        self.direct_lifts = tuple(float(h) for h in direct_lifts)
        self.refine_bent = refine_bent
        self.shape = shape if shape is not None else ShapeOptions()
        self.assembly = MotionAssembly(ctx, self.shape)

    @property
    def trajopt(self) -> TrajectoryOptimiser:
        """The trajectory optimiser; the first access waits for its background build."""
        return self._build.get()

    def start_build(self) -> None:
        """Start the optimiser's background build if it has not started."""
        self._build.start()

    @property
    def limits(self) -> tuple[FloatArray, FloatArray]:
        """Joint velocity [rad/s] and acceleration [rad/s^2] limits ``(dof,)`` each."""
        scene = self.ctx.scene
        return scene.joint_array("velocity_limit"), scene.joint_array("acceleration_limit")

    @property
    def build(self) -> OptimiserBuild:
        """The optimiser's build: ``ready``, ``build_time`` (CPU [s]), ``waited`` [s]."""
        return self._build

    def transfers(self, tally: MotionTally | None = None) -> Transfers:
        """The transfer building blocks of one motion call, counting into ``tally`` (default:
        a new one), checking direct paths in :attr:`margin_world`."""
        return Transfers(
            self.ctx, self._build, self.margin_world,
            tally if tally is not None else MotionTally(),
            direct=self.direct, direct_lifts=self.direct_lifts, refine_bent=self.refine_bent,
            subsets=self.subsets,
        )  # fmt: skip

    def configure(self, request: MotionRequest) -> None:
        """Set the resting and held objects of ``request`` (at its start) in every world."""
        q_start = np.asarray(request.q_start, dtype=np.float64)
        for world in (self.world, self.margin_world, self.near_world):
            configure_world(self.ctx, world, request.objects, request.held, q_start)

    def lifts(
        self, request: MotionRequest, fixed: float | None = None
    ) -> tuple[list[float], list[float]]:
        """Per arm, the lifts [m] of its retreat and approach
        (:func:`~streams.motion.phases.grasp_lifts`)."""
        return grasp_lifts(self.ctx, self.shape, request, fixed)

    def phases(
        self,
        request: MotionRequest,
        one_at_a_time: bool = False,
        lift: float | None = None,
        last_first: bool = False,
    ) -> tuple[list[FloatArray], list[FloatArray]] | None:
        """Retreat and approach as lists of paths ``(n, dof)``
        (:func:`~streams.motion.phases.retreat_and_approach`)."""
        return retreat_and_approach(self.ctx, self.shape, request, one_at_a_time, lift, last_first)

    def transfer_problem(
        self, request: MotionRequest, q_from: FloatArray, q_to: FloatArray
    ) -> TransferProblem:
        """The transfer between the lifted configurations with the optimiser's spheres per
        held object (:func:`~streams.motion.phases.transfer_problem`)."""
        held_slots = self._build.options.held_slots
        return transfer_problem(self.ctx, held_slots, request, q_from, q_to)
