"""Typed adapter building the pinocchio model of a cell's arms (one or more) and the scene
geometry.

The arms are one pinocchio model whose joints follow the scene's :class:`ArmLayout`, each arm
built from its own robot description with its link and joint names prefixed by the arm's
name. Scene geometry is added as pinocchio geometry objects: the table and resting objects on
the universe joint, held objects on the last joint of the arm holding them. Collision pairs
encode the filtering rules of :class:`sdar_tamp.world.collision.CollisionWorld`.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from sdar_tamp.world import _coal
from sdar_tamp.world._pin import array_to_se3, build_model, se3_to_array
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.layout import ArmLayout
from sdar_tamp.world.scene import ArmSpec, Scene
from sdar_tamp.world.transforms import FloatArray, inverse, translation
from sdar_tamp.world.urdf import read_urdf


@dataclass(frozen=True)
class ArmGeometry:
    """One collision shape of an arm: its index in the arm-only geometry model."""

    name: str
    arm: str
    link_index: int  # 0: fixed to the base; k: moved by the arm's k-th joint (1-based)
    index: int


@dataclass(frozen=True)
class CellCollisionModel:
    """The combined kinematic model and the arms' collision shapes."""

    model: Any
    data: Any = field(repr=False)
    arm_geometry: Any = field(repr=False)  # pin.GeometryModel holding the arm shapes only
    shapes: tuple[ArmGeometry, ...]
    layout: ArmLayout
    wrist_joint: dict[str, int]  # arm -> joint id of its last joint
    tool0_frame: dict[str, int]  # arm -> frame id of its tool (flange) frame
    T_wrist_tool: dict[str, FloatArray]  # arm -> its tool frame in its last joint's frame

    @property
    def arm_names(self) -> tuple[str, ...]:
        return self.layout.names


def prefixed_urdf(text: str, prefix: str) -> str:
    """The URDF ``text`` with every link and joint name (and every reference to one)
    prefixed by ``prefix``, so that several arms' descriptions live in one model."""
    root = ET.fromstring(text)
    for element in root.iter():
        tag = element.tag
        if tag in ("link", "joint") and element.get("name") is not None:
            element.set("name", prefix + str(element.get("name")))
        elif tag in ("parent", "child") and element.get("link") is not None:
            element.set("link", prefix + str(element.get("link")))
        elif tag == "mimic" and element.get("joint") is not None:
            element.set("joint", prefix + str(element.get("joint")))
    return ET.tostring(root, encoding="unicode")


def _arm_model(spec: ArmSpec, text: str) -> tuple[Any, Any, FloatArray]:
    """The arm's model and geometry with every joint but its own locked (at the arm's
    ``locked_joints`` values), and the pose ``T_root_base`` of its base frame in the
    description's root."""
    prefix = f"{spec.name}_"
    model, geometry = build_model(spec.urdf, prefixed_urdf(text, prefix))
    keep = {prefix + j for j in spec.joint_names}
    lock = [j for j in range(1, model.njoints) if str(model.names[j]) not in keep]
    q0 = np.asarray(pin.neutral(model), dtype=np.float64)
    for name, value in spec.locked_joints:
        q0[int(model.idx_qs[model.getJointId(prefix + name)])] = value
    data = model.createData()
    pin.framesForwardKinematics(model, data, q0)
    T_root_base = se3_to_array(data.oMf[model.getFrameId(prefix + spec.base_frame)])
    if lock:
        model, geometry = pin.buildReducedModel(model, geometry, lock, q0)
    return model, geometry, T_root_base


