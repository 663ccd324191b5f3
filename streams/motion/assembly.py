"""The timed motion of a segment from its retreat, transfer stages and approach: each path
timed rest to rest, or the corners at the lifted configurations rounded into the transfer
and the whole timed as one blended path (:mod:`streams.motion.shape`), without stopping at
the pre-grasp points."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.transforms import FloatArray
from streams.context import WorldContext
from streams.motion.records import MotionRequest, flag
from streams.motion.shape import (
    ShapeOptions,
    arc_length,
    round_corner,
    straight_end_deviation,
    straight_prefix,
)
from streams.motion.timing import TimedTrajectory, spline_curve, time_parameterize
from streams.motion.transfers import DIRECT_SAMPLES

#: Joint-space spacing [rad] of the transfer curve's samples in a blended path.
BLEND_SPACING = 0.05
#: Share of a single transfer's length either corner of a blended path may cut.
BLEND_SHARE = 0.45
#: Largest distance [m] of the TCP from the grasp's tool axis, and angle [rad] of the tool
#: from the grasp's orientation, on the straight part of a blended retreat or approach.
STRAIGHT_TOL = 0.002
STRAIGHT_ANGLE_TOL = np.radians(2.0)


class MotionAssembly:
    """Times the paths of a segment at the scene's limits and ``velocity_safety``, blended
    as ``shape`` says."""

    def __init__(self, ctx: WorldContext, shape: ShapeOptions) -> None:
        self.ctx = ctx
        self.shape = shape
        self._v = ctx.scene.joint_array("velocity_limit")
        self._a = ctx.scene.joint_array("acceleration_limit")
        self.safety = ctx.scene.velocity_safety

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
        (see :mod:`streams.motion.shape`), the first and last stage timed each as one path with
        the retreat and approach, or None when neither end can blend (a chained retreat or
        approach, or one no longer than the straight part) or the blended path leaves the
        straight tool axis at a grasp."""
        if not self.shape.blend:
            return None
        straight = self.shape.straight
        ctx = self.ctx
        kins = {i: (ctx.kinematics[a], ctx.layout.slice(a)) for i, a in enumerate(ctx.arm_names)}
        up = {i: kins[i] for i in kins if flag(request.retreat, i)}
        down = {i: kins[i] for i in kins if flag(request.approach, i)}
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
