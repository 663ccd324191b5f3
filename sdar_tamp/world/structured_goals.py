"""Goals of the structured families (S, D, M): a random successor map with the family's
cycles and chains, and goal poses that give the dependency graph exactly its edges.

Object ``i`` with successor ``j`` gets its goal on (a perturbation of) ``j``'s start, overlapping
no other start and no other goal; objects without successor get a goal overlapping no other
object's start (see :mod:`sdar_tamp.world.generators`).
"""

from __future__ import annotations

import itertools
from functools import partial

import numpy as np

from sdar_tamp.world.footprint import corners, inside_rectangle, overlap_matrix
from sdar_tamp.world.placement import candidate_poses, clear_of, first_passing
from sdar_tamp.world.scene import Workspace
from sdar_tamp.world.transforms import BoolArray, FloatArray


def successor_map(family: str, n: int, rng: np.random.Generator) -> dict[int, int]:
    """Random successor map with the family's cycles and chains (indices into a permutation)."""
    order = [int(v) for v in rng.permutation(n)]
    succ: dict[int, int] = {}
    if family == "S":
        cycles = [int(rng.integers(max(2, (n + 1) // 2), n + 1))]
    elif family == "D":
        total = int(rng.integers(max(4, (n + 1) // 2), n + 1))
        first = int(rng.integers(2, total - 1))
        cycles = [first, total - first]
    else:  # M: 1-2 cycles, 1-2 chains, >= 1 independent
        cycles = [int(rng.integers(2, 5)) for _ in range(int(rng.integers(1, 3)))]
        while sum(cycles) > n - 3:
            cycles.pop()
        cycles = cycles or [2]
    pos = 0
    for length in cycles:
        members = order[pos : pos + length]
        pos += length
        for k, i in enumerate(members):
            succ[i] = members[(k + 1) % length]
    rest = order[pos:]
    n_chains = 1 if family == "M" else int(rng.integers(0, len(rest) // 2 + 1))
    if family == "M" and len(rest) >= 6:
        n_chains = int(rng.integers(1, 3))
    for _ in range(n_chains):
        free = len(rest) - (1 if family == "M" else 0)
        if free < 2:
            break
        length = int(rng.integers(2, min(4, free) + 1))
        chain, rest = rest[:length], rest[length:]
        for a, b in itertools.pairwise(chain):
            succ[a] = b
    return succ


def structured_goals(
    succ: dict[int, int],
    starts: FloatArray,
    sizes: FloatArray,
    rng: np.random.Generator,
    workspace: Workspace,
    samples: int,
    gap: float,
) -> FloatArray | None:
    """Goal poses ``(n, 3)`` for the ``starts``: object ``i`` with successor ``j`` overlaps
    ``j``'s start, each other object no start but its own, and no goal another's; None when
    no candidate pose passes for some object."""
    n = len(starts)
    start_rect = corners(starts, sizes)
    goals = np.full((n, 3), np.nan)
    # objects with a successor first (their goals are pinned near a start), then free goals
    for i in [*sorted(succ), *(i for i in range(n) if i not in succ)]:
        if i in succ:
            j = succ[i]
            jitter = np.column_stack(
                [
                    rng.uniform(-0.01, 0.01, 64),
                    rng.uniform(-0.01, 0.01, 64),
                    rng.uniform(-0.3, 0.3, 64),
                ]
            )
            cand = np.vstack([starts[j] + jitter, starts[j]])
            ws = workspace
            cand = cand[
                inside_rectangle(corners(cand, np.tile(sizes[i], (len(cand), 1))), ws.x, ws.y)
            ]
            allowed = np.zeros(n, dtype=bool)
            allowed[[i, j]] = True
        else:
            cand = candidate_poses(samples, sizes[i], rng, workspace)
            allowed = np.zeros(n, dtype=bool)
            allowed[i] = True
        test = partial(
            _goal_ok,
            i=i,
            successor=succ.get(i),
            allowed=allowed,
            start_rect=start_rect,
            goals=goals,
            sizes=sizes,
            gap=gap,
        )
        first = first_passing(cand, test)
        if first is None:
            return None
        goals[i] = cand[first]
    return goals


def _goal_ok(
    cand: FloatArray,
    *,
    i: int,
    successor: int | None,
    allowed: BoolArray,
    start_rect: FloatArray,
    goals: FloatArray,
    sizes: FloatArray,
    gap: float,
) -> BoolArray:
    """Mask of goal candidates for object ``i``: overlapping no start but the ``allowed``
    ones, the successor's start if any, and clear of the goals placed so far."""
    hits = overlap_matrix(corners(cand, np.tile(sizes[i], (len(cand), 1))), start_rect)
    ok = ~hits[:, ~allowed].any(axis=1)
    if successor is not None:
        ok &= hits[:, successor]
    placed = ~np.isnan(goals[:, 0])
    ok &= clear_of(cand, size=sizes[i], poses=goals[placed], sizes=sizes[placed], gap=gap)
    return np.asarray(ok, dtype=np.bool_)
