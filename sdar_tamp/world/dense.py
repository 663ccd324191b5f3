"""The ``N`` (dense) family: tightly packed tables of mixed cuboids whose neighbours trade places.

Built to test what the paper's families rarely show: objects at the paper's clearance from
each other on every side, several sizes on one table, and goals that are a neighbour's place.

* **Sizes**: every pair of consecutive objects draws one of :data:`DENSE_SIZES` (a bar, a
  short bar, a thin bar and a cube; all graspable, see :mod:`sdar_tamp.world.graspability`).
* **Start**: objects are placed one by one, ``gap`` apart (yaw near 0 or a quarter turn): every
  other one at the clear candidate pose nearest the workspace centre, so the table fills from
  the middle outwards, and the next, the same cuboid, at the clear pose nearest it: a packing
  far denser than random placement, made of neighbouring pairs.
* **Goals**: pairs of neighbours *trade places* where each fits the other's spot (each
  goal is the other's start, turned half a turn, then by a small angle where that stays clear):
  dependency 2-cycles of touching objects. The others are *turned on their spot* by a quarter
  turn, else a small angle, where the turned footprint stays clear of every goal, else half a
  turn (the same footprint, another pose): each must be picked and placed again.

Every choice comes from the caller's generator, so the family is as reproducible as the others.
"""

from __future__ import annotations

import math

import numpy as np

from sdar_tamp.world.footprint import corners, inflate, inside_rectangle, overlap_matrix
from sdar_tamp.world.transforms import BoolArray, FloatArray

#: The cuboids [m] (length, width, height) of a dense table; the gripper closes on the width.
DENSE_SIZES: tuple[tuple[float, float, float], ...] = (
    (0.08, 0.04, 0.05),
    (0.06, 0.04, 0.05),
    (0.07, 0.03, 0.04),
    (0.045, 0.045, 0.05),
)
#: Largest turn [rad] of a swapped goal besides the half turn.
SMALL_TURN = 0.25
#: Yaw noise [rad] of start poses around 0 and a quarter turn.
YAW_NOISE = 0.15
#: Share of the objects proposed to trade places with a neighbour (a pair whose objects do not
#: fit each other's spot keeps its places).
SWAP_SHARE = 2.0 / 3.0


