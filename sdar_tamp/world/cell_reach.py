"""Which table points an arm reaches with a top-down grasp: the check a cell's layout is
chosen by.

A point ``(x, y)`` of the table counts as reached by an arm when, for every yaw asked, the
arm's tool centre point reaches the top-down pose at ``(x, y, z)`` (the grasp) and the pose
``lift`` above it (the approach), both within the joint limits and free of collisions of the
arm with itself (shapes at least two joints apart) and with the table top (every moving link
but the first). A two-finger grasp is the same at ``yaw`` and ``yaw + pi``, so either counts.
Poses are solved with the batched numeric IK (:mod:`.numeric_ik`), redundancy resolved toward
the arm's home, so 6- and 7-joint arms are checked alike.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from sdar_tamp.world._pin import PinRobot, chain_to, colliding_configurations
from sdar_tamp.world.errors import KinematicsError
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.numeric_ik import NumericIKOptions, numeric_ik
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import (
    BoolArray,
    FloatArray,
    inverse,
    top_down_pose,
    translation,
)

#: Yaws [rad] of the grasps a point must admit (modulo pi: the fingers are symmetric).
DEFAULT_YAWS = (0.0, np.pi / 4, np.pi / 2, 3 * np.pi / 4)
#: Height [m] of the approach pose above the grasp.
DEFAULT_LIFT = 0.08
#: IK effort, cheapest first: a pose none solves (within limits, collision free) is retried
#: with the next; the last resolves redundancy toward the centre of the limits instead.
_CHEAP = NumericIKOptions(seeds=2, iterations=100, rounds=3)
_FULL = NumericIKOptions(seeds=8, iterations=150, rounds=2)


@dataclass(frozen=True)
class ReachArm:
    """One arm of a cell: its robot, base pose in the world, tool frame (the flange) with the
    tool centre point ``tcp_offset`` [m] along its z, limits and home of the joints from the
    robot's root to the tool frame."""

    robot: PinRobot
    T_world_base: FloatArray  # (4, 4)
    tool_frame: str
    tcp_offset: float
    lower: FloatArray  # (dof,) [rad]
    upper: FloatArray  # (dof,) [rad]
    home: FloatArray  # (dof,) [rad]


@dataclass(frozen=True)
class ArmSolutions:
    """IK of one arm at top-down poses: joints ``q`` ``(n, dof)`` and which are usable ``(n,)``
    (solved within the limits and collision free)."""

    q: FloatArray
    ok: BoolArray


def solve_top_down(
    arm: ReachArm,
    xy: FloatArray,
    z: float,
    yaw: float | FloatArray,
    table_top: float = 0.0,
    seed: int = 0,
) -> ArmSolutions:
    """IK of the top-down TCP poses at ``xy`` ``(n, 2)``, height ``z`` [m] and ``yaw`` [rad]
    (one, or ``(n,)``) in the world frame, checked against the arm itself and the table top at
    height ``table_top`` [m]."""
    chain = chain_to(arm.robot, arm.tool_frame)
    if chain.dof != len(arm.lower):
        raise KinematicsError(
            f"{arm.robot.urdf_path.name}: {chain.dof} joints to {arm.tool_frame!r}, "
            f"limits for {len(arm.lower)}"
        )
    p = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    yaws = np.broadcast_to(np.asarray(yaw, dtype=np.float64), (len(p),))
    T_world = top_down_pose(p[:, 0], p[:, 1], np.full(len(p), z), yaws)
    T_base = inverse(arm.T_world_base) @ T_world @ translation(0.0, 0.0, -arm.tcp_offset)
    top = table_top - float(arm.T_world_base[2, 3])
    q = np.repeat(arm.home[None], len(p), axis=0)
    ok = np.zeros(len(p), dtype=bool)
    centre = (arm.lower + arm.upper) / 2.0
    for options, ref in ((_CHEAP, arm.home), (_FULL, arm.home), (_FULL, centre)):
        todo = np.flatnonzero(~ok)
        if len(todo) == 0:
            break
        result = numeric_ik(chain, T_base[todo], arm.lower, arm.upper, ref, options, seed)
        full = np.zeros((len(todo), arm.robot.nq))
        full[:, [j.q_index for j in chain.joints]] = result.q
        good = result.ok & ~colliding_configurations(arm.robot, full, top)
        q[todo[good]] = result.q[good]
        ok[todo[good]] = True
    return ArmSolutions(q, np.asarray(ok, dtype=np.bool_))


