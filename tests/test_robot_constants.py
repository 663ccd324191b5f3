"""No robot or gripper constant in the packages: the cell file describes the robot.

The packages read every arm's robot description, joints, limits and gripper from the cell
(``sdar_tamp/world/scene.py``, ``docs/robots.md``). The only names and numbers of the shipped
UR5e cell left in code are in the module that describes it for the first scene form and for
callers without a cell (:mod:`sdar_tamp.world.shipped_cell`), and in the allowed places below.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("sdar_tamp", "streams", "solvers")
#: What counts as a robot or gripper constant: the UR5e's parameter set and name, the former
#: finger constants, the UR joint names, the shipped TCP offset and the gripper's model name.
FORBIDDEN = re.compile(
    r"\bUR5E\b|FINGER_DEPTH|FINGER_WIDTH|FINGER_ENVELOPE"
    r"|\b(?:shoulder_pan|shoulder_lift|elbow|wrist_[123])_joint\b|\b0\.178(?!\d)|2F-85"
)
#: Module -> the constants it may name, and why.
ALLOWED: dict[str, tuple[set[str], str]] = {
    "sdar_tamp/world/shipped_cell.py": (
        {"UR5E", "0.178", "2F-85", "shoulder_pan_joint"},
        "describes the shipped UR5e cell (legacy scene form, instance loader's default)",
    ),
    "sdar_tamp/world/ur_ik.py": (
        {"UR5E"},
        "the UR family's closed form: the UR5e's published parameters are the known answer its "
        "tests check against; the planner reads each arm's parameters from its URDF "
        "(ur_identify)",
    ),
}


def _hits() -> dict[str, set[str]]:
    found: dict[str, set[str]] = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            text = path.read_text(encoding="utf-8")
            names = {m.group(0) for m in FORBIDDEN.finditer(text)}
            if names:
                found[path.relative_to(ROOT).as_posix()] = names
    return found


def test_no_robot_or_gripper_constant_outside_the_allowed_modules() -> None:
    bad = {
        module: sorted(names - ALLOWED.get(module, (set(), ""))[0])
        for module, names in _hits().items()
    }
    bad = {module: names for module, names in bad.items() if names}
    assert not bad, f"robot or gripper constants outside the cell: {bad}"


def test_the_pattern_finds_what_it_forbids() -> None:
    for text in ("UR5E", "FINGER_DEPTH", "wrist_2_joint", "elbow_joint", "0.178", "2F-85"):
        assert FORBIDDEN.search(text), text
    for text in ("UR5Ex", "wrist_4_joint", "0.1789", "panda_joint1"):
        assert not FORBIDDEN.search(text), text
    assert set(_hits()) <= set(ALLOWED)
