"""The options of one stream planning solve (validated by :func:`solvers.solve`)."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class StreamOptions:
    """The solve() options the stream algorithms use (validated by :func:`solvers.solve`)."""

    algorithm: str = "adaptive"
    unit_costs: bool = False
    success_cost: float = math.inf
    max_time: float = math.inf
    max_iterations: float = math.inf
    max_skeletons: float = math.inf
    search_sample_ratio: float = 1.0
    initial_complexity: int = 0
    complexity_step: int = 1
    max_complexity: float = math.inf
    max_planner_time: float = math.inf
    search: str = "wastar"
    heuristic: str = "ff"
    weight: float = 2.0
    backend: str = "sdar"  # the classical planner: "sdar" (this package's) or "fd" (Fast Downward)
    max_cost: float = math.inf  # plans above it are not returned (PlanConstraints.max_cost)
    effort_weight: float | None = None  # optimistic actions pay weight * stream effort
    unit_efforts: bool = False  # every stream call has effort 1
    enforce_max_time: bool = True  # user calls in a worker thread, abandoned at max_time
    verbose: bool = False  # one line per round and the final counts on stdout
