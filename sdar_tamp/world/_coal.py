"""Typed adapter over coal: the primitive shapes of the world and a direct pair query.

coal ships without type stubs; shapes are returned as ``Any`` and only passed on to
pinocchio geometry objects or to :func:`shape_distance`.
"""

from __future__ import annotations

from typing import Any

import coal
import numpy as np

from sdar_tamp.world.transforms import FloatArray


def box(size: tuple[float, float, float] | FloatArray) -> Any:
    """A box of full side lengths ``size`` ``(3,)`` [m], centred on its frame."""
    x, y, z = (float(v) for v in size)
    return coal.Box(x, y, z)


def _transform(T: FloatArray) -> Any:
    return coal.Transform3s(np.ascontiguousarray(T[:3, :3]), np.ascontiguousarray(T[:3, 3]))


def shape_distance(
    shape_a: Any, T_world_a: FloatArray, shape_b: Any, T_world_b: FloatArray
) -> float:
    """Signed distance between two shapes [m]; negative is penetration depth."""
    request = coal.DistanceRequest()
    result = coal.DistanceResult()
    coal.distance(shape_a, _transform(T_world_a), shape_b, _transform(T_world_b), request, result)
    return float(result.min_distance)


def hull_volume(points: FloatArray) -> float:
    """The volume [m^3] of the convex hull of ``points`` ``(n, 3)`` (coal's qhull); 0 when
    they span less than three dimensions (qhull is not called then: it fails on them)."""
    pts = np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 3))
    if len(pts) < 4:
        return 0.0
    spread = np.linalg.svd(pts - pts.mean(axis=0), compute_uv=False)
    if spread[2] <= 1e-9 * max(float(spread[0]), 1e-300):
        return 0.0
    model = coal.BVHModelOBBRSS()
    model.beginModel(0, len(pts))
    model.addVertices(pts)
    model.endModel()
    model.buildConvexHull(True, "Qt")
    return float(model.convex.computeVolume())
