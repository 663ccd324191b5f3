"""Sphere approximations of the arm links, the gripper and boxes (held or resting objects).

Every sphere set *covers* its primitive: a cylinder of radius ``r`` and length ``L`` becomes
``n`` spheres on its axis, spacing ``s = L / n``, radius ``sqrt(r^2 + (s/2)^2)``; a box becomes a
grid of cells, one sphere per cell circumscribing it. The optimiser keeps these spheres apart;
the exact coal check (:mod:`streams.motion.exact_check`) decides in the end.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sdar_tamp.world.transforms import FloatArray
from streams._pin_geometry import Primitive, arm_primitives

_GRIPPER_PREFIX = "gripper"

IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class ArmSpheres:
    """Spheres of one arm: joint frame index, centre in that frame ``(n, 3)``, radius ``(n,)``."""

    joint: IntArray  # 1..6 (base spheres are left out: the base never moves)
    centre: FloatArray
    radius: FloatArray

    def __len__(self) -> int:
        return len(self.radius)


def cylinder_spheres(
    radius: float, half_length: float, spacing: float = 1.2
) -> tuple[FloatArray, FloatArray]:
    """Spheres ``(n, 3)``, ``(n,)`` covering a cylinder on the z axis centred at the origin,
    about ``spacing`` radii apart."""
    length = 2.0 * half_length
    n = max(1, int(np.ceil(length / (spacing * radius))))
    s = length / n
    z = -half_length + s * (np.arange(n) + 0.5)
    centres = np.stack([np.zeros(n), np.zeros(n), z], axis=1)
    return centres, np.full(n, np.hypot(radius, s / 2.0))


def box_spheres(half: FloatArray, max_per_axis: int = 3) -> tuple[FloatArray, FloatArray]:
    """Spheres covering a box of half sides ``half`` ``(3,)`` centred at the origin.

    Cells are about as long as the box's smallest side (at most ``max_per_axis`` per axis).
    """
    h = np.asarray(half, dtype=np.float64)
    cell = 2.0 * h.min()
    n = np.clip(np.ceil(2.0 * h / (1.25 * cell)), 1, max_per_axis).astype(int)
    step = 2.0 * h / n
    axes = [-h[i] + step[i] * (np.arange(n[i]) + 0.5) for i in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    return grid, np.full(len(grid), float(np.linalg.norm(step / 2.0)))


def _gripper_box(prims: list[Primitive]) -> tuple[FloatArray, FloatArray]:
    """Centre and half sides of the joint-frame bounding box of the gripper primitives."""
    pts = []
    for p in prims:
        h = np.array(p.half)
        if p.kind == "cylinder":
            h = np.array([p.half[0], p.half[0], p.half[2]])
        grid = np.array(np.meshgrid(*[[-1.0, 1.0]] * 3)).reshape(3, -1).T * h
        pts.append(grid @ p.T_joint_shape[:3, :3].T + p.T_joint_shape[:3, 3])
    allp = np.concatenate(pts)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    return (lo + hi) / 2.0, (hi - lo) / 2.0


def arm_spheres(
    urdf: Path, coarse: bool = False, package_dirs: tuple[Path, ...] = ()
) -> ArmSpheres:
    """The sphere model of one arm (links 1..6 and the gripper) from the URDF's primitives.

    ``coarse``: fewer, larger spheres (cylinders 2 radii apart, the whole gripper as one box),
    used for the arm-arm pairs of the optimiser.
    """
    joints: list[int] = []
    centres: list[FloatArray] = []
    radii: list[FloatArray] = []
    prims = [p for p in arm_primitives(urdf, package_dirs) if p.joint != 0]
    if coarse:
        grip = [p for p in prims if p.name.startswith(_GRIPPER_PREFIX)]
        prims = [p for p in prims if not p.name.startswith(_GRIPPER_PREFIX)]
        centre, half = _gripper_box(grip)
        T = np.eye(4)
        T[:3, 3] = centre
        box = (float(half[0]), float(half[1]), float(half[2]))
        prims.append(Primitive("gripper", grip[0].joint, T, "box", box))
    for p in prims:
        if p.kind == "cylinder":
            c, r = cylinder_spheres(p.half[0], p.half[2], 2.0 if coarse else 1.2)
        else:
            c, r = box_spheres(np.array(p.half))
        world = c @ p.T_joint_shape[:3, :3].T + p.T_joint_shape[:3, 3]
        joints.extend([p.joint] * len(r))
        centres.append(world)
        radii.append(r)
    return ArmSpheres(
        np.array(joints, dtype=np.int64), np.concatenate(centres), np.concatenate(radii)
    )


def object_spheres(
    size: tuple[float, float, float], T_frame_obj: FloatArray, max_spheres: int
) -> tuple[FloatArray, FloatArray]:
    """Spheres ``(m, 3)``, ``(m,)`` covering a box of ``size`` [m] posed at ``T_frame_obj``,
    with ``m <= max_spheres`` (cells grow until the count fits)."""
    half = np.asarray(size, dtype=np.float64) / 2.0
    for per_axis in (3, 2, 1):
        c, r = box_spheres(half, per_axis)
        if len(r) <= max_spheres:
            break
    return c @ T_frame_obj[:3, :3].T + T_frame_obj[:3, 3], r
