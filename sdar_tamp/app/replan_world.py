"""The world a re-planned continuation starts from: the instance it solves and where the arms
begin (:mod:`sdar_tamp.app.replanning`).

The continuation's instance holds the objects resting at the cut: an instance object keeps
its goal (one already there, to rounding or turned half a turn, has its pose as goal: no task
moves it again); an object the instance does not know (added by an observation) has none, so it
stays where it is, unless it blocks a goal of the objects still to place (its footprint,
grown by the fingers' clearance, meets such a goal), in which case it is given a free pose
nearby as its goal: it is moved away like a buffered object. Objects gone are not in it.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

import numpy as np

from sdar_tamp.world.footprint import corners, inflate, inside_rectangle, overlap_matrix
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D
from sdar_tamp.world.transforms import FloatArray
from streams.stream_types import ArmConf, CellConf

CLEARANCE = 0.03  #: [m] room kept around an added object for the fingers of a goal's grasp
#: [m], [rad]: an object this close to its goal rests at it (half the validator's tolerances of a
#: goal); its goal is its pose, so no task moves it again.
AT_GOAL = (5e-4, math.radians(0.5))
Pose3 = tuple[float, float, float]


def continuation_instance(
    instance: Instance,
    resting: Mapping[str, Pose3],
    sizes: Mapping[str, tuple[float, float, float]],
    seed: int = 0,
    force: frozenset[str] = frozenset(),
) -> tuple[Instance, tuple[str, ...]]:
    """The instance of the continuation and the added objects it moves away (their goals are
    free poses; those in ``force`` whether they block a goal or not); raises nothing: an added
    object for which no free pose is found keeps its pose as goal (the solve then names it as
    blocking)."""
    goals = {o.name: o.goal for o in instance.objects}
    for name, pose in resting.items():
        if name in goals and at_goal(pose, goals[name]):
            goals[name] = Pose2D(*pose)
    objects: list[ObjectSpec] = []
    names = sorted(resting, key=lambda n: (n not in goals, n))
    todo = [n for n in names if n in goals and goals[n].as_tuple() != tuple(resting[n])]
    moved: list[str] = []
    for name in names:
        here = Pose2D(*resting[name])
        goal = goals.get(name)
        if goal is None:
            goal = here
            if name in force or _blocks(name, here, sizes, {n: goals[n] for n in todo}):
                free = _free_pose(name, here, instance, resting, sizes, goals, seed)
                if free is not None:
                    goal = free
                    moved.append(name)
        objects.append(ObjectSpec(name, sizes[name], here, goal))
    return dataclasses.replace(instance, objects=tuple(objects)), tuple(moved)


def at_goal(pose: Pose3, goal: Pose2D) -> bool:
    """Whether an object resting at ``pose`` is at ``goal`` within :data:`AT_GOAL` (yaw modulo
    pi: a cuboid turned half a turn is the same)."""
    turn = (pose[2] - goal.yaw) % math.pi
    near = math.hypot(pose[0] - goal.x, pose[1] - goal.y) <= AT_GOAL[0]
    return near and min(turn, math.pi - turn) <= AT_GOAL[1]


def _rect(pose: Pose2D, size: tuple[float, ...], margin: float = 0.0) -> FloatArray:
    return corners(np.array([pose.as_tuple()]), inflate(np.array([size[:2]]), margin))


def _blocks(
    name: str, here: Pose2D, sizes: Mapping[str, tuple[float, float, float]],
    goals: Mapping[str, Pose2D],
) -> bool:  # fmt: skip
    if not goals:
        return False
    mine = _rect(here, sizes[name], CLEARANCE)
    rects = np.concatenate([_rect(g, sizes[n]) for n, g in goals.items()])
    return bool(overlap_matrix(mine, rects).any())


def _free_pose(
    name: str,
    here: Pose2D,
    instance: Instance,
    resting: Mapping[str, Pose3],
    sizes: Mapping[str, tuple[float, float, float]],
    goals: Mapping[str, Pose2D],
    seed: int,
) -> Pose2D | None:
    """The nearest of seeded random poses (yaw kept) inside the workspace, clear by
    :data:`CLEARANCE` of every other resting object and every goal."""
    rng = np.random.default_rng(seed)
    ws = instance.workspace
    others = [Pose2D(*p) for n, p in resting.items() if n != name]
    other_sizes = [sizes[n] for n in resting if n != name]
    others += list(goals.values())
    other_sizes += [sizes[n] for n in goals]
    if others:
        obstacles = np.concatenate([_rect(p, s) for p, s in zip(others, other_sizes, strict=True)])
    else:
        obstacles = np.zeros((0, 4, 2))
    xy = np.stack([rng.uniform(*ws.x, 4000), rng.uniform(*ws.y, 4000)], axis=1)
    order = np.argsort(np.hypot(xy[:, 0] - here.x, xy[:, 1] - here.y))
    for k in order:
        pose = Pose2D(float(xy[k, 0]), float(xy[k, 1]), here.yaw)
        rect = _rect(pose, sizes[name], CLEARANCE)
        if not inside_rectangle(_rect(pose, sizes[name]), ws.x, ws.y)[0]:
            continue
        if len(obstacles) and overlap_matrix(rect, obstacles).any():
            continue
        return pose
    return None


def start_configuration(
    home: CellConf, q: FloatArray, arm_slices: Mapping[str, slice],
    free: frozenset[str] = frozenset(),
) -> CellConf:  # fmt: skip
    """The cell configuration at ``q`` ``(dof,)`` [rad]: an arm at home keeps its home
    configuration; an arm elsewhere (over the table, at a grasp or a placement) gets a
    pre-grasp mark, so that its first motion leaves by a straight lift, unless it is in
    ``free`` (stopped in the middle of a motion, clear of the objects: it leaves directly)."""
    arms = []
    for conf in home.arms:
        q_arm = tuple(float(v) for v in q[arm_slices[conf.arm]])
        at_home = math.dist(q_arm, conf.q) <= 1e-9
        mark = None if conf.arm in free else q_arm
        arms.append(conf if at_home else ArmConf(conf.arm, q_arm, pre=mark))
    return CellConf(*arms)