def reached(
    arm: ReachArm,
    xy: FloatArray,
    z: float,
    yaws: Sequence[float] = DEFAULT_YAWS,
    lift: float = DEFAULT_LIFT,
    table_top: float = 0.0,
    seed: int = 0,
) -> BoolArray:
    """``(n,)``: the points ``xy`` ``(n, 2)`` [m] the arm grasps top-down at height ``z`` [m]
    at every yaw of ``yaws`` (or that yaw plus pi), the approach ``lift`` [m] above included."""
    p = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    turns = np.array([[y, y + np.pi] for y in yaws]).ravel()  # (2 k,)
    n, m = len(p), len(turns)
    points = np.repeat(p, m, axis=0)
    angles = np.tile(turns, n)
    ok = solve_top_down(arm, points, z, angles, table_top, seed).ok
    up = np.flatnonzero(ok)
    ok[up] = solve_top_down(arm, points[up], z + lift, angles[up], table_top, seed).ok
    either = np.any(ok.reshape(n, len(yaws), 2), axis=2)
    return np.asarray(np.all(either, axis=1), dtype=np.bool_)


def grid(x: tuple[float, float], y: tuple[float, float], step: float) -> FloatArray:
    """Points ``(n, 2)`` of the rectangle ``x`` by ``y`` [m], ``step`` [m] apart, both edges
    included (the step shrinks to fit the rectangle exactly)."""
    if step <= 0.0:
        raise KinematicsError(f"grid step must be > 0 [m], got {step}")
    nx = max(1, int(np.ceil((x[1] - x[0]) / step - 1e-9))) + 1
    ny = max(1, int(np.ceil((y[1] - y[0]) / step - 1e-9))) + 1
    X, Y = np.meshgrid(np.linspace(*x, nx), np.linspace(*y, ny), indexing="ij")
    return np.stack([X.ravel(), Y.ravel()], axis=1)


def largest_rectangle(
    ok: BoolArray, xs: FloatArray, ys: FloatArray
) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """The largest axis-aligned rectangle (by area) of grid points all ``ok``:
    ``((x0, x1), (y0, y1))`` [m], or ``None`` when no point is ok. ``ok`` is
    ``(len(xs), len(ys))``."""
    best: tuple[float, tuple[int, int, int, int]] | None = None
    nx, ny = ok.shape
    for i0 in range(nx):
        column = np.ones(ny, dtype=bool)
        for i1 in range(i0, nx):
            column &= ok[i1]
            if not column.any():
                break
            j = 0
            while j < ny:  # runs of True in the rows all ok from i0 to i1
                if not column[j]:
                    j += 1
                    continue
                k = j
                while k + 1 < ny and column[k + 1]:
                    k += 1
                area = (xs[i1] - xs[i0]) * (ys[k] - ys[j])
                if best is None or area > best[0]:
                    best = (area, (i0, i1, j, k))
                j = k + 1
    if best is None:
        return None
    i0, i1, j, k = best[1]
    return (float(xs[i0]), float(xs[i1])), (float(ys[j]), float(ys[k]))


def scene_reach_arms(scene: Scene) -> dict[str, ReachArm]:
    """Every arm of a loaded cell, for the reach check (its description, base pose, tool frame,
    gripper's TCP offset, limits and home)."""
    out: dict[str, ReachArm] = {}
    for spec in scene.arms:
        kin = ArmKinematics.from_scene(scene, spec.name)
        out[spec.name] = ReachArm(
            kin.robot, kin.T_world_base, spec.tool_frame, spec.gripper.tcp_offset,
            spec.lower_array, spec.upper_array, np.array(spec.home),
        )  # fmt: skip
    return out


def unreached_points(scene: Scene, step: float) -> dict[str, FloatArray]:
    """Per arm, the points ``(k, 2)`` [m] of the cell's workspace (a grid of ``step`` [m],
    edges included) it does not grasp top-down at the default object's mid-height at every
    yaw of :data:`DEFAULT_YAWS` (:func:`reached`); empty arrays when it reaches them all."""
    if not step > 0.0:
        raise KinematicsError(f"step must be > 0 [m]; got {step}")
    points = grid(scene.workspace.x, scene.workspace.y, step)
    z = scene.object_size[2] / 2.0
    return {name: points[~reached(arm, points, z)] for name, arm in scene_reach_arms(scene).items()}


def uncovered_points(missed: dict[str, FloatArray]) -> FloatArray:
    """The points ``(k, 2)`` [m] no arm reaches, from :func:`unreached_points`' answer: a
    cell whose arms share the workspace needs each point reached by at least one arm."""
    sets = [{(float(x), float(y)) for x, y in points} for points in missed.values()]
    common = set.intersection(*sets) if sets else set()
    return np.array(sorted(common), dtype=np.float64).reshape(-1, 2)
