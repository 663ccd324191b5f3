"""The plan file: one timed trajectory of a cell's arms with gripper events, as
self-describing JSON.

Layout (``version`` 2; every length in m, angle in rad, time in s)::

    {"format": "sdar-plan", "version": 2, "units": {"length": "m", "angle": "rad", "time": "s"},
     "instance": "M1",
     "arms": [{"name", "joints" (the arm's d URDF joint names), "T_world_base" (4x4, the URDF
               base_link), "T_tool0_tcp" (4x4), "home" (d)}, ...one or more arms, scene order],
     "trajectory": {"t": [n times from 0, spacing <= 0.02],
                    "q": [n rows of d1 + ... + dk joints: arm 1's, then arm 2's, ... arm k's]},
     "events": [{"t", "arm", "type": "grasp" | "release", "object", "T_tcp_object" (4x4)}],
                # events of several arms may share a time (simultaneous gripper actions);
                # after its gripper event an arm stands still GRIPPER_DWELL (0.5 s)
     "final_poses": {"o1": [x, y, yaw]},
     "metrics": {"actions", "steps", "dual_arm_steps", "execution_time", "planning_time", ...},
     "steps": [{"t_start", "t_end", "level", "objects", "kind"}],   # optional
     "observations": [{"t", "resting": {"o1": [x, y, yaw]}, "added": {"b1": [lx, ly, lz]}}]}
                # optional: at time t the observed arrangement replaces the planned one

``arms`` is a list of any length >= 1 (a cell of one to four arms, or more: nothing caps it),
with distinct names; ``dual_arm_steps`` counts the motions in which two arms or more move at
once (for a two-arm cell: both arms, its meaning in version 1). Version 1 is the same layout
with exactly two arms; :func:`~sdar_tamp.plan_reading.load_plan` reads both versions
(:data:`READ_VERSIONS`), :func:`~sdar_tamp.plan_writing.save_plan` writes :data:`VERSION`.

:func:`~sdar_tamp.plan_reading.load_plan` checks the shape of everything and raises
:class:`PlanFileError` naming the file, the line and column, and the key path
(``plan.json:40:7: trajectory.q[3]: expected 12 numbers, got 11``). Each arm has as many joints
as its ``joints`` list names (six for a UR5e, seven for a Panda); given a cell's arm layout the
reader also checks each arm's joint count against it. :func:`~sdar_tamp.plan_writing.save_plan`
writes a plan; :func:`~sdar_tamp.plan_building.build_plan_file` assembles one from motion
segments and gripper events. This module holds the values: :class:`PlanFile` and its parts
(the metrics are a :class:`~sdar_tamp.plan_metrics.PlanMetrics`). Values holding arrays compare
by identity (their arrays are read-only copies); compare
:func:`~sdar_tamp.plan_writing.plan_to_dict` outputs for equality.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from sdar_tamp.errors import SdarError
from sdar_tamp.plan_metrics import PlanMetrics
from sdar_tamp.world.layout import ArmLayout
from sdar_tamp.world.transforms import FloatArray

FORMAT = "sdar-plan"
VERSION = 2  #: the version :func:`~sdar_tamp.plan_writing.save_plan` writes
#: Versions the reader accepts, each with the arm counts it allows (``(n, n)``: exactly n;
#: ``(n, None)``: n or more): version 1 holds exactly two arms, version 2 any number >= 1.
READ_VERSIONS: Mapping[int, tuple[int, int | None]] = MappingProxyType({1: (2, 2), 2: (1, None)})
UNITS = {"length": "m", "angle": "rad", "time": "s"}
MAX_DT = 0.02  #: largest spacing of trajectory samples [s]
EVENT_TYPES = ("grasp", "release")
MAX_DEPTH = 64  #: deepest nesting of JSON lists and objects a plan file may have
#: After its gripper event an arm stands still this long [s] (the gripper closes or opens; a
#: parallel gripper takes about half a second). :func:`~sdar_tamp.plan_building.build_plan_file`
#: keeps every arm still.
GRIPPER_DWELL = 0.5


def plan_joint_names(arm: str, robot_joints: Sequence[str]) -> tuple[str, ...]:
    """The names in ``arms[].joints``: the arm's name, ``_``, the robot's (URDF) joint name."""
    return tuple(f"{arm}_{j}" for j in robot_joints)


class PlanFileError(SdarError):
    """A malformed plan file; ``file``, ``key`` (JSON key path) and ``detail`` are kept."""

    def __init__(self, file: str, key: str, detail: str) -> None:
        self.file, self.key, self.detail = file, key, detail
        super().__init__(f"{file}: {key}: {detail}" if key else f"{file}: {detail}")


def readonly(value: Any) -> FloatArray:
    """A read-only float64 copy of ``value``."""
    a = np.array(value, dtype=np.float64)
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class ArmInfo:
    """One arm: name, joint names, base and tool frames ``(4, 4)``, home ``(joints,)``
    [rad]."""

    name: str
    joints: tuple[str, ...]
    T_world_base: FloatArray
    T_tool0_tcp: FloatArray
    home: FloatArray

    def __post_init__(self) -> None:
        for key in ("T_world_base", "T_tool0_tcp", "home"):
            object.__setattr__(self, key, readonly(getattr(self, key)))


@dataclass(frozen=True, eq=False)
class PlanEvent:
    """A gripper closing (``grasp``) or opening (``release``) at time ``t`` [s].

    ``T_tcp_object`` ``(4, 4)``: the object's pose in the tool-centre-point frame."""

    t: float
    arm: str
    type: str
    object: str
    T_tcp_object: FloatArray

    def __post_init__(self) -> None:
        object.__setattr__(self, "T_tcp_object", readonly(self.T_tcp_object))


@dataclass(frozen=True)
class StepRecord:
    """One synchronous motion segment ``[t_start, t_end]`` [s] (information for viewers)."""

    t_start: float
    t_end: float
    level: str
    objects: tuple[str, ...]
    kind: str


@dataclass(frozen=True)
class PlanObservation:
    """The world seen at time ``t`` [s] (a re-planned plan): from then on the objects resting
    on the table are exactly ``resting`` (name -> ``(x, y, yaw)`` [m, m, rad]); what the arms
    hold stays held. ``added``: name -> side lengths [m] of objects the instance does not know.
    An instance object neither resting nor held is gone (its goal no longer applies)."""

    t: float
    resting: dict[str, tuple[float, float, float]]
    added: dict[str, tuple[float, float, float]]


@dataclass(frozen=True, eq=False)
class PlanFile:
    """A timed plan: samples ``q`` ``(n, layout.dof)`` [rad] at ``t`` ``(n,)`` [s] (the arms'
    joints in ``arms`` order), gripper events, final object poses ``name -> (x, y, yaw)``
    [m, m, rad] and metrics."""

    instance: str
    arms: tuple[ArmInfo, ...]
    t: FloatArray
    q: FloatArray
    events: tuple[PlanEvent, ...]
    final_poses: dict[str, tuple[float, float, float]]
    metrics: PlanMetrics
    steps: tuple[StepRecord, ...] = ()
    observations: tuple[PlanObservation, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "t", readonly(self.t))
        object.__setattr__(self, "q", readonly(self.q))

    @property
    def duration(self) -> float:
        """Time of the last sample [s]."""
        return float(self.t[-1])

    @property
    def arm_names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.arms)

    @property
    def layout(self) -> ArmLayout:
        """The arms' joints in ``q``, each arm as many as its home configuration has (raises
        :class:`ArmLayoutError` for repeated names)."""
        return ArmLayout(self.arm_names, tuple(len(a.home) for a in self.arms))
