"""A rest-to-rest motion re-timed through a clamped cubic spline, with exact derivative bounds.

The samples ``q`` ``(m, k)`` [rad] at times ``t`` ``(m,)`` [s] of one arm's motion from rest to
rest are joined by the cubic spline through every sample with zero velocity at both ends. Its
second derivative is linear between the knots, so its largest magnitude is at a knot; its first
derivative is quadratic, so its largest magnitude is at a knot or where the second derivative
changes sign. Both bounds are exact. Played ``r`` times faster, the velocity scales by ``r`` and
the acceleration by ``r**2``; :func:`retime` picks the largest ``r`` within the limits and a
duration that is a whole number of ``tick`` [s].

Why this is safe to sample on any grid: the plan rules (:mod:`sdar_tamp.plan_rules`) measure
velocity and acceleration by first and second divided differences of the samples, which are mean
values of the derivatives of any smooth motion through them. The spline, at rest before its start
and after its end, is such a motion (continuous velocity, bounded acceleration), so any sampling
of it, merged with any sampling of the other arms, stays within the limits it respects.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.transforms import FloatArray


@dataclass(frozen=True, eq=False)
class ClampedSpline:
    """The cubic spline through ``(t[i], q[i])`` with zero slope at both ends.

    ``t`` ``(m,)`` [s], ``q`` ``(m, k)`` [rad], ``M`` ``(m, k)``: second derivatives at the knots
    [rad/s^2]."""

    t: FloatArray
    q: FloatArray
    M: FloatArray

    @staticmethod
    def fit(t: FloatArray, q: FloatArray) -> ClampedSpline:
        t = np.asarray(t, dtype=np.float64)
        q = np.asarray(q, dtype=np.float64)
        if t.ndim != 1 or len(t) < 2 or q.shape[0] != len(t) or np.any(np.diff(t) <= 0.0):
            raise ParameterError(
                f"t: expected at least 2 increasing times matching q's rows, got {t.shape}, "
                f"{q.shape}"
            )
        h = np.diff(t)
        d = np.diff(q, axis=0) / h[:, None]
        m = len(t)
        A = np.zeros((m, m))
        rhs = np.zeros_like(q)
        A[0, 0], A[0, 1], rhs[0] = 2.0 * h[0], h[0], 6.0 * d[0]
        A[-1, -2], A[-1, -1], rhs[-1] = h[-1], 2.0 * h[-1], -6.0 * d[-1]
        i = np.arange(1, m - 1)
        A[i, i - 1], A[i, i], A[i, i + 1] = h[:-1], 2.0 * (h[:-1] + h[1:]), h[1:]
        rhs[1:-1] = 6.0 * (d[1:] - d[:-1])
        M = np.asarray(np.linalg.solve(A, rhs), dtype=np.float64)
        return ClampedSpline(t, q, M)

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0])

    def __call__(self, x: FloatArray) -> FloatArray:
        """Values ``(len(x), k)`` at times ``x`` [s] (clamped to the knots' span)."""
        t, q, M = self.t, self.q, self.M
        x = np.clip(np.asarray(x, dtype=np.float64), t[0], t[-1])
        i = np.clip(np.searchsorted(t, x, side="right") - 1, 0, len(t) - 2)
        h = (t[i + 1] - t[i])[:, None]
        a = (t[i + 1][:, None] - x[:, None]) / h
        b = 1.0 - a
        out: FloatArray = a * q[i] + b * q[i + 1]
        out += ((a**3 - a) * M[i] + (b**3 - b) * M[i + 1]) * h * h / 6.0
        return out

    def peak_acceleration(self) -> FloatArray:
        """Largest ``|q''|`` per coordinate ``(k,)`` [rad/s^2] (exact)."""
        peak: FloatArray = np.abs(self.M).max(axis=0)
        return peak

    def peak_velocity(self) -> FloatArray:
        """Largest ``|q'|`` per coordinate ``(k,)`` [rad/s] (exact)."""
        t, q, M = self.t, self.q, self.M
        h = np.diff(t)[:, None]
        d = np.diff(q, axis=0) / h
        m0, m1 = M[:-1], M[1:]
        # q'(a) with a = (t_{i+1} - x) / h in [0, 1]: d - h (3a^2 - 1) m0 / 6 + h (3b^2 - 1) m1 / 6
        left = d - h * (2.0 * m0 + m1) / 6.0  # at a = 1 (the interval's start)
        right = d + h * (m0 + 2.0 * m1) / 6.0  # at a = 0 (its end)
        with np.errstate(divide="ignore", invalid="ignore"):
            a_star = np.where(np.abs(m1 - m0) > 0.0, m1 / (m1 - m0), -1.0)  # q'' = 0
        inside = (a_star > 0.0) & (a_star < 1.0)
        a_star = np.where(inside, a_star, 0.0)
        b_star = 1.0 - a_star
        mid = d + h * (-(3 * a_star**2 - 1) * m0 + (3 * b_star**2 - 1) * m1) / 6.0
        mid = np.where(inside, mid, 0.0)
        peak: FloatArray = np.max(np.abs(np.stack([left, right, mid])), axis=(0, 1))
        return peak


def retime(
    t: FloatArray,
    q: FloatArray,
    v_max: FloatArray,
    a_max: FloatArray,
    tick: float,
    max_rate: float = math.inf,
) -> FloatArray:
    """Samples ``(n + 1, k)`` every ``tick`` [s] of the rest-to-rest motion through ``q``
    ``(m, k)`` at ``t`` ``(m,)``, played as fast as ``v_max`` [rad/s] and ``a_max`` [rad/s^2]
    ``(k,)`` allow, at most ``max_rate`` times faster than ``t`` (its duration rounded up to
    ``n`` ticks). The first and last samples are
    exactly ``q[0]`` and ``q[-1]``."""
    if not (math.isfinite(tick) and tick > 0.0):
        raise ParameterError(f"tick: expected a finite time > 0 [s], got {tick!r}")
    spline = ClampedSpline.fit(t, q)
    v_peak, a_peak = spline.peak_velocity(), spline.peak_acceleration()
    with np.errstate(divide="ignore"):
        rate_v = np.where(v_peak > 0.0, np.asarray(v_max) / v_peak, np.inf)
        rate_a = np.where(a_peak > 0.0, np.sqrt(np.asarray(a_max) / a_peak), np.inf)
    rate = float(min(rate_v.min(), rate_a.min(), max_rate))
    if not math.isfinite(rate):  # no motion at all
        return np.stack([q[0], q[-1]])
    n = max(1, math.ceil(spline.duration / (rate * tick) - 1e-9))  # within 1e-9 relative
    x = t[0] + np.arange(n + 1) * (spline.duration / n)
    out = spline(x)
    out[0], out[-1] = q[0], q[-1]
    return out
