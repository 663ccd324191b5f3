"""The shape of a pick-and-place motion: lift height from clearance, and blended corners.

A synchronous motion leaves a grasp straight up the tool axis (retreat), transfers, and comes
down the tool axis to the next grasp (approach). Two choices shape it:

* **Lift height** (:func:`clearance_lift`): the smallest straight lift after which the lowest
  point of the gripper's fingers (and of the held object) is ``lift_margin`` above the table
  and above every object resting within reach of the gripper (the grasped or released object
  itself included: the fingers surround it) anywhere on its way over the table to the other
  end of the motion (the transfer between the lifted configurations sweeps that corridor),
  bounded to ``[min_lift, max_lift]``.
* **Blending** (:func:`round_corner`): instead of stopping at the lifted (pre-grasp) point,
  the path keeps only the first ``straight`` metres of the retreat (and the last ``straight``
  of the approach) straight, and joins them to the transfer by a quadratic Bezier corner whose
  control point is the lifted configuration. The blended path is timed as one path; on its
  straight ends the tool centre point moves at most ``grasp_speed``. A blended path that
  collides is replaced by the unblended one by the caller.

:func:`straight_end_deviation` is the check that a trajectory still ends (or starts) with the
straight tool move: the largest distance of the TCP from the grasp's tool axis, and of the
tool's orientation from the grasp's, over the last (first) ``straight`` metres.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.transforms import FloatArray

#: Spacing [m] of the points on the way to the motion's other end tested for neighbours.
CORRIDOR_STEP = 0.01
#: Below this vertical share of the tool axis the lift is not from clearance (side grasps).
MIN_RISE = 0.5


@dataclass(frozen=True)
class ShapeOptions:
    """How motions are shaped (see the module docstring). Lengths [m], speed [m/s].

    ``reach`` [rad]: the least joint-space length of the transfer a rounded corner takes
    (it takes as much as it cuts of the retreat or approach, if more); ``near``: how far
    beyond the gripper's (and held object's) horizontal reach a resting object still counts
    as a neighbour; ``step``: spacing of the straight moves' IK waypoints;
    ``default_lift``: the fixed lift used when the clearance lift is unusable. ``min_lift``
    leaves a blended corner room above the straight part (a lower corner turns sharper and
    is slower to follow)."""

    blend: bool = True
    straight: float = 0.02
    grasp_speed: float = 0.25
    lift_margin: float = 0.015
    min_lift: float = 0.05
    max_lift: float = 0.12
    near: float = 0.05
    reach: float = 0.0
    step: float = 0.005
    default_lift: float = 0.08

    def __post_init__(self) -> None:
        for name in ("straight", "grasp_speed", "min_lift", "step", "default_lift"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ParameterError(f"{name} must be a finite number > 0, got {value}")
        for name in ("lift_margin", "near", "reach"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ParameterError(f"{name} must be a finite number >= 0 [m], got {value}")
        if not self.min_lift <= self.max_lift:
            raise ParameterError(
                f"max_lift must be >= min_lift ({self.min_lift} m), got {self.max_lift}"
            )


def clearance_lift(
    T_world_tcp: FloatArray,
    envelope: FloatArray,
    objects: Mapping[str, ObjectBox],
    held: ObjectBox | None,
    options: ShapeOptions,
    toward: FloatArray | None = None,
) -> float | None:
    """The straight lift [m] along the tool axis that clears the neighbours of a grasp at
    ``T_world_tcp`` ``(4, 4)`` by a gripper whose fingers ``envelope`` ``(8, 3)`` encloses in
    the TCP frame (:attr:`sdar_tamp.world.gripper.Gripper.envelope`; ``held``: the held
    object's box at that pose) on the way to the point ``toward`` ``(2,)`` [m] on the table
    (the other end of the motion; default: the grasp's own neighbourhood only), or None for a
    grasp whose tool axis is too far from vertical (the caller keeps its fixed lift)."""
    T = np.asarray(T_world_tcp, dtype=np.float64)
    rise = -float(T[2, 2])  # height gained per metre of retreat (tool z points down)
    if rise < MIN_RISE:
        return None
    points = np.asarray(envelope, dtype=np.float64) @ T[:3, :3].T + T[:3, 3]
    if held is not None:
        points = np.concatenate([points, box_corners(held)])
    z_low = float(points[:, 2].min())
    reach = float(np.linalg.norm(points[:, :2] - T[:2, 3], axis=1).max()) + options.near
    start = T[:2, 3]
    end = start if toward is None else np.asarray(toward, dtype=np.float64)
    n = max(2, int(np.ceil(np.linalg.norm(end - start) / CORRIDOR_STEP)) + 1)
    way = start + np.linspace(0.0, 1.0, n)[:, None] * (end - start)
    top = 0.0  # the table
    for box in objects.values():
        if footprint_distances(box, way).min() <= reach:
            top = max(top, float(box_corners(box)[:, 2].max()))
    need = (top + options.lift_margin - z_low) / rise
    return float(np.clip(need, options.min_lift, options.max_lift))


def box_corners(box: ObjectBox) -> FloatArray:
    """The eight corners ``(8, 3)`` [m] of a box in the world."""
    h = 0.5 * np.asarray(box.size, dtype=np.float64)
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    T = np.asarray(box.T_world_obj, dtype=np.float64)
    return np.asarray((signs * h) @ T[:3, :3].T + T[:3, 3], dtype=np.float64)


def footprint_distance(box: ObjectBox, xy: FloatArray) -> float:
    """Horizontal distance [m] from the point ``xy`` ``(2,)`` to the box's footprint (the
    box's horizontal extent, for a box resting upright)."""
    T = np.asarray(box.T_world_obj, dtype=np.float64)
    local = T[:2, :2].T @ (np.asarray(xy, dtype=np.float64) - T[:2, 3])
    out = np.maximum(np.abs(local) - 0.5 * np.asarray(box.size[:2]), 0.0)
    return float(np.linalg.norm(out))


def footprint_distances(box: ObjectBox, xy: FloatArray) -> FloatArray:
    """:func:`footprint_distance` for every point of ``xy`` ``(n, 2)``: ``(n,)`` [m]."""
    T = np.asarray(box.T_world_obj, dtype=np.float64)
    local = (np.asarray(xy, dtype=np.float64) - T[:2, 3]) @ T[:2, :2]
    out = np.maximum(np.abs(local) - 0.5 * np.asarray(box.size[:2]), 0.0)
    return np.asarray(np.linalg.norm(out, axis=1), dtype=np.float64)


def straight_prefix(
    kinematics: Mapping[int, tuple[ArmKinematics, slice]], path: FloatArray, straight: float
) -> int | None:
    """Index of the first waypoint of ``path`` ``(m, dof)`` at which every arm of
    ``kinematics`` (index -> kinematics and columns) has moved its TCP ``straight`` [m] from
    the first waypoint; None when that is the last waypoint or never (no room to blend)."""
    moved = np.ones(len(path), dtype=bool)
    for kin, sl in kinematics.values():
        p = np.stack([kin.fk_tcp(q)[:3, 3] for q in path[:, sl]])
        moved &= np.linalg.norm(p - p[0], axis=1) >= straight - 1e-9
    hits = np.flatnonzero(moved)
    if len(hits) == 0 or hits[0] >= len(path) - 1:
        return None
    return int(hits[0])


def arc_length(path: FloatArray) -> FloatArray:
    """Cumulative chord length ``(m,)`` [rad] of ``path`` ``(m, dof)``."""
    d = np.linalg.norm(np.diff(path, axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(d)])


def round_corner(
    before: FloatArray,
    keep: int,
    after: FloatArray,
    max_after: float,
    min_after: float = 0.0,
    samples: int = 9,
) -> FloatArray:
    """``before`` ``(m, dof)`` (ending at the corner) then ``after`` ``(n, dof)`` (starting at
    it), with the corner cut: ``before[:keep + 1]``, a quadratic Bezier from ``before[keep]``
    with the corner as control point to the point of ``after`` as far along it as the part of
    ``before`` cut, but at least ``min_after`` and at most ``max_after`` [rad], then the rest
    of ``after``."""
    corner = before[-1]
    cut = float(arc_length(before[keep:])[-1])
    s_after = arc_length(after)
    j = int(np.searchsorted(s_after, min(max(cut, min_after), max_after)))
    j = int(np.clip(j, 1, len(after) - 1))
    a, b = before[keep], after[j]
    w = np.linspace(0.0, 1.0, samples)[1:-1, None]
    curve = (1 - w) ** 2 * a + 2 * w * (1 - w) * corner + w**2 * b
    return np.concatenate([before[: keep + 1], curve, after[j:]])


def straight_end_deviation(
    kin: ArmKinematics, q: FloatArray, q_grasp: FloatArray, straight: float
) -> tuple[float, float]:
    """Largest lateral distance [m] of the TCP from the grasp's tool axis, and largest angle
    [rad] of the tool from the grasp's orientation, over the samples ``q`` ``(m, dof)`` (in
    order from the grasp outwards) before the first one ``straight`` [m] away from the grasp;
    ``(inf, inf)`` when the samples never get that far."""
    T_g = kin.fk_tcp(np.asarray(q_grasp, dtype=np.float64))
    axis = T_g[:3, 2]
    lateral = angle = 0.0
    for qi in q:
        T = kin.fk_tcp(qi)
        d = T[:3, 3] - T_g[:3, 3]
        if np.linalg.norm(d) >= straight - 1e-9:
            return lateral, angle
        lateral = max(lateral, float(np.linalg.norm(d - (d @ axis) * axis)))
        c = (np.trace(T_g[:3, :3].T @ T[:3, :3]) - 1.0) / 2.0
        angle = max(angle, float(np.arccos(np.clip(c, -1.0, 1.0))))
    return math.inf, math.inf
