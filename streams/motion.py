"""SDAR-M synchronous dual-arm motion with fallbacks (the paper's Alg. 2).

A synchronous segment takes the arms from ``q_start`` to ``q_goal`` (``(dof,)`` [rad]) with
the held objects fixed for the whole segment (gripper actions happen between segments):

1. retreat: arms flagged ``retreat`` first move their tool straight back along the tool axis
   (IK interpolation), both arms at once, by a lift [m] chosen per grasp from the clearance
   of its neighbours (:func:`streams.shape.clearance_lift`; or the request's fixed ``lift``);
2. transfer: between the two lifted (pre-grasp) configurations, produced by a *strategy*;
3. approach: arms flagged ``approach`` move straight down the tool axis to the goal.

The motion is first shaped as one blended path (:mod:`streams.shape`): only the first and
last ``straight`` centimetres stay straight, the corners at the lifted configurations are
rounded into the transfer, and the path is timed as one, without stopping at the pre-grasp
points. If that path leaves the straight tool axis or fails the exact check, the unblended
motion is used: every phase and stage timed rest to rest (:mod:`streams.timing`). Either way
the whole trajectory is checked exactly with coal (:mod:`streams.validate`), and only a
trajectory that passes is returned as a success. Strategies, tried in order until one
passes:

* ``plain`` (:class:`PlainStrategy`): one synchronous optimisation, warm-started from the
  straight line, then from a lifted via-point (SDAR-M's stream map, where OMPL is installed,
  tries a sampled collision-free path's warm start in between:
  :func:`streams.sampling.warm_started_strategies`);
* ``untangle`` (:class:`UntangleStrategy`, rules in ``docs/arm_untangling.md``): the arm that
  reaches deeper into the other arm's half yields: it moves to a lifted park pose above its
  own half while the other arm goes straight to its goal; then it moves to its own goal while
  the other waits. If that fails, the roles swap;
* ``sequential`` (:class:`SequentialStrategy`): one arm at a time; the first arm retracts to
  its home pose, the second moves to its goal, then the first moves to its goal.

``plan_dual_motion(..., fallbacks=False)`` is the paper's "plain" planner (no fallbacks);
``sequential_only=True`` is the baseline motion planner (:class:`OneArmStrategy`: the arms
move one after the other; SDAR-M then also keeps the idle arm at home, so that one arm works
while the other waits at its retract pose).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.transforms import FloatArray
from streams.cartesian import straight_tool_move, tool_pose_ik
from streams.context import WorldContext
from streams.shape import (
    ShapeOptions,
    arc_length,
    clearance_lift,
    round_corner,
    straight_end_deviation,
    straight_prefix,
)
from streams.sphere_pairs import HeldSpheres
from streams.spheres import object_spheres
from streams.timing import TimedTrajectory, spline_curve, time_parameterize
from streams.trajopt import (
    OPTIMISERS,
    OptimiserBuild,
    OptimiserCache,
    TrajectoryOptimiser,
    TrajOptOptions,
    TransferQuery,
    straight_line,
)
from streams.validate import HeldObject, ValidationReport, configure_world, validate_trajectory

#: Spheres per resting object in the optimiser's obstacle model (8: one per octant, tight
#: enough that a pre-grasp beside a neighbour does not start inside its sphere).
OBSTACLE_SPHERES = 8
#: Samples of the curve checked for a transfer taken without optimisation (the check
#: refines them to 5 mm of TCP travel).
DIRECT_SAMPLES = 16


@dataclass(frozen=True)
class MotionRequest:
    """One synchronous segment. Arms are in the scene's order (its layout); ``retreat`` and
    ``approach`` say per arm whether it leaves or reaches a grasp (missing entries: no)."""

    q_start: FloatArray  # (dof,) [rad]
    q_goal: FloatArray  # (dof,) [rad]
    objects: Mapping[str, ObjectBox]  # resting objects
    held: Mapping[str, HeldObject] = field(default_factory=dict)  # arm -> held object
    retreat: tuple[bool, ...] = ()
    approach: tuple[bool, ...] = ()
    lift: float | None = None  # [m] fixed for every grasp; None: per grasp from clearance


@dataclass(frozen=True)
class MotionResult:
    """``level`` is the strategy that produced the motion (None on failure)."""

    success: bool
    level: str | None
    trajectory: TimedTrajectory | None
    optimisation_time: float  # [s] spent in the trajectory optimiser, all attempts
    planning_time: float  # [s] wall time of the whole call
    attempts: tuple[str, ...]  # "level: outcome" for every strategy tried
    validation: ValidationReport | None = None
    reason: str = ""
    blended: bool = False  # retreat, transfer and approach timed as one blended path
    ipopt_solves: int = 0  # optimiser calls that ran IPOPT (a feasible straight line needs none)
    direct_paths: int = 0  # transfers (or stages) taken straight or lightly bent, not optimised
    sampled_paths: int = 0  # transfers found by the sampling-based planner (OMPL)


@dataclass(frozen=True)
class TransferProblem:
    """The transfer between the lifted configurations, with everything a strategy needs."""

    q_from: FloatArray  # (dof,)
    q_to: FloatArray  # (dof,)
    held: tuple[HeldSpheres, ...]  # per arm
    obstacles: tuple[FloatArray, FloatArray]


class TransferStrategy(Protocol):
    """Produces the transfer as a list of stages (each a ``(k, dof)`` path) or None."""

    @property
    def name(self) -> str: ...

    def __call__(
        self, planner: MotionPlanner, problem: TransferProblem
    ) -> list[FloatArray] | None: ...


#: Joint-space spacing [rad] of the transfer curve's samples in a blended path.
BLEND_SPACING = 0.05
#: Share of a single transfer's length either corner of a blended path may cut.
BLEND_SHARE = 0.45
#: Largest distance [m] of the TCP from the grasp's tool axis, and angle [rad] of the tool
#: from the grasp's orientation, on the straight part of a blended retreat or approach.
STRAIGHT_TOL = 0.002
STRAIGHT_ANGLE_TOL = np.radians(2.0)

#: Clearance [m] a transfer taken without optimisation keeps from resting and held objects
#: on the exact check (the optimiser's sphere model asks 15 mm of its spheres).
DIRECT_MARGIN = 0.005
#: [m] where the two arms' shapes come closer than this at a checked sample of a planned
#: motion, the chords to the neighbouring samples are checked finely (see
#: :func:`streams.validate.validate_trajectory`): between samples at most 5 mm of tool travel
#: apart, two wrists passing a millimetre apart at the samples can touch.
ARM_CLEARANCE = 0.002
#: TCP lifts [m] of the lightly bent paths tried when the straight line is not clear.
DIRECT_LIFTS = (0.05, 0.12)
#: Largest joint distance [rad] of a bent path's via configuration from the mid-point of its
#: ends (farther: another IK branch, not a light bend).
DIRECT_VIA_SPREAD = 1.0
#: Whether a bent direct path is refined by the optimiser (see :class:`MotionPlanner`):
#: on the ``paper`` suite execution 805.0 -> 794.3 s in all (no instance longer), the same
#: actions; on the hard transfers of ``bench_motion.py --hard`` one arm 1.73 -> 1.40 s.
REFINE_BENT = True


class MotionPlanner:
    """Owns the optimiser and scratch collision worlds. The optimiser comes from
    ``optimisers`` (default: the process-wide :data:`streams.trajopt.OPTIMISERS`; built once
    per scene and options, in the background, so constructing a planner costs nothing and
    only the first optimisation may wait for the build; None: a private cache). Worlds:
    ``world`` for the exact validation, ``margin_world`` (objects grown by ``direct_margin``
    [m]) for transfers taken without optimisation.

    ``direct_lifts``: TCP lifts [m] of the bent paths tried after the straight line (empty:
    the straight line only); ``direct=False`` always optimises (the sphere model's own
    straight-line test still applies); ``refine_bent``: a bent path is handed to the optimiser as
    its warm start and the result kept when it executes faster and passes the same check;
    ``shape``: lift heights and blending (:mod:`streams.shape`). Trajectories use the scene's
    ``velocity_safety``."""

    def __init__(
        self,
        ctx: WorldContext,
        options: TrajOptOptions | None = None,
        *,
        direct: bool = True,
        direct_margin: float = DIRECT_MARGIN,
        direct_lifts: Sequence[float] = DIRECT_LIFTS,
        optimisers: OptimiserCache | None = OPTIMISERS,
        shape: ShapeOptions | None = None,
        refine_bent: bool = REFINE_BENT,
    ) -> None:
        if direct_margin < 0.0:
            raise ParameterError(f"direct_margin must be >= 0 [m], got {direct_margin}")
        self.ctx = ctx
        cache = optimisers if optimisers is not None else OptimiserCache()
        self._build = cache.get(ctx, options)
        self._trajopt: TrajectoryOptimiser | None = None
        self.world = ctx.new_world()
        self.margin_world = ctx.new_world(margin=direct_margin)
        self.near_world = ctx.new_world(arm_margin=ARM_CLEARANCE)
        self.direct = direct
        self.direct_lifts = tuple(float(h) for h in direct_lifts)
        self.refine_bent = refine_bent
        self._v = ctx.scene.joint_array("velocity_limit")
        self._a = ctx.scene.joint_array("acceleration_limit")
        self.safety = ctx.scene.velocity_safety
        self.shape = shape if shape is not None else ShapeOptions()
        self.optimisation_time = 0.0  # reset per plan_dual_motion call
        self.ipopt_solves = 0
        self.direct_paths = 0  # transfers taken without optimisation, per plan_dual_motion call
        self.sampled_paths = 0  # transfers found by sampling, per plan_dual_motion call

    @property
    def trajopt(self) -> TrajectoryOptimiser:
        """The trajectory optimiser; the first access waits for its background build."""
        if self._trajopt is None:
            self._trajopt = self._build.get()
        return self._trajopt

    @trajopt.setter
    def trajopt(self, value: TrajectoryOptimiser) -> None:
        self._trajopt = value

    @property
    def limits(self) -> tuple[FloatArray, FloatArray]:
        """Joint velocity [rad/s] and acceleration [rad/s^2] limits ``(dof,)`` each."""
        return self._v, self._a

    @property
    def build(self) -> OptimiserBuild:
        """The optimiser's build: ``ready``, ``build_time`` (CPU [s]), ``waited`` [s]."""
        return self._build

    # -- building blocks used by strategies ----------------------------------------------
    def nominal_duration(self, q_a: FloatArray, q_b: FloatArray) -> float:
        """A generous duration [s] for the optimiser's velocity/acceleration rows."""
        d = np.abs(np.asarray(q_b) - np.asarray(q_a))
        t = np.maximum(d / self._v + self._v / self._a, 2.0 * np.sqrt(d / self._a))
        return float(2.0 * t.max() + 0.5)

    def optimise(
        self,
        problem: TransferProblem,
        q_a: FloatArray,
        q_b: FloatArray,
        warm_start: FloatArray | None = None,
        fixed: tuple[bool, ...] = (),
    ) -> FloatArray | None:
        """One optimised transfer from ``q_a`` to ``q_b`` (sphere model), or None.

        ``fixed``: per arm, whether it waits (missing entries: no). An arm whose two end
        configurations are equal waits too: its joints are held fixed.
        """
        if np.allclose(q_a, q_b):
            return np.stack([q_a, q_b])
        still = self._still(q_a, q_b)
        fixed = tuple(_flag(fixed, i) or still[i] for i in range(len(still)))
        if warm_start is None and self.direct:
            direct = self.direct_path(q_a, q_b, fixed)
            if direct is not None:
                self.direct_paths += 1
                return self.refine_direct(problem, direct, fixed)
        query = TransferQuery(
            q_a, q_b, problem.held, problem.obstacles, self.nominal_duration(q_a, q_b), fixed
        )
        result = self.trajopt.solve(query, warm_start)
        self.optimisation_time += result.solve_time
        self.ipopt_solves += int(result.rounds > 0)
        return result.path if result.success else None

    def refine_direct(
        self, problem: TransferProblem, direct: FloatArray, fixed: tuple[bool, ...] = ()
    ) -> FloatArray:
        """``direct`` (waypoints from :meth:`direct_path`), or when it is bent and
        ``refine_bent`` is on, the optimiser's path warm-started from it if that executes faster
        and its timed curve passes the same check in ``margin_world``."""
        if not self.refine_bent or len(direct) < 3:
            return direct
        path = self.optimise(problem, direct[0], direct[-1], self.warm_start_along(direct), fixed)
        if path is None:
            return direct
        v, a = self.limits
        if time_parameterize(path, v, a).duration >= time_parameterize(direct, v, a).duration:
            return direct
        curve = spline_curve(path, max(DIRECT_SAMPLES, 2 * len(path)))
        if not validate_trajectory(self.ctx, self.margin_world, curve).ok:
            return direct
        return path

    def warm_start_along(self, waypoints: FloatArray) -> FloatArray:
        """The optimiser's knots ``(K, dof)``, evenly spaced along the curve the time
        parameterisation follows through ``waypoints``."""
        K = self._build.options.knots
        dense = spline_curve(waypoints, 4 * K)
        picked: FloatArray = dense[np.round(np.linspace(0.0, 1.0, K) * (4 * K - 1)).astype(int)]
        return picked

    def _still(self, q_a: FloatArray, q_b: FloatArray) -> list[bool]:
        """Per arm: its joints are the same at ``q_a`` and ``q_b``."""
        return [bool(np.allclose(q_a[sl], q_b[sl])) for sl in self.ctx.layout.slices]

    def direct_path(
        self, q_a: FloatArray, q_b: FloatArray, fixed: tuple[bool, ...] = ()
    ) -> FloatArray | None:
        """The straight joint-space line from ``q_a`` to ``q_b``, else a lightly bent path
        through a lifted via configuration (:data:`DIRECT_LIFTS`), as waypoints ``(k, dof)``,
        if the curve the time parameterisation follows through them passes the exact check
        in ``margin_world`` (configured like ``world``); else None. Arms that wait stay put."""
        equal = self._still(q_a, q_b)
        if any(_flag(fixed, i) and not equal[i] for i in range(len(equal))):
            return None
        still = [_flag(fixed, i) or equal[i] for i in range(len(equal))]
        candidates = [np.stack([q_a, q_b])]
        for height in self.direct_lifts:
            via = self.lifted_via(q_a, q_b, height, knots=3)[1]
            for sl, waits in zip(self.ctx.layout.slices, still, strict=True):
                if waits:
                    via[sl] = q_a[sl]
            if np.abs(via - 0.5 * (q_a + q_b)).max() > DIRECT_VIA_SPREAD:
                continue  # another IK branch (a wrist turned round): a long, slow detour
            candidates.append(np.stack([q_a, via, q_b]))
        for waypoints in candidates:
            curve = spline_curve(waypoints, DIRECT_SAMPLES)
            if validate_trajectory(self.ctx, self.margin_world, curve).ok:
                return waypoints
        return None

    def optimise_or_lift(
        self,
        problem: TransferProblem,
        q_a: FloatArray,
        q_b: FloatArray,
        fixed: tuple[bool, ...] = (),
    ) -> FloatArray | None:
        """:meth:`optimise` from the straight line, then from a lifted via-point."""
        path = self.optimise(problem, q_a, q_b, fixed=fixed)
        if path is None:
            path = self.optimise(problem, q_a, q_b, self.lifted_via(q_a, q_b), fixed)
        return path

    def lifted_via(
        self, q_a: FloatArray, q_b: FloatArray, height: float = 0.15, knots: int | None = None
    ) -> FloatArray:
        """A warm start ``(K, dof)`` (``knots``, default the optimiser's) through a via
        configuration whose TCPs are ``height`` [m] above the higher end, half-way between
        the two."""
        K = knots if knots is not None else self._build.options.knots
        mid = 0.5 * (q_a + q_b)
        via = mid.copy()
        for arm in self.ctx.arm_names:
            kin = self.ctx.kinematics[arm]
            sl = self.ctx.layout.slice(arm)
            Ta, Tb = kin.fk_tcp(q_a[sl]), kin.fk_tcp(q_b[sl])
            T = Tb.copy()
            T[:3, 3] = 0.5 * (Ta[:3, 3] + Tb[:3, 3])
            T[2, 3] = max(Ta[2, 3], Tb[2, 3]) + height
            q = tool_pose_ik(kin, T, mid[sl])
            if q is not None:
                via[sl] = q
        half = K // 2
        return np.concatenate(
            [straight_line(q_a, via, half + 1)[:-1], straight_line(via, q_b, K - half)]
        )

    def park(self, arm: str, q_goal_arm: FloatArray, height: float = 0.30) -> FloatArray | None:
        """The untangling park pose of ``arm``: TCP above its own half of the table at the
        goal's ``y``, ``height`` [m] up, with the goal's orientation."""
        kin = self.ctx.kinematics[arm]
        spec = self.ctx.scene.arm(arm)
        T = kin.fk_tcp(q_goal_arm)
        ws = self.ctx.scene.workspace
        base_x = spec.base_xyz[0]
        T[0, 3] = base_x + np.sign(-base_x) * 0.40
        T[1, 3] = float(np.clip(T[1, 3], *ws.y))
        T[2, 3] = height
        return tool_pose_ik(kin, T, q_goal_arm)

    def depth(self, q: FloatArray) -> FloatArray:
        """``(arms,)``: how far [m] each arm's TCP reaches past the table centre line, away
        from its own base."""
        out = np.zeros(len(self.ctx.layout))
        for i, arm in enumerate(self.ctx.arm_names):
            p = self.ctx.kinematics[arm].fk_tcp(self.ctx.layout.part(q, arm))[:3, 3]
            out[i] = p[0] * np.sign(-self.ctx.scene.arm(arm).base_xyz[0])
        return out

    # -- assembling ------------------------------------------------------------------------
    def lifts(
        self, request: MotionRequest, fixed: float | None = None
    ) -> tuple[list[float], list[float]]:
        """Per arm, the lift [m] of its retreat and of its approach: ``fixed`` (default the
        request's ``lift``) for every grasp, or, when both are None, from the clearance of
        each grasp's neighbours (the shape's default lift where that is unusable)."""
        lift = fixed if fixed is not None else request.lift
        n = len(self.ctx.layout)
        if lift is not None:
            return [lift] * n, [lift] * n
        out: tuple[list[float], list[float]] = ([], [])
        for arm in self.ctx.arm_names:
            kin = self.ctx.kinematics[arm]
            sl = self.ctx.layout.slice(arm)
            h = request.held.get(arm)
            ends = (request.q_start[sl], request.q_goal[sl])
            xy = [kin.fk_tcp(q)[:2, 3] for q in ends]
            for side, q in enumerate(ends):
                held = None
                if h is not None:
                    held = ObjectBox(kin.fk_tool0(q) @ h.T_tool0_obj, h.size)
                found = clearance_lift(
                    kin.fk_tcp(q), request.objects, held, self.shape, xy[1 - side]
                )
                out[side].append(found if found is not None else self.shape.default_lift)
        return out

    def phases(
        self, request: MotionRequest, one_at_a_time: bool = False, lift: float | None = None
    ) -> tuple[list[FloatArray], list[FloatArray]] | None:
        """Retreat and approach as lists of paths ``(n, dof)``: one synchronised (padded) path
        each, or, with ``one_at_a_time``, one arm's after the other's (layout order); None if
        a straight tool move is unreachable. ``lift`` [m]: fixed for every grasp (default:
        :meth:`lifts`)."""
        ret, app = [], []
        up, down = self.lifts(request, lift)
        step = self.shape.step
        for i, arm in enumerate(self.ctx.arm_names):
            kin = self.ctx.kinematics[arm]
            sl = self.ctx.layout.slice(arm)
            q0, q1 = request.q_start[sl], request.q_goal[sl]
            r = straight_tool_move(kin, q0, -up[i], step) if _flag(request.retreat, i) else q0[None]
            a = (
                straight_tool_move(kin, q1, -down[i], step)
                if _flag(request.approach, i)
                else q1[None]
            )
            if r is None or a is None:
                return None
            ret.append(r)
            app.append(a[::-1])
        if one_at_a_time:
            return _chain(ret), _chain(app)
        return [_sync(ret)], [_sync(app)]

    def transfer_problem(
        self, request: MotionRequest, q_from: FloatArray, q_to: FloatArray
    ) -> TransferProblem:
        o = self._build.options
        held = []
        for arm in self.ctx.arm_names:
            h = request.held.get(arm)
            if h is None:
                held.append(HeldSpheres.empty())
            else:
                c, r = object_spheres(h.size, h.T_tool0_obj, o.held_slots)
                held.append(HeldSpheres(c, r))
        cs, rs = [], []
        for box in request.objects.values():
            c, r = object_spheres(box.size, box.T_world_obj, OBSTACLE_SPHERES)
            cs.append(c)
            rs.append(r)
        obstacles = (
            (np.concatenate(cs), np.concatenate(rs)) if cs else (np.zeros((0, 3)), np.zeros(0))
        )
        return TransferProblem(q_from, q_to, tuple(held), obstacles)

    def assemble(
        self,
        retreat: Sequence[FloatArray],
        stages: Sequence[FloatArray],
        approach: Sequence[FloatArray],
    ) -> TimedTrajectory:
        """The paths in order, each timed rest to rest."""
        traj = self.timed(retreat[0])
        for path in (*retreat[1:], *stages, *approach):
            traj = traj.then(self.timed(path))
        return traj

    def timed(self, path: FloatArray, path_speed: FloatArray | None = None) -> TimedTrajectory:
        """``path`` ``(n, dof)`` timed rest to rest at the scene's ``velocity_safety``."""
        return time_parameterize(path, self._v, self._a, safety=self.safety, path_speed=path_speed)

    def blend(
        self,
        request: MotionRequest,
        retreat: Sequence[FloatArray],
        stages: Sequence[FloatArray],
        approach: Sequence[FloatArray],
    ) -> TimedTrajectory | None:
        """The motion with the corners at the lifted configurations rounded into the transfer
        (see :mod:`streams.shape`), the first and last stage timed each as one path with
        the retreat and approach, or None when neither end can blend (a chained retreat or
        approach, or one no longer than the straight part) or the blended path leaves the
        straight tool axis at a grasp."""
        if not self.shape.blend:
            return None
        straight = self.shape.straight
        ctx = self.ctx
        kins = {i: (ctx.kinematics[a], ctx.layout.slice(a)) for i, a in enumerate(ctx.arm_names)}
        up = {i: kins[i] for i in kins if _flag(request.retreat, i)}
        down = {i: kins[i] for i in kins if _flag(request.approach, i)}
        r_keep = straight_prefix(up, retreat[0], straight) if up and len(retreat) == 1 else None
        a_path = approach[-1][::-1]
        a_keep = straight_prefix(down, a_path, straight) if down and len(approach) == 1 else None
        if r_keep is None and a_keep is None:
            return None
        curves = [self._dense(stage) for stage in stages]
        share = BLEND_SHARE if len(curves) == 1 else 1.0
        first_len, last_len = (float(arc_length(curves[k])[-1]) for k in (0, -1))
        if a_keep is not None:
            curves[-1] = round_corner(
                a_path, a_keep, curves[-1][::-1], share * last_len, self.shape.reach
            )[::-1]
        if r_keep is not None:
            curves[0] = round_corner(
                retreat[0], r_keep, curves[0], share * first_len, self.shape.reach
            )
        caps = [np.full(len(c), np.inf) for c in curves]
        if r_keep is not None:
            caps[0][: r_keep + 1] = self._tcp_cap(retreat[0][: r_keep + 1], up)
        if a_keep is not None:
            tail = self._tcp_cap(a_path[: a_keep + 1], down)[::-1]
            caps[-1][-(a_keep + 1) :] = np.minimum(caps[-1][-(a_keep + 1) :], tail)
        pieces: list[TimedTrajectory] = []
        if r_keep is None:
            pieces.extend(self.timed(p) for p in retreat)
        pieces.extend(self.timed(c, cap) for c, cap in zip(curves, caps, strict=True))
        if a_keep is None:
            pieces.extend(self.timed(p) for p in approach)
        traj = pieces[0]
        for piece in pieces[1:]:
            traj = traj.then(piece)
        for flags, q_grasp, q in ((up, request.q_start, traj.q), (down, request.q_goal,
                                                                   traj.q[::-1])):  # fmt: skip
            for kin, sl in flags.values():
                lateral, angle = straight_end_deviation(kin, q[:, sl], q_grasp[sl], straight)
                if lateral > STRAIGHT_TOL or angle > STRAIGHT_ANGLE_TOL:
                    return None
        return traj

    def _dense(self, stage: FloatArray) -> FloatArray:
        """The curve the timing follows through ``stage``'s waypoints, densely sampled."""
        length = float(np.linalg.norm(np.diff(stage, axis=0), axis=1).sum())
        return spline_curve(stage, max(DIRECT_SAMPLES, int(np.ceil(length / BLEND_SPACING)) + 1))

    def _tcp_cap(self, path: FloatArray, arms: Mapping[int, tuple[ArmKinematics, slice]]
                 ) -> FloatArray:  # fmt: skip
        """Per waypoint of ``path`` ``(m, dof)``: the path speed [rad/s] at which no TCP of
        ``arms`` moves faster than the shape's ``grasp_speed`` (the steeper adjacent chord)."""
        dq = np.linalg.norm(np.diff(path, axis=0), axis=1)
        ratio = np.zeros(len(dq))
        for kin, sl in arms.values():
            p = np.stack([kin.fk_tcp(q)[:3, 3] for q in path[:, sl]])
            dp = np.linalg.norm(np.diff(p, axis=0), axis=1)
            ratio = np.maximum(ratio, dp / np.maximum(dq, 1e-12))
        chord = self.shape.grasp_speed / np.maximum(ratio, 1e-12)
        out = np.full(len(path), np.inf)
        out[:-1] = chord
        out[1:] = np.minimum(out[1:], chord)
        return out


