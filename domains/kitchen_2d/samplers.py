"""Samplers of the 2-D kitchen, and :func:`make_problem`.

Top view, SI units [m]. A cup is a disc ``CUP`` across; its pose is the ``(x, y)`` of its
centre. A region is an axis-aligned rectangle ``(x_lo, y_lo, x_hi, y_hi)``; a cup lies inside
it when its whole disc does. Two cups collide when their centres are closer than ``CUP``
(touching is allowed). The gripper's configuration is a point ``(x, y)``: it holds a cup by a
grasp, the offset from the cup's centre to the gripper; a motion is the straight segment
between two configurations, and ``Distance`` is its length.

``sample-pose`` is either finite (``sampler="grid"``: the centres of a ``GRID`` grid inside the
region, in a seeded random order, then nothing more) or infinite (``sampler="random"``:
uniformly random centres, forever). The shelf is ``SHELF_DEPTH`` deep and ``shelf_width`` wide:
at 1.0 m both cups fit side by side; at 0.5 m no two poses on it are ``CUP`` apart, so the
problem is infeasible, and with the grid sampler every stream can be exhausted to prove it.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from pathlib import Path

import numpy as np

from sdar_tamp.language.formulas import TOTAL_COST, And, Equal
from sdar_tamp.language.generators import from_fn, from_gen_fn, from_list_fn, from_test
from sdar_tamp.language.options import StreamInfo
from sdar_tamp.language.problem import PDDLProblem

HERE = Path(__file__).resolve().parent
CUP = 0.3  # [m] diameter of a cup
GRID = 0.05  # [m] spacing of the grid sampler
SHELF_DEPTH = 0.35  # [m]
COUNTER = (-1.6, 0.0, -0.4, SHELF_DEPTH)  # [m] x_lo, y_lo, x_hi, y_hi
GRASP = (0.0, -0.25)  # [m] the gripper's offset from the cup's centre (from the front)
START: tuple[float, float] = (0.0, -1.0)  # [m] the gripper's initial configuration
SAMPLERS = ("grid", "random")

Point = tuple[float, float]
Rectangle = tuple[float, float, float, float]


class Kitchen:
    """The samplers of one problem, drawing from one seeded generator."""

    def __init__(self, regions: Mapping[str, Rectangle], sampler: str, seed: int) -> None:
        if sampler not in SAMPLERS:
            raise ValueError(f"sampler must be one of {SAMPLERS}, got {sampler!r}")
        self.regions = dict(regions)
        self.sampler = sampler
        self.rng = np.random.default_rng(seed)

    def centres(self, region: str) -> tuple[Rectangle, bool]:
        """The box the centre of a cup inside ``region`` lies in, and whether it is empty."""
        x_lo, y_lo, x_hi, y_hi = self.regions[region]
        r = CUP / 2
        box = (x_lo + r, y_lo + r, x_hi - r, y_hi - r)
        return box, box[0] > box[2] + 1e-9 or box[1] > box[3] + 1e-9

    def sample_pose(self, cup: str, region: str) -> Iterator[tuple[Point]]:
        """Poses of ``cup`` inside ``region``: the grid's (finite) or random ones (endless)."""
        box, empty = self.centres(region)
        if empty:
            return
        if self.sampler == "random":
            while True:
                x, y = self.rng.uniform(box[:2], box[2:])
                yield ((round(float(x), 4), round(float(y), 4)),)
        xs = _steps(box[0], box[2])
        ys = _steps(box[1], box[3])
        grid = [(x, y) for x in xs for y in ys]
        for index in self.rng.permutation(len(grid)):
            yield (grid[int(index)],)

    @staticmethod
    def sample_grasp(cup: str) -> list[tuple[Point]]:
        return [(GRASP,)]

    @staticmethod
    def inverse_kinematics(cup: str, pose: Point, grasp: Point) -> tuple[Point]:
        return ((round(pose[0] + grasp[0], 4), round(pose[1] + grasp[1], 4)),)

    @staticmethod
    def plan_motion(q1: Point, q2: Point) -> tuple[tuple[Point, Point]]:
        return ((q1, q2),)

    @staticmethod
    def cfree(cup: str, pose: Point, cup2: str, pose2: Point) -> bool:
        return cup == cup2 or math.dist(pose, pose2) >= CUP - 1e-9

    @staticmethod
    def distance(q1: Point, q2: Point) -> float:
        return round(math.dist(q1, q2), 4)


def _steps(lo: float, hi: float) -> list[float]:
    count = math.floor((hi - lo) / GRID + 1e-9) + 1
    return [round(lo + GRID * k, 4) for k in range(count)]


def stream_info(negate: bool = False) -> dict[str, StreamInfo]:
    """The stream options of a variant: with ``negate``, ``test-cfree`` is a negated test."""
    return {"test-cfree": StreamInfo(negate=True)} if negate else {}


def make_problem(
    shelf_width: float = 1.0,
    sampler: str = "grid",
    seed: int = 0,
    cups: tuple[str, ...] = ("cup1", "cup2"),
) -> PDDLProblem:
    """Move every cup from the counter into the shelf (``shelf_width`` [m] wide).

    Args:
        shelf_width: [m] 1.0: both cups fit; 0.5: they do not (infeasible).
        sampler: ``"grid"`` (finite pose sampler) or ``"random"`` (infinite).
        seed: seeds the pose sampler.
    """
    shelf: Rectangle = (0.5, 1.0, 0.5 + shelf_width, 1.0 + SHELF_DEPTH)
    kitchen = Kitchen({"counter": COUNTER, "shelf": shelf}, sampler, seed)
    init: list[tuple[object, ...]] = [
        ("HandEmpty",),
        ("CanMove",),
        ("Conf", START),
        ("AtConf", START),
        Equal((TOTAL_COST,), 0),
        ("Region", "counter"),
        ("Region", "shelf"),
    ]
    y = (COUNTER[1] + COUNTER[3]) / 2
    for index, cup in enumerate(cups):
        pose = (round(COUNTER[0] + CUP / 2 + index * (CUP + 0.1), 4), y)
        init += [("Cup", cup), ("Placeable", cup, "shelf"), ("Pose", cup, pose)]
        init += [("Contain", cup, pose, "counter"), ("AtPose", cup, pose)]
    return PDDLProblem(
        (HERE / "domain.pddl").read_text(encoding="utf-8"),
        {},
        (HERE / "stream.pddl").read_text(encoding="utf-8"),
        {
            "sample-pose": from_gen_fn(kitchen.sample_pose),
            "sample-grasp": from_list_fn(kitchen.sample_grasp),
            "inverse-kinematics": from_fn(kitchen.inverse_kinematics),
            "plan-motion": from_fn(kitchen.plan_motion),
            "test-cfree": from_test(kitchen.cfree),
            "distance": kitchen.distance,
        },
        init,
        And(*(("In", cup, "shelf") for cup in cups)),
    )
