"""Natural cubic splines through joint-space waypoints over their cumulative chord length: the
curve :func:`streams.motion.timing.time_parameterize` times (its second derivatives by a
tridiagonal solve, value and derivatives at any point, evenly spaced points along it)."""

from __future__ import annotations

import numpy as np

from sdar_tamp.world.transforms import FloatArray


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
    s: FloatArray, y: FloatArray, M: FloatArray, x: FloatArray, piece: FloatArray | None = None
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Value, first and second derivative ``(k, n)`` of the spline at ``x`` ``(k,)``, each on
    the cubic piece that holds it (or that holds ``piece`` ``(k,)``: a point on a knot then
    takes the piece on the side of ``piece``)."""
    where = x if piece is None else piece
    i = np.clip(np.searchsorted(s, where, side="right") - 1, 0, len(s) - 2)
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
