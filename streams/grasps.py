"""Grasp sampling for cuboids with a two-finger gripper.

Tool frame convention (the scene's ``tcp``): the gripper approaches along its z axis and the
fingers close along its y axis. A grasp is the pose of the tool centre point in the object
frame, ``T_object_tcp``; the TCP sits at the object's centre, raised for a short object so
that the fingertips stay clear of the table (:mod:`sdar_tamp.world.graspability`, which the
instance loader shares: an object it accepts has a top-down grasp).

Order (the paper's expanding grasp angles): every top-down grasp first, then tilted grasps
with growing approach angles ``+t, -t`` for ``t`` in ``tilts``; then, appended after that
set, the *pair tilts* (:attr:`GraspOptions.pair_tilts`), moderate angles that lean two
grippers closing on touching neighbours at once away from each other without reaching over
the other neighbours (SDAR-M searches them only for such pairs). The tilt turns the tool about
its closing axis, i.e. in the plane perpendicular to the closing axis. Closing axes are tried
short side first; a side wider than the gripper's graspable width is rejected (up to
:data:`~sdar_tamp.world.graspability.WIDTH_TOLERANCE`), and so is a tilt that would leave
the fingers too little of a short object to hold. With
``symmetric=True`` both 180-degree variants (tool turned by pi about its approach axis) are
returned; they are distinct wrist configurations of the same physical grasp.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.graspability import (
    MIN_FINGER_CONTACT,
    WIDTH_TOLERANCE,
    GraspLimits,
    finger_contact,
    fits_between_fingers,
    grasp_height,
)
from sdar_tamp.world.transforms import FloatArray

#: The paper's grasp set: top-down, then 45 degrees either way.
DEFAULT_TILTS = (np.pi / 4,)
#: Moderate tilts [rad] (20 and 30 degrees) appended for pairs of grasps: two wrists above
#: objects 7 cm apart collide when both grasp top-down, and a 45-degree gripper meets the
#: neighbours of a densely packed object.
DEFAULT_PAIR_TILTS = (np.pi / 9, np.pi / 6)


@dataclass(frozen=True)
class GraspOptions:
    """Which grasps :func:`sample_grasps` builds for each object (the grasp set).

    ``tilts`` [rad]: growing approach angles in (0, pi/2), each tried as ``+t`` then ``-t``
    after every top-down grasp; ``symmetric``: both 180-degree wrist variants of each grasp;
    ``pair_tilts`` [rad]: angles in (0, pi/2) appended after the grasp set proper, ``+t``
    then ``-t`` (for two objects grasped at once; see the module docstring). With the defaults
    an object graspable across both sides has 12 grasps, then 16 pair grasps.
    """

    tilts: tuple[float, ...] = DEFAULT_TILTS
    symmetric: bool = True
    pair_tilts: tuple[float, ...] = DEFAULT_PAIR_TILTS

    def __post_init__(self) -> None:
        for name in ("tilts", "pair_tilts"):
            angles = getattr(self, name)
            if any(not 0.0 < t < np.pi / 2 for t in angles):
                raise ParameterError(
                    f"grasp {name} must lie in (0, pi/2) [rad], got {list(angles)}"
                )


@dataclass(frozen=True, eq=False)
class Grasp:
    """A grasp of a cuboid.

    ``T_object_tcp`` ``(4, 4)``; ``width`` is the object side between the fingers [m];
    ``approach`` ``(3,)`` is the unit approach direction (tool z) in the object frame; ``tilt``
    [rad] is the angle away from top-down; ``index`` is the rank in the sampling order.
    Grasps hold arrays, so they compare (and hash) by identity.
    """

    index: int
    T_object_tcp: FloatArray
    width: float
    approach: FloatArray
    tilt: float
    closing_axis: int  # 0: fingers close along the object's x axis, 1: along y
    flipped: bool

    @property
    def is_top_down(self) -> bool:
        return abs(self.tilt) < 1e-12


#: The paper's grasp set (:data:`DEFAULT_TILTS`, both wrist variants).
DEFAULT_GRASPS = GraspOptions()


def _rot_y(angle: float) -> FloatArray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def grasp_rotation(closing_axis: int, tilt: float, flipped: bool) -> FloatArray:
    """``R_object_tcp`` ``(3, 3)``: tool z down (then tilted about tool y), y along the axis."""
    y = np.zeros(3)
    y[closing_axis] = 1.0
    z = np.array([0.0, 0.0, -1.0])
    R = np.stack([np.cross(y, z), y, z], axis=1) @ _rot_y(tilt)
    if flipped:
        R = R @ np.diag([-1.0, -1.0, 1.0])
    return R


def sample_grasps(
    size: tuple[float, float, float],
    limits: GraspLimits,
    tilts: Sequence[float] = DEFAULT_TILTS,
    symmetric: bool = True,
    min_width: float = 0.0,
    pair_tilts: Sequence[float] = (),
) -> tuple[Grasp, ...]:
    """All grasps of a cuboid of ``size`` (lx, ly, lz) [m], in the order described above.

    ``limits``: the gripper's (the largest side its fingers close on, their reach and width;
    :attr:`sdar_tamp.world.scene.Scene.grasp_limits` for the grasps every arm can use);
    ``tilts`` [rad]: growing positive tilt angles, each tried as ``+t`` then ``-t``;
    ``pair_tilts`` [rad]: the same, appended after every grasp of ``tilts`` (an angle of
    ``tilts`` is not repeated).
    """
    for t in (*tilts, *pair_tilts):
        if t <= 0.0 or t >= np.pi / 2:
            raise ValueError(f"tilts must lie in (0, pi/2) [rad], got {[*tilts, *pair_tilts]}")
    axes = [
        a
        for a in sorted((0, 1), key=lambda a: size[a])
        if min_width - WIDTH_TOLERANCE <= size[a]
        and fits_between_fingers(size[a], limits.max_width)
    ]
    extra = sorted(t for t in set(pair_tilts) if not any(abs(t - u) < 1e-9 for u in tilts))
    angles = [0.0] + [s * t for t in (*sorted(tilts), *extra) for s in (1.0, -1.0)]
    flips = (False, True) if symmetric else (False,)
    out: list[Grasp] = []
    for tilt in angles:
        if finger_contact(size[2], limits, tilt) < MIN_FINGER_CONTACT - WIDTH_TOLERANCE:
            continue  # too little of a short object would be left between the fingers
        for axis in axes:
            for flip in flips:
                R = grasp_rotation(axis, tilt, flip)
                T = np.eye(4)
                T[:3, :3] = R
                T[2, 3] = grasp_height(size[2], limits, tilt) - 0.5 * size[2]
                out.append(Grasp(len(out), T, float(size[axis]), R[:, 2].copy(), tilt, axis, flip))
    return tuple(out)


def half_turn_twins(grasps: Sequence[Grasp]) -> tuple[int | None, ...]:
    """Per grasp, the index in ``grasps`` of its half-turn twin, or None.

    A cuboid is symmetric under a half turn about its vertical axis, so the grasp of closing
    axis ``a``, tilt ``t`` and ``flipped`` ``f`` and the grasp ``(a, -t, not f)`` hold it the
    same way: the tool of one is the tool of the other turned by pi about the object's
    vertical axis, and for a top-down grasp (the tool axis vertical) about its own axis, so
    only wrist 3 differs (by pi). For a tilted grasp the twin leans the gripper to the other
    side of the object (other clearances from the neighbours)."""
    index = {(g.closing_axis, round(g.tilt, 9), g.flipped): k for k, g in enumerate(grasps)}
    return tuple(
        index.get((g.closing_axis, round(-g.tilt, 9) + 0.0, not g.flipped)) for g in grasps
    )


def pregrasp_offset(T_world_tcp: FloatArray, lift: float) -> FloatArray:
    """Poses ``(..., 4, 4)`` backed off by ``lift`` [m] against the approach (tool z)."""
    out = np.array(T_world_tcp, dtype=np.float64, copy=True)
    out[..., :3, 3] -= lift * out[..., :3, 2]
    return out
