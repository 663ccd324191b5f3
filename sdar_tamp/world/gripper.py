"""The parallel gripper of an arm: opening, stroke, tool centre point, dwell and finger measures.

A cell describes each arm's gripper in its scene file (see ``docs/robots.md``)::

    gripper:
      max_opening: 0.060     # pre-grasp opening between the pads [m]
      stroke: 0.085          # full opening [m] (>= max_opening; default max_opening)
      tcp_offset: 0.15       # tool centre point along the tool frame's z [m]
      grasp_margin: 0.01     # a graspable side is <= max_opening - grasp_margin [m]
      dwell: 0.5             # still time after a gripper event [s] (default DEFAULT_DWELL)
      fingers: [left_finger_link, right_finger_link]   # URDF links, measured
      # or: finger_box: {depth: 0.017, width: 0.022, length: 0.065, thickness: 0.012}

The finger measures come from the robot description (:mod:`.finger_geometry`: the collision
shapes of the two finger links, in the TCP frame) or from a declared box: ``depth`` how far
the fingertips reach beyond the TCP, ``width`` their extent across the closing axis,
``length`` their extent along the approach and ``thickness`` each pad's along the closing
axis (the pads stand ``max_opening`` apart).
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass

import numpy as np

from sdar_tamp.world._pin import PinRobot
from sdar_tamp.world._yaml import Node
from sdar_tamp.world.errors import KinematicsError
from sdar_tamp.world.finger_geometry import finger_geometry
from sdar_tamp.world.graspability import GraspLimits
from sdar_tamp.world.transforms import FloatArray

#: Still time after a gripper event when the scene names none [s] (a parallel gripper's
#: closing time; the plan files' ``GRIPPER_DWELL``).
DEFAULT_DWELL = 0.5

Corner = tuple[float, float, float]


@dataclass(frozen=True)
class Gripper:
    """A two-finger parallel gripper. Lengths [m], ``dwell`` [s].

    ``envelope_corners``: the eight corners of the box enclosing both fingers at the
    pre-grasp opening, in the TCP frame (z the approach, y the closing axis; x, then y, then z
    varying slowest to fastest); ``finger_links``: the URDF links measured (empty for a
    declared box)."""

    max_opening: float
    stroke: float
    tcp_offset: float
    grasp_margin: float
    dwell: float
    finger_depth: float
    finger_width: float
    envelope_corners: tuple[Corner, ...]
    finger_links: tuple[str, ...] = ()

    @property
    def max_graspable_width(self) -> float:
        """The widest side the gripper closes on: opening minus margin [m]."""
        return self.max_opening - self.grasp_margin

    @property
    def envelope(self) -> FloatArray:
        """The corners ``(8, 3)`` of the box enclosing the fingers in the TCP frame [m]."""
        return np.array(self.envelope_corners, dtype=np.float64)

    @property
    def limits(self) -> GraspLimits:
        """What the grasp rules need of this gripper."""
        return GraspLimits(self.max_graspable_width, self.finger_depth, self.finger_width)


def box_envelope(
    x: tuple[float, float], y: tuple[float, float], z: tuple[float, float]
) -> tuple[Corner, ...]:
    """The corners of an axis-aligned box ``[x0, x1] x [y0, y1] x [z0, z1]`` (x slowest)."""
    return tuple((a, b, c) for a in x for b in y for c in z)


GRIPPER_KEYS = ["max_opening", "tcp_offset", "grasp_margin"]
GRIPPER_OPTIONAL = ["stroke", "dwell", "fingers", "finger_box"]


def read_gripper(
    node: Node,
    robot: PinRobot,
    tool_frame: str,
    default_fingers: Sequence[str] = (),
    q: FloatArray | None = None,
    locked: Collection[str] = (),
) -> Gripper:
    """The gripper the scene node ``node`` describes, its fingers measured on ``robot`` from
    the frame ``tool_frame`` (the TCP is ``tcp_offset`` along its z) at the configuration
    ``q`` (the joints ``locked`` held there). A node naming neither ``fingers`` nor
    ``finger_box`` measures ``default_fingers`` (the legacy scene form).

    Raises:
        SceneError: a missing or bad key, a stroke below the opening, no graspable width,
            both or neither of ``fingers`` and ``finger_box``, or finger links that cannot be
            measured (at the ``fingers`` key).
    """
    k = node.mapping(GRIPPER_KEYS, GRIPPER_OPTIONAL)
    opening = k["max_opening"].as_float(positive=True)
    tcp_offset = k["tcp_offset"].as_float(positive=True)
    _check_tcp_frame(k["tcp_offset"], robot, tool_frame, tcp_offset, q)
    margin = k["grasp_margin"].as_float()
    if not 0.0 <= margin < opening:
        raise k["grasp_margin"].error(f"a margin in [0, max_opening = {opening}) [m]")
    stroke = opening
    if "stroke" in k:
        stroke = k["stroke"].as_float(positive=True)
        if stroke < opening:
            raise k["stroke"].error(f"a stroke >= max_opening ({opening} m)")
    dwell = DEFAULT_DWELL
    if "dwell" in k:
        dwell = k["dwell"].as_float()
        if dwell < 0.0:
            raise k["dwell"].error("a time >= 0 [s]")
    if "fingers" in k and "finger_box" in k:
        raise k["finger_box"].error("either fingers or finger_box, not both", show_value=False)
    if "finger_box" in k:
        box = k["finger_box"].mapping(["depth", "width", "length", "thickness"])
        depth, width, length, thick = (
            box[key].as_float(positive=True) for key in ("depth", "width", "length", "thickness")
        )
        half_y = 0.5 * opening + thick
        corners = box_envelope(
            (-0.5 * width, 0.5 * width), (-half_y, half_y), (depth - length, depth)
        )
        return Gripper(opening, stroke, tcp_offset, margin, dwell, depth, width, corners)
    if "fingers" in k:
        links_node = k["fingers"]
        links = tuple(item.as_str() for item in links_node.items())
    elif default_fingers:
        links_node, links = node, tuple(default_fingers)
    else:
        raise node.error("key 'fingers' (two URDF links) or 'finger_box'", show_value=False)
    try:
        measured = finger_geometry(robot, links, tool_frame, tcp_offset, q, locked)
    except KinematicsError as error:
        raise links_node.error(
            f"finger links that can be measured: {error}", show_value=False
        ) from None
    corners = tuple((float(x), float(y), float(z)) for x, y, z in measured.envelope)
    return Gripper(
        opening, stroke, tcp_offset, margin, dwell, measured.depth, measured.width, corners, links
    )


#: How far [m] a description's ``tcp`` frame may lie from ``tcp_offset`` along the tool frame.
TCP_TOLERANCE = 1e-6


def _check_tcp_frame(
    node: Node,
    robot: PinRobot,
    tool_frame: str,
    tcp_offset: float,
    q: FloatArray | None,
) -> None:
    """A description with a ``tcp`` frame must put it ``tcp_offset`` along the tool frame's z
    (the planner's forward kinematics takes that frame where it exists, the rest the offset)."""
    model = robot.model
    if not model.existFrame("tcp") or not model.existFrame(tool_frame):
        return
    config = robot.neutral() if q is None else q
    T_tool = robot.frame_pose(config, robot.frame_id(tool_frame))
    T_tcp = robot.frame_pose(config, robot.frame_id("tcp"))
    offset = np.linalg.inv(T_tool) @ T_tcp
    expected = np.eye(4)
    expected[2, 3] = tcp_offset
    gap = float(np.abs(offset - expected).max())
    if gap > TCP_TOLERANCE:
        x, y, z = (float(v) for v in offset[:3, 3])
        raise node.error(
            f"the offset of the description's 'tcp' frame from {tool_frame!r} "
            f"({x:.4f}, {y:.4f}, {z:.4f}) m, unturned (it differs by {gap:.2g})"
        )
