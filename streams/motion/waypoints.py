"""Joint-space waypoint helpers: evenly spaced straight lines, densified paths, and per-arm
paths combined into one configuration path (synchronised, or one arm after the other)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from sdar_tamp.world.transforms import FloatArray


def straight_line(q_a: FloatArray, q_b: FloatArray, knots: int) -> FloatArray:
    """``(knots, n)`` evenly spaced configurations from ``q_a`` to ``q_b``."""
    s = np.linspace(0.0, 1.0, knots)[:, None]
    return (1.0 - s) * np.asarray(q_a)[None] + s * np.asarray(q_b)[None]


def densify(path: FloatArray, factor: int) -> FloatArray:
    """The path with ``factor - 1`` evenly spaced points inserted in every segment."""
    s = np.linspace(0.0, 1.0, factor + 1)[:-1]
    seg = path[:-1, None] * (1.0 - s[None, :, None]) + path[1:, None] * s[None, :, None]
    return np.concatenate([seg.reshape(-1, path.shape[1]), path[-1:]])


def sync_arms(paths: list[FloatArray]) -> FloatArray:
    """Per-arm paths ``(n_i, arm dof)`` as one ``(max n, dof)`` path: shorter ones are
    resampled (linearly between their waypoints), so every arm starts and ends together."""
    n = max(len(p) for p in paths)
    x = np.linspace(0.0, 1.0, n)
    out = []
    for p in paths:
        if len(p) == 1:
            out.append(np.repeat(p, n, axis=0))
            continue
        xp = np.linspace(0.0, 1.0, len(p))
        out.append(np.stack([np.interp(x, xp, p[:, j]) for j in range(p.shape[1])], axis=1))
    return np.concatenate(out, axis=1)


def chain_arms(paths: list[FloatArray], order: Sequence[int] | None = None) -> list[FloatArray]:
    """Per-arm paths ``(n_i, arm dof)`` as one ``(n_i, dof)`` path per arm: the arms move one
    after the other, in ``order`` (indices into ``paths``; default layout order), the others
    waiting where they are (each timed rest to rest). The paths come in the order of moving."""
    turns = range(len(paths)) if order is None else order
    moved: set[int] = set()
    out = []
    for k in turns:
        n = len(paths[k])
        parts = [
            paths[k] if j == k else np.repeat(p[-1:] if j in moved else p[:1], n, axis=0)
            for j, p in enumerate(paths)
        ]
        out.append(np.concatenate(parts, axis=1))
        moved.add(k)
    return out
