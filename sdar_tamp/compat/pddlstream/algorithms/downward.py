"""``pddlstream.algorithms.downward``: the planner names and the cost scale.

PDDLStream runs Fast Downward with integer costs (``cost * cost_scale``, default 1000); the
core planner works with real-valued costs, so the scale only matters to programs that read it
(e.g. ``effort_weight = 1 / get_cost_scale()``). It is a per-process setting, as there.
"""

from __future__ import annotations

import math

from solvers.solve import PLANNER_ALIASES

__all__ = [
    "DEFAULT_MAX_TIME",
    "DEFAULT_PLANNER",
    "MAX_FD_COST",
    "SEARCH_OPTIONS",
    "get_cost_scale",
    "get_min_unit",
    "round_cost",
    "scale_cost",
    "set_cost_scale",
]

MAX_FD_COST = 1e8
DEFAULT_MAX_TIME = 30
DEFAULT_CONSERVATIVE_PLANNER = "ff-astar"
DEFAULT_GREEDY_PLANNER = "ff-astar2"
DEFAULT_PLANNER = DEFAULT_GREEDY_PLANNER
#: planner name -> "search-heuristic (weight w)" of the core planner it maps to
SEARCH_OPTIONS = {
    name: f"{search}-{heuristic} (weight {weight:g})"
    for name, (search, heuristic, weight) in PLANNER_ALIASES.items()
}
_SCALE = {"value": 1e3}


def get_cost_scale() -> float:
    return _SCALE["value"]


def set_cost_scale(cost_scale: float) -> None:
    if not cost_scale > 0:
        raise ValueError(f"cost_scale must be > 0, got {cost_scale}")
    _SCALE["value"] = float(cost_scale)


def scale_cost(cost: float) -> float:
    """``cost`` in integer planner units (``inf`` stays ``inf``)."""
    return cost if math.isinf(cost) else math.ceil(get_cost_scale() * float(cost))


def round_cost(cost: float) -> float:
    return int(get_cost_scale() * cost) / get_cost_scale()


def get_min_unit() -> float:
    return 1.0 / get_cost_scale()


def print_search_options() -> None:
    for index, (name, config) in enumerate(sorted(SEARCH_OPTIONS.items())):
        print(f"\n{index}) {name}: {config}")
