"""Optimising only the arms that move: with three arms or more, a transfer in which some arms
wait (a stage of untangling or of the sequential fallbacks, or a step that moves a few arms)
is optimised over the moving arms alone, the waiting arms' spheres (coarse spheres and held
objects, where they wait) added to the obstacle spheres.

The NLP's size grows with the square of its arms (one arm-arm block per pair,
:mod:`streams.motion.nlp`), so one arm moving among three waiting ones is a one-arm problem
instead of a four-arm one. The sub-problems' optimisers are built once per set of moving arms
(:class:`SubsetOptimisers`, in the background like the planner's own) with CasADi's own
evaluation of the derivatives: a compiled library per set of arms would cost a compile each.
Two arms are always optimised together as before (the two-arm planner is unchanged), and the
result is checked exactly with every arm like any other transfer.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from sdar_tamp.world.transforms import FloatArray
from streams.context import WorldContext
from streams.motion.optimiser_build import OptimiserBuild
from streams.motion.optimiser_cache import OptimiserCache
from streams.motion.optimiser_records import TrajOptOptions
from streams.motion.sphere_pairs import HeldSpheres, path_spheres

#: The fewest arms of a cell whose transfers with waiting arms are optimised over the moving
#: arms alone (two arms: always both, as the two-arm planner does).
MIN_ARMS = 3


def sub_context(ctx: WorldContext, arms: tuple[int, ...]) -> WorldContext:
    """The world of the arms at layout positions ``arms`` alone (the same table, workspace and
    arm descriptions; their kinematics shared with ``ctx``)."""
    specs = tuple(ctx.scene.arms[i] for i in arms)
    scene = dataclasses.replace(ctx.scene, arms=specs)
    names = tuple(s.name for s in specs)
    return WorldContext(scene, {a: ctx.kinematics[a] for a in names}, {a: ctx.fk[a] for a in names})


class SubsetOptimisers:
    """The optimisers of the sets of moving arms of ``ctx`` (one built per set, in the
    background, uncompiled), from ``cache`` (shared like the planner's own)."""

    def __init__(self, ctx: WorldContext, options: TrajOptOptions, cache: OptimiserCache) -> None:
        self.ctx = ctx
        self.options = dataclasses.replace(options, compiled=False)
        self._cache = cache
        self._contexts: dict[tuple[int, ...], WorldContext] = {}

    @property
    def sets(self) -> tuple[tuple[int, ...], ...]:
        """The sets of moving arms (layout positions) asked for so far."""
        return tuple(self._contexts)

    def get(self, arms: tuple[int, ...]) -> tuple[WorldContext, OptimiserBuild]:
        """The world and the optimiser's build of the arms at positions ``arms``."""
        sub = self._contexts.get(arms)
        if sub is None:
            sub = self._contexts[arms] = sub_context(self.ctx, arms)
        return sub, self._cache.get(sub, self.options)


def joint_columns(ctx: WorldContext, arms: tuple[int, ...]) -> FloatArray:
    """The entries of a configuration ``(layout.dof,)`` that hold the joints of ``arms``."""
    every = np.arange(ctx.layout.dof)
    out: FloatArray = np.concatenate([every[ctx.layout.slice(i)] for i in arms])
    return out


def waiting_spheres(
    ctx: WorldContext, q: FloatArray, held: tuple[HeldSpheres, ...], waiting: tuple[int, ...]
) -> tuple[FloatArray, FloatArray]:
    """World centres ``(m, 3)`` [m] and radii ``(m,)`` [m] of the coarse spheres (held objects
    included) of the arms at positions ``waiting``, at the configuration ``q``."""
    ps = path_spheres(ctx, np.asarray(q, dtype=np.float64)[None], held)
    centres = [ps.coarse_centres[i][0] for i in waiting]
    radii = [ps.coarse_radii[i] for i in waiting]
    if not centres:
        return np.zeros((0, 3)), np.zeros(0)
    return np.concatenate(centres), np.concatenate(radii)