def _flag(flags: tuple[bool, ...], i: int) -> bool:
    """Entry ``i`` of a per-arm flag tuple (missing entries are False)."""
    return i < len(flags) and flags[i]


def _only(i: int, n: int) -> tuple[bool, ...]:
    """Per-arm ``fixed`` flags with every arm but ``i`` waiting."""
    return tuple(k != i for k in range(n))


def _sync(paths: list[FloatArray]) -> FloatArray:
    """Per-arm paths ``(n_i, arm dof)`` as one ``(max n, dof)`` path: shorter ones are
    resampled (linearly between their waypoints), so every arm starts and ends together."""
    n = max(len(p) for p in paths)
    x = np.linspace(0.0, 1.0, n)
    out = []
    for p in paths:
        if len(p) == 1:
            out.append(np.repeat(p, n, axis=0))
            continue
        xp = np.linspace(0.0, 1.0, len(p))
        out.append(np.stack([np.interp(x, xp, p[:, j]) for j in range(p.shape[1])], axis=1))
    return np.concatenate(out, axis=1)


def _chain(paths: list[FloatArray]) -> list[FloatArray]:
    """Per-arm paths ``(n_i, arm dof)`` as one ``(n_i, dof)`` path per arm: the arms move one
    after the other in layout order, the others waiting where they are (each timed rest to
    rest)."""
    out = []
    for k, path in enumerate(paths):
        n = len(path)
        done = [np.repeat(p[-1:], n, axis=0) for p in paths[:k]]
        waiting = [np.repeat(p[:1], n, axis=0) for p in paths[k + 1 :]]
        out.append(np.concatenate([*done, path, *waiting], axis=1))
    return out


