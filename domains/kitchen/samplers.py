"""Samplers of the kitchen domain, and :func:`make_problem`.

Stations are points of the floor plan [m]; the robot works at a station from a configuration
``(x, y)`` within reach of it. ``sample-conf`` proposes standing points around a station (a
finite, seeded set); ``Distance`` is the Euclidean distance between two configurations [m].
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from pathlib import Path

import numpy as np

from sdar_tamp.language.formulas import TOTAL_COST, And, Equal
from sdar_tamp.language.generators import from_gen_fn
from sdar_tamp.language.problem import PDDLProblem

HERE = Path(__file__).resolve().parent
REACH = 0.6  # [m] distance from a standing point to the station it serves
CONFS_PER_STATION = 2

Conf = tuple[float, float]

STATIONS: Mapping[str, tuple[float, float]] = {
    "shelf": (0.0, 2.0),
    "basin": (3.0, 1.0),  # the sink next to the stove
    "tub": (-4.0, -3.0),  # the sink in the far corner
    "stove": (3.0, -1.0),
    "table": (0.0, -2.0),
}


class Kitchen:
    """The samplers of one problem, drawing from one seeded generator."""

    def __init__(self, seed: int) -> None:
        self.rng = np.random.default_rng(seed)

    def sample_conf(self, station: str) -> Iterator[tuple[Conf]]:
        """Standing points at distance ``REACH`` around ``station``, at random angles."""
        sx, sy = STATIONS[station]
        for angle in self.rng.uniform(0.0, 2 * math.pi, CONFS_PER_STATION):
            yield (
                (round(sx + REACH * math.cos(angle), 3), round(sy + REACH * math.sin(angle), 3)),
            )

    @staticmethod
    def distance(q1: Conf, q2: Conf) -> float:
        return round(math.dist(q1, q2), 3)


def make_problem(items: tuple[str, ...] = ("cabbage", "turnip"), seed: int = 0) -> PDDLProblem:
    """Clean, cook and serve every item; the robot starts at the origin."""
    kitchen = Kitchen(seed)
    q0: Conf = (0.0, 0.0)
    init: list[tuple[object, ...]] = [
        ("handempty",),
        ("conf", q0),
        ("atconf", q0),
        Equal((TOTAL_COST,), 0),
        ("sink", "basin"),
        ("sink", "tub"),
        ("stove", "stove"),
        ("servingtable", "table"),
    ]
    init += [("station", name) for name in STATIONS]
    for item in items:
        init += [("item", item), ("on", item, "shelf")]
    return PDDLProblem(
        (HERE / "domain.pddl").read_text(encoding="utf-8"),
        {},
        (HERE / "stream.pddl").read_text(encoding="utf-8"),
        {"sample-conf": from_gen_fn(kitchen.sample_conf), "distance": kitchen.distance},
        init,
        And(*(("served", item) for item in items)),
    )
