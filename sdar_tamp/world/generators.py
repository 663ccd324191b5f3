"""Seeded generators of the paper's instance families (section V).

* ``R`` random: independent random start and goal arrangements;
* ``S`` single cycle: exactly one dependency cycle (a simple cycle), the rest acyclic;
* ``D`` double cycle: exactly two disjoint simple cycles, the rest acyclic;
* ``M`` mixed (12 objects in the paper): at least one independent object, one chain of two or
  more and one cycle;
* ``N`` dense (beyond the paper): mixed sizes packed from the middle at the clearance,
  neighbours of one size trading places, the others turned on their spot
  (:mod:`sdar_tamp.world.dense`).

Starts (and the goals of ``R``) are placed at random (:mod:`sdar_tamp.world.placement`).
Structured families are built from a *successor map* (:mod:`sdar_tamp.world.structured_goals`):
object ``i`` with successor ``j`` gets its goal on (a perturbation of) ``j``'s start, overlapping
no other start and no other goal, so the dependency graph has exactly the edges ``i -> j``;
objects without successor get a goal overlapping no other object's start. Each instance is
verified with :mod:`sdar_tamp.world.dependency`; failures are retried with the same generator,
bounded.
Every random choice comes from ``numpy.random.default_rng(seed)``: same seed, same instance.

Reach. The generators place objects anywhere in the workspace; a cell's workspace is chosen
so that each of its points is grasped top-down by at least one of the cell's arms (``sdar
cells CELL --reach STEP``, :mod:`sdar_tamp.world.cell_reach`), whatever their number: an
object pose must be graspable by at least one arm, not by every arm (on the paper cell both
arms happen to reach all of it; on the cells of the shared table the side arms reach their
third only). The command line's acceptance test asks the same of every start and goal with
the cell's own arms (:class:`streams.feasibility.ProofCheck`: an object no arm can pick or
place is refused).
An optional acceptance test (``accept``: instance -> the reason it is refused, or ``None``)
rejects further samples, e.g. those the infeasibility proofs of :mod:`streams.feasibility`
show unsolvable (the command line passes them); a refused sample is retried like any other.

Requests that cannot be met are refused early: :func:`max_objects` is a sound area bound (more
objects than it allows cannot be placed with the clearance, whatever the placement), checked
before any sampling; and the retries stop after ``GeneratorOptions.crowded_attempts``
attempts in a row in which the random placement found no room for every object.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

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
from sdar_tamp.world.graspability import GraspLimits
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D, validate_instance
from sdar_tamp.world.placement import random_arrangement
from sdar_tamp.world.scene import Workspace
from sdar_tamp.world.shipped_cell import SHIPPED_GRASP
from sdar_tamp.world.structured_goals import structured_goals, successor_map
from sdar_tamp.world.transforms import FloatArray

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
    # the gripper the objects must suit (None: the shipped cell's, as the instance loader's)
    grasp: GraspLimits | None = None

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
        if inst is not None and has_family_structure(family, inst):
            validate_instance(inst, SHIPPED_GRASP if opts.grasp is None else opts.grasp)
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
    return GeneratorOptions(size=small, workspace=opts.workspace, gap=opts.gap, grasp=opts.grasp)


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


def has_family_structure(family: str, inst: Instance) -> bool:
    """Whether the dependency graph of ``inst`` has the structure ``family`` promises (see
    the module docstring; ``R`` promises none)."""
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


def _attempt(
    family: str, n: int, rng: np.random.Generator, opts: GeneratorOptions, name: str, seed: int
) -> Instance | int | None:
    """An instance; or the number of objects placed when a random arrangement found no
    room for the next one; or ``None`` when the goals could not be pinned."""
    if family == "N":
        return _dense_attempt(n, rng, opts, name, seed)
    sizes = np.tile(np.array(opts.size[:2]), (n, 1))
    starts = random_arrangement(n, sizes, rng, opts.workspace, opts.samples, opts.gap)
    if len(starts) < n:
        return len(starts)
    if family == "R":
        goals: FloatArray | None = random_arrangement(
            n, sizes, rng, opts.workspace, opts.samples, opts.gap
        )
        if goals is not None and len(goals) < n:
            return len(goals)
    else:
        succ = successor_map(family, n, rng)
        goals = structured_goals(succ, starts, sizes, rng, opts.workspace, opts.samples, opts.gap)
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
