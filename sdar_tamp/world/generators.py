"""Seeded generators of the paper's instance families (section V).

* ``R`` random: independent random start and goal arrangements;
* ``S`` single cycle: exactly one dependency cycle (a simple cycle), the rest acyclic;
* ``D`` double cycle: exactly two disjoint simple cycles, the rest acyclic;
* ``M`` mixed (12 objects in the paper): at least one independent object, one chain of two or
  more and one cycle.

Structured families are built from a *successor map*: object ``i`` with successor ``j`` gets
its goal on (a perturbation of) ``j``'s start, overlapping no other start and no other goal, so
the dependency graph has exactly the edges ``i -> j``; objects without successor get a goal
overlapping no other object's start. Each instance is verified with
:mod:`sdar_tamp.world.dependency`; failures are retried with the same generator, bounded.
Every random choice comes from ``numpy.random.default_rng(seed)``: same seed, same instance.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.dependency import instance_dependency_graph
from sdar_tamp.world.errors import GenerationError
from sdar_tamp.world.footprint import corners, inflate, inside_rectangle, overlap_matrix
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D, validate_instance
from sdar_tamp.world.scene import Workspace
from sdar_tamp.world.transforms import BoolArray, FloatArray

FAMILIES = ("R", "S", "D", "M")
DEFAULT_SIZE = (0.08, 0.04, 0.05)
DEFAULT_WORKSPACE = Workspace((-0.25, 0.25), (-0.30, 0.30))


@dataclass(frozen=True)
class GeneratorOptions:
    """Sizes [m], spacing between start footprints [m] and retry budgets."""

    size: tuple[float, float, float] = DEFAULT_SIZE
    workspace: Workspace = DEFAULT_WORKSPACE
    # minimum clearance between footprints of one arrangement [m]: room for a finger of the
    # 60 mm pre-grasp opening (1 cm from the pad to the object, 1.2 cm finger, 3 mm margin)
    # beside every side of every object, so each object can be grasped in the start and in
    # the goal arrangement
    gap: float = 0.026
    attempts: int = 200  # whole-instance retries
    samples: int = 4000  # candidate poses drawn per placement


def generate_instance(
    family: str,
    n_objects: int,
    seed: int,
    options: GeneratorOptions | None = None,
    name: str | None = None,
) -> Instance:
    """One instance of ``family`` with ``n_objects`` objects; deterministic in ``seed``."""
    if family not in FAMILIES:
        raise ParameterError(f"family: expected one of {list(FAMILIES)}, got {family!r}")
    minimum = {"R": 1, "S": 2, "D": 4, "M": 5}[family]
    if n_objects < minimum:
        raise ParameterError(f"objects: family {family} needs at least {minimum}, got {n_objects}")
    opts = options or GeneratorOptions()
    rng = np.random.default_rng(seed)
    for _ in range(opts.attempts):
        inst = _attempt(family, n_objects, rng, opts, name or f"{family}{n_objects}", seed)
        if inst is not None and _verified(family, inst):
            validate_instance(inst)
            return inst
    raise GenerationError(
        f"family {family} with {n_objects} objects (seed {seed}): no instance with the promised "
        f"structure after {opts.attempts} attempts; try fewer objects or a larger workspace"
    )


def _verified(family: str, inst: Instance) -> bool:
    g = instance_dependency_graph(inst)
    cycles = g.cycle_components()
    if family == "S":
        return len(cycles) == 1 and g.is_simple_cycle(cycles[0])
    if family == "D":
        return len(cycles) == 2 and all(g.is_simple_cycle(c) for c in cycles)
    if family == "M":
        s = g.structure()
        return bool(s.independent and s.chains and s.cycles)
    return True


def _successors(family: str, n: int, rng: np.random.Generator) -> dict[int, int]:
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


def _attempt(
    family: str, n: int, rng: np.random.Generator, opts: GeneratorOptions, name: str, seed: int
) -> Instance | None:
    sizes = np.tile(np.array(opts.size[:2]), (n, 1))
    starts = _arrangement(n, sizes, rng, opts)
    if starts is None:
        return None
    if family == "R":
        goals = _arrangement(n, sizes, rng, opts)
    else:
        goals = _structured_goals(_successors(family, n, rng), starts, sizes, rng, opts)
    if goals is None:
        return None
    objects = tuple(
        ObjectSpec(
            f"o{i}", opts.size, Pose2D(*map(float, starts[i])), Pose2D(*map(float, goals[i]))
        )
        for i in range(n)
    )
    return Instance(name, opts.workspace, objects, family=family, seed=seed)


def _candidates(
    k: int, size: FloatArray, rng: np.random.Generator, opts: GeneratorOptions
) -> FloatArray:
    """``k`` random poses ``(k, 3)`` whose footprint lies in the workspace."""
    ws = opts.workspace
    poses = np.column_stack(
        [rng.uniform(*ws.x, k), rng.uniform(*ws.y, k), rng.uniform(-np.pi / 2, np.pi / 2, k)]
    )
    ok = inside_rectangle(corners(poses, np.tile(size, (k, 1))), ws.x, ws.y)
    return poses[ok]


def _arrangement(
    n: int, sizes: FloatArray, rng: np.random.Generator, opts: GeneratorOptions
) -> FloatArray | None:
    """Random sequential placement of ``n`` footprints, pairwise at least ``gap`` apart."""
    placed = np.zeros((0, 3))
    for i in range(n):
        cand = _candidates(opts.samples, sizes[i], rng, opts)
        ok = _clear(cand, sizes[i], placed, sizes[: len(placed)], opts.gap)
        if not ok.any():
            return None
        placed = np.vstack([placed, cand[np.argmax(ok)]])
    return placed


def _clear(
    cand: FloatArray, size: FloatArray, poses: FloatArray, sizes: FloatArray, gap: float
) -> BoolArray:
    """Mask of candidates at least ``gap`` away from every footprint at ``poses``."""
    if len(poses) == 0:
        return np.ones(len(cand), dtype=bool)
    grown = corners(cand, np.tile(inflate(size, gap / 2), (len(cand), 1)))
    hit = overlap_matrix(grown, corners(poses, inflate(sizes, gap / 2))).any(axis=1)
    return np.asarray(~hit, dtype=np.bool_)


def _structured_goals(
    succ: dict[int, int],
    starts: FloatArray,
    sizes: FloatArray,
    rng: np.random.Generator,
    opts: GeneratorOptions,
) -> FloatArray | None:
    n = len(starts)
    start_rect = corners(starts, sizes)
    goals = np.full((n, 3), np.nan)
    # objects with a successor first (their goals are pinned near a start), then free goals
    for i in [*sorted(succ), *(i for i in range(n) if i not in succ)]:
        placed = ~np.isnan(goals[:, 0])
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
            ws = opts.workspace
            cand = cand[
                inside_rectangle(corners(cand, np.tile(sizes[i], (len(cand), 1))), ws.x, ws.y)
            ]
            allowed = np.zeros(n, dtype=bool)
            allowed[[i, j]] = True
        else:
            cand = _candidates(opts.samples, sizes[i], rng, opts)
            allowed = np.zeros(n, dtype=bool)
            allowed[i] = True
        if len(cand) == 0:
            return None
        hits = overlap_matrix(corners(cand, np.tile(sizes[i], (len(cand), 1))), start_rect)
        ok = ~hits[:, ~allowed].any(axis=1)
        if i in succ:
            ok &= hits[:, succ[i]]
        ok &= _clear(cand, sizes[i], goals[placed], sizes[placed], opts.gap)
        if not ok.any():
            return None
        goals[i] = cand[np.argmax(ok)]
    return goals