# -- strategies ---------------------------------------------------------------------------
#: A further attempt at a transfer: the optimised path, or None.
Rescue = Callable[["MotionPlanner", "TransferProblem"], "FloatArray | None"]


@dataclass(frozen=True)
class PlainStrategy:
    """One synchronous optimisation: straight-line warm start, then ``rescue`` (if any),
    then a lifted via-point.

    ``rescue`` is tried between the two warm starts; SDAR-M's is
    :func:`streams.sampling.sampled_warm_start` (a sampled path warm-starts the optimiser).
    It should succeed with an optimised path or not at all: a failure of this rung is what
    lets SDAR-M try another grounding first."""

    name: str = "plain"
    lifted_warm_start: bool = True
    rescue: Rescue | None = None

    def __call__(self, planner: MotionPlanner, problem: TransferProblem) -> list[FloatArray] | None:
        path = planner.optimise(problem, problem.q_from, problem.q_to)
        if path is None and self.rescue is not None:
            path = self.rescue(planner, problem)
        if path is None and self.lifted_warm_start:
            ws = planner.lifted_via(problem.q_from, problem.q_to)
            path = planner.optimise(problem, problem.q_from, problem.q_to, ws)
        return None if path is None else [path]


@dataclass(frozen=True)
class UntangleStrategy:
    """Arm untangling (see the module docstring and ``docs/arm_untangling.md``)."""

    name: str = "untangle"
    park_height: float = 0.30  # [m]

    def __call__(self, planner: MotionPlanner, problem: TransferProblem) -> list[FloatArray] | None:
        ctx = planner.ctx
        order = np.argsort(-planner.depth(problem.q_from))
        n = len(ctx.layout)
        for y in (int(k) for k in order):
            arm = ctx.arm_names[y]
            sl = ctx.layout.slice(y)
            park = planner.park(arm, problem.q_to[sl], self.park_height)
            if park is None:
                continue
            q_mid = problem.q_to.copy()
            q_mid[sl] = park
            first = planner.optimise_or_lift(problem, problem.q_from, q_mid)
            if first is None:
                continue
            second = planner.optimise(problem, q_mid, problem.q_to, fixed=_only(y, n))
            if second is not None:
                return [first, second]
        return None


