"""Time parameterisation of a joint-space path under velocity and acceleration limits.

The waypoints ``(N, n)`` are joined by a natural cubic spline ``q(s)`` over the cumulative
chord length ``s`` [rad]; on a grid of ``s`` the path speed is found by a backward pass (the
largest ``x = sdot^2`` from which the end can still be reached at rest) and a forward pass
(accelerate as hard as the joint limits allow), with ``u = sddot`` constant between grid
points and the constraints

    |q'(s)_j| sqrt(x) <= v_j,     |q'(s)_j u + q''(s)_j x| <= a_j     (every joint j)

at both ends of every grid step. The backward pass solves a two-variable linear programme per
grid point by enumerating the vertices of its polygon. Limits are scaled by ``safety``
(default 0.95; the scene's ``velocity_safety``); an optional cap on the path speed per
waypoint slows chosen parts (a grasp's straight approach). The motion starts and ends at rest;
the result is resampled at a uniform step of at most ``dt``.

The samples are then checked with the measures a plan validator uses: the velocity of every
interval, the second divided difference at every interior sample, and at both ends half the
acceleration limit for the robot at rest one step away (so two rest-to-rest trajectories
joined end to start, each sampled at its own step, stay within the limit at the junction).
Where the discretisation breaks one of them, the whole profile is slowed uniformly (time
scaled by the smallest factor that would restore every limit) and sampled again; with
``safety=1`` this is what keeps the result valid. Should a few rounds not settle, later ones
overshoot, and as a last resort the profile is slowed by its own peaks over the whole path
(:meth:`_Profile.peak_ratio`), which bound the measures of any sampling: every trajectory
returned keeps the limits as the validator measures them. So does a chain of them joined end
to start (:meth:`TimedTrajectory.then`): at a junction the two end rules add up to the full
limit, whatever the two sample spacings.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.transforms import FloatArray
from streams.motion.spline import natural_spline as natural_spline
from streams.motion.spline import spline_curve as spline_curve
from streams.motion.spline import spline_eval as spline_eval
from streams.motion.spline import tridiagonal_solve as tridiagonal_solve

IntArray = npt.NDArray[np.intp]


@dataclass(frozen=True)
class TimedTrajectory:
    """Samples ``q`` ``(m, n)`` [rad] at times ``t`` ``(m,)`` [s], starting at ``t = 0``."""

    t: FloatArray
    q: FloatArray

    @property
    def duration(self) -> float:
        return float(self.t[-1]) if len(self.t) else 0.0

    def then(self, other: TimedTrajectory) -> TimedTrajectory:
        """This trajectory followed by ``other`` (which must start where this one ends)."""
        if len(self.t) == 0:
            return other
        return TimedTrajectory(
            np.concatenate([self.t, self.duration + other.t[1:]]),
            np.concatenate([self.q, other.q[1:]]),
        )


def _accel_rows(dq: FloatArray, ddq: FloatArray, ds: float) -> FloatArray:
    """Rows ``(k - 1, 2n, 2)`` in ``(x, u)`` of the joint accelerations at both ends of every
    step between the ``k`` grid points of ``dq``, ``ddq`` ``(k, n)`` (``x_{i+1} = x + 2 u
    ds``); each row times ``(x, u)`` must stay in ``[-a, a]``."""
    start = np.stack([ddq[:-1], dq[:-1]], axis=2)
    end = np.stack([ddq[1:], dq[1:] + 2 * ds * ddq[1:]], axis=2)
    return np.concatenate([start, end], axis=1)


@functools.lru_cache(maxsize=8)
def _pairs(m: int) -> tuple[IntArray, IntArray]:
    """Index pairs ``i < j`` of ``m`` constraint rows (every candidate vertex)."""
    i, j = np.triu_indices(m, 1)
    return i, j


#: Candidates farther than this outside the box rows are dropped before the full check
#: (looser than the check's own 1e-9: the full check alone decides).
_SLACK = 1e-6


def _constraints(rows: FloatArray, a2: FloatArray, ds: float) -> tuple[FloatArray, FloatArray]:
    """The backward pass's constraint rows ``G`` ``(k, 4 + 2r, 2)`` and right-hand sides
    ``h`` ``(k, 4 + 2r)`` in ``(x, u)`` for the acceleration rows ``(k, r, 2)`` of ``k``
    grid steps: the box ``0 <= x <= xv``, ``0 <= x + 2 u ds <= xn`` (``xv`` and ``xn`` are
    left at 0 here), then ``rows <= a2`` and ``-rows <= a2``."""
    k = len(rows)
    box = np.array([[1.0, 0.0], [-1.0, 0.0], [1.0, 2 * ds], [-1.0, -2 * ds]])
    G = np.concatenate([np.broadcast_to(box, (k, 4, 2)), rows, -rows], axis=1)
    h = np.zeros((k, G.shape[1]))
    h[:, 4:] = np.concatenate([a2, a2])
    return G, h


class _Vertices:
    """Every candidate vertex of the backward pass's polygons, all grid steps at once.

    A vertex is the intersection of two constraint lines. Those that do not involve the
    line ``x + 2 u ds = xn`` (row 2, the only one that changes during the pass) are
    computed once for every step (``x``, ``u`` ``(k, pairs)``, ``keep`` marks those inside
    the fixed box rows); those on row 2 are computed per step (:meth:`max_x`).

    Where the path's tangent vanishes (a path that turns back on itself, such as a retreat
    followed by the approach to the same grasp) no joint limits the speed and ``xv`` is
    infinite: vertices on that line come out infinite or NaN (``inf * 0``) and fail the
    checks, as they should, without a warning."""

    def __init__(self, G: FloatArray, h: FloatArray, xv: FloatArray) -> None:
        with np.errstate(invalid="ignore"):
            self._build(G, h, xv)

    def _build(self, G: FloatArray, h: FloatArray, xv: FloatArray) -> None:
        self.G, self.h = G, h.copy()
        self.h[:, 0] = xv
        i, j = _pairs(G.shape[1])
        fixed = (i != 2) & (j != 2)
        i, j = i[fixed], j[fixed]
        Gi0, Gi1, Gj0, Gj1 = G[:, i, 0], G[:, i, 1], G[:, j, 0], G[:, j, 1]
        det = Gi0 * Gj1 - Gi1 * Gj0
        ok = np.abs(det) > 1e-12
        det = np.where(ok, det, 1.0)
        hi, hj = self.h[:, i], self.h[:, j]
        self.x = (hi * Gj1 - Gi1 * hj) / det
        self.u = (Gi0 * hj - hi * Gj0) / det
        self.w = self.x + G[:, 2:3, 1] * self.u
        self.keep = (
            ok & (self.x <= xv[:, None] + _SLACK) & (self.x >= -_SLACK) & (self.w >= -_SLACK)
        )
        i2, j2 = _pairs(G.shape[1])
        row2 = (i2 == 2) | (j2 == 2)
        self.i2, self.j2 = i2[row2], j2[row2]

    def max_x(self, k: int, xn: float) -> float:
        """Largest ``x`` over the vertices of step ``k``'s polygon with ``x + 2 u ds <= xn``
        that satisfy every constraint (0 when none does)."""
        with np.errstate(invalid="ignore"):
            return self._max_x(k, xn)

    def _max_x(self, k: int, xn: float) -> float:
        G, h = self.G[k], self.h[k].copy()
        h[2] = xn
        sel = self.keep[k] & (self.w[k] <= xn + _SLACK)
        i, j = self.i2, self.j2
        det = G[i, 0] * G[j, 1] - G[i, 1] * G[j, 0]
        ok = np.abs(det) > 1e-12
        i, j, det = i[ok], j[ok], det[ok]
        x2 = (h[i] * G[j, 1] - G[i, 1] * h[j]) / det
        u2 = (G[i, 0] * h[j] - h[i] * G[j, 0]) / det
        near = (x2 <= h[0] + _SLACK) & (x2 >= -_SLACK)
        x = np.concatenate([self.x[k, sel], x2[near]])
        u = np.concatenate([self.u[k, sel], u2[near]])
        if not len(x):
            return 0.0
        feas = np.all(G @ np.stack([x, u]) <= h[:, None] + 1e-9, axis=0)
        return float(max(0.0, x[feas].max())) if feas.any() else 0.0


def _u_range(rows: FloatArray, a2: FloatArray, x: float) -> tuple[float, float]:
    """Interval of ``u`` with ``|rows @ (x, u)| <= a2`` at a given ``x``."""
    c, d = rows[:, 0] * x, rows[:, 1]
    use = np.abs(d) > 1e-12
    b1 = (a2[use] - c[use]) / d[use]
    b2 = (-a2[use] - c[use]) / d[use]
    lo = float(np.max(np.minimum(b1, b2), initial=-np.inf))
    hi = float(np.min(np.maximum(b1, b2), initial=np.inf))
    return lo, hi


def sample_limit_ratio(
    t: FloatArray, q: FloatArray, v_max: FloatArray, a_max: FloatArray
) -> tuple[float, float]:
    """Largest ratios (velocity, acceleration) of the samples' divided differences to the
    limits: interval velocities, interior second differences, and at both ends the
    acceleration from (and to) rest one step away against half the limit (see the module
    docstring). Both ``<= 1``: the samples keep the limits."""
    if len(t) < 2:
        return 0.0, 0.0
    h = np.diff(t)
    vel = np.diff(q, axis=0) / h[:, None]
    rv = float(np.max(np.abs(vel) / v_max))
    ends = np.stack([np.abs(vel[0]) / h[0], np.abs(vel[-1]) / h[-1]]) / (0.5 * a_max)
    ra = float(ends.max())
    if len(vel) > 1:
        acc = np.diff(vel, axis=0) / (0.5 * (h[1:] + h[:-1]))[:, None]
        ra = max(ra, float(np.max(np.abs(acc) / a_max)))
    return rv, ra


#: Rounds of uniform slowing after the first sampling (each scales time by the ratio found).
_SLOWDOWN_ROUNDS = 6


def time_parameterize(
    waypoints: FloatArray,
    v_max: FloatArray,
    a_max: FloatArray,
    dt: float = 0.02,
    grid_step: float = 0.02,
    safety: float = 0.95,
    max_grid: int = 150,
    path_speed: FloatArray | None = None,
) -> TimedTrajectory:
    """A rest-to-rest trajectory through ``waypoints`` ``(N, n)`` [rad] within ``v_max``
    [rad/s] and ``a_max`` [rad/s^2] ``(n,)``, sampled every ``<= dt`` [s].

    The speed grid has a spacing of ``grid_step`` [rad] of path length, at most ``max_grid``
    points. ``safety`` in (0, 1] scales the limits of the profile; the samples keep the
    unscaled limits in any case (see the module docstring). ``path_speed`` ``(N,)``: a cap
    on the path speed [rad/s of chord length] at each waypoint (``inf``: none); between two
    waypoints the smaller of their caps applies."""
    if not 0.0 < safety <= 1.0:
        raise ParameterError(f"safety must lie in (0, 1], got {safety}")
    W = np.asarray(waypoints, dtype=np.float64)
    keep = np.concatenate([[True], np.linalg.norm(np.diff(W, axis=0), axis=1) > 1e-9])
    W = W[keep]
    cap = None if path_speed is None else np.asarray(path_speed, dtype=np.float64)[keep]
    if len(W) < 2:
        return TimedTrajectory(np.zeros(1), W[:1].copy())
    v_true, a_true = np.asarray(v_max, dtype=np.float64), np.asarray(a_max, dtype=np.float64)
    v, a = safety * v_true, safety * a_true
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(W, axis=0), axis=1))])
    M = natural_spline(s, W)
    n_grid = int(np.clip(np.ceil(s[-1] / grid_step) + 1, 8, max_grid))
    sg = np.linspace(0.0, s[-1], n_grid)
    ds = sg[1] - sg[0]
    _, dq, ddq = spline_eval(s, W, M, sg)
    with np.errstate(divide="ignore"):
        xv = np.min(np.where(np.abs(dq) > 1e-12, (v / np.abs(dq)) ** 2, np.inf), axis=1)
    if cap is not None:
        xv = np.minimum(xv, _grid_cap(s, cap, sg) ** 2)
    moving = np.any(dq != 0.0, axis=0) | np.any(ddq != 0.0, axis=0)  # a joint at rest
    a2 = np.concatenate([a[moving], a[moving]])  # (an idle arm's) has rows of zeros that
    rows = _accel_rows(dq[:, moving], ddq[:, moving], ds)  # bind nothing: left out
    vertices = _Vertices(*_constraints(rows, a2, ds), xv[:-1])
    xmax = np.zeros(n_grid)
    for i in range(n_grid - 2, -1, -1):
        xmax[i] = vertices.max_x(i, float(xmax[i + 1]))
    x = np.zeros(n_grid)
    u = np.zeros(n_grid - 1)
    for i in range(n_grid - 1):
        lo, hi = _u_range(rows[i], a2, x[i])
        ui = min(hi, (xmax[i + 1] - x[i]) / (2 * ds))
        ui = max(ui, lo, -x[i] / (2 * ds))
        u[i] = ui
        x[i + 1] = float(np.clip(x[i] + 2 * ui * ds, 0.0, xmax[i + 1]))
        u[i] = (x[i + 1] - x[i]) / (2 * ds)
    profile = _Profile(s, W, M, sg, x, u)
    scale = 1.0
    for r in range(_SLOWDOWN_ROUNDS + _OVERSHOOT_ROUNDS + 1):
        t, q = profile.sample(scale, dt)
        rv, ra = sample_limit_ratio(t, q, v_true, a_true)
        worst = max(rv, float(np.sqrt(ra)))
        if worst <= 1.0:
            return TimedTrajectory(t, q)
        scale *= (worst if r < _SLOWDOWN_ROUNDS else worst * worst) * (1.0 + 1e-4)
    # still over: slowed by the profile's own peaks, which bound any sampling's measures
    t, q = profile.sample(profile.peak_ratio(v_true, a_true) * (1.0 + _PEAK_MARGIN), dt)
    return TimedTrajectory(t, q)


#: Rounds after :data:`_SLOWDOWN_ROUNDS` that scale time by the square of the ratio found. Near a
#: sharp turn of the curve (a path that goes back the way it came, where the grid misses the
#: curvature's peak) the samples, denser along a slower profile, come closer to that peak at
#: every round, so a scaling by the ratio alone leaves them over the limit round after round
#: (1.13, 1.07, 1.04, 1.02, 1.009 of the acceleration limit); these rounds overshoot instead.
_OVERSHOOT_ROUNDS = 4

#: Relative margin [-] on the profile's peak ratio in the last slowing (rounding of the samples'
#: divided differences; far below the validator's tolerance of the limits).
_PEAK_MARGIN = 1e-7


@dataclass(frozen=True)
class _Profile:
    """The path speed found by the passes: the spline (knots ``s`` ``(N,)``, values ``W``
    ``(N, n)``, second derivatives ``M``), the grid ``sg`` ``(k,)``, ``x = sdot^2`` at the
    grid points and ``u = sddot`` ``(k - 1,)`` constant on each grid step."""

    s: FloatArray
    W: FloatArray
    M: FloatArray
    sg: FloatArray
    x: FloatArray
    u: FloatArray

    def sample(self, scale: float, dt: float) -> tuple[FloatArray, FloatArray]:
        """Times ``(m,)`` [s] and samples ``(m, n)`` [rad] of the profile with time stretched by
        ``scale`` (>= 1), at the uniform step of at most ``dt`` [s]."""
        sg, u, s = self.sg, self.u, self.s
        sq = np.sqrt(self.x)
        step = 2 * (sg[1] - sg[0]) / np.maximum(sq[:-1] + sq[1:], 1e-12)
        tg = np.concatenate([[0.0], np.cumsum(step)])
        T = scale * float(tg[-1])
        n_samples = max(1, int(np.ceil(T / dt)))
        t = np.linspace(0.0, T, n_samples + 1).astype(np.float64)
        tp = t / scale  # the profile's own time
        k = np.clip(np.searchsorted(tg, tp, side="right") - 1, 0, len(sg) - 2)
        tau = tp - tg[k]
        s_t = np.clip(sg[k] + sq[k] * tau + 0.5 * u[k] * tau * tau, 0.0, s[-1])
        s_t[-1] = s[-1]
        q, _, _ = spline_eval(s, self.W, self.M, s_t)
        return t, q

    def peak_ratio(self, v_max: FloatArray, a_max: FloatArray) -> float:
        """The smallest time stretch that keeps the whole motion within ``v_max`` [rad/s] and
        ``a_max`` [rad/s^2] ``(n,)``: ``max(rv, sqrt(ra))`` of the peak ratios over the path,
        not only at samples (stretching time by ``c`` divides velocities by ``c`` and
        accelerations by ``c^2``).

        Between consecutive grid points and knots the spline is one cubic and ``u`` one
        constant, so the joint acceleration ``q'(s) u + q''(s) x(s)`` (``x`` linear in ``s``)
        is a quadratic in ``s``: its peak is exact from three values (the ends and the vertex
        when inside). The velocity ``|q'(s)| sqrt(x(s))`` is bounded by the peak of the
        quadratic ``|q'|`` times the larger end of ``sqrt(x)``. A divided difference of
        samples of a motion is a mean of its derivative, so no sampling exceeds these peaks;
        nor does an end sample's measure from rest (half the acceleration peak, the motion
        starting and ending at rest)."""
        sg, s = self.sg, self.s
        inner = s[(s > sg[0]) & (s < sg[-1])]
        pts = np.unique(np.concatenate([sg, inner]))
        lo, hi = pts[:-1], pts[1:]
        mid = 0.5 * (lo + hi)
        k = np.clip(np.searchsorted(sg, mid, side="right") - 1, 0, len(sg) - 2)
        u = self.u[k][:, None]

        def x_at(p: FloatArray) -> FloatArray:
            x: FloatArray = np.maximum(self.x[k] + 2.0 * self.u[k] * (p - sg[k]), 0.0)
            return x[:, None]

        ends = []
        for p in (lo, mid, hi):
            _, d1, d2 = spline_eval(self.s, self.W, self.M, p, piece=mid)
            ends.append((d1, d1 * u + d2 * x_at(p)))
        vel = _quadratic_peak(*(d1 for d1, _ in ends)) * np.sqrt(np.maximum(x_at(lo), x_at(hi)))
        acc = _quadratic_peak(*(a for _, a in ends))
        rv = float(np.max(vel / v_max))
        ra = float(np.max(acc / a_max))
        return max(1.0, rv, float(np.sqrt(ra)))


def _quadratic_peak(f0: FloatArray, fm: FloatArray, f1: FloatArray) -> FloatArray:
    """Largest ``|f|`` ``(k, n)`` over ``[-1, 1]`` of the quadratics with values ``f0``, ``fm``,
    ``f1`` at -1, 0 and 1."""
    c2 = 0.5 * (f0 + f1) - fm
    c1 = 0.5 * (f1 - f0)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(np.abs(c2) > 1e-300, -c1 / (2.0 * c2), 2.0)
    z = np.where(np.abs(z) < 1.0, z, 1.0)
    vertex = fm + c1 * z + c2 * z * z
    out: FloatArray = np.maximum(np.maximum(np.abs(f0), np.abs(f1)), np.abs(vertex))
    return out


def _grid_cap(s: FloatArray, cap: FloatArray, sg: FloatArray) -> FloatArray:
    """Per grid point ``sg``: the smaller cap of the two waypoints around it."""
    i = np.clip(np.searchsorted(s, sg, side="right") - 1, 0, len(s) - 2)
    on = np.isclose(sg, s[i + 1])
    return np.where(on, np.minimum(cap[i + 1], cap[np.minimum(i + 2, len(s) - 1)]),
                    np.minimum(cap[i], cap[i + 1]))  # fmt: skip
