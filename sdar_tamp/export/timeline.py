"""What every export format reads from a plan: joint columns per arm, positions at any time,
velocities and accelerations at the samples, and the gripper state over time.

The plan's samples are its trajectory; between samples the motion is linear in joint space
(as :mod:`sdar_tamp.plan_rules` and the replay read it). Derivatives at the samples:

* velocity at an inner sample ``i``: the derivative at ``t[i]`` of the parabola through the
  samples ``i - 1``, ``i``, ``i + 1``, ``(h[i] * m[i-1] + h[i-1] * m[i]) / (h[i-1] + h[i])``
  with ``m[k] = (q[k+1] - q[k]) / h[k]`` and ``h[k] = t[k+1] - t[k]`` (the central difference
  on a uniform grid), a weighted mean of the two neighbouring interval velocities, so within
  the velocity limits the validator checks on those; zero at the first and the last sample
  (a plan starts and ends at rest);
* acceleration at every sample: the second divided difference the validator bounds,
  ``(m[i] - m[i-1]) / ((h[i-1] + h[i]) / 2)``, with the robot at rest before ``t = 0`` and
  after the end (inner samples: the parabola's second derivative, so both agree).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.world.transforms import BoolArray, FloatArray, inverse

TIME_TOL = 1e-9  #: [s] an event this close before a sample time counts at that time


def arm_columns(plan: PlanFile) -> tuple[slice, ...]:
    """The columns of ``plan.q`` of each arm, in the plan's arm order (its layout)."""
    return plan.layout.slices


def sample_derivatives(t: FloatArray, q: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Velocities and accelerations ``(n, k)`` [rad/s, rad/s^2] at the samples ``q`` ``(n, k)``
    taken at ``t`` ``(n,)`` [s] (see the module docstring)."""
    n = len(t)
    v = np.zeros_like(q, dtype=np.float64)
    if n < 2:
        return v, np.zeros_like(v)
    h = np.diff(t)
    m = np.diff(q, axis=0) / h[:, None]
    if n > 2:
        left, right = h[:-1, None], h[1:, None]
        v[1:-1] = (right * m[:-1] + left * m[1:]) / (left + right)
    rest = np.zeros((1, q.shape[1]))
    m_ext = np.concatenate([rest, m, rest])
    h_ext = np.concatenate([h[:1], h, h[-1:]])
    a = np.diff(m_ext, axis=0) / (0.5 * (h_ext[1:] + h_ext[:-1]))[:, None]
    return v, a


def positions_at(plan: PlanFile, times: FloatArray) -> FloatArray:
    """Configurations ``(len(times), dof)`` [rad] (every arm's joints, the plan's layout) at
    ``times`` [s], linear between samples;
    before 0 and after the end the robot stands at the first and last sample."""
    times = np.asarray(times, dtype=np.float64)
    return np.stack([np.interp(times, plan.t, plan.q[:, j]) for j in range(plan.q.shape[1])], 1)


def controller_grid(duration: float, period: float) -> FloatArray:
    """``k * period`` [s] for ``k = 0 .. ceil(duration / period)``: a uniform grid that reaches
    the end of the plan (its last time may pass the end by less than one period)."""
    if not (np.isfinite(period) and period > 0.0):
        raise ParameterError(f"period must be a finite number > 0 [s], got {period!r}")
    count = int(np.ceil(duration / period - 1e-9))
    return np.arange(count + 1, dtype=np.float64) * period


@dataclass(frozen=True)
class GripperState:
    """Per sample time and arm (plan order): ``closed`` ``(n, arms)`` and the object ``held``
    (``""`` when open). A gripper is open at the start; an event at ``t_e`` counts from
    ``t_e`` on (within :data:`TIME_TOL`)."""

    closed: BoolArray
    held: tuple[tuple[str, ...], ...]


def gripper_states(plan: PlanFile, times: FloatArray) -> GripperState:
    """The commanded gripper state of every arm at ``times`` [s]."""
    names = plan.arm_names
    held: list[tuple[str, ...]] = []
    events = plan.events  # sorted by time (load_plan checks it)
    k, now = 0, {name: "" for name in names}
    for time in np.asarray(times, dtype=np.float64):
        while k < len(events) and events[k].t <= time + TIME_TOL:
            e = events[k]
            now[e.arm] = e.object if e.type == "grasp" else ""
            k += 1
        held.append(tuple(now[name] for name in names))
    closed = np.array([[bool(h) for h in row] for row in held], dtype=bool)
    closed = closed.reshape(-1, len(names))
    return GripperState(closed, tuple(held))


def base_to_base(plan: PlanFile, i: int = 0, j: int = 1) -> FloatArray:
    """``T_base_i_base_j`` ``(4, 4)``: arm ``j``'s ``base_link`` in arm ``i``'s (plan order;
    by default the second arm's in the first's)."""
    for name, k in (("i", i), ("j", j)):
        if isinstance(k, bool) or not isinstance(k, int) or not 0 <= k < len(plan.arms):
            raise ParameterError(
                f"{name}: expected an arm index in [0, {len(plan.arms)}), got {k!r}"
            )
    return inverse(plan.arms[i].T_world_base) @ plan.arms[j].T_world_base
