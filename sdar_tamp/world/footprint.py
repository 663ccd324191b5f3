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


def clearance(a: FloatArray, b: FloatArray, reach: float) -> FloatArray:
    """``(n,)`` [m]: for each rectangle ``a[i]``, the largest margin by which it can be grown
    (on its own axes, as :func:`inflate`) and still overlap no rectangle of ``b``, up to
    ``reach``: ``inf`` when every rectangle of ``b`` is farther than that, ``<= 0`` when one
    overlaps ``a[i]`` as it is. So ``a[i]`` grown by ``m < reach`` is clear of ``b`` iff
    ``clearance(a, b, reach)[i] > m``.

    Per pair, the separating-axis gaps: along an axis of ``a`` a margin widens ``a`` by itself,
    along an axis of ``b`` by ``|cos| + |sin|`` of the angle between them. Bounding circles
    (grown by ``reach``) skip the far pairs, so only the close ones are computed.
    """
    a = np.asarray(a, dtype=np.float64).reshape(-1, 4, 2)
    b = np.asarray(b, dtype=np.float64).reshape(-1, 4, 2)
    out = np.full(len(a), np.inf)
    if len(a) == 0 or len(b) == 0:
        return out
    ca, ua, ha = _frame(a)
    cb, ub, hb = _frame(b)
    ra = np.hypot(ha[:, 0], ha[:, 1]) + np.sqrt(2.0) * reach
    rb = np.hypot(hb[:, 0], hb[:, 1])
    dx = ca[:, None, 0] - cb[None, :, 0]  # (n, m)
    dy = ca[:, None, 1] - cb[None, :, 1]
    i, j = np.nonzero(dx * dx + dy * dy < (ra[:, None] + rb[None]) ** 2)
    if len(i) == 0:
        return out
    d = cb[j] - ca[i]  # (k, 2)
    ua, ha, ub, hb = ua[i], ha[i], ub[j], hb[j]  # (k, 2, 2) axes as rows, (k, 2) half sides
    dot = np.abs(np.einsum("kad,kbd->kab", ua, ub))  # |a's axis . b's axis|, (k, 2, 2)
    on_a = np.abs(np.einsum("kad,kd->ka", ua, d)) - ha - np.einsum("kab,kb->ka", dot, hb)
    along = dot.sum(axis=1)  # (k, 2): how much a margin widens a along b's axes
    on_b = np.abs(np.einsum("kbd,kd->kb", ub, d)) - hb - np.einsum("kab,ka->kb", dot, ha)
    pair = np.maximum(on_a.max(axis=1), (on_b / along).max(axis=1))
    np.minimum.at(out, i, pair)
    return out


def _frame(rect: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Centres ``(n, 2)``, unit axes ``(n, 2, 2)`` (rows) and half sides ``(n, 2)`` [m] of
    rectangles ``(n, 4, 2)`` given by their corners in order."""
    e = np.stack([rect[:, 1] - rect[:, 0], rect[:, 2] - rect[:, 1]], axis=1)  # (n, 2, 2)
    length = np.linalg.norm(e, axis=-1)  # (n, 2)
    return rect.mean(axis=1), e / length[..., None], length / 2.0


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
