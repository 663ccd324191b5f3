"""What code downstream of the planner reads of one arm of a cell: its joint names, its robot
description file and its tool-centre-point offset.

Plan files, the validator, the scheduler, the viewer and the exports ask these functions rather
than the :class:`~sdar_tamp.world.scene.ArmSpec` fields, so that every arm may have its own
robot, joint count and gripper. A spec that names its joints (``joint_names``), its robot
(``urdf``) or its gripper (``gripper``) is read as such; a spec without them is an arm of the
scene's one robot description and gripper, whose six joints carry the UR names (the form of
the scene files that name one ``robot`` for both arms).
"""

from __future__ import annotations

from pathlib import Path

from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.scene import JOINT_KEYS, ArmSpec, Scene


def ur_joint_names() -> tuple[str, ...]:
    """The joints of a Universal Robots arm, base to wrist (``shoulder_pan_joint`` to
    ``wrist_3_joint``)."""
    return tuple(f"{key}_joint" for key in JOINT_KEYS)


def arm_joint_names(spec: ArmSpec) -> tuple[str, ...]:
    """The robot description's names of the arm's joints, in configuration order (one per
    entry of ``spec.home``)."""
    names: tuple[str, ...] | None = getattr(spec, "joint_names", None)
    if names:
        named = tuple(str(n) for n in names)
    elif len(spec.home) == len(JOINT_KEYS):
        named = ur_joint_names()
    else:
        raise SceneError(
            f"arm {spec.name!r}: {len(spec.home)} joints and no joint names; name them in the "
            "scene file (arms[].joints)"
        )
    if len(named) != len(spec.home):
        raise SceneError(f"arm {spec.name!r}: {len(named)} joint names for {len(spec.home)} joints")
    return named


def arm_robot_file(scene: Scene, spec: ArmSpec) -> Path:
    """The robot description (URDF) the arm is an instance of."""
    own: Path | None = getattr(spec, "urdf", None)
    return Path(own) if own is not None else scene.robot_urdf


def arm_tcp_offset(scene: Scene, spec: ArmSpec) -> float:
    """The tool centre point's offset along the flange's z axis [m] (the arm's gripper)."""
    gripper = getattr(spec, "gripper", None)
    return float((gripper if gripper is not None else scene.gripper).tcp_offset)
