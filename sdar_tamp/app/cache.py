"""What stays built between solves: the world and the motion planner of one scene."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

from streams.context import WorldContext
from streams.motion.optimiser_records import TrajOptOptions
from streams.motion.planner import MotionPlanner


@dataclass(frozen=True)
class PlanningWorld:
    """A scene's world context and motion planner, and the time [s] it took to get them
    (0 when they came from the cache)."""

    ctx: WorldContext
    planner: MotionPlanner
    setup_time: float


class PlannerCache:
    """Keeps the world and the motion planner of the last scene and optimiser options, so
    that solves of instances on the same scene build them once (the optimiser takes a few
    seconds to build). One cache per thread or process; share it between calls of
    :func:`sdar_tamp.app.pipeline.solve_instance`."""

    def __init__(self) -> None:
        self._key: tuple[Path | None, TrajOptOptions] | None = None
        self._world: tuple[WorldContext, MotionPlanner] | None = None
        self.builds = 0  # worlds built so far

    def world(
        self, scene_path: Path | None, trajopt: TrajOptOptions, defer_build: bool = False
    ) -> PlanningWorld:
        """The world of ``scene_path`` (None: the shipped scene) with a motion planner using
        ``trajopt``; ``defer_build``: a new planner's optimiser build waits for
        :meth:`~streams.motion.planner.MotionPlanner.start_build` or its first use."""
        start = time.perf_counter()
        key = (scene_path, trajopt)
        if self._world is None or self._key != key:
            ctx = WorldContext.load(scene_path)
            self._world = (ctx, MotionPlanner(ctx, trajopt, defer_build=defer_build))
            self._key = key
            self.builds += 1
        ctx, planner = self._world
        return PlanningWorld(ctx, planner, time.perf_counter() - start)
