"""Spheres fitted to a link's collision surface (a triangle mesh), covering it exactly.

The fit is deterministic and uses no random numbers:

1. Triangles are split at their edge midpoints until no edge is longer than
   ``edge_fraction`` of the link's bounding-box diagonal.
2. Their centroids, weighted by area, are clustered into ``k`` groups (k-means with a
   farthest-point start: the first centre is the centroid farthest from the mean, each next
   one the centroid farthest from the centres so far).
3. Each group gets the smallest sphere (Badoiu-Clarkson iterations) holding every vertex of
   its triangles. A sphere is convex, so it holds the whole triangles: the spheres cover the
   surface (up to ``tolerance``, the distance by which a tessellated primitive's true surface
   may stray from its triangles, added to every radius).

``k`` grows from 1 to ``max_spheres`` and the first fit whose volume (of the union of its
spheres) is within
``volume_ratio`` times the convex hull's volume is kept; if none is, the smallest summed
volume is kept. The interior is not sampled: a group that wraps around a link (the usual
case for few spheres) has its centre inside it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sdar_tamp.errors import ParameterError
from sdar_tamp.world._coal import hull_volume
from sdar_tamp.world.transforms import FloatArray

#: Lloyd iterations of the clustering (it stops earlier when no triangle changes group).
_LLOYD = 30
#: Badoiu-Clarkson iterations of the enclosing sphere.
_BALL = 60


@dataclass(frozen=True)
class FitOptions:
    """How spheres are fitted to one link (see the module's docstring)."""

    max_spheres: int = 8  # per link
    volume_ratio: float = 2.0  # union of the spheres' volume / convex hull volume to stop at
    edge_fraction: float = 0.1  # of the link's bounding-box diagonal

    def __post_init__(self) -> None:
        if self.max_spheres < 1:
            raise ParameterError(f"max_spheres must be >= 1, got {self.max_spheres}")
        if not (math.isfinite(self.volume_ratio) and self.volume_ratio >= 1.0):
            raise ParameterError(
                f"volume_ratio must be a finite number >= 1, got {self.volume_ratio}"
            )
        if not (math.isfinite(self.edge_fraction) and 0.0 < self.edge_fraction <= 1.0):
            raise ParameterError(f"edge_fraction must lie in (0, 1], got {self.edge_fraction}")


@dataclass(frozen=True)
class FittedSpheres:
    """Spheres covering one link: centres ``(n, 3)`` and radii ``(n,)`` [m], in the frame of
    the triangles; ``hull_volume`` [m^3] is the convex hull's volume of the surface."""

    centre: FloatArray
    radius: FloatArray
    hull_volume: float

    @property
    def volume(self) -> float:
        """The volume of the union of the spheres [m^3] (:func:`union_volume`)."""
        return union_volume(self.centre, self.radius)


def union_volume(centre: FloatArray, radius: FloatArray, resolution: int = 40) -> float:
    """The volume [m^3] of the union of spheres ``(n, 3)``, ``(n,)``, counted on a grid of
    ``resolution`` cells a side over their bounding box (cell midpoints; a few percent)."""
    lo = (centre - radius[:, None]).min(axis=0)
    hi = (centre + radius[:, None]).max(axis=0)
    step = (hi - lo) / resolution
    axes = [lo[i] + step[i] * (np.arange(resolution) + 0.5) for i in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    inside = np.zeros(len(grid), dtype=bool)
    for c, r in zip(centre, radius, strict=True):
        inside |= ((grid - c) ** 2).sum(axis=1) <= r * r
    return float(inside.mean() * np.prod(hi - lo))


def surface_points(triangles: FloatArray, n: int, rng: np.random.Generator) -> FloatArray:
    """``n`` points ``(n, 3)`` drawn uniformly on the surface of ``triangles`` ``(m, 3, 3)``."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    area = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    pick = rng.choice(len(triangles), n, p=area / area.sum())
    u, v = rng.uniform(size=n), rng.uniform(size=n)
    flip = u + v > 1.0
    u[flip], v[flip] = 1.0 - u[flip], 1.0 - v[flip]
    out: FloatArray = a[pick] + u[:, None] * (b - a)[pick] + v[:, None] * (c - a)[pick]
    return out


def subdivide(triangles: FloatArray, max_edge: float) -> FloatArray:
    """``triangles`` ``(m, 3, 3)`` split at their edge midpoints (four by four) until no edge
    is longer than ``max_edge`` [m]; the surface is the same."""
    if not max_edge > 0.0:
        raise ParameterError(f"max_edge must be > 0 [m], got {max_edge}")
    done: list[FloatArray] = []  # triangles short enough
    todo = np.asarray(triangles, dtype=np.float64).reshape(-1, 3, 3)
    while len(todo):
        edges = np.linalg.norm(todo - np.roll(todo, 1, axis=1), axis=2).max(axis=1)
        done.append(todo[edges <= max_edge])
        big = todo[edges > max_edge]
        a, b, c = big[:, 0], big[:, 1], big[:, 2]
        ab, bc, ca = (a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0
        todo = np.concatenate(
            [np.stack(t, axis=1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))]
        )
    return np.concatenate(done)


def _farthest_start(points: FloatArray, weights: FloatArray, k: int) -> FloatArray:
    mean = weights @ points / weights.sum()
    first = int(np.argmax(np.linalg.norm(points - mean, axis=1)))
    centres = [points[first]]
    gap = np.linalg.norm(points - points[first], axis=1)
    for _ in range(1, k):
        nxt = int(np.argmax(gap))
        centres.append(points[nxt])
        gap = np.minimum(gap, np.linalg.norm(points - points[nxt], axis=1))
    return np.array(centres)


def _clusters(points: FloatArray, weights: FloatArray, k: int) -> list[NDArray[np.int64]]:
    """Index arrays of the ``k`` groups of ``points`` (empty groups dropped)."""
    centres = _farthest_start(points, weights, k)
    label = np.full(len(points), -1)
    for _ in range(_LLOYD):
        d = ((points[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2)
        new = np.argmin(d, axis=1)
        if np.array_equal(new, label):
            break
        label = new
        for j in range(k):
            mine = label == j
            if mine.any():
                centres[j] = weights[mine] @ points[mine] / weights[mine].sum()
    return [np.flatnonzero(label == j) for j in range(k) if (label == j).any()]


def enclosing_sphere(points: FloatArray) -> tuple[FloatArray, float]:
    """A sphere ``(centre (3,), radius)`` holding every point of ``points`` ``(n, 3)``:
    Badoiu-Clarkson iterations from the bounding box's centre (within a few percent of the
    smallest), the radius then set to the farthest point so that every point is held."""
    c = (points.min(axis=0) + points.max(axis=0)) / 2.0
    best_c, best_r = c, float(np.linalg.norm(points - c, axis=1).max())
    for i in range(1, _BALL + 1):
        d = np.linalg.norm(points - c, axis=1)
        far = int(np.argmax(d))
        if d[far] < best_r:
            best_c, best_r = c, float(d[far])
        c = c + (points[far] - c) / (i + 1)
    return best_c.copy(), best_r


@dataclass(frozen=True)
class _Surface:
    """Split triangles as the clustering reads them: centroids ``(m, 3)``, area weights
    ``(m,)``, the distinct vertices ``(v, 3)`` and each triangle's vertex indices ``(m, 3)``."""

    centroid: FloatArray
    weight: FloatArray
    vertex: FloatArray
    corner: NDArray[np.int64]

    @staticmethod
    def of(triangles: FloatArray) -> _Surface:
        cross = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
        area = np.linalg.norm(cross, axis=1) / 2.0
        weight = area + 1e-12 * max(float(area.max()), 1.0)
        vertex, inverse = np.unique(triangles.reshape(-1, 3), axis=0, return_inverse=True)
        corner = inverse.reshape(-1, 3).astype(np.int64)
        return _Surface(triangles.mean(axis=1), weight, vertex, corner)


def _fit_k(surface: _Surface, k: int, tolerance: float) -> tuple[FloatArray, FloatArray]:
    centres, radii = [], []
    for members in _clusters(surface.centroid, surface.weight, k):
        c, r = enclosing_sphere(surface.vertex[np.unique(surface.corner[members])])
        centres.append(c)
        radii.append(r + tolerance)
    return np.array(centres), np.array(radii)


def fit_spheres(
    triangles: FloatArray, options: FitOptions = FitOptions(), tolerance: float = 0.0
) -> FittedSpheres:
    """Spheres covering the surface of ``triangles`` ``(m, 3, 3)`` [m] (one link's collision
    surface in one frame), at most ``options.max_spheres`` of them; ``tolerance`` [m] is
    added to every radius (see the module's docstring).

    Raises:
        ParameterError: no triangles, a coordinate that is not finite, or a negative
            tolerance.
    """
    tri = np.asarray(triangles, dtype=np.float64).reshape(-1, 3, 3)
    if len(tri) == 0:
        raise ParameterError("fit_spheres needs at least one triangle, got none")
    if not np.isfinite(tri).all():
        raise ParameterError("fit_spheres: the triangles have coordinates that are not finite")
    if not (math.isfinite(tolerance) and tolerance >= 0.0):
        raise ParameterError(f"tolerance must be a finite number >= 0 [m], got {tolerance}")
    vertices = tri.reshape(-1, 3)
    diagonal = float(np.linalg.norm(vertices.max(axis=0) - vertices.min(axis=0)))
    hull = hull_volume(vertices)
    if diagonal > 0.0:
        tri = subdivide(tri, options.edge_fraction * diagonal)
    surface = _Surface.of(tri)
    best: tuple[float, FloatArray, FloatArray] | None = None
    for k in range(1, min(options.max_spheres, len(tri)) + 1):
        centres, radii = _fit_k(surface, k, tolerance)
        volume = union_volume(centres, radii)
        if best is None or volume < best[0]:
            best = (volume, centres, radii)
        if volume <= options.volume_ratio * hull:
            break
    assert best is not None  # k = 1 always runs
    return FittedSpheres(best[1], best[2], hull)


def box_triangles(half: FloatArray) -> FloatArray:
    """The 12 triangles ``(12, 3, 3)`` of a box of half sides ``half`` centred at the origin."""
    h = np.asarray(half, dtype=np.float64)
    corner = np.array([[(i >> 2) & 1, (i >> 1) & 1, i & 1] for i in range(8)]) * 2.0 - 1.0
    v = corner * h
    faces = [
        (0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
        (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3),
    ]  # fmt: skip
    out: FloatArray = v[np.array(faces)]
    return out


def cylinder_triangles(
    radius: float, half_length: float, sides: int = 24
) -> tuple[FloatArray, float]:
    """Triangles of a prism inscribed in a cylinder on the z axis centred at the origin, and
    the largest distance [m] from the cylinder's surface to them (``radius (1 - cos(pi /
    sides))``)."""
    a = 2.0 * np.pi * np.arange(sides) / sides
    ring = np.stack([radius * np.cos(a), radius * np.sin(a), np.zeros(sides)], axis=1)
    lift = np.array([0.0, 0.0, half_length])
    top, bottom = ring + lift, ring - lift
    nxt = np.roll(np.arange(sides), -1)
    centre_top = np.broadcast_to([0.0, 0.0, half_length], (sides, 3))
    centre_bottom = np.broadcast_to([0.0, 0.0, -half_length], (sides, 3))
    tris = [
        np.stack([bottom, bottom[nxt], top[nxt]], axis=1),
        np.stack([bottom, top[nxt], top], axis=1),
        np.stack([centre_top, top, top[nxt]], axis=1),
        np.stack([centre_bottom, bottom[nxt], bottom], axis=1),
    ]
    return np.concatenate(tris), float(radius * (1.0 - np.cos(np.pi / sides)))