@dataclass(frozen=True)
class SequentialStrategy:
    """One arm at a time: retract the first to home, move the others, move the first."""

    name: str = "sequential"

    def __call__(self, planner: MotionPlanner, problem: TransferProblem) -> list[FloatArray] | None:
        ctx = planner.ctx
        layout = ctx.layout
        n = len(layout)
        order = np.argsort(-planner.depth(problem.q_from))
        for f in (int(k) for k in order):
            first, others = _only(f, n), tuple(k == f for k in range(n))
            q1 = layout.replace(problem.q_from, f, ctx.home(ctx.arm_names[f]))
            q2 = layout.replace(problem.q_to, f, q1[layout.slice(f)])
            stages = []
            for qa, qb, fixed in ((problem.q_from, q1, first), (q1, q2, others),
                                  (q2, problem.q_to, first)):  # fmt: skip
                path = planner.optimise_or_lift(problem, qa, qb, fixed)
                if path is None:
                    break
                stages.append(path)
            else:
                return stages
        return None


@dataclass(frozen=True)
class OneArmStrategy:
    """The baseline motion planner's transfer: the arms move one after the other, each
    straight to its goal while the other waits; an arm bound for its home pose moves first,
    otherwise the arm reaching deeper into the other's half."""

    name: str = "one-arm"

    def __call__(self, planner: MotionPlanner, problem: TransferProblem) -> list[FloatArray] | None:
        ctx = planner.ctx
        layout = ctx.layout
        n = len(layout)
        moving = [
            i
            for i in range(n)
            if not np.allclose(layout.part(problem.q_from, i), layout.part(problem.q_to, i))
        ]
        depth = planner.depth(problem.q_from)
        homeward = {
            i: bool(np.allclose(layout.part(problem.q_to, i), ctx.home(ctx.arm_names[i])))
            for i in moving
        }
        moving.sort(key=lambda i: (not homeward[i], -depth[i]))
        stages: list[FloatArray] = []
        q = problem.q_from.copy()
        for i in moving:
            q_next = layout.replace(q, i, layout.part(problem.q_to, i))
            path = planner.optimise_or_lift(problem, q, q_next, _only(i, n))
            if path is None:
                return None
            stages.append(path)
            q = q_next
        return stages or [np.stack([problem.q_from, problem.q_to])]


