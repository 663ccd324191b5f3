"""Stopping the arms along their current motion (:func:`brake`): when the running plan would
meet the observed world before its next cut point, the arms are brought to rest on the plan's
own path as fast as the acceleration limits allow, and re-planning starts from there
(:func:`sdar_tamp.app.replanning.replan`).

The braking follows the plan's samples (linear between them, as the executor and the
validator read them) at a slowing pace: the plan time ``p`` reached advances by at most one
sample spacing per spacing, so every configuration is one the plan passes through, no joint
moves faster than in the plan, and an arm the plan keeps still (a gripper's dwell) stays still
at least as long. Sample after sample, ``p`` advances the least that keeps every joint's
second divided difference within its limit, until the arms can stand still (the last velocity
within the rule of a plan's end, half the limit over one spacing: any still hold may follow).
A path that turns too sharply to follow at the speed reached gives no braking.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_rules import LIMIT_RTOL, TIME_TOL
from sdar_tamp.plan_state import Cut
from sdar_tamp.world.transforms import FloatArray

#: Candidate advances of the plan time per sample, as shares of the spacing (the least that
#: keeps the limits is taken).
_SHARES = np.linspace(0.0, 1.0, 401)
#: Share of each acceleration limit the braking's steps use: all of it (less rounding), since
#: the plan itself may be at its limit where braking begins, following its path at full speed.
_MARGIN = 1.0 - 1e-9
#: Share of half the limit within which the last velocity must lie to stand still.
_STOP_MARGIN = 0.98


@dataclasses.dataclass(frozen=True)
class Braking:
    """``plan`` up to the first sample at or after the time reached, then the braking samples,
    ending at rest; ``cut``: its last sample (where re-planning starts)."""

    plan: PlanFile
    cut: Cut


def brake(plan: PlanFile, at: float, v_max: FloatArray, a_max: FloatArray) -> Braking | None:
    """The arms of ``plan`` brought to rest along its path from time ``at`` [s] within
    ``v_max`` [rad/s] and ``a_max`` [rad/s^2] ``(dof,)`` (see the module docstring); None when
    an arm holds an object at ``at`` or a gripper acts before the arms are at rest (the
    continuation starts with empty grippers), or when the path cannot be followed."""
    t, q = plan.t, plan.q
    i0 = min(int(np.searchsorted(t, at - TIME_TOL)), len(t) - 1)
    if i0 == 0 or _holding(plan, float(t[i0])):
        return None
    h = float(t[i0] - t[i0 - 1])
    v = (q[i0] - q[i0 - 1]) / h
    p, ts, qs = float(t[i0]), [float(t[i0])], [q[i0]]
    limit = _MARGIN * a_max * h
    while np.any(np.abs(v) > 0.5 * _STOP_MARGIN * a_max * h):  # to stand still after any spacing
        if len(ts) > len(t):
            return None
        cand = p + _SHARES * h
        q_c = np.stack([np.interp(cand, t, q[:, j]) for j in range(q.shape[1])], axis=1)
        dv = (q_c - qs[-1]) / h - v
        ok = np.all(np.abs(dv) <= limit, axis=1)
        if not ok.any():
            return None
        k = int(np.argmax(ok))
        v = (q_c[k] - qs[-1]) / h
        p = float(cand[k])
        ts.append(ts[-1] + h)
        qs.append(q_c[k])
    if any(float(t[i0]) - TIME_TOL <= e.t <= p + TIME_TOL for e in plan.events):
        return None  # a gripper acts on the way
    bt, bq = np.array(ts), np.stack(qs)
    if np.any(np.abs(np.diff(bq, axis=0)) / h > v_max * (1.0 + LIMIT_RTOL)):
        return None
    events = sum(e.t < float(t[i0]) - TIME_TOL for e in plan.events)
    braked = dataclasses.replace(
        plan,
        t=np.concatenate([t[:i0], bt]),
        q=np.concatenate([q[:i0], bq]),
        events=plan.events[:events],
    )
    return Braking(braked, Cut(len(braked.t) - 1, float(braked.t[-1]), events))


def _holding(plan: PlanFile, t: float) -> bool:
    """Whether an arm holds an object at ``t`` [s] (a grasp at ``t`` counts)."""
    held: set[str] = set()
    for e in plan.events:
        if e.t > t + TIME_TOL:
            break
        if e.type == "grasp":
            held.add(e.arm)
        elif e.t < t - TIME_TOL:
            held.discard(e.arm)
    return bool(held)
