"""Drawable geometry of an arm: the URDF collision shapes as triangle meshes, posed by FK.

The shapes are read from the robot description (cylinders and boxes, each placed in its link
frame); the link frames come from pinocchio through :class:`sdar_tamp.world._pin.PinRobot`.
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sdar_tamp.errors import SdarError
from sdar_tamp.world._pin import PinRobot, chain_to
from sdar_tamp.world.transforms import FloatArray

IntArray = NDArray[np.int64]

#: The two finger frames (drawn as the gripper's jaw line, when the robot has them).
FINGER_FRAMES = ("gripper_left_finger", "gripper_right_finger")
#: The robot description's root frame (pinocchio's name for it).
ROOT_FRAME = "universe"


@dataclass(frozen=True)
class Shape:
    """A collision shape of one link. ``size``: box sides, or (radius, radius, length) [m]."""

    link: str
    kind: str  # "cylinder" or "box"
    size: tuple[float, float, float]
    T_link_shape: FloatArray = field(repr=False)


def _rpy(r: float, p: float, y: float) -> FloatArray:
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    out: FloatArray = Rz @ Ry @ Rx
    return out


def _floats(text: str | None, n: int, default: float = 0.0) -> list[float]:
    values = [float(v) for v in text.split()] if text else [default] * n
    if len(values) != n:
        raise SdarError(f"expected {n} numbers in a URDF attribute, got {text!r}")
    return values


def collision_shapes(urdf: Path) -> tuple[Shape, ...]:
    """Every cylinder and box collision element of the URDF at ``urdf`` (others are skipped)."""
    try:
        root = ET.parse(urdf).getroot()
    except (OSError, ET.ParseError) as error:
        raise SdarError(f"cannot read the robot description {urdf}: {error}") from None
    shapes: list[Shape] = []
    for link in root.iter("link"):
        for col in link.iter("collision"):
            origin = col.find("origin")
            xyz = _floats(origin.get("xyz") if origin is not None else None, 3)
            rpy = _floats(origin.get("rpy") if origin is not None else None, 3)
            T = np.eye(4)
            T[:3, :3] = _rpy(*rpy)
            T[:3, 3] = xyz
            cyl, box = col.find("geometry/cylinder"), col.find("geometry/box")
            if cyl is not None:
                r, length = float(cyl.get("radius", "0")), float(cyl.get("length", "0"))
                shapes.append(Shape(link.get("name", ""), "cylinder", (r, r, length), T))
            elif box is not None:
                lx, ly, lz = _floats(box.get("size"), 3)
                shapes.append(Shape(link.get("name", ""), "box", (lx, ly, lz), T))
    return tuple(shapes)


_BOX_FACES = np.array(
    [[0, 1, 2], [0, 2, 3], [4, 6, 5], [4, 7, 6], [0, 4, 5], [0, 5, 1],
     [1, 5, 6], [1, 6, 2], [2, 6, 7], [2, 7, 3], [3, 7, 4], [3, 4, 0]],
    dtype=np.int64,
)  # fmt: skip


def box_mesh(size: tuple[float, float, float]) -> tuple[FloatArray, IntArray]:
    """Vertices ``(8, 3)`` [m] and triangles ``(12, 3)`` of a box centred at the origin."""
    half = np.asarray(size, dtype=np.float64) / 2.0
    square = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])
    bottom = np.column_stack([square, -np.ones(4)])
    top = np.column_stack([square, np.ones(4)])
    return np.vstack([bottom, top]) * half, _BOX_FACES.copy()


def cylinder_mesh(radius: float, length: float, segments: int) -> tuple[FloatArray, IntArray]:
    """A closed cylinder along z, centred: vertices ``(2 s, 3)``, triangles ``(4 s - 4, 3)``."""
    a = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    ring = np.column_stack([radius * np.cos(a), radius * np.sin(a)])
    v = np.vstack([np.column_stack([ring, np.full(segments, -length / 2)]),
                   np.column_stack([ring, np.full(segments, length / 2)])])  # fmt: skip
    k = np.arange(segments)
    k1 = (k + 1) % segments
    sides = np.vstack([np.column_stack([k, k1, k + segments]),
                       np.column_stack([k1, k1 + segments, k + segments])])  # fmt: skip
    fan = np.arange(1, segments - 1)
    bottom = np.column_stack([np.zeros_like(fan), fan + 1, fan])
    top = np.column_stack([np.full_like(fan, segments), fan + segments, fan + 1 + segments])
    return v, np.vstack([sides, bottom, top]).astype(np.int64)


def shape_mesh(shape: Shape, segments: int = 12) -> tuple[FloatArray, IntArray]:
    """Mesh of ``shape`` in its link frame: vertices ``(m, 3)`` [m], triangles ``(f, 3)``."""
    if shape.kind == "box":
        v, f = box_mesh(shape.size)
    else:
        v, f = cylinder_mesh(shape.size[0], shape.size[2], segments)
    out: FloatArray = v @ shape.T_link_shape[:3, :3].T + shape.T_link_shape[:3, 3]
    return out, f


@dataclass(frozen=True)
class ArmDrawing:
    """One arm ready to draw: kinematics in the world and its shapes as one merged mesh.

    ``vertices`` ``(m, 3)`` are in the frames of their links; ``vertex_link[i]`` indexes
    ``links``; ``faces`` ``(f, 3)`` index ``vertices``; ``face_shape[j]`` indexes ``shapes``.
    """

    name: str
    robot: PinRobot = field(repr=False)
    T_world_base: FloatArray = field(repr=False)
    T_tool0_tcp: FloatArray = field(repr=False)
    shapes: tuple[Shape, ...]
    links: tuple[str, ...]
    vertices: FloatArray = field(repr=False)
    vertex_link: IntArray = field(repr=False)
    faces: IntArray = field(repr=False)
    face_shape: IntArray = field(repr=False)
    segments: int = 10
    #: Where the arm's joints go in the robot's configuration (None: the arm is the whole
    #: robot); the robot's other joints (a hand's fingers, say) stay at 0.
    q_index: tuple[int, ...] | None = None

    @staticmethod
    def build(
        name: str,
        robot: PinRobot,
        T_world_base: FloatArray,
        T_tool0_tcp: FloatArray,
        segments: int = 10,
        shapes: tuple[Shape, ...] | None = None,
        joints: tuple[str, ...] | None = None,
    ) -> ArmDrawing:
        """The arm ``name`` of ``robot``, placed at ``T_world_base``; cylinders get ``segments``
        sides. ``shapes``: a subset of the robot's collision shapes (default: all of them);
        ``joints``: the robot's joints the arm's configuration holds, in order (default: all
        of them)."""
        shapes = collision_shapes(robot.urdf_path) if shapes is None else shapes
        links = tuple(dict.fromkeys(s.link for s in shapes))
        verts, vlink, faces, fshape = [], [], [], []
        offset = 0
        for i, s in enumerate(shapes):
            v, f = shape_mesh(s, segments)
            verts.append(v)
            vlink.append(np.full(len(v), links.index(s.link), dtype=np.int64))
            faces.append(f + offset)
            fshape.append(np.full(len(f), i, dtype=np.int64))
            offset += len(v)
        return ArmDrawing(
            name,
            robot,
            np.asarray(T_world_base, dtype=np.float64).reshape(4, 4),
            np.asarray(T_tool0_tcp, dtype=np.float64).reshape(4, 4),
            shapes,
            links,
            np.vstack(verts) if verts else np.zeros((0, 3)),
            np.concatenate(vlink) if vlink else np.zeros(0, dtype=np.int64),
            np.vstack(faces) if faces else np.zeros((0, 3), dtype=np.int64),
            np.concatenate(fshape) if fshape else np.zeros(0, dtype=np.int64),
            segments,
            _q_index(robot, joints),
        )

    def select(self, links: tuple[str, ...], keep: bool = True) -> ArmDrawing:
        """The same arm drawing only the shapes of ``links`` (``keep=False``: all others)."""
        shapes = tuple(s for s in self.shapes if (s.link in links) == keep)
        return dataclasses.replace(
            ArmDrawing.build(
                self.name, self.robot, self.T_world_base, self.T_tool0_tcp, self.segments, shapes
            ),
            q_index=self.q_index,
        )

    def static_links(self) -> tuple[str, ...]:
        """The drawn links no joint moves (fixed to the robot's root: ``base_link``)."""
        model = self.robot.model
        return tuple(
            link
            for link in self.links
            if int(model.frames[self.robot.frame_id(link)].parentJoint) == 0
        )

    @property
    def dof(self) -> int:
        """Joints of the arm's configuration."""
        return len(self.q_index) if self.q_index is not None else self.robot.nq

    def chain_frames(self) -> tuple[str, ...]:
        """The frames the top-down stick figure joins, tool centre point aside: the robot's
        root, every joint of the chain to ``tool0`` (at its child link's origin), ``tool0``."""
        joints = tuple(j.name for j in chain_to(self.robot, "tool0").joints)
        return (ROOT_FRAME, *joints, "tool0")

    def chain_points(self, q: FloatArray) -> FloatArray:
        """World positions ``(n, k + 3, 3)`` [m] of :meth:`chain_frames` and the tool centre
        point (the robot's ``tcp`` frame, else ``tool0`` and ``T_tool0_tcp``) at configurations
        ``q`` ``(n, dof)``."""
        has_tcp = self.robot.model.existFrame("tcp")
        frames = (*self.chain_frames(), "tcp") if has_tcp else self.chain_frames()
        T = self.frame_poses(q, frames)
        if not has_tcp:
            T = np.concatenate([T, (T[:, -1] @ self.T_tool0_tcp)[:, None]], axis=1)
        out: FloatArray = T[..., :3, 3]
        return out

    def frame_poses(self, q: FloatArray, frames: tuple[str, ...]) -> FloatArray:
        """``T_world_frame`` ``(n, k, 4, 4)`` of ``frames`` at configurations ``q``
        ``(n, dof)``."""
        ids = tuple(self.robot.frame_id(f) for f in frames)
        qs = np.asarray(q, dtype=np.float64).reshape(-1, self.dof)
        full = np.zeros((len(qs), self.robot.nq))
        if self.q_index is None:
            full[:] = qs
        else:
            full[:, list(self.q_index)] = qs
        out = np.empty((len(qs), len(ids), 4, 4))
        for i, qi in enumerate(full):
            out[i] = self.robot.frame_poses(np.ascontiguousarray(qi), ids)
        posed: FloatArray = self.T_world_base @ out
        return posed

    def tcp_poses(self, q: FloatArray) -> FloatArray:
        """``T_world_tcp`` ``(n, 4, 4)``: tool0 by FK, then the plan's ``T_tool0_tcp``."""
        out: FloatArray = self.frame_poses(q, ("tool0",))[:, 0] @ self.T_tool0_tcp
        return out

    def mesh_vertices(self, q: FloatArray) -> FloatArray:
        """World vertices ``(n, m, 3)`` [m] of the merged mesh at configurations ``(n, dof)``."""
        T = self.frame_poses(q, self.links)[:, self.vertex_link]  # (n, m, 4, 4)
        out: FloatArray = np.einsum("nmij,mj->nmi", T[..., :3, :3], self.vertices)
        return out + T[..., :3, 3]


def _q_index(robot: PinRobot, joints: tuple[str, ...] | None) -> tuple[int, ...] | None:
    """Configuration indices of ``joints`` in ``robot`` (None: every joint, in order)."""
    if joints is None or tuple(joints) == robot.joint_names:
        return None
    model = robot.model
    missing = [j for j in joints if not model.existJointName(j)]
    if missing:
        raise SdarError(f"{robot.urdf_path.name}: no joint named {missing[0]!r}")
    return tuple(int(model.joints[model.getJointId(j)].idx_q) for j in joints)