def default_strategies(
    fallbacks: bool = True, sequential_only: bool = False
) -> tuple[TransferStrategy, ...]:
    """The ladder of Alg. 2: plain, untangle, sequential (or a part of it).
    ``sequential_only``: the baseline motion planner (:class:`OneArmStrategy`). The ladder
    with a sampled first rung is :func:`streams.sampling.sampled_strategies`."""
    if sequential_only:
        return (OneArmStrategy(),)
    if not fallbacks:
        return (PlainStrategy(),)
    return (PlainStrategy(), UntangleStrategy(), SequentialStrategy())


def _clear_phases(
    planner: MotionPlanner, request: MotionRequest, one_at_a_time: bool
) -> tuple[list[FloatArray], list[FloatArray]] | str:
    """Retreat and approach that are collision-free on their own (every strategy shares
    them): synchronised, else one arm after the other; or why there are none."""
    reason = "approach or retreat unreachable"
    lifts = (None,) if request.lift is not None else (None, planner.shape.default_lift)
    for lift in lifts:  # the clearance lifts, then the fixed default
        for chained in dict.fromkeys((one_at_a_time, True)):
            phases = planner.phases(request, one_at_a_time=chained, lift=lift)
            if phases is None:
                break
            for label, paths in zip(("retreat", "approach"), phases, strict=True):
                report = validate_trajectory(
                    planner.ctx, planner.world, np.concatenate(paths), near=planner.near_world
                )
                if not report.ok:
                    reason = f"{label} collides ({report.reason})"
                    break
            else:
                return phases
    return reason


