"""What a two-finger gripper can hold: one set of rules shared by the instance loader and
the grasp sampler, so an object the loader accepts always gets grasps.

The gripper's measures come from the cell (:class:`GraspLimits`, from each arm's
:class:`~sdar_tamp.world.gripper.Gripper`): its fingers reach ``finger_depth`` beyond the tool
centre point along the approach and are ``finger_width`` wide across it. A grasp holds the
object at its centre height, unless the fingertips would then come closer than
:data:`TABLE_CLEARANCE` to the table: then the tool centre is raised
(:func:`grasp_height`). A grasp must keep at least :data:`MIN_FINGER_CONTACT` of the object
between the fingers.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

#: Slack [m] of every width comparison: a side equal to the graspable width in exact
#: arithmetic (0.06 - 0.01 comes out 0.049999999999999996) is graspable.
WIDTH_TOLERANCE = 1e-9
#: Smallest gap kept between a fingertip and the table top [m].
TABLE_CLEARANCE = 0.003
#: Least height of the object the fingers must hold [m].
MIN_FINGER_CONTACT = 0.01


@dataclass(frozen=True)
class GraspLimits:
    """What the grasp rules need of a gripper [m]: the widest side it closes on (opening
    minus margin), how far its fingertips reach beyond the tool centre point along the
    approach, and the fingers' extent across the closing axis."""

    max_width: float
    finger_depth: float
    finger_width: float

    @staticmethod
    def shared(limits: Iterable[GraspLimits]) -> GraspLimits:
        """The limits a grasp must meet to suit every gripper of ``limits`` (the narrowest
        opening, the deepest and widest fingers)."""
        items = list(limits)
        if not items:
            raise ValueError("GraspLimits.shared: expected at least one gripper's limits")
        return GraspLimits(
            min(g.max_width for g in items),
            max(g.finger_depth for g in items),
            max(g.finger_width for g in items),
        )


def fits_between_fingers(side: float, max_width: float) -> bool:
    """A side [m] the fingers can close on (``max_width`` [m], the opening minus margin)."""
    return side <= max_width + WIDTH_TOLERANCE


def fingertip_drop(limits: GraspLimits, tilt: float) -> float:
    """How far [m] below the tool centre point the fingertips reach at ``tilt`` [rad] from
    top-down (the tilt turns the tool about its closing axis)."""
    t = abs(tilt)
    return limits.finger_depth * math.cos(t) + 0.5 * limits.finger_width * math.sin(t)


def grasp_height(height: float, limits: GraspLimits, tilt: float = 0.0) -> float:
    """Height [m] of the tool centre point above the object's base for an object
    ``height`` [m] tall: its centre, raised if the fingertips would come closer than
    :data:`TABLE_CLEARANCE` to the table."""
    return max(0.5 * height, fingertip_drop(limits, tilt) + TABLE_CLEARANCE)


def finger_contact(height: float, limits: GraspLimits, tilt: float = 0.0) -> float:
    """Height [m] of the object between the fingers at :func:`grasp_height`."""
    return height - max(0.0, grasp_height(height, limits, tilt) - fingertip_drop(limits, tilt))


def grasp_problem(size: tuple[float, float, float], limits: GraspLimits) -> str | None:
    """Why a cuboid of ``size`` (lx, ly, lz) [m] cannot be grasped top-down by a gripper of
    ``limits``, or ``None``."""
    lx, ly, lz = size
    max_width = limits.max_width
    if not fits_between_fingers(min(lx, ly), max_width):
        return (
            f"both horizontal sides ({lx:g} and {ly:g} m) are wider than the gripper can "
            f"close on; expected a side <= {max_width:g} m (opening minus margin)"
        )
    if finger_contact(lz, limits) < MIN_FINGER_CONTACT - WIDTH_TOLERANCE:
        least = MIN_FINGER_CONTACT + TABLE_CLEARANCE
        return (
            f"height {lz:g} m is too short: the fingers, {TABLE_CLEARANCE:g} m above the "
            f"table, would hold {max(finger_contact(lz, limits), 0.0):.3g} m of it; expected a "
            f"height >= {least:g} m"
        )
    return None