def dense_sizes(n: int, rng: np.random.Generator) -> FloatArray:
    """``(n, 3)`` sizes drawn from :data:`DENSE_SIZES`, one per pair of consecutive objects
    (objects ``2k`` and ``2k + 1`` are the same cuboid)."""
    kinds = np.repeat(rng.integers(0, len(DENSE_SIZES), (n + 1) // 2), 2)[:n]
    return np.asarray(DENSE_SIZES, dtype=float)[kinds]


def packed_arrangement(
    sizes: FloatArray,
    rng: np.random.Generator,
    x: tuple[float, float],
    y: tuple[float, float],
    gap: float,
    samples: int,
) -> FloatArray:
    """Poses ``(k, 3)`` of the objects placed one after the other, ``gap`` [m] apart: object
    ``2k`` at the clear candidate nearest the centre of the ``x`` by ``y`` workspace, object
    ``2k + 1`` at the one nearest object ``2k`` (its neighbour); ``k < len(sizes)`` when no
    candidate had room for the next object."""
    centre = np.array([0.5 * (x[0] + x[1]), 0.5 * (y[0] + y[1])])
    placed = np.zeros((0, 3))
    for i in range(len(sizes)):
        cand = np.column_stack(
            [
                rng.uniform(*x, samples),
                rng.uniform(*y, samples),
                rng.integers(0, 2, samples) * (math.pi / 2)
                + rng.uniform(-YAW_NOISE, YAW_NOISE, samples),
            ]
        )
        cand = cand[inside_rectangle(corners(cand, np.tile(sizes[i, :2], (samples, 1))), x, y)]
        cand = cand[_clear(cand, sizes[i, :2], placed, sizes[: len(placed), :2], gap)]
        if len(cand) == 0:
            break
        target = placed[i - 1, :2] if i % 2 else centre
        best = int(np.argmin(np.linalg.norm(cand[:, :2] - target, axis=1)))
        placed = np.vstack([placed, cand[best]])
    return placed


def neighbour_pairs(
    n: int, rng: np.random.Generator, share: float = SWAP_SHARE
) -> list[tuple[int, int]]:
    """The neighbours ``(2k, 2k + 1)`` proposed to trade places: about ``share`` of the ``n``
    objects (the number of pairs is drawn between half and all of that)."""
    most = min(int(share * n) // 2, n // 2)
    want = int(rng.integers(max(1, most // 2), most + 1)) if most else 0
    chosen = sorted(int(k) for k in rng.choice(n // 2, size=want, replace=False))
    return [(2 * k, 2 * k + 1) for k in chosen]


def dense_goals(
    starts: FloatArray,
    sizes: FloatArray,
    pairs: list[tuple[int, int]],
    rng: np.random.Generator,
    gap: float,
    x: tuple[float, float],
    y: tuple[float, float],
) -> tuple[FloatArray, list[tuple[int, int]]]:
    """Goals ``(n, 3)`` and the pairs that trade places (see the module docstring): a proposed
    pair trades places only where both objects fit the other's spot; the goal footprints stay
    ``gap`` apart and inside the workspace."""
    n = len(starts)
    goals = starts.copy()
    goals[:, 2] += math.pi  # the fallback of every object: its spot, half a turn round
    swapped: list[tuple[int, int]] = []
    for i, j in pairs:
        trial = goals.copy()
        trial[i], trial[j] = starts[j], starts[i]
        trial[[i, j], 2] += math.pi
        if all(_fits(trial[a], a, trial, sizes, gap, x, y) for a in (i, j)):
            goals = trial
            swapped.append((i, j))
    for a in [k for pair in swapped for k in pair]:
        turned = goals[a].copy()
        turned[2] += rng.uniform(-SMALL_TURN, SMALL_TURN)
        if _fits(turned, a, goals, sizes, gap, x, y):
            goals[a] = turned
    moved = {k for pair in swapped for k in pair}
    for a in (k for k in range(n) if k not in moved):
        for turn in (math.pi / 2, rng.uniform(-SMALL_TURN, SMALL_TURN)):
            turned = starts[a].copy()
            turned[2] += turn + rng.uniform(-YAW_NOISE, YAW_NOISE)
            if _fits(turned, a, goals, sizes, gap, x, y):
                goals[a] = turned
                break
    goals[:, 2] = np.mod(goals[:, 2] + math.pi, 2 * math.pi) - math.pi
    return goals, swapped


def _fits(
    pose: FloatArray,
    index: int,
    goals: FloatArray,
    sizes: FloatArray,
    gap: float,
    x: tuple[float, float],
    y: tuple[float, float],
) -> bool:
    """Whether object ``index`` at ``pose`` is inside the workspace and ``gap`` from every
    other goal."""
    rect = corners(pose[None, :], sizes[index : index + 1, :2])
    if not bool(inside_rectangle(rect, x, y)[0]):
        return False
    others = np.arange(len(goals)) != index
    return bool(_clear(pose[None, :], sizes[index, :2], goals[others], sizes[others, :2], gap)[0])


def _clear(
    cand: FloatArray, size: FloatArray, poses: FloatArray, sizes: FloatArray, gap: float
) -> BoolArray:
    """Mask of candidate poses at least ``gap`` [m] from every footprint at ``poses``."""
    if len(poses) == 0 or len(cand) == 0:
        return np.ones(len(cand), dtype=bool)
    grown = corners(cand, np.tile(inflate(size, gap / 2), (len(cand), 1)))
    hit = overlap_matrix(grown, corners(poses, inflate(sizes, gap / 2))).any(axis=1)
    return np.asarray(~hit, dtype=np.bool_)
