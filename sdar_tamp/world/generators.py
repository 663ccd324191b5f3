"""Seeded generators of the paper's instance families (section V).

* ``R`` random: independent random start and goal arrangements;
* ``S`` single cycle: exactly one dependency cycle (a simple cycle), the rest acyclic;
* ``D`` double cycle: exactly two disjoint simple cycles, the rest acyclic;
* ``M`` mixed (12 objects in the paper): at least one independent object, one chain of two or
  more and one cycle;
* ``N`` dense (beyond the paper): mixed sizes packed from the middle at the clearance,
  neighbours of one size trading places, the others turned on their spot
  (:mod:`sdar_tamp.world.dense`).

Structured families are built from a *successor map*: object ``i`` with successor ``j`` gets
its goal on (a perturbation of) ``j``'s start, overlapping no other start and no other goal, so
the dependency graph has exactly the edges ``i -> j``; objects without successor get a goal
overlapping no other object's start. Each instance is verified with
:mod:`sdar_tamp.world.dependency`; failures are retried with the same generator, bounded.
Every random choice comes from ``numpy.random.default_rng(seed)``: same seed, same instance.
An optional acceptance test (``accept``: instance -> the reason it is refused, or ``None``)
rejects further samples, e.g. those the infeasibility proofs of :mod:`streams.feasibility`
show unsolvable (the command line passes them); a refused sample is retried like any other.

Requests that cannot be met are refused early: :func:`max_objects` is a sound area bound (more
objects than it allows cannot be placed with the clearance, whatever the placement), checked
before any sampling; and the retries stop after ``GeneratorOptions.crowded_attempts``
attempts in a row in which the random placement found no room for every object.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np

from sdar_tamp.arguments import COUNT, SEED, Real
from sdar_tamp.errors import ParameterError
from sdar_tamp.world.dense import (
    DENSE_SIZES,
    dense_goals,
    dense_sizes,
    neighbour_pairs,
    packed_arrangement,
)
from sdar_tamp.world.dependency import instance_dependency_graph
from sdar_tamp.world.errors import GenerationError
from sdar_tamp.world.footprint import corners, inflate, inside_rectangle, overlap_matrix
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D, validate_instance
from sdar_tamp.world.scene import Workspace
from sdar_tamp.world.transforms import BoolArray, FloatArray

FAMILIES = ("R", "S", "D", "M", "N")
DEFAULT_SIZE = (0.08, 0.04, 0.05)
DEFAULT_WORKSPACE = Workspace((-0.25, 0.25), (-0.30, 0.30))
_LENGTH = Real(0.0, closed=True, unit="m")
#: An acceptance test of generated instances: the reason one is refused, or ``None``.
Acceptance = Callable[[Instance], str | None]
_SIDE = Real(0.0, unit="m")


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
    # give up after this many attempts in a row in which the random placement of the start
    # (or, for R, the goal) arrangement found no room for every object: the table is too full
    crowded_attempts: int = 5

    def __post_init__(self) -> None:
        for name in ("attempts", "samples", "crowded_attempts"):
            COUNT.check(name, getattr(self, name))
        _LENGTH.check("gap", self.gap)
        for k, side in enumerate(self.size):
            _SIDE.check(f"size[{k}]", side)


def max_objects(options: GeneratorOptions | None = None) -> int:
    """The most objects that can rest in the workspace at the clearance ``gap`` [m]: a sound
    upper bound from areas. Every footprint grown by ``gap / 2`` on each side is disjoint
    from the others' (that is how clearance is tested) and lies within the workspace grown by
    ``gap / 2``; so ``n`` footprints need ``n (l + gap)(w + gap)`` of the grown workspace's
    area. More objects than this can never be placed; fewer may still fail to be found."""
    opts = options or GeneratorOptions()
    return math.floor(_table_area(opts) / _grown_area(opts) + 1e-9)


def generate_instance(
    family: str,
    n_objects: int,
    seed: int,
    options: GeneratorOptions | None = None,
    name: str | None = None,
    accept: Acceptance | None = None,
) -> Instance:
    """One instance of ``family`` with ``n_objects`` objects; deterministic in ``seed`` (and
    in ``accept``, which refuses a sample by returning why, see the module docstring)."""
    if family not in FAMILIES:
        raise ParameterError(f"family: expected one of {list(FAMILIES)}, got {family!r}")
    n_objects = COUNT.check("objects", n_objects)
    seed = SEED.check("seed", seed)
    minimum = {"R": 1, "S": 2, "D": 4, "M": 5, "N": 3}[family]
    if n_objects < minimum:
        raise ParameterError(f"objects: family {family} needs at least {minimum}, got {n_objects}")
    opts = options or GeneratorOptions()
    limit = max_objects(_smallest(opts) if family == "N" else opts)
    if n_objects > limit:
        raise ParameterError(
            f"objects: at most {limit} objects of {opts.size[0]:g} x {opts.size[1]:g} m with "
            f"{opts.gap:g} m clearance fit on the {_extent(opts)} workspace (their grown "
            f"footprints need {n_objects * _grown_area(opts):.3f} m^2 of "
            f"{_table_area(opts):.3f} m^2); got {n_objects}"
        )
    rng = np.random.default_rng(seed)
    crowded = most = full = refused = 0
    reason = ""
    for _ in range(opts.attempts):
        inst = _attempt(family, n_objects, rng, opts, name or f"{family}{n_objects}", seed)
        if isinstance(inst, int):
            crowded, most, full = crowded + 1, max(most, inst), full + 1
            if crowded >= opts.crowded_attempts:
                raise GenerationError(
                    f"family {family} with {n_objects} objects (seed {seed}): the table is "
                    f"too full: random placement found room for at most {most} of them with "
                    f"{opts.gap:g} m clearance in {crowded} attempts in a row; try fewer "
                    "objects, a smaller clearance or a larger workspace"
                )
            continue
        crowded = 0
        if inst is not None and _verified(family, inst):
            validate_instance(inst)
            why = accept(inst) if accept is not None else None
            if why is None:
                return inst
            refused, reason = refused + 1, why
    crowding = (
        f" (in {full} of them no room was found for more than {most} objects)" if full else ""
    )
    if refused:
        crowding += f" ({refused} refused by the acceptance test, the last one: {reason})"
    raise GenerationError(
        f"family {family} with {n_objects} objects (seed {seed}): no instance with the promised "
        f"structure after {opts.attempts} attempts{crowding}; try fewer objects or a larger "
        "workspace"
    )


def _smallest(opts: GeneratorOptions) -> GeneratorOptions:
    """The options with the smallest footprint of the dense family's sizes: the area bound of
    a table of mixed sizes."""
    small = min(DENSE_SIZES, key=lambda s: s[0] * s[1])
    return GeneratorOptions(size=small, workspace=opts.workspace, gap=opts.gap)


def _extent(opts: GeneratorOptions) -> str:
    ws = opts.workspace
    return f"{ws.x[1] - ws.x[0]:g} x {ws.y[1] - ws.y[0]:g} m"


def _grown_area(opts: GeneratorOptions) -> float:
    """Area [m^2] of one footprint grown by half the clearance on every side."""
    return (opts.size[0] + opts.gap) * (opts.size[1] + opts.gap)


def _table_area(opts: GeneratorOptions) -> float:
    """Area [m^2] of the workspace grown by half the clearance on every side."""
    ws = opts.workspace
    return (ws.x[1] - ws.x[0] + opts.gap) * (ws.y[1] - ws.y[0] + opts.gap)


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
    if family == "N":  # at least one pair of neighbours trading places
        edges = set(g.edges)
        return any((j, i) in edges for i, j in edges)
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
) -> Instance | int | None:
    """An instance; or the number of objects placed when a random arrangement found no
    room for the next one; or ``None`` when the goals could not be pinned."""
    if family == "N":
        return _dense_attempt(n, rng, opts, name, seed)
    sizes = np.tile(np.array(opts.size[:2]), (n, 1))
    starts = _arrangement(n, sizes, rng, opts)
    if len(starts) < n:
        return len(starts)
    if family == "R":
        goals: FloatArray | None = _arrangement(n, sizes, rng, opts)
        if goals is not None and len(goals) < n:
            return len(goals)
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


def _dense_attempt(
    n: int, rng: np.random.Generator, opts: GeneratorOptions, name: str, seed: int
) -> Instance | int | None:
    """A dense instance (``opts.size`` is not used: the sizes are mixed)."""
    ws = opts.workspace
    sizes = dense_sizes(n, rng)
    starts = packed_arrangement(sizes, rng, ws.x, ws.y, opts.gap, opts.samples)
    if len(starts) < n:
        return len(starts)
    goals, swapped = dense_goals(starts, sizes, neighbour_pairs(n, rng), rng, opts.gap, ws.x, ws.y)
    if not swapped:
        return None
    objects = tuple(
        ObjectSpec(
            f"o{i}",
            (float(sizes[i, 0]), float(sizes[i, 1]), float(sizes[i, 2])),
            Pose2D(*map(float, starts[i])),
            Pose2D(*map(float, goals[i])),
        )
        for i in range(n)
    )
    return Instance(name, ws, objects, family="N", seed=seed)


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
) -> FloatArray:
    """Random sequential placement of ``n`` footprints, pairwise at least ``gap`` apart; the
    poses ``(k, 3)`` placed, ``k < n`` when no candidate had room for the next one."""
    placed = np.zeros((0, 3))
    for i in range(n):
        cand = _candidates(opts.samples, sizes[i], rng, opts)
        clear = partial(
            _clear, size=sizes[i], poses=placed, sizes=sizes[: len(placed)], gap=opts.gap
        )
        first = _first(cand, clear)
        if first is None:
            return placed
        placed = np.vstack([placed, cand[first]])
    return placed


def _first(
    cand: FloatArray, test: Callable[[FloatArray], BoolArray], chunk: int = 256
) -> int | None:
    """The index of the first candidate pose that passes ``test`` (a mask of poses), testing
    chunk by chunk: the same answer as ``argmax`` over the whole mask, for less work."""
    for lo in range(0, len(cand), chunk):
        ok = test(cand[lo : lo + chunk])
        if ok.any():
            return lo + int(np.argmax(ok))
    return None


def _clear(
    cand: FloatArray, *, size: FloatArray, poses: FloatArray, sizes: FloatArray, gap: float
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
        test = partial(
            _goal_ok,
            i=i,
            successor=succ.get(i),
            allowed=allowed,
            start_rect=start_rect,
            goals=goals,
            sizes=sizes,
            opts=opts,
        )
        first = _first(cand, test)
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
    opts: GeneratorOptions,
) -> BoolArray:
    """Mask of goal candidates for object ``i``: overlapping no start but the ``allowed``
    ones, the successor's start if any, and clear of the goals placed so far."""
    hits = overlap_matrix(corners(cand, np.tile(sizes[i], (len(cand), 1))), start_rect)
    ok = ~hits[:, ~allowed].any(axis=1)
    if successor is not None:
        ok &= hits[:, successor]
    placed = ~np.isnan(goals[:, 0])
    ok &= _clear(cand, size=sizes[i], poses=goals[placed], sizes=sizes[placed], gap=opts.gap)
    return np.asarray(ok, dtype=np.bool_)
