"""Typed adapter building the pinocchio model of both arms and the scene geometry.

The arms are one pinocchio model whose joints follow the scene's :class:`ArmLayout`. Scene
geometry is added as pinocchio geometry objects: the table and resting objects on the
universe joint, held objects on the last joint of the arm holding them (wrist_3 of a UR).
Collision pairs encode the filtering rules of :class:`sdar_tamp.world.collision.CollisionWorld`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from sdar_tamp.world import _coal
from sdar_tamp.world._pin import array_to_se3, build_model, se3_to_array
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.kinematics import arm_description
from sdar_tamp.world.layout import ArmLayout
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray, translation
from sdar_tamp.world.urdf import read_urdf


@dataclass(frozen=True)
class ArmGeometry:
    """One collision shape of an arm: its index in the arm-only geometry model."""

    name: str
    arm: str
    link_index: int  # 0 base, then k: the link joint k of the chain moves (the last + gripper)
    index: int


@dataclass(frozen=True)
class CellCollisionModel:
    """The combined kinematic model and the arms' collision shapes."""

    model: Any
    data: Any = field(repr=False)
    arm_geometry: Any = field(repr=False)  # pin.GeometryModel holding the arm shapes only
    shapes: tuple[ArmGeometry, ...]
    layout: ArmLayout
    wrist_joint: dict[str, int]  # arm -> joint id of the chain's last joint (wrist_3)
    tool0_frame: dict[str, int]  # arm -> frame id of tool0
    T_wrist_tool0: FloatArray  # tool0 in the last joint's frame

    @property
    def arm_names(self) -> tuple[str, ...]:
        return self.layout.names


def _prefixed_urdf(text: str, prefix: str) -> str:
    text = re.sub(r'(<(?:link|joint)\s+name=")', rf"\g<1>{prefix}", text)
    return re.sub(r'(<(?:parent|child)\s+link=")', rf"\g<1>{prefix}", text)


def build_dual_arm(scene: Scene) -> CellCollisionModel:
    """Both arms of ``scene`` in one pinocchio model, bases at their world poses."""
    text = read_urdf(scene.robot_urdf, scene.package_dirs)
    model = pin.Model()
    geometry = pin.GeometryModel()
    for spec in scene.arms:
        arm_text = _prefixed_urdf(text, f"{spec.name}_")
        arm_model, arm_geom = build_model(scene.robot_urdf, arm_text)
        model, geometry = pin.appendModel(
            model, arm_model, geometry, arm_geom, 0, array_to_se3(spec.T_world_base)
        )
    shapes: list[ArmGeometry] = []
    wrist: dict[str, int] = {}
    for spec in scene.arms:
        joints = _chain_joints(model, f"{spec.name}_{arm_description(scene, spec.name).tool_frame}")
        wrist[spec.name] = int(joints[-1])
        for gi, obj in enumerate(geometry.geometryObjects):
            if not obj.name.startswith(f"{spec.name}_"):
                continue
            link = joints.index(obj.parentJoint) + 1 if obj.parentJoint in joints else 0
            shapes.append(ArmGeometry(str(obj.name), spec.name, link, gi))
    tool0 = {a.name: int(model.getFrameId(f"{a.name}_tool0")) for a in scene.arms}
    T_wrist_tool0 = se3_to_array(model.frames[tool0[scene.arms[0].name]].placement)
    layout = scene.layout
    if model.nq != layout.dof:
        raise SceneError(
            f"{scene.file}: the robot description has {model.nq // len(layout)} joints per arm; "
            f"the scene's arms have {list(layout.dofs)}"
        )
    return CellCollisionModel(
        model,
        model.createData(),
        geometry,
        tuple(shapes),
        layout,
        wrist,
        tool0,
        T_wrist_tool0,
    )


def tool0_pose(arms: CellCollisionModel, q: FloatArray, arm: str) -> FloatArray:
    """``T_world_tool0`` of ``arm`` at the configuration ``q`` ``(layout.dof,)``."""
    pin.framesForwardKinematics(arms.model, arms.data, q)
    return se3_to_array(arms.data.oMf[arms.tool0_frame[arm]])


def _chain_joints(model: Any, frame: str) -> list[int]:
    """The ids of the joints from the root to ``frame``, root first (the arm's chain: joint
    ``k`` of the list carries link ``k + 1``)."""
    if not model.existFrame(frame):
        raise SceneError(f"the robot description has no frame {frame!r}")
    ids: list[int] = []
    j = int(model.frames[model.getFrameId(frame)].parentJoint)
    while j != 0:
        ids.append(j)
        j = int(model.parents[j])
    if not ids:
        raise SceneError(f"no joint moves the frame {frame!r} of the robot description")
    return ids[::-1]


@dataclass(frozen=True)
class SceneGeometry:
    """A ready-to-query geometry model: pairs, names and a broad-phase manager."""

    geometry: Any
    data: Any
    manager: Any
    pair_names: tuple[tuple[str, str], ...]


