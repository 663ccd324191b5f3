"""Sphere approximations of the arm links, the gripper and boxes (held or resting objects).

Every sphere set *covers* its primitive: a cylinder of radius ``r`` and length ``L`` becomes
``n`` spheres on its axis, spacing ``s = L / n``, radius ``sqrt(r^2 + (s/2)^2)``; a box becomes a
grid of cells, one sphere per cell circumscribing it (a sphere of the URDF is its bounding
box). A link whose shapes are meshes gets spheres fitted to its surface
(:mod:`streams.motion.sphere_fit`). The optimiser keeps these spheres apart; the exact coal
check (:mod:`streams.motion.exact_check`) decides in the end.
"""

from __future__ import annotations

import functools
import hashlib
import re
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.transforms import FloatArray
from sdar_tamp.world.urdf import read_urdf
from streams._pin_geometry import Primitive, arm_primitives
from streams.motion import sphere_cache
from streams.motion.sphere_fit import (
    FitOptions,
    box_triangles,
    cylinder_triangles,
    fit_spheres,
)

#: Which shapes get fitted spheres: only meshes, or every shape.
FITS = ("meshes", "all")
_COLLISION = re.compile(r"<collision\b.*?</collision>", re.DOTALL)
_FILENAME = re.compile(r"""<mesh\b[^>]*?\bfilename\s*=\s*["']([^"']*)["']""", re.DOTALL)

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