def plan_dual_motion(
    planner: MotionPlanner,
    request: MotionRequest,
    fallbacks: bool = True,
    sequential_only: bool = False,
    strategies: Sequence[TransferStrategy] | None = None,
) -> MotionResult:
    """Plan one synchronous segment; see the module docstring."""
    t0 = time.perf_counter()
    planner.optimisation_time = 0.0
    planner.ipopt_solves = 0
    planner.direct_paths = 0
    planner.sampled_paths = 0
    ladder = tuple(strategies) if strategies is not None else default_strategies(
        fallbacks, sequential_only)  # fmt: skip
    ctx = planner.ctx
    q_start = np.asarray(request.q_start, dtype=np.float64)
    configure_world(ctx, planner.world, request.objects, request.held, q_start)
    configure_world(ctx, planner.margin_world, request.objects, request.held, q_start)
    configure_world(ctx, planner.near_world, request.objects, request.held, q_start)
    phases = _clear_phases(planner, request, sequential_only and strategies is None)
    if isinstance(phases, str):
        return MotionResult(False, None, None, 0.0, time.perf_counter() - t0, (),
                            reason=phases)  # fmt: skip
    retreat, approach = phases
    problem = planner.transfer_problem(request, retreat[-1][-1], approach[0][0])
    attempts: list[str] = []
    report: ValidationReport | None = None

    def succeeded(
        level: str, traj: TimedTrajectory, valid: ValidationReport, blended: bool
    ) -> MotionResult:
        return MotionResult(True, level, traj, planner.optimisation_time,
                            time.perf_counter() - t0, tuple(attempts), valid,
                            ipopt_solves=planner.ipopt_solves, direct_paths=planner.direct_paths,
                            sampled_paths=planner.sampled_paths, blended=blended)  # fmt: skip

    for strategy in ladder:
        stages = strategy(planner, problem)
        if stages is None:
            attempts.append(f"{strategy.name}: optimisation failed")
            continue
        blended = planner.blend(request, retreat, stages, approach)
        if blended is not None:
            report = validate_trajectory(
                ctx, planner.world, blended.q, blended.t, near=planner.near_world
            )
            if report.ok:
                attempts.append(f"{strategy.name}: ok (blended)")
                return succeeded(strategy.name, blended, report, blended=True)
        traj = planner.assemble(retreat, stages, approach)
        report = validate_trajectory(ctx, planner.world, traj.q, traj.t, near=planner.near_world)
        if report.ok:
            attempts.append(f"{strategy.name}: ok")
            return succeeded(strategy.name, traj, report, blended=False)
        attempts.append(
            f"{strategy.name}: validation failed ({report.reason} at sample {report.index}"
            + "".join(f", {p.first}-{p.second}" for p in report.pairs[:2])
            + ")"
        )
    return MotionResult(False, None, None, planner.optimisation_time, time.perf_counter() - t0,
                        tuple(attempts), report, reason="; ".join(attempts),
                        ipopt_solves=planner.ipopt_solves,
                        direct_paths=planner.direct_paths,
                        sampled_paths=planner.sampled_paths)  # fmt: skip