def build_dual_arm(scene: Scene) -> CellCollisionModel:
    """The arms of ``scene`` (any number) in one pinocchio model, each from its own robot
    description and joints (any other joint of the description locked, see
    ``ArmSpec.locked_joints``), bases at their world poses. (The name is historical: the
    model holds every arm of the cell.)"""
    texts = {u: read_urdf(u, scene.package_dirs) for u in dict.fromkeys(a.urdf for a in scene.arms)}
    model = pin.Model()
    geometry = pin.GeometryModel()
    for spec in scene.arms:
        arm_model, arm_geom, T_root_base = _arm_model(spec, texts[spec.urdf])
        model, geometry = pin.appendModel(
            model, arm_model, geometry, arm_geom, 0,
            array_to_se3(spec.T_world_base @ inverse(T_root_base)),
        )  # fmt: skip
    shapes: list[ArmGeometry] = []
    wrist: dict[str, int] = {}
    tool: dict[str, int] = {}
    T_wrist_tool: dict[str, FloatArray] = {}
    for spec in scene.arms:
        for name, kind, exists in (
            *((j, "joint", model.existJointName(f"{spec.name}_{j}")) for j in spec.joint_names),
            (spec.tool_frame, "frame", model.existFrame(f"{spec.name}_{spec.tool_frame}")),
        ):
            if not exists:
                raise SceneError(
                    f"{scene.file}: arm {spec.name!r}: its robot description "
                    f"{spec.urdf.name} has no {kind} {name!r}"
                )
        joints = [int(model.getJointId(f"{spec.name}_{j}")) for j in spec.joint_names]
        wrist[spec.name] = joints[-1]
        tool[spec.name] = int(model.getFrameId(f"{spec.name}_{spec.tool_frame}"))
        frame = model.frames[tool[spec.name]]
        if int(frame.parentJoint) != joints[-1]:
            raise SceneError(
                f"{scene.file}: arm {spec.name!r}: the tool frame {spec.tool_frame!r} is not "
                "fixed to the arm's last joint"
            )
        T_wrist_tool[spec.name] = se3_to_array(frame.placement)
        for gi, obj in enumerate(geometry.geometryObjects):
            if _owner(str(obj.name), scene.arm_names) != spec.name:
                continue
            parent = int(obj.parentJoint)
            link = joints.index(parent) + 1 if parent in joints else 0
            shapes.append(ArmGeometry(str(obj.name), spec.name, link, gi))
    layout = scene.layout
    if model.nq != layout.dof:  # the reduction keeps exactly the arms' joints
        raise SceneError(
            f"{scene.file}: the robot descriptions give {model.nq} joints; the scene's arms "
            f"have {list(layout.dofs)}"
        )
    return CellCollisionModel(
        model, model.createData(), geometry, tuple(shapes), layout, wrist, tool, T_wrist_tool
    )


def _owner(shape: str, arms: tuple[str, ...]) -> str | None:
    """The arm whose name, then ``_``, begins ``shape``: the longest such name (an arm ``s``
    beside an arm ``s_e``: ``s_e_base_link_0`` is the second's)."""
    found = [arm for arm in arms if shape.startswith(f"{arm}_")]
    return max(found, key=len) if found else None


def tool0_pose(arms: CellCollisionModel, q: FloatArray, arm: str) -> FloatArray:
    """``T_world_tool`` of ``arm``'s tool (flange) frame at the configuration ``q``
    ``(layout.dof,)``."""
    pin.framesForwardKinematics(arms.model, arms.data, q)
    return se3_to_array(arms.data.oMf[arms.tool0_frame[arm]])


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
    Pairs of two different arms' shapes (every pair of arms) count as colliding closer than
    ``arm_margin`` [m]."""
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
        placement = array_to_se3(arms.T_wrist_tool[arm] @ T_tool0_obj)
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
        index = {s.name: arms.layout.index(s.arm) for s in arms.shapes}
        owner = np.array([index.get(name, -1) for name in all_names])  # -1: no arm's shape
        margins = np.where(
            active & (owner[:, None] >= 0) & (owner[None, :] >= 0)
            & (owner[:, None] != owner[None, :]),
            arm_margin, 0.0,
        )  # fmt: skip
        data.setSecurityMargins(geometry, margins, True, False)
    manager = pin.BroadPhaseManager_DynamicAABBTreeCollisionManager(arms.model, geometry, data)
    return SceneGeometry(geometry, data, manager, names)


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