def box_spheres(
    half: FloatArray, max_per_axis: int = 3, coarse: bool = False
) -> tuple[FloatArray, FloatArray]:
    """Spheres covering a box of half sides ``half`` ``(3,)`` centred at the origin.

    Cells are about as long as the box's smallest side (``coarse``: its middle side, as a
    cylinder's coarse spheres are about as long as its diameter), at most ``max_per_axis``
    per axis.
    """
    h = np.asarray(half, dtype=np.float64)
    cell = 2.0 * (np.median(h) if coarse else h.min())
    n = np.clip(np.ceil(2.0 * h / (1.25 * cell)), 1, max_per_axis).astype(int)
    step = 2.0 * h / n
    axes = [-h[i] + step[i] * (np.arange(n[i]) + 0.5) for i in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    return grid, np.full(len(grid), float(np.linalg.norm(step / 2.0)))


def _corners(p: Primitive) -> FloatArray:
    """The eight corners ``(8, 3)`` of a shape's bounding box in its joint frame (a mesh's
    primitive is its bounding box, so meshes are bounded too)."""
    h = np.array(p.half)
    if p.kind == "cylinder":
        h = np.array([p.half[0], p.half[0], p.half[2]])
    grid = np.array(np.meshgrid(*[[-1.0, 1.0]] * 3)).reshape(3, -1).T * h
    out: FloatArray = grid @ p.T_joint_shape[:3, :3].T + p.T_joint_shape[:3, 3]
    return out


def _gripper_box(prims: list[Primitive]) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Rotation ``(3, 3)`` (the box's axes in the joint frame), centre (joint frame) and half
    sides of the smallest box holding the gripper primitives among those whose axes are the
    joint frame's or one primitive's (a hand mounted turned about the flange, as the Panda's,
    gets a box along the hand, not the much larger one along the flange's axes); the joint
    frame's axes unless another is smaller by more than 1e-9 of its volume."""
    corners = np.concatenate([_corners(p) for p in prims])
    best: tuple[float, FloatArray, FloatArray, FloatArray] | None = None
    for R in [np.eye(3), *(p.T_joint_shape[:3, :3] for p in prims)]:
        local = corners @ R  # coordinates along the box's axes
        lo, hi = local.min(axis=0), local.max(axis=0)
        volume = float(np.prod(hi - lo))
        if best is None or volume < best[0] * (1.0 - 1e-9):
            best = (volume, R, (lo + hi) / 2.0, (hi - lo) / 2.0)
    assert best is not None
    _, R, mid, half = best
    centre: FloatArray = R @ mid
    return R, centre, half


def gripper_shapes(prims: list[Primitive]) -> list[Primitive]:
    """The shapes of the tool: the tool joint is the last joint (by pinocchio's depth-first
    index) holding a link fixed to it through fixed joints (the UR5e's gripper base and
    fingers on the wrist, the Panda's hand on joint 7); the tool is every shape on such a
    link of that joint, and every shape of the joints after it (a Panda's finger joints).
    None when no link is fixed to a moving joint."""
    fixed = [p.joint for p in prims if p.fixed_to_joint and p.joint != 0]
    if not fixed:
        return []
    tool = max(fixed)
    return [p for p in prims if (p.joint == tool and p.fixed_to_joint) or p.joint > tool]


def _shape_triangles(p: Primitive) -> tuple[FloatArray, float]:
    """A shape's triangles in its joint frame and how far its true surface strays from them."""
    if p.triangles is not None:
        return p.triangles, 0.0
    if p.kind == "cylinder":
        tri, tolerance = cylinder_triangles(p.half[0], p.half[2])
    else:
        tri, tolerance = box_triangles(np.array(p.half)), 0.0
    return tri @ p.T_joint_shape[:3, :3].T + p.T_joint_shape[:3, 3], tolerance


def link_surface(group: list[Primitive]) -> tuple[FloatArray, float]:
    """The triangles ``(m, 3, 3)`` of one link's shapes ``group`` in their joint frame (a
    box's or cylinder's tessellated), and the largest distance [m] from the shapes' true
    surface to them: what :func:`~streams.motion.sphere_fit.fit_spheres` covers."""
    parts = [_shape_triangles(p) for p in group]
    return np.concatenate([t for t, _ in parts]), max(tol for _, tol in parts)


def fitted_links(prims: list[Primitive], fit: str) -> dict[tuple[int, str], list[Primitive]]:
    """The shapes whose link gets fitted spheres (``fit``: ``"meshes"`` or ``"all"``),
    grouped by ``(joint, link)`` in the shapes' order."""
    groups: dict[tuple[int, str], list[Primitive]] = {}
    for p in prims:
        if fit == "all" or p.triangles is not None:
            groups.setdefault((p.joint, p.link), []).append(p)
    return groups


def _fitted(group: list[Primitive], options: FitOptions) -> tuple[FloatArray, FloatArray]:
    tri, tolerance = link_surface(group)
    fit = fit_spheres(tri, options, tolerance)
    return fit.centre, fit.radius


def _covered_shapes(
    prims: list[Primitive], coarse: bool, fit: str, options: FitOptions
) -> tuple[list[int], list[FloatArray], list[FloatArray]]:
    """Joint, centres and radii of each shape's (or fitted link's) spheres, in shape order."""
    groups = fitted_links(prims, fit)
    link_options = (
        replace(options, max_spheres=max(1, options.max_spheres // 2)) if coarse else options
    )
    joints: list[int] = []
    centres: list[FloatArray] = []
    radii: list[FloatArray] = []
    for p in prims:
        if fit == "all" or p.triangles is not None:
            group = groups.pop((p.joint, p.link), None)
            if group is None:
                continue  # the link's spheres are out already
            c, r = _fitted(group, link_options)
            joints.extend([p.joint] * len(r))
            centres.append(c)
            radii.append(r)
            continue
        if p.kind == "cylinder":
            c, r = cylinder_spheres(p.half[0], p.half[2], 2.0 if coarse else 1.2)
        else:
            c, r = box_spheres(np.array(p.half), coarse=coarse)
        world = c @ p.T_joint_shape[:3, :3].T + p.T_joint_shape[:3, 3]
        joints.extend([p.joint] * len(r))
        centres.append(world)
        radii.append(r)
    return joints, centres, radii


def model_digest(urdf: Path, package_dirs: tuple[Path, ...] = ()) -> str:
    """A SHA-256 of the URDF's text (its collision meshes resolved) and of every collision
    mesh file it names: two descriptions with the same digest have the same geometry."""
    text = read_urdf(urdf, package_dirs)
    digest = hashlib.sha256(text.encode("utf-8"))
    for block in _COLLISION.findall(text):
        for name in _FILENAME.findall(block):
            path = Path(name)
            if path.is_file():
                digest.update(path.read_bytes())
    return digest.hexdigest()


def arm_spheres(
    urdf: Path,
    coarse: bool = False,
    package_dirs: tuple[Path, ...] = (),
    fit: str = "meshes",
    options: FitOptions | None = None,
) -> ArmSpheres:
    """The sphere model of one arm (its moving links and the gripper) from the URDF.

    Boxes and cylinders get spheres that cover them by construction; meshes (with
    ``fit="all"``, every shape) get spheres fitted to their link's collision surface
    (:mod:`streams.motion.sphere_fit`; ``options`` default to :class:`FitOptions`; at most
    ``options.max_spheres`` per link).
    ``coarse``: fewer, larger spheres (cylinders 2 radii apart, half the fitted spheres per
    link, the whole gripper -- :func:`gripper_shapes` -- as one box along the hand), used for
    the arm-arm pairs of the optimiser. Models are kept by :func:`model_digest` and the
    parameters, in memory and (fitted ones) on disk (:mod:`streams.motion.sphere_cache`): the
    same description is fitted once.

    Raises:
        ParameterError: ``fit`` is neither ``"meshes"`` nor ``"all"``.
        SceneError: the URDF does not load (see :func:`streams._pin_geometry.arm_primitives`).
    """
    if fit not in FITS:
        raise ParameterError(f"fit must be one of {', '.join(FITS)}, got {fit!r}")
    digest = model_digest(urdf, package_dirs)
    return _arm_spheres(digest, urdf, coarse, package_dirs, fit, options or FitOptions())


@functools.lru_cache(maxsize=16)
def _arm_spheres(
    digest: str,
    urdf: Path,
    coarse: bool,
    package_dirs: tuple[Path, ...],
    fit: str,
    options: FitOptions,
) -> ArmSpheres:
    key = sphere_cache.cache_key(digest, coarse, fit, options)
    stored = sphere_cache.load(key)
    model = (
        ArmSpheres(*stored)
        if stored is not None
        else _build(urdf, coarse, package_dirs, fit, options, key)
    )
    for array in (model.joint, model.centre, model.radius):
        array.flags.writeable = False
    return model


def _build(
    urdf: Path,
    coarse: bool,
    package_dirs: tuple[Path, ...],
    fit: str,
    options: FitOptions,
    key: str,
) -> ArmSpheres:
    """The model of :func:`arm_spheres`, kept on disk under ``key`` when a link was fitted."""
    prims = [p for p in arm_primitives(urdf, package_dirs) if p.joint != 0]
    grip: list[Primitive] = []
    if coarse:
        grip = gripper_shapes(prims)
        prims = [p for p in prims if not any(p is g for g in grip)]
    joints, centres, radii = _covered_shapes(prims, coarse, fit, options)
    if grip:
        R, centre, half = _gripper_box(grip)
        c, r = box_spheres(half)
        if not np.array_equal(R, np.eye(3)):
            c = c @ R.T
        joints.extend([min(g.joint for g in grip)] * len(r))  # the tool joint
        centres.append(c + centre)
        radii.append(r)
    model = ArmSpheres(
        np.array(joints, dtype=np.int64), np.concatenate(centres), np.concatenate(radii)
    )
    if fitted_links(prims, fit):
        sphere_cache.store(key, model.joint, model.centre, model.radius)
    return model


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
