"""The building blocks of a transfer that the strategies share: one optimised transfer (after
the straight or lightly bent direct path where that is clear), the warm starts (a lifted
via-point, a curve's knots), and the untangling geometry (park pose, reach depth), for arms
placed anywhere around the table (each by its base pose and the direction it faces).

A :class:`Transfers` serves one motion call: the planner makes it with that call's
:class:`~streams.motion.records.MotionTally`, and every optimisation, direct path and
sampled path is counted there.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from sdar_tamp.world.collision import CollisionWorld
from sdar_tamp.world.transforms import FloatArray
from streams.context import WorldContext
from streams.motion.cartesian import tool_pose_ik
from streams.motion.exact_check import validate_trajectory
from streams.motion.optimiser import TrajectoryOptimiser
from streams.motion.optimiser_build import OptimiserBuild
from streams.motion.optimiser_records import TransferQuery
from streams.motion.records import MotionTally, TransferProblem, flag
from streams.motion.subsets import MIN_ARMS, SubsetOptimisers, joint_columns, waiting_spheres
from streams.motion.timing import spline_curve, time_parameterize
from streams.motion.waypoints import straight_line

#: Samples of the curve checked for a transfer taken without optimisation (the check
#: refines them to 5 mm of TCP travel).
DIRECT_SAMPLES = 16
#: TCP lifts [m] of the lightly bent paths tried when the straight line is not clear.
DIRECT_LIFTS = (0.05, 0.12)
#: Largest joint distance [rad] of a bent path's via configuration from the mid-point of its
#: ends (farther: another IK branch, not a light bend).
DIRECT_VIA_SPREAD = 1.0
#: Whether a bent direct path is refined by the optimiser (see :class:`Transfers`):
#: on the ``paper`` suite execution 805.0 -> 794.3 s in all (no instance longer), the same
#: actions; on the hard transfers of ``bench_motion.py --hard`` one arm 1.73 -> 1.40 s.
REFINE_BENT = True
#: Distance [m] of an untangling park pose's TCP in front of its arm's base.
PARK_REACH = 0.40


class Transfers:
    """Optimised and direct transfers for one motion call, counted in ``tally``.

    ``build``: the trajectory optimiser (its first use waits for the background build);
    ``margin_world``: the exact check's world for transfers taken without optimisation
    (configured for the segment by the caller); ``direct_lifts``: TCP lifts [m] of the bent
    paths tried after the straight line (empty: the straight line only); ``direct=False``
    always optimises (the sphere model's own straight-line test still applies);
    ``refine_bent``: a bent path is handed to the optimiser as its warm start and the result
    kept when it executes faster and passes the same check. ``subsets``: with
    :data:`~streams.motion.subsets.MIN_ARMS` arms or more, a transfer in which some arms wait
    is optimised over the moving arms alone (:mod:`streams.motion.subsets`); None: always over
    every arm."""

    def __init__(
        self,
        ctx: WorldContext,
        build: OptimiserBuild,
        margin_world: CollisionWorld,
        tally: MotionTally,
        *,
        direct: bool = True,
        direct_lifts: Sequence[float] = DIRECT_LIFTS,
        refine_bent: bool = REFINE_BENT,
        subsets: SubsetOptimisers | None = None,
    ) -> None:
        self.ctx = ctx
        self.subsets = subsets
        self.build = build
        self.margin_world = margin_world
        self.tally = tally
        self.direct = direct
        self.direct_lifts = tuple(float(h) for h in direct_lifts)
        self.refine_bent = refine_bent
        self._v = ctx.scene.joint_array("velocity_limit")
        self._a = ctx.scene.joint_array("acceleration_limit")

    @property
    def trajopt(self) -> TrajectoryOptimiser:
        """The trajectory optimiser; the first access waits for its background build."""
        return self.build.get()

    @property
    def limits(self) -> tuple[FloatArray, FloatArray]:
        """Joint velocity [rad/s] and acceleration [rad/s^2] limits ``(dof,)`` each."""
        return self._v, self._a

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
        fixed = tuple(flag(fixed, i) or still[i] for i in range(len(still)))
        if warm_start is None and self.direct:
            direct = self.direct_path(q_a, q_b, fixed)
            if direct is not None:
                self.tally.direct_paths += 1
                return self.refine_direct(problem, direct, fixed)
        moving = tuple(i for i, waits in enumerate(fixed) if not waits)
        if self._by_subset(q_a, q_b, moving):
            return self._optimise_moving(problem, q_a, q_b, warm_start, moving)
        query = TransferQuery(
            q_a, q_b, problem.held, problem.obstacles, self.nominal_duration(q_a, q_b), fixed
        )
        result = self.trajopt.solve(query, warm_start)
        self.tally.optimisation_time += result.solve_time
        self.tally.ipopt_solves += int(result.rounds > 0)
        return result.path if result.success else None

    def _by_subset(self, q_a: FloatArray, q_b: FloatArray, moving: tuple[int, ...]) -> bool:
        """Whether the transfer is optimised over the ``moving`` arms alone: a cell of
        :data:`~streams.motion.subsets.MIN_ARMS` arms or more, some arms waiting, and those
        at the same joints at both ends."""
        n = len(self.ctx.layout)
        if self.subsets is None or n < MIN_ARMS or not 0 < len(moving) < n:
            return False
        waiting = [sl for i, sl in enumerate(self.ctx.layout.slices) if i not in moving]
        return all(np.allclose(q_a[sl], q_b[sl]) for sl in waiting)

    def _optimise_moving(
        self,
        problem: TransferProblem,
        q_a: FloatArray,
        q_b: FloatArray,
        warm_start: FloatArray | None,
        moving: tuple[int, ...],
    ) -> FloatArray | None:
        """The optimised transfer of the ``moving`` arms among the waiting ones (their spheres
        as obstacles), every arm's joints in the path ``(K, dof)``."""
        assert self.subsets is not None
        _, build = self.subsets.get(moving)
        cols = joint_columns(self.ctx, moving)
        waiting = tuple(i for i in range(len(self.ctx.layout)) if i not in moving)
        wc, wr = waiting_spheres(self.ctx, q_a, problem.held, waiting)
        oc, orad = problem.obstacles
        query = TransferQuery(
            q_a[cols], q_b[cols], tuple(problem.held[i] for i in moving),
            (np.concatenate([oc, wc]), np.concatenate([orad, wr])),
            self.nominal_duration(q_a, q_b),
        )  # fmt: skip
        result = build.get().solve(query, None if warm_start is None else warm_start[:, cols])
        self.tally.optimisation_time += result.solve_time
        self.tally.ipopt_solves += int(result.rounds > 0)
        if not result.success:
            return None
        path = np.tile(np.asarray(q_a, dtype=np.float64), (len(result.path), 1))
        path[:, cols] = result.path
        return path

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
        K = self.build.options.knots
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
        if any(flag(fixed, i) and not equal[i] for i in range(len(equal))):
            return None
        still = [flag(fixed, i) or equal[i] for i in range(len(equal))]
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
        K = knots if knots is not None else self.build.options.knots
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
        """The untangling park pose of ``arm``: its TCP :data:`PARK_REACH` [m] in front of its
        base along the direction it faces (on its own side of the table), across that
        direction at its goal's offset from the base (the point clipped to the workspace),
        ``height`` [m] up, with the goal's orientation; the IK branch nearest the goal's
        joints. For two arms facing each other across x this is ``x = base_x +- 0.40``,
        ``y`` the goal's (clipped)."""
        kin = self.ctx.kinematics[arm]
        T = kin.fk_tcp(q_goal_arm)
        base, facing = self._base_xy(arm), self._facing(arm)
        across = np.array([-facing[1], facing[0]])
        offset = float((T[:2, 3] - base) @ across)
        xy = base + PARK_REACH * facing + offset * across
        ws = self.ctx.scene.workspace
        T[0, 3] = float(np.clip(xy[0], *ws.x))
        T[1, 3] = float(np.clip(xy[1], *ws.y))
        T[2, 3] = height
        return tool_pose_ik(kin, T, q_goal_arm)

    def depth(self, q: FloatArray) -> FloatArray:
        """``(arms,)``: how far [m] each arm's TCP reaches past the table centre, along the
        direction its base faces (away from its own base; for two arms facing each other
        across x: past the centre line ``x = 0`` into the other arm's half)."""
        out = np.zeros(len(self.ctx.layout))
        for i, arm in enumerate(self.ctx.arm_names):
            p = self.ctx.kinematics[arm].fk_tcp(self.ctx.layout.part(q, arm))[:3, 3]
            out[i] = float(p[:2] @ self._facing(arm))
        return out

    def _base_xy(self, arm: str) -> FloatArray:
        return np.array(self.ctx.scene.arm(arm).base_xyz[:2], dtype=np.float64)

    def _facing(self, arm: str) -> FloatArray:
        """The unit direction ``(2,)`` the base of ``arm`` faces on the table (its x axis,
        by its yaw), rounded to the axes where it is within 1e-9 of one."""
        yaw = self.ctx.scene.arm(arm).base_yaw
        f = np.array([np.cos(yaw), np.sin(yaw)])
        f[np.abs(f) < 1e-9] = 0.0
        out: FloatArray = f / np.linalg.norm(f)
        return out
