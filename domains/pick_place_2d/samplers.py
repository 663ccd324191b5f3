"""Samplers of the 2-D pick-and-place world, and :func:`make_problem`.

Side view, SI units [m]: the table is the line ``z = 0``; a block is a rectangle of width ``w``
and height ``h`` standing on it, and its pose is the ``x`` of its centre. A region is an interval
``(lo, hi)`` of the table. The robot is a gripper (a ``GRIPPER_W x GRIPPER_H`` rectangle) whose
configuration is the centre ``(x, z)`` of that rectangle; it holds a block from above, the block
hanging just below it. A trajectory is a polyline of configurations together with the shapes it
carries; it is collision-free against a standing block when no carried shape overlaps it at any
point of the polyline (touching is allowed).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sdar_tamp.language.generators import from_fn, from_gen_fn, from_list_fn, from_test
from sdar_tamp.language.problem import PDDLProblem

HERE = Path(__file__).resolve().parent
GRIPPER_W = 0.4  # [m]
GRIPPER_H = 0.2  # [m]
TRAVEL_Z = 4.0  # [m] height of the lifted paths, above every block


@dataclass(frozen=True)
class Block:
    """A block's size: width and height [m]."""

    width: float
    height: float


@dataclass(frozen=True)
class Grasp:
    """A top grasp: the gripper's x offset from the block's centre [m]."""

    dx: float


@dataclass(frozen=True)
class Shape:
    """A rectangle carried by the gripper: centre offset from the gripper centre, and size [m]."""

    dx: float
    dz: float
    width: float
    height: float


@dataclass(frozen=True)
class Trajectory:
    """A polyline of gripper configurations ``(x, z)`` [m] and the shapes it carries."""

    path: tuple[tuple[float, float], ...]
    shapes: tuple[Shape, ...]

    def __repr__(self) -> str:
        return "Traj(" + " -> ".join(f"({x:.2f},{z:.2f})" for x, z in self.path) + ")"


def gripper_shape() -> Shape:
    return Shape(0.0, 0.0, GRIPPER_W, GRIPPER_H)


def held_shape(block: Block, grasp: Grasp) -> Shape:
    """The held block relative to the gripper: ``grasp`` is the gripper's x offset on the block."""
    return Shape(-grasp.dx, -GRIPPER_H / 2 - block.height / 2, block.width, block.height)


def block_box(block: Block, x: float) -> tuple[float, float, float, float]:
    """``(xmin, xmax, zmin, zmax)`` of ``block`` standing at ``x`` [m]."""
    return (x - block.width / 2, x + block.width / 2, 0.0, block.height)


def segment_hits_box(
    a: tuple[float, float], b: tuple[float, float], box: tuple[float, float, float, float]
) -> bool:
    """Whether the segment ``a``-``b`` passes through the *open* box (slab method)."""
    t0, t1 = 0.0, 1.0
    for start, end, lo, hi in ((a[0], b[0], box[0], box[1]), (a[1], b[1], box[2], box[3])):
        delta = end - start
        if abs(delta) < 1e-12:
            if not lo < start < hi:
                return False
            continue
        u0, u1 = (lo - start) / delta, (hi - start) / delta
        if u0 > u1:
            u0, u1 = u1, u0
        t0, t1 = max(t0, u0), min(t1, u1)
        if t1 - t0 <= 1e-12:
            return False
    return True


def trajectory_collides(traj: Trajectory, block: Block, x: float) -> bool:
    """Whether any carried shape sweeps through ``block`` standing at ``x``."""
    xmin, xmax, zmin, zmax = block_box(block, x)
    for shape in traj.shapes:
        # the shape's centre must stay out of the box grown by half the shape (Minkowski sum)
        grown = (
            xmin - shape.width / 2 - shape.dx,
            xmax + shape.width / 2 - shape.dx,
            zmin - shape.height / 2 - shape.dz,
            zmax + shape.height / 2 - shape.dz,
        )
        for a, b in zip(traj.path, traj.path[1:], strict=False):
            if segment_hits_box(a, b, grown):
                return True
    return False


def intervals_overlap(a: tuple[float, float], b: tuple[float, float]) -> bool:
    """Whether two open intervals overlap."""
    return a[0] < b[1] - 1e-9 and b[0] < a[1] - 1e-9