def build_scene_geometry(
    arms: CellCollisionModel,
    table_size: tuple[float, float, float],
    resting: dict[str, tuple[FloatArray, FloatArray]],
    held: dict[str, tuple[str, FloatArray, FloatArray]],
    pairs: list[tuple[str, str]],
    arm_margin: float = 0.0,
) -> SceneGeometry:
    """Add table, resting objects ``name -> (T_world_obj, size)`` and held objects
    ``arm -> (name, T_tool0_obj, size)`` to the arm shapes; activate the named ``pairs``.
    Pairs of two arms' shapes count as colliding closer than ``arm_margin`` [m]."""
    geometry = arms.arm_geometry.copy()
    sx, sy, sz = table_size
    table = pin.GeometryObject(
        "table", 0, array_to_se3(translation(0.0, 0.0, -sz / 2)), _coal.box((sx, sy, sz))
    )
    geometry.addGeometryObject(table)
    for name, (T, size) in resting.items():
        geometry.addGeometryObject(
            pin.GeometryObject(f"object:{name}", 0, array_to_se3(T), _coal.box(size))
        )
    for arm, (name, T_tool0_obj, size) in held.items():
        placement = array_to_se3(arms.T_wrist_tool0 @ T_tool0_obj)
        geometry.addGeometryObject(
            pin.GeometryObject(f"held:{name}", arms.wrist_joint[arm], placement, _coal.box(size))
        )
    # pairs, names and margins as index matrices: one C++ call each instead of a Python
    # loop over hundreds of pairs (indexing geometryObjects copies a Python proxy per access)
    all_names = [str(obj.name) for obj in geometry.geometryObjects]
    ids = {name: k for k, name in enumerate(all_names)}
    n = len(all_names)
    first = np.array([ids[a] for a, _ in pairs], dtype=np.intp)
    second = np.array([ids[b] for _, b in pairs], dtype=np.intp)
    active = np.zeros((n, n), dtype=bool)
    active[np.minimum(first, second), np.maximum(first, second)] = True
    geometry.setCollisionPairs(active, True)
    flipped = np.zeros((n, n), dtype=bool)  # named the other way round in ``pairs``
    flipped[second, first] = first > second
    rows, cols = np.nonzero(active)  # row-major: the order the pairs were added in
    names = tuple(
        (all_names[j], all_names[i]) if flipped[i, j] else (all_names[i], all_names[j])
        for i, j in zip(rows.tolist(), cols.tolist(), strict=True)
    )
    data = geometry.createData()
    if arm_margin > 0.0:
        owner = np.array([_arm_index(a, arms) for a in all_names])
        margins = np.where(
            active & (owner[:, None] >= 0) & (owner[None, :] >= 0)
            & (owner[:, None] != owner[None, :]),
            arm_margin, 0.0,
        )  # fmt: skip
        data.setSecurityMargins(geometry, margins, True, False)
    manager = pin.BroadPhaseManager_DynamicAABBTreeCollisionManager(arms.model, geometry, data)
    return SceneGeometry(geometry, data, manager, names)


def _arm_index(shape: str, arms: CellCollisionModel) -> int:
    """The index of the arm a link or gripper shape belongs to (its name's prefix), else -1."""
    return next((k for k, arm in enumerate(arms.wrist_joint) if shape.startswith(f"{arm}_")), -1)


def any_collision(arms: CellCollisionModel, scene: SceneGeometry, q: FloatArray) -> bool:
    """Broad phase then narrow phase; stops at the first colliding pair."""
    return bool(pin.computeCollisions(arms.model, arms.data, scene.manager, q, True))


def colliding_pairs(arms: CellCollisionModel, scene: SceneGeometry, q: FloatArray) -> list[int]:
    """Indices (into ``scene.pair_names``) of every colliding pair, narrow phase on all."""
    pin.computeCollisions(arms.model, arms.data, scene.geometry, scene.data, q, False)
    return [i for i, r in enumerate(scene.data.collisionResults) if r.isCollision()]


def pair_distances(arms: CellCollisionModel, scene: SceneGeometry, q: FloatArray) -> FloatArray:
    """Signed distance of every active pair ``(n_pairs,)`` [m]."""
    pin.computeDistances(arms.model, arms.data, scene.geometry, scene.data, q)
    return np.array([r.min_distance for r in scene.data.distanceResults], dtype=np.float64)


def link_poses(
    arms: CellCollisionModel, scene: SceneGeometry, q: FloatArray
) -> dict[str, FloatArray]:
    """World pose of every geometry ``name -> (4, 4)`` at ``q`` ``(layout.dof,)``."""
    pin.updateGeometryPlacements(arms.model, arms.data, scene.geometry, scene.data, q)
    return {
        str(obj.name): se3_to_array(scene.data.oMg[i])
        for i, obj in enumerate(scene.geometry.geometryObjects)
    }
