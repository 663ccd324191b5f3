"""A plan as one URScript program per arm (one to four arms, or more): a ``servoj`` stream and
gripper calls.

Each program (``def sdar_<arm>(): ... end``) first moves the arm to the plan's first
configuration with ``movej``, calls ``sdar_wait_for_start()`` (a placeholder: bind it to the
signal that starts every arm together, such as a shared digital input), then streams
``servoj(q, 0, 0, servo_t, servo_lookahead, servo_gain)`` with the plan's configuration at
``t = k * period`` for ``k = 1 .. ceil(duration / period)`` (``servoj`` blocks for ``servo_t``
= ``period`` [s]; its ``a`` and ``v`` arguments are unused by the controller). A gripper event
at ``t_e`` becomes ``sdar_gripper_close("o3")`` or ``sdar_gripper_open("o3")`` right after the
first target at a time >= ``t_e``; the plan holds the arm still for 0.5 s after every event, so
the stream keeps streaming that configuration while the gripper acts. The two gripper
functions are placeholders that only log: replace their bodies with your gripper's
non-blocking commands (for a Robotiq URCap, for example, ``rq_close()`` and ``rq_open()``).

The header comment states the units, the parameters and the base-to-base transform to every
other arm of the plan (``# T_<arm>_<other>``); the ``Base`` frame of the UR controller is the
URDF ``base_link`` rotated by pi about z.

URScript runs on Universal Robots controllers only: every arm must be a UR-family arm. Given
the cell (``scene``), each arm's robot description is checked (its chain to ``tool0`` has the
UR geometry, :func:`~sdar_tamp.world.ur_identify.ur_parameters`); without it, each arm's
joints must be the six UR joints. Any other arm (a Panda, say) is refused with an error naming
the arm and, given the cell, its robot file.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.export.timeline import (
    TIME_TOL,
    arm_columns,
    base_to_base,
    controller_grid,
    positions_at,
)
from sdar_tamp.plan_file import PlanFile, plan_joint_names
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.shipped_cell import UR_JOINT_NAMES
from sdar_tamp.world.transforms import FloatArray, inverse, pose_xyz_yaw


@dataclass(frozen=True)
class ServoSettings:
    """``servoj`` parameters: ``period`` [s] between targets (the ``t`` argument; 0.008 is the
    CB3 controller period, e-Series controllers take 0.002 and up), ``lookahead`` [s] in
    [0.03, 0.2] and ``gain`` in [100, 2000] (UR's ranges); ``start_speed`` [rad/s] and
    ``start_acceleration`` [rad/s^2] of the ``movej`` to the first configuration."""

    period: float = 0.008
    lookahead: float = 0.1
    gain: float = 300.0
    start_speed: float = 0.5
    start_acceleration: float = 1.0

    def __post_init__(self) -> None:
        for name, value, low, high in (
            ("period", self.period, 0.002, 1.0),
            ("lookahead", self.lookahead, 0.03, 0.2),
            ("gain", self.gain, 100.0, 2000.0),
            ("start_speed", self.start_speed, 1e-3, math.pi),
            ("start_acceleration", self.start_acceleration, 1e-3, 15.0),
        ):
            ok = isinstance(value, int | float) and not isinstance(value, bool)
            if not (ok and math.isfinite(value) and low <= value <= high):
                raise ParameterError(
                    f"{name} must be a number in [{low:g}, {high:g}], got {value!r}"
                )


def script_name(arm: str) -> str:
    """The file name of ``arm``'s program."""
    return f"{arm}.script"


def urscript_programs(
    plan: PlanFile, settings: ServoSettings | None = None, scene: Scene | None = None
) -> dict[str, str]:
    """Arm name -> URScript program text (see the module docstring); ``scene``: the cell, whose
    robot descriptions tell whether each arm is a UR arm (default: the plan's joint names)."""
    settings = settings or ServoSettings()
    check_ur_arms(plan, scene)
    _check_names(plan)
    grid = controller_grid(plan.duration, settings.period)
    q = positions_at(plan, grid)
    out: dict[str, str] = {}
    for index, (info, cols) in enumerate(zip(plan.arms, arm_columns(plan), strict=True)):
        lines = _header(plan, index, settings, len(grid) - 1)
        name = _identifier(info.name)
        lines += [f"def sdar_{name}():", *_definitions(settings)]
        lines.append(
            f"  movej({_vector(q[0, cols])}, a=start_acceleration, v=start_speed)"
            "  # to the plan's first configuration"
        )
        lines.append("  sdar_wait_for_start()")
        events = [e for e in plan.events if e.arm == info.name]
        k_event = 0
        while k_event < len(events) and events[k_event].t <= 0.0:  # at t = 0: before any motion
            lines.append(_gripper_call(events[k_event].type, events[k_event].object))
            k_event += 1
        for k in range(1, len(grid)):
            lines.append(
                f"  servoj({_vector(q[k, cols])}, 0, 0, servo_t, servo_lookahead, servo_gain)"
            )
            while k_event < len(events) and events[k_event].t <= grid[k] + TIME_TOL:
                lines.append(_gripper_call(events[k_event].type, events[k_event].object))
                k_event += 1
        lines += ["  stopj(start_acceleration)", "end", ""]
        out[info.name] = "\n".join(lines)
    return out


def write_urscript(
    plan: PlanFile,
    folder: Path,
    settings: ServoSettings | None = None,
    scene: Scene | None = None,
) -> list[Path]:
    """Write one ``<arm>.script`` per arm into ``folder`` (created if missing); nothing is
    written when an arm is not a UR arm (:func:`check_ur_arms`)."""
    programs = urscript_programs(plan, settings, scene)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for arm, text in programs.items():
        path = folder / script_name(arm)
        path.write_text(text, encoding="utf-8")
        paths.append(path)
    return paths


def check_ur_arms(plan: PlanFile, scene: Scene | None = None) -> None:
    """Raise :class:`ParameterError` naming the first arm of ``plan`` that is not a UR arm: by
    its robot description in ``scene`` when the scene has an arm of that name, else by its
    joint names (the six UR joints, ``<arm>_shoulder_pan_joint`` to ``<arm>_wrist_3_joint``)."""
    from sdar_tamp.world._pin import PinRobot  # pinocchio: imported on use
    from sdar_tamp.world.ur_identify import ur_parameters

    checked: dict[Path, bool] = {}
    for info in plan.arms:
        if scene is not None and info.name in scene.arm_names:
            path = scene.arm(info.name).urdf
            if path not in checked:
                checked[path] = ur_parameters(PinRobot.load(path, scene.package_dirs)) is not None
            if not checked[path]:
                raise ParameterError(
                    f"urscript: arm {info.name!r} is not a Universal Robots arm: its robot "
                    f"description {path} has no UR-family chain to tool0 (six revolute joints "
                    "with the UR geometry); URScript runs on UR controllers only, export "
                    "joint-trajectory or csv for this arm"
                )
            continue
        ur = plan_joint_names(info.name, UR_JOINT_NAMES)
        if info.joints != ur:
            raise ParameterError(
                f"urscript: arm {info.name!r} is not a Universal Robots arm: its "
                f"{len(info.joints)} joints are {list(info.joints)}, a UR arm's {list(ur)}; "
                "URScript runs on UR controllers only (pass the cell with --scene to check its "
                "robot description), export joint-trajectory or csv for this arm"
            )


#: The controller's ``Base`` frame in the URDF ``base_link`` frame.
T_BASE_LINK_CONTROLLER = pose_xyz_yaw(0.0, 0.0, 0.0, math.pi)


def _header(plan: PlanFile, index: int, settings: ServoSettings, count: int) -> list[str]:
    info = plan.arms[index]
    others = [k for k in range(len(plan.arms)) if k != index]
    start = (
        "# Start this program alone (bind sdar_wait_for_start() to your start signal)."
        if not others
        else "# Start this program and the other arm's together (bind sdar_wait_for_start())."
        if len(others) == 1
        else "# Start this program and the other arms' together (bind sdar_wait_for_start())."
    )
    lines = [
        f"# sdar-tamp plan of instance {plan.instance}: arm {info.name!r}, {plan.duration:.3f} s.",
        "# Units: m, rad, s. Joint order: " + ", ".join(info.joints) + ".",
        f"# servoj stream: {count} targets, one every servo_t = {settings.period:g} s,",
        f"# lookahead_time {settings.lookahead:g} s, gain {settings.gain:g}.",
        "# Gripper calls: sdar_gripper_close(object), sdar_gripper_open(object) at the plan's",
        "# event times (placeholders below: bind them to your gripper, non-blocking; the plan",
        "# holds the arm still 0.5 s after every event).",
        start,
        f"# T_world_base of {info.name} (URDF base_link; world: table centre, z up):",
        *_matrix(info.T_world_base),
    ]
    for k in others:  # every other arm's base, in plan order
        other = plan.arms[k]
        T = base_to_base(plan, index, k)
        Tc = inverse(T_BASE_LINK_CONTROLLER) @ T @ T_BASE_LINK_CONTROLLER
        lines += [
            f"# T_{info.name}_{other.name}: the {other.name} arm's base_link in this arm's "
            "base_link:",
            *_matrix(T),
            "# The same between the controllers' Base frames (base_link rotated by pi about z):",
            *_matrix(Tc),
        ]
    return lines


def _definitions(settings: ServoSettings) -> list[str]:
    return [
        f"  servo_t = {settings.period!r}  # [s] time per servoj target",
        f"  servo_lookahead = {settings.lookahead!r}  # [s] smoothing of the target stream",
        f"  servo_gain = {settings.gain!r}  # proportional gain",
        f"  start_speed = {settings.start_speed!r}  # [rad/s] movej to the first configuration",
        f"  start_acceleration = {settings.start_acceleration!r}  # [rad/s^2]",
        "  def sdar_gripper_close(object_name):",
        "    # Replace with your gripper's close command (non-blocking), e.g. rq_close().",
        '    textmsg("sdar: close the gripper on ", object_name)',
        "  end",
        "  def sdar_gripper_open(object_name):",
        "    # Replace with your gripper's open command (non-blocking), e.g. rq_open().",
        '    textmsg("sdar: open the gripper from ", object_name)',
        "  end",
        "  def sdar_wait_for_start():",
        "    # Replace with the signal that starts every arm at once, e.g.",
        "    # while not get_standard_digital_in(0): sync() end",
        "    sync()",
        "  end",
    ]


_NAME = re.compile(r"[A-Za-z0-9_.\-]+")


def _check_names(plan: PlanFile) -> None:
    """Arm, joint and object names are written into comments and strings: letters, digits,
    ``_``, ``.`` and ``-`` only."""
    names = [("arm", a.name) for a in plan.arms]
    names += [("joint", j) for a in plan.arms for j in a.joints]
    names += [("object", e.object) for e in plan.events]
    for what, name in names:
        if not _NAME.fullmatch(name):
            raise ParameterError(
                f"{what} name {name!r}: expected letters, digits, '_', '.' or '-' for URScript"
            )


def _gripper_call(kind: str, obj: str) -> str:
    function = "sdar_gripper_close" if kind == "grasp" else "sdar_gripper_open"
    return f'  {function}("{obj}")'


def _vector(q: FloatArray) -> str:
    return "[" + ", ".join(f"{float(x):.9f}" for x in np.asarray(q)) + "]"


def _matrix(T: FloatArray) -> list[str]:
    return ["#   [" + ", ".join(f"{round(float(x), 6) + 0.0: .6f}" for x in row) + "]" for row in T]


def _identifier(name: str) -> str:
    """``name`` made a URScript identifier (letters, digits, underscores)."""
    return "".join(c if c.isalnum() or c == "_" else "_" for c in name)
