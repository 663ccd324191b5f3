"""What the code still knows of the shipped UR5e cell (``cells/ur5e_facing.yaml``).

Everything else reads the robot and its gripper from the cell file. What remains here serves
files written before cells named their robot fully (the first scene file form) and callers
that check an instance before they know its cell:

* :data:`LEGACY_JOINT_KEYS`: the short keys of ``joint_limits`` in the first scene form
  (``shoulder_pan`` for the joint ``shoulder_pan_joint``); a key ``k`` names the joint
  ``k + "_joint"`` when the arm has one;
* :data:`LEGACY_FINGERS`: the finger links measured when a gripper names neither ``fingers``
  nor ``finger_box`` (the first scene form's gripper had neither);
* :data:`SHIPPED_GRASP`: the grasp limits of the shipped cell's gripper, the default of the
  instance loader (an instance without ``scene:`` uses that cell; tests check the two agree).
"""

from __future__ import annotations

from sdar_tamp.world.graspability import GraspLimits

LEGACY_JOINT_KEYS = ("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3")
LEGACY_JOINT_SUFFIX = "_joint"
LEGACY_FINGERS = ("gripper_left_finger", "gripper_right_finger")
#: Opening 0.06 m minus margin 0.01 m; fingertips 0.017 m beyond the TCP, 0.022 m wide (the
#: Robotiq 2F-85 mould of ``robots/ur5e_2f85.urdf``).
SHIPPED_GRASP = GraspLimits(max_width=0.05, finger_depth=0.017, finger_width=0.022)
#: The joints of a Universal Robots arm as its ROS descriptions name them, base to wrist: a
#: plan without a cell is a UR plan (URScript export) when its arms carry these names.
UR_JOINT_NAMES = tuple(key + LEGACY_JOINT_SUFFIX for key in LEGACY_JOINT_KEYS)
