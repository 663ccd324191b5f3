"""Random sequential placement of footprints on the table, pairwise at least a clearance apart.

Candidate poses are drawn uniformly in the workspace (yaw in ``[-pi/2, pi/2]``) and the first
that keeps the clearance to every footprint placed so far is taken
(:func:`random_arrangement`); :func:`first_passing` and :func:`clear_of` are the pieces the
structured goals of :mod:`sdar_tamp.world.structured_goals` use too.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import numpy as np

from sdar_tamp.world.footprint import corners, inflate, inside_rectangle, overlap_matrix
from sdar_tamp.world.scene import Workspace
from sdar_tamp.world.transforms import BoolArray, FloatArray


def candidate_poses(
    k: int, size: FloatArray, rng: np.random.Generator, workspace: Workspace
) -> FloatArray:
    """``k`` random poses ``(k, 3)`` whose footprint lies in the workspace."""
    ws = workspace
    poses = np.column_stack(
        [rng.uniform(*ws.x, k), rng.uniform(*ws.y, k), rng.uniform(-np.pi / 2, np.pi / 2, k)]
    )
    ok = inside_rectangle(corners(poses, np.tile(size, (k, 1))), ws.x, ws.y)
    return poses[ok]


def random_arrangement(
    n: int,
    sizes: FloatArray,
    rng: np.random.Generator,
    workspace: Workspace,
    samples: int,
    gap: float,
) -> FloatArray:
    """Random sequential placement of ``n`` footprints, pairwise at least ``gap`` apart; the
    poses ``(k, 3)`` placed, ``k < n`` when none of the ``samples`` candidates drawn for the
    next one had room for it."""
    placed = np.zeros((0, 3))
    for i in range(n):
        cand = candidate_poses(samples, sizes[i], rng, workspace)
        clear = partial(clear_of, size=sizes[i], poses=placed, sizes=sizes[: len(placed)], gap=gap)
        first = first_passing(cand, clear)
        if first is None:
            return placed
        placed = np.vstack([placed, cand[first]])
    return placed


def first_passing(
    cand: FloatArray, test: Callable[[FloatArray], BoolArray], chunk: int = 256
) -> int | None:
    """The index of the first candidate pose that passes ``test`` (a mask of poses), testing
    chunk by chunk: the same answer as ``argmax`` over the whole mask, for less work."""
    for lo in range(0, len(cand), chunk):
        ok = test(cand[lo : lo + chunk])
        if ok.any():
            return lo + int(np.argmax(ok))
    return None


def clear_of(
    cand: FloatArray, *, size: FloatArray, poses: FloatArray, sizes: FloatArray, gap: float
) -> BoolArray:
    """Mask of candidates at least ``gap`` away from every footprint at ``poses``."""
    if len(poses) == 0:
        return np.ones(len(cand), dtype=bool)
    grown = corners(cand, np.tile(inflate(size, gap / 2), (len(cand), 1)))
    hit = overlap_matrix(grown, corners(poses, inflate(sizes, gap / 2))).any(axis=1)
    return np.asarray(~hit, dtype=np.bool_)
