"""Object footprints on the table: oriented rectangles and their exact overlap test.

Two rectangles overlap when their interiors intersect: touching edges or corners do not count.
The test is the separating-axis theorem over the four edge normals, vectorised over all pairs.
"""

from __future__ import annotations

import numpy as np

from sdar_tamp.world.transforms import BoolArray, FloatArray

_HALF = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]]) / 2.0


def corners(poses: FloatArray, sizes: FloatArray) -> FloatArray:
    """Corners ``(n, 4, 2)`` [m] of rectangles at ``poses`` ``(n, 3)`` = (x, y, yaw) with
    side lengths ``sizes`` ``(n, 2)`` (along the object's x and y axes)."""
    p = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    s = np.asarray(sizes, dtype=np.float64).reshape(-1, 2)
    c, si = np.cos(p[:, 2]), np.sin(p[:, 2])
    rot = np.stack([np.stack([c, -si], -1), np.stack([si, c], -1)], -2)  # (n, 2, 2)
    local = _HALF[None] * s[:, None, :]  # (n, 4, 2)
    out: FloatArray = np.einsum("nij,nkj->nki", rot, local) + p[:, None, :2]
    return out


def _axes(rect: FloatArray) -> FloatArray:
    """Unit edge normals ``(n, 2, 2)`` of rectangles ``(n, 4, 2)``."""
    e = np.stack([rect[:, 1] - rect[:, 0], rect[:, 2] - rect[:, 1]], axis=1)
    out: FloatArray = e / np.linalg.norm(e, axis=-1, keepdims=True)
    return out


def _separated(axes: FloatArray, a: FloatArray, b: FloatArray, tol: float) -> BoolArray:
    """For axes ``(n, 2, 2)`` owned by ``a`` ``(n, 4, 2)``: separated from each ``b`` ``(m, 4, 2)``
    on one of them? Returns ``(n, m)``."""
    pa = np.einsum("nkd,nad->nak", a, axes)  # (n, 2, 4)
    pb = np.einsum("mkd,nad->nmak", b, axes)  # (n, m, 2, 4)
    amin, amax = pa.min(-1)[:, None], pa.max(-1)[:, None]  # (n, 1, 2)
    bmin, bmax = pb.min(-1), pb.max(-1)  # (n, m, 2)
    sep = (amax <= bmin + tol) | (bmax <= amin + tol)
    return np.asarray(sep.any(-1), dtype=np.bool_)


def overlap_matrix(a: FloatArray, b: FloatArray, tol: float = 1e-9) -> BoolArray:
    """``(n, m)`` mask: rectangle ``a[i]`` overlaps rectangle ``b[j]`` (interiors intersect by
    more than ``tol`` [m] on every axis). ``a`` is ``(n, 4, 2)``, ``b`` is ``(m, 4, 2)``."""
    a = np.asarray(a, dtype=np.float64).reshape(-1, 4, 2)
    b = np.asarray(b, dtype=np.float64).reshape(-1, 4, 2)
    if len(a) == 0 or len(b) == 0:
        return np.zeros((len(a), len(b)), dtype=np.bool_)
    sep = _separated(_axes(a), a, b, tol) | _separated(_axes(b), b, a, tol).T
    return ~sep


def inflate(sizes: FloatArray, margin: float) -> FloatArray:
    """Side lengths grown by ``margin`` [m] on every side."""
    return np.asarray(sizes, dtype=np.float64) + 2.0 * margin


def inside_rectangle(rect: FloatArray, x: tuple[float, float], y: tuple[float, float]) -> BoolArray:
    """``(n,)`` mask: every corner of ``rect`` ``(n, 4, 2)`` lies in ``[x0, x1] x [y0, y1]``."""
    tol = 1e-9
    r = np.asarray(rect, dtype=np.float64)
    ok = (
        (r[..., 0] >= x[0] - tol)
        & (r[..., 0] <= x[1] + tol)
        & (r[..., 1] >= y[0] - tol)
        & (r[..., 1] <= y[1] + tol)
    )
    return np.asarray(ok.all(-1), dtype=np.bool_)
