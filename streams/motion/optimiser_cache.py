"""Built trajectory optimisers by scene and options, owned by whoever shares them between
planners (the application's planner cache keeps one planner, and so one optimiser, per
scene; a benchmark or a test suite passes one cache to several planners)."""

from __future__ import annotations

import threading
from typing import Any

from streams.context import WorldContext
from streams.motion.optimiser_build import OptimiserBuild
from streams.motion.optimiser_records import TrajOptOptions


class OptimiserCache:
    """Optimisers by scene and options, each built once (in the background) and shared by
    every planner that asks for the same pair. A solver is not safe to call from two
    threads at once: share one cache between planners used in one thread."""

    def __init__(self) -> None:
        self._builds: dict[tuple[Any, TrajOptOptions], OptimiserBuild] = {}
        self._lock = threading.Lock()

    def get(
        self,
        ctx: WorldContext,
        options: TrajOptOptions | None = None,
        background: bool = True,
        start: bool = True,
    ) -> OptimiserBuild:
        """The build for ``ctx.scene`` and ``options`` (started now if it is the first,
        unless ``start=False``: see :class:`OptimiserBuild`)."""
        key = (ctx.scene, options or TrajOptOptions())
        with self._lock:
            build = self._builds.get(key)
            if build is None:
                build = self._builds[key] = OptimiserBuild(ctx, key[1], background, start)
        return build

    def __len__(self) -> int:
        return len(self._builds)
