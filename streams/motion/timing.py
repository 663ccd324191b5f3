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
scaled by the smallest factor that restores every limit) and sampled again; with
``safety=1`` this is what keeps the result valid.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.transforms import FloatArray

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


def natural_spline(s: FloatArray, y: FloatArray) -> FloatArray:
    """Second derivatives ``(N, n)`` of the natural cubic spline through ``(s_i, y_i)``."""
    N = len(s)
    M = np.zeros_like(y)
    if N < 3:
        return M
    h = np.diff(s)
    d = np.diff(y, axis=0) / h[:, None]
    off, diag, rhs = h[1:-1], 2.0 * (h[:-1] + h[1:]), 6.0 * (d[1:] - d[:-1])
    if N - 2 <= DENSE_SPLINE:
        A = np.diag(diag)
        if N > 3:
            A += np.diag(off, 1) + np.diag(off, -1)
        M[1:-1] = np.linalg.solve(A, rhs)
    else:
        M[1:-1] = tridiagonal_solve(off, diag, rhs)
    return M


#: Spline systems up to this size are solved densely (LAPACK is faster there, 0.05 ms at 50
#: unknowns); larger ones by :func:`tridiagonal_solve` (0.7 ms at 500, where a dense solve
#: takes 6 ms on an idle core and several times more beside another process).
DENSE_SPLINE = 64


def tridiagonal_solve(off: FloatArray, diag: FloatArray, rhs: FloatArray) -> FloatArray:
    """``X`` ``(m, n)`` with ``A X = rhs`` for the symmetric tridiagonal ``A`` of diagonal
    ``diag`` ``(m,)`` and off-diagonal ``off`` ``(m - 1,)``, diagonally dominant (a spline's
    system): Gaussian elimination without pivoting in O(m). The pivots are a scalar loop; the
    two sweeps over the right-hand sides are first-order linear recurrences, each evaluated
    as a parallel prefix in log2(m) array operations (the products of the recurrence's
    coefficients, all of modulus below one, only shrink)."""
    m = len(diag)
    d, o = diag.tolist(), off.tolist()
    pivot, ratio = [0.0] * m, [0.0] * m  # ratio[i]: off[i] / pivot[i], the back sweep's
    pivot[0] = d[0]
    for i in range(1, m):
        ratio[i - 1] = o[i - 1] / pivot[i - 1]
        pivot[i] = d[i] - o[i - 1] * ratio[i - 1]
    p = np.array(pivot)
    forward = np.zeros(m)
    forward[1:] = -off / p[1:]
    z = _linear_recurrence(forward, rhs / p[:, None])  # z_i = rhs_i / p_i - off z_{i-1} / p_i
    backward = -np.array(ratio)[::-1]  # x_i = z_i - ratio_i x_{i+1}, from the last row
    out: FloatArray = _linear_recurrence(backward, z[::-1])[::-1]
    return out


def _linear_recurrence(a: FloatArray, b: FloatArray) -> FloatArray:
    """``x`` ``(m, n)`` with ``x_0 = b_0`` and ``x_i = a_i x_{i-1} + b_i`` (Hillis-Steele
    prefix: after the pass of stride ``k`` each ``x_i`` holds the sum over its last ``2k``
    terms and ``p_i`` the product of their coefficients)."""
    x, p = np.array(b, dtype=np.float64), np.array(a, dtype=np.float64)
    p[0] = 0.0
    k = 1
    while k < len(p):
        x[k:] = x[k:] + p[k:, None] * x[:-k]
        p[k:] = p[k:] * p[:-k]
        k *= 2
    return x


def spline_eval(
    s: FloatArray, y: FloatArray, M: FloatArray, x: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Value, first and second derivative ``(k, n)`` of the spline at ``x`` ``(k,)``."""
    i = np.clip(np.searchsorted(s, x, side="right") - 1, 0, len(s) - 2)
    h = (s[i + 1] - s[i])[:, None]
    a = (s[i + 1][:, None] - x[:, None]) / h
    b = 1.0 - a
    y0, y1, m0, m1 = y[i], y[i + 1], M[i], M[i + 1]
    val = a * y0 + b * y1 + ((a**3 - a) * m0 + (b**3 - b) * m1) * h * h / 6.0
    der = (y1 - y0) / h + (-(3 * a * a - 1) * m0 + (3 * b * b - 1) * m1) * h / 6.0
    dd = a * m0 + b * m1
    return val, der, dd


def spline_curve(waypoints: FloatArray, samples: int) -> FloatArray:
    """``samples`` points ``(samples, n)`` evenly spaced in chord length along the curve
    :func:`time_parameterize` follows through ``waypoints`` ``(N, n)`` (two waypoints: the
    straight line)."""
    W = np.asarray(waypoints, dtype=np.float64)
    keep = np.concatenate([[True], np.linalg.norm(np.diff(W, axis=0), axis=1) > 1e-9])
    W = W[keep]
    if len(W) < 2:
        return np.repeat(W[:1], samples, axis=0)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(W, axis=0), axis=1))])
    q, _, _ = spline_eval(s, W, natural_spline(s, W), np.linspace(0.0, s[-1], samples))
    q[-1] = W[-1]
    return q


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
    a2 = np.concatenate([a, a])
    rows = _accel_rows(dq, ddq, ds)
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
    sq = np.sqrt(x)
    step = 2 * ds / np.maximum(sq[:-1] + sq[1:], 1e-12)
    tg = np.concatenate([[0.0], np.cumsum(step)])
    scale = 1.0
    for _ in range(_SLOWDOWN_ROUNDS + 1):
        T = scale * float(tg[-1])
        n_samples = max(1, int(np.ceil(T / dt)))
        t = np.linspace(0.0, T, n_samples + 1).astype(np.float64)
        tp = t / scale  # the profile's own time
        k = np.clip(np.searchsorted(tg, tp, side="right") - 1, 0, n_grid - 2)
        tau = tp - tg[k]
        s_t = np.clip(sg[k] + sq[k] * tau + 0.5 * u[k] * tau * tau, 0.0, s[-1])
        s_t[-1] = s[-1]
        q, _, _ = spline_eval(s, W, M, s_t)
        rv, ra = sample_limit_ratio(t, q, v_true, a_true)
        worst = max(rv, float(np.sqrt(ra)))
        if worst <= 1.0:
            break
        scale *= worst * (1.0 + 1e-4)
    return TimedTrajectory(t, q)


def _grid_cap(s: FloatArray, cap: FloatArray, sg: FloatArray) -> FloatArray:
    """Per grid point ``sg``: the smaller cap of the two waypoints around it."""
    i = np.clip(np.searchsorted(s, sg, side="right") - 1, 0, len(s) - 2)
    on = np.isclose(sg, s[i + 1])
    return np.where(on, np.minimum(cap[i + 1], cap[np.minimum(i + 2, len(s) - 1)]),
                    np.minimum(cap[i], cap[i + 1]))  # fmt: skip
