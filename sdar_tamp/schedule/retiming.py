"""One arm's motion re-timed for that arm alone, on the scheduler's grid.

A synchronous motion is timed for every arm together: its profile is as fast as the arm with
the hardest path allows, so the other arms move slower than their own limits permit. Alone, an
arm's share of the motion can be timed again along the same geometric path:

* with a :data:`PathTimer` (a time-optimal parameterisation under the arm's velocity and
  acceleration limits, e.g. :func:`streams.motion.timing.time_parameterize`, passed in by the
  application), the path through the motion's samples (thinned to at least ``spacing`` [rad]
  apart, so that the slow samples near the ends do not bend the path) is timed from rest to
  rest; within ``straight`` [m] of the tool's travel from a gripper event the tool centre
  point moves at most ``grasp_speed`` [m/s], as in the synchronous motion;
* without one, the motion through all its samples is played uniformly faster
  (:func:`~sdar_tamp.schedule.spline.retime`).

:meth:`ArmRetimer.retime` returns whichever of these and the synchronous pace
(:func:`on_ticks`) is shortest, sampled one ``tick`` apart. A path timer's samples, at most one
tick apart, are placed one tick apart: every step gets longer, so velocities and accelerations
(divided differences, with the arm at rest before and after) only shrink.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.schedule.spline import retime
from sdar_tamp.world.transforms import FloatArray


class ToolKinematics(Protocol):
    """What re-timing reads of an arm's kinematics (an
    :class:`~sdar_tamp.world.kinematics.ArmKinematics` is one): the flange poses
    ``(m, 4, 4)`` at configurations ``(m, k)`` and the tool centre point in the flange frame."""

    def fk_batch(self, q: FloatArray) -> FloatArray: ...

    @property
    def T_tool0_tcp(self) -> FloatArray: ...


#: ``(path (m, k) [rad], v_max (k,) [rad/s], a_max (k,) [rad/s^2], path_speed (m,) [rad/s] or
#: None, dt [s]) -> (t (n + 1,), q (n + 1, k))``: a rest-to-rest motion along the path, every
#: step at most ``dt``, starting at ``t = 0``; ``path_speed`` caps the joint-space path speed at
#: each waypoint (``inf``: none).
PathTimer = Callable[
    [FloatArray, FloatArray, FloatArray, FloatArray | None, float], tuple[FloatArray, FloatArray]
]


def on_ticks(
    t: FloatArray, q: FloatArray, tick: float, v_max: FloatArray, a_max: FloatArray
) -> FloatArray:
    """The rest-to-rest motion ``q`` ``(m, k)`` at ``t`` ``(m,)`` on a grid of ``tick`` [s].

    When no sampling step exceeds ``tick``, the same samples one tick apart: every step gets
    ``c = tick / h >= 1`` times longer, velocities shrink by ``1 / c`` and accelerations
    (second divided differences, with the arm at rest one tick before and after) by at least
    as much, so the motion meets every limit the original met. Otherwise the smooth motion
    through the samples at its own pace or slower, within ``v_max`` [rad/s] and ``a_max``
    [rad/s^2] ``(k,)`` (:func:`~sdar_tamp.schedule.spline.retime`)."""
    if np.all(np.diff(t) <= tick + 1e-12):
        return np.array(q)
    return retime(t, q, v_max, a_max, tick, max_rate=1.0)


def thin(q: FloatArray, spacing: float) -> FloatArray:
    """The rows of ``q`` ``(m, k)`` at least ``spacing`` [rad] apart (Euclidean), walking from
    the first; the last row is always kept (replacing the one before it when that is closer)."""
    keep = [0]
    for i in range(1, len(q) - 1):
        if np.linalg.norm(q[i] - q[keep[-1]]) >= spacing:
            keep.append(i)
    if len(q) > 1:
        if len(keep) > 1 and np.linalg.norm(q[-1] - q[keep[-1]]) < spacing:
            keep[-1] = len(q) - 1
        else:
            keep.append(len(q) - 1)
    return np.array(q[keep])


@dataclass(frozen=True)
class ArmRetimer:
    """Re-times one arm's rest-to-rest motions (see the module docstring).

    ``kinematics``: the arm's (for the tool centre point near gripper events); ``v_max``
    [rad/s] and ``a_max`` [rad/s^2] ``(k,)``: its limits; ``tick`` [s]: the grid; ``timer``:
    the path timer (None: uniform re-timing only); ``straight`` [m] and ``grasp_speed``
    [m/s]: the slow tool travel at a gripper event; ``spacing`` [rad]: the least distance of
    the path's waypoints."""

    kinematics: ToolKinematics
    v_max: FloatArray
    a_max: FloatArray
    tick: float
    timer: PathTimer | None = None
    straight: float = 0.02
    grasp_speed: float = 0.25
    spacing: float = 0.01

    def __post_init__(self) -> None:
        for name in ("tick", "straight", "grasp_speed", "spacing"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0.0):
                raise ParameterError(f"{name}: expected a finite number > 0, got {value!r}")

    def retime(self, t: FloatArray, q: FloatArray, slow_start: bool, slow_end: bool) -> FloatArray:
        """The motion ``q`` ``(m, k)`` at ``t`` ``(m,)`` as samples one tick apart ``(n + 1,
        k)``, as fast as the arm alone may go; ``slow_start`` / ``slow_end``: the motion leaves
        / reaches a gripper event (the tool moves slowly there)."""
        best = on_ticks(t, q, self.tick, self.v_max, self.a_max)
        if self.timer is None:
            fast = retime(t, q, self.v_max, self.a_max, self.tick)
            return fast if len(fast) < len(best) else best
        path = thin(q, self.spacing)
        if len(path) < 2:
            return best
        caps = self.tool_caps(path, slow_start, slow_end)
        _, samples = self.timer(path, self.v_max, self.a_max, caps, self.tick)
        if len(samples) < len(best):
            samples = np.array(samples)
            samples[0], samples[-1] = q[0], q[-1]
            return samples
        return best

    def tool_caps(self, path: FloatArray, slow_start: bool, slow_end: bool) -> FloatArray | None:
        """Per waypoint of ``path`` ``(m, k)``: the joint-space path speed [rad/s] at which the
        tool centre point moves at most ``grasp_speed`` on the segments within ``straight`` of
        a slow end (``inf`` elsewhere); None when neither end is slow."""
        if not (slow_start or slow_end):
            return None
        p = (self.kinematics.fk_batch(path) @ self.kinematics.T_tool0_tcp)[:, :3, 3]
        dp = np.linalg.norm(np.diff(p, axis=0), axis=1)
        dq = np.linalg.norm(np.diff(path, axis=0), axis=1)
        travel = np.concatenate([[0.0], np.cumsum(dp)])
        near = np.zeros(len(dp), dtype=bool)
        if slow_start:
            near |= travel[:-1] < self.straight
        if slow_end:
            near |= travel[-1] - travel[1:] < self.straight
        chord = np.where(near, self.grasp_speed * dq / np.maximum(dp, 1e-12), np.inf)
        caps = np.full(len(path), np.inf)
        caps[:-1] = chord
        caps[1:] = np.minimum(caps[1:], chord)
        return caps