class World:
    """The samplers of one problem, drawing from one seeded generator."""

    def __init__(
        self, blocks: Mapping[str, Block], regions: Mapping[str, tuple[float, float]], seed: int
    ) -> None:
        self.blocks = dict(blocks)
        self.regions = dict(regions)
        self.rng = np.random.default_rng(seed)

    def sample_pose(self, b: str, r: str) -> Iterator[tuple[float] | None]:
        """Uniform poses of ``b`` entirely inside ``r`` (none when it does not fit)."""
        lo, hi = self.regions[r]
        half = self.blocks[b].width / 2
        if hi - lo < 2 * half:
            return
        while True:
            yield (round(float(self.rng.uniform(lo + half, hi - half)), 3),)

    def sample_grasp(self, b: str) -> list[tuple[Grasp]]:
        """The top grasp at the block's centre."""
        return [(Grasp(0.0),)]

    def inverse_kinematics(self, b: str, p: float, g: Grasp) -> tuple[tuple[float, float]]:
        """The gripper configuration that holds ``b`` at ``p`` with grasp ``g``."""
        return ((round(p + g.dx, 3), round(self.blocks[b].height + GRIPPER_H / 2, 3)),)

    def _motions(
        self, q1: tuple[float, float], q2: tuple[float, float], shapes: tuple[Shape, ...]
    ) -> Iterator[tuple[Trajectory]]:
        if q1 == q2 or any(q[1] + s.dz - s.height / 2 < -1e-9 for q in (q1, q2) for s in shapes):
            return  # no motion, or a carried shape would be pushed into the table
        yield (Trajectory((q1, q2), shapes),)  # the straight line first
        yield (Trajectory((q1, (q1[0], TRAVEL_Z), (q2[0], TRAVEL_Z), q2), shapes),)

    def plan_free_motion(
        self, q1: tuple[float, float], q2: tuple[float, float]
    ) -> Iterator[tuple[Trajectory]]:
        """The straight line, then the path lifted to ``TRAVEL_Z``."""
        return self._motions(q1, q2, (gripper_shape(),))

    def plan_holding_motion(
        self, q1: tuple[float, float], q2: tuple[float, float], b: str, g: Grasp
    ) -> Iterator[tuple[Trajectory]]:
        """As :meth:`plan_free_motion`, carrying ``b`` held by ``g``."""
        return self._motions(q1, q2, (gripper_shape(), held_shape(self.blocks[b], g)))

    def cfree_pose(self, b: str, p: float, b2: str, p2: float) -> bool:
        if b == b2:
            return True
        box, box2 = block_box(self.blocks[b], p), block_box(self.blocks[b2], p2)
        return not intervals_overlap(box[:2], box2[:2])

    def traj_collision(self, t: Trajectory, b2: str, p2: float) -> bool:
        return trajectory_collides(t, self.blocks[b2], p2)


DEFAULT_BLOCKS = {"A": Block(1.0, 1.0), "B": Block(1.0, 1.2)}
DEFAULT_REGIONS = {"table": (-5.0, 1.5), "goal": (2.0, 3.4)}


def make_problem(seed: int = 0) -> PDDLProblem:
    """Block A must go into the goal region, where block B stands in the way.

    The goal region (1.4 m) fits one 1 m block, so B has to be moved onto the table first; A
    stands on the table and carrying it straight into the goal would sweep through B.
    """
    world = World(DEFAULT_BLOCKS, DEFAULT_REGIONS, seed)
    start = {"A": -3.0, "B": 2.7}
    q0 = (0.0, 3.0)
    init: list[tuple[object, ...]] = [("handempty",), ("conf", q0), ("atconf", q0)]
    for name, region in DEFAULT_REGIONS.items():
        init.append(("region", name))
        del region
    for name, x in start.items():
        init += [("block", name), ("pose", x), ("blockpose", name, x), ("atpose", name, x)]
        for region, (lo, hi) in DEFAULT_REGIONS.items():
            half = DEFAULT_BLOCKS[name].width / 2
            if lo <= x - half and x + half <= hi:
                init.append(("contained", name, x, region))
    stream_map = {
        "sample-pose": from_gen_fn(world.sample_pose),
        "sample-grasp": from_list_fn(world.sample_grasp),
        "inverse-kinematics": from_fn(world.inverse_kinematics),
        "plan-free-motion": from_gen_fn(world.plan_free_motion),
        "plan-holding-motion": from_gen_fn(world.plan_holding_motion),
        "test-cfree-pose": from_test(world.cfree_pose),
        "trajcollision": world.traj_collision,
    }
    return PDDLProblem(
        (HERE / "domain.pddl").read_text(encoding="utf-8"),
        {},
        (HERE / "stream.pddl").read_text(encoding="utf-8"),
        stream_map,
        init,
        ("in", "A", "goal"),
    )
