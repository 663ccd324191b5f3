"""Samplers of the 2-D house, and :func:`make_problem`.

Top view, SI units [m]. Locations are axis-aligned rectangles ``(x_lo, y_lo, x_hi, y_hi)``; an
object is a disc ``OBJECT`` across, its pose the ``(x, y)`` of its centre; it lies on a
location when its whole disc does, and two objects overlap when their centres are closer than
``OBJECT``. The robot's configuration is a point in front of a location (``NAV_POSES`` per
location, a finite list); a path is the straight segment between two configurations and
``PathLength`` its length. Handling an object costs 1 plus a tenth of the reach from the
robot's configuration to the object's pose (``HandlingCost``, four arguments).

``sample-place`` draws uniformly random centres on a location, forever, from the problem's
seeded generator; the goal's location (the shelf) holds ``clutter`` objects already, so many
placements collide. The collision test is used through the derived ``Unsafe``, as PDDLStream
programs do; :func:`stream_info` gives it ``StreamInfo(eager=False, negate=True)`` (the
``"negate"`` idiom), nothing (``"auto"``: negated automatically, as in PDDLStream's namo
example), or ``eager=True`` on it and on both cost functions (``"eager"``: evaluate every
instance as soon as its inputs exist).
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from sdar_tamp.language.formulas import TOTAL_COST, And, Equal
from sdar_tamp.language.generators import from_gen_fn, from_list_fn, from_test
from sdar_tamp.language.options import FunctionInfo, StreamInfo
from sdar_tamp.language.problem import PDDLProblem

HERE = Path(__file__).resolve().parent
OBJECT = 0.2  # [m] diameter of an object
NAV_POSES = 3  # navigation poses per location
LOCATIONS: dict[str, tuple[float, float, float, float]] = {
    "counter": (-2.0, 0.0, -1.0, 0.6),
    "table": (0.0, 2.0, 1.0, 2.8),
    "shelf": (2.0, 0.0, 2.9, 0.5),
}
MODES = ("negate", "auto", "eager")

Point = tuple[float, float]


class House:
    """The samplers of one problem, drawing from one seeded generator."""

    def __init__(self, seed: int, call_seconds: float = 0.0) -> None:
        self.rng = np.random.default_rng(seed)
        self.call_seconds = call_seconds

    def _work(self) -> None:
        """Spend ``call_seconds`` [s] (stands for the geometry a real test or cost computes)."""
        end = time.perf_counter() + self.call_seconds
        while time.perf_counter() < end:
            pass

    @staticmethod
    def nav_poses(location: str) -> list[tuple[Point]]:
        """``NAV_POSES`` configurations 0.4 m in front of the location's lower edge."""
        x_lo, y_lo, x_hi, _ = LOCATIONS[location]
        step = (x_hi - x_lo) / (NAV_POSES + 1)
        return [(round(x_lo + step * (k + 1), 4), round(y_lo - 0.4, 4)) for k in range(NAV_POSES)]

    def list_nav_poses(self, location: str) -> list[tuple[Point]]:
        return [(q,) for q in self.nav_poses(location)]  # type: ignore[misc]

    @staticmethod
    def plan_path(q1: Point, q2: Point) -> Iterator[tuple[tuple[Point, Point]]]:
        """The straight path (one answer)."""
        yield ((q1, q2),)

    def sample_place(self, location: str, obj: str) -> Iterator[tuple[Point]]:
        """Random centres of ``obj`` on ``location`` (endless)."""
        x_lo, y_lo, x_hi, y_hi = LOCATIONS[location]
        r = OBJECT / 2
        while True:
            x, y = self.rng.uniform((x_lo + r, y_lo + r), (x_hi - r, y_hi - r))
            yield ((round(float(x), 4), round(float(y), 4)),)

    @staticmethod
    def collision_free(o1: str, p1: Point, o2: str, p2: Point) -> bool:
        return o1 == o2 or math.dist(p1, p2) >= OBJECT - 1e-9

    def timed_collision_free(self, o1: str, p1: Point, o2: str, p2: Point) -> bool:
        self._work()
        return self.collision_free(o1, p1, o2, p2)

    def timed_handling_cost(self, location: str, obj: str, pose: Point, conf: Point) -> float:
        self._work()
        return self.handling_cost(location, obj, pose, conf)

    @staticmethod
    def path_length(path: tuple[Point, Point]) -> float:
        return round(math.dist(*path), 4)

    @staticmethod
    def handling_cost(location: str, obj: str, pose: Point, conf: Point) -> float:
        return round(1.0 + 0.1 * math.dist(pose, conf), 4)


def stream_info(mode: str = "negate") -> dict[str, StreamInfo | FunctionInfo]:
    """The options of a variant (see the module docstring)."""
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
    if mode == "auto":
        return {}
    eager = mode == "eager"
    info: dict[str, StreamInfo | FunctionInfo] = {
        "test-collision-free": StreamInfo(eager=eager, negate=True)
    }
    if eager:
        info["pathlength"] = FunctionInfo(eager=True)
        info["handlingcost"] = FunctionInfo(eager=True)
    return info


def make_problem(
    seed: int = 0, movers: int = 2, clutter: int = 3, call_seconds: float = 0.0
) -> PDDLProblem:
    """Carry ``movers`` objects from the counter to the shelf, which holds ``clutter`` others.

    Args:
        seed: seeds the placement sampler.
        movers: objects to move (1-4).
        clutter: objects already on the shelf (0-4), spread along its back edge.
        call_seconds: [s] time each collision test and handling cost spends (0: none).
    """
    house = House(seed, call_seconds)
    start = House.nav_poses("counter")[0]
    init: list[tuple[object, ...]] = [
        ("Robot", "robot"),
        ("HandEmpty", "robot"),
        ("At", "robot", "counter"),
        ("Conf", start),
        ("AtConf", "robot", start),
        Equal((TOTAL_COST,), 0),
    ]
    init += [("Location", name) for name in LOCATIONS]
    goal = []
    for index in range(movers):
        obj, pose = f"mover{index}", (round(-1.85 + 0.25 * index, 4), 0.3)
        init += [("Obj", obj), ("Pose", pose), ("At", obj, "counter"), ("AtPose", obj, pose)]
        goal.append(("At", obj, "shelf"))
    shelf = LOCATIONS["shelf"]
    for index in range(clutter):
        obj, pose = f"clutter{index}", (round(shelf[0] + 0.15 + 0.22 * index, 4), 0.38)
        init += [("Obj", obj), ("Pose", pose), ("At", obj, "shelf"), ("AtPose", obj, pose)]
    return PDDLProblem(
        (HERE / "domain.pddl").read_text(encoding="utf-8"),
        {},
        (HERE / "stream.pddl").read_text(encoding="utf-8"),
        {
            "sample-navpose": from_list_fn(house.list_nav_poses),
            "plan-path": from_gen_fn(House.plan_path),
            "sample-place": from_gen_fn(house.sample_place),
            "test-collision-free": from_test(house.timed_collision_free),
            "pathlength": House.path_length,
            "handlingcost": house.timed_handling_cost,
        },
        init,
        And(*goal),
    )
