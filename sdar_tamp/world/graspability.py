"""What the two-finger gripper can hold: one set of limits shared by the instance loader and
the grasp sampler, so an object the loader accepts always gets grasps.

The fingers (the shipped Robotiq 2F-85 mould) reach :data:`FINGER_DEPTH` beyond the tool
centre point along the approach and are :data:`FINGER_WIDTH` wide across it. A grasp holds the
object at its centre height, unless the fingertips would then come closer than
:data:`TABLE_CLEARANCE` to the table: then the tool centre is raised
(:func:`grasp_height`). A grasp must keep at least :data:`MIN_FINGER_CONTACT` of the object
between the fingers.
"""

from __future__ import annotations

import math

#: Slack [m] of every width comparison: a side equal to the graspable width in exact
#: arithmetic (0.06 - 0.01 comes out 0.049999999999999996) is graspable.
WIDTH_TOLERANCE = 1e-9
#: How far the fingertips reach beyond the tool centre point along the approach [m].
FINGER_DEPTH = 0.017
#: Finger extent across the closing axis, perpendicular to the approach [m].
FINGER_WIDTH = 0.022
#: Smallest gap kept between a fingertip and the table top [m].
TABLE_CLEARANCE = 0.003
#: Least height of the object the fingers must hold [m].
MIN_FINGER_CONTACT = 0.01


def fits_between_fingers(side: float, max_width: float) -> bool:
    """A side [m] the fingers can close on (``max_width`` [m], the opening minus margin)."""
    return side <= max_width + WIDTH_TOLERANCE


def fingertip_drop(tilt: float) -> float:
    """How far [m] below the tool centre point the fingertips reach at ``tilt`` [rad] from
    top-down (the tilt turns the tool about its closing axis)."""
    t = abs(tilt)
    return FINGER_DEPTH * math.cos(t) + 0.5 * FINGER_WIDTH * math.sin(t)


def grasp_height(height: float, tilt: float = 0.0) -> float:
    """Height [m] of the tool centre point above the object's base for an object
    ``height`` [m] tall: its centre, raised if the fingertips would come closer than
    :data:`TABLE_CLEARANCE` to the table."""
    return max(0.5 * height, fingertip_drop(tilt) + TABLE_CLEARANCE)


def finger_contact(height: float, tilt: float = 0.0) -> float:
    """Height [m] of the object between the fingers at :func:`grasp_height`."""
    return height - max(0.0, grasp_height(height, tilt) - fingertip_drop(tilt))


def grasp_problem(size: tuple[float, float, float], max_width: float) -> str | None:
    """Why a cuboid of ``size`` (lx, ly, lz) [m] cannot be grasped top-down, or ``None``."""
    lx, ly, lz = size
    if not fits_between_fingers(min(lx, ly), max_width):
        return (
            f"both horizontal sides ({lx:g} and {ly:g} m) are wider than the gripper can "
            f"close on; expected a side <= {max_width:g} m (opening minus margin)"
        )
    if finger_contact(lz) < MIN_FINGER_CONTACT - WIDTH_TOLERANCE:
        least = MIN_FINGER_CONTACT + TABLE_CLEARANCE
        return (
            f"height {lz:g} m is too short: the fingers, {TABLE_CLEARANCE:g} m above the "
            f"table, would hold {max(finger_contact(lz), 0.0):.3g} m of it; expected a "
            f"height >= {least:g} m"
        )
    return None
