"""Which planner configuration applies: one typed :class:`PlannerConfig` for every option.

The command line, :func:`sdar_tamp.app.solving.solve_rearrangement`,
:func:`sdar_tamp.app.pipeline.solve_instance` and ``solve(problem, algorithm="sdar",
sdar_options=config.sdar_options())`` all read it, so every entry point plans alike:

- ``task_planner`` (SDAR-T or the baseline), ``motion_planner`` (the stream behind
  ``plan-dual-motion``), ``max_time`` [s], ``seed``, ``gripper_time`` [s];
- ``execution``: ``sync`` (one synchronous timeline, as planned) or ``async`` (each arm on
  its own timeline, :mod:`sdar_tamp.schedule`; the synchronous plan is kept when the
  schedule is not shorter);
- ``grasps``: the grasp set (:class:`streams.grasps.GraspOptions`);
- ``sdar``: SDAR-M's budgets (:class:`solvers.sdar.options.SdarOptions`: candidates, grasps
  tried per object, buffers, ...). The fields that follow from the motion planner
  (``one_arm_at_a_time``, and ``quick_attempts`` which only the ``sdar`` motion planner uses)
  and the run's ``max_time`` and ``progress`` are set by :meth:`PlannerConfig.sdar_options`;
- ``trajopt``: the trajectory optimiser's shape and solver settings
  (:class:`streams.motion.optimiser_records.TrajOptOptions`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from sdar_tamp.arguments import MAX_TIME, SEED, Real
from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import GRIPPER_DWELL
from solvers.sdar.options import SdarOptions
from streams.grasps import DEFAULT_GRASPS, GraspOptions
from streams.motion.optimiser_records import TrajOptOptions

TASK_PLANNERS = ("sdar", "baseline")
MOTION_PLANNERS = ("sdar", "plain", "sequential")
#: How the plan is executed: one synchronous timeline, or each arm on its own
#: (:mod:`sdar_tamp.schedule`, kept only when shorter and valid): ``async`` re-times the
#: synchronous steps, ``timelines`` gives each arm its own timeline (prioritised planning in
#: time) and keeps the shorter of the two; ``assigned`` assigns the plan's moves anew to
#: whichever arm is free, with motions planned for it, and keeps the shortest of the three.
EXECUTIONS = ("sync", "async", "timelines", "assigned")
GRIPPER_TIME = GRIPPER_DWELL  # [s] one gripper action (both grippers at once take as long)
_DURATION = Real(0.0, closed=True, unit="s")  # gripper_time


def check_choice(name: str, value: str, choices: tuple[str, ...]) -> str:
    """``value`` if it is one of ``choices``, else a :class:`ParameterError` naming ``name``."""
    if value not in choices:
        raise ParameterError(f"{name} must be one of {', '.join(choices)}; got {value!r}")
    return value


@dataclass(frozen=True)
class PlannerConfig:
    """Every option of a rearrangement solve (see the module docstring).

    Raises:
        ParameterError: a value out of range or an unknown planner name; or ``sdar`` sets a
            field that the configuration owns (``max_time``, ``progress``,
            ``one_arm_at_a_time``): the message says which field to set instead.
    """

    task_planner: str = "sdar"
    motion_planner: str = "sdar"
    max_time: float = 60.0  # [s] planning budget; inf: none
    seed: int = 0
    execution: str = "sync"
    gripper_time: float = GRIPPER_TIME  # [s]
    grasps: GraspOptions = DEFAULT_GRASPS
    sdar: SdarOptions = field(default_factory=SdarOptions)
    trajopt: TrajOptOptions = field(default_factory=TrajOptOptions)

    def __post_init__(self) -> None:
        check_choice("task_planner", self.task_planner, TASK_PLANNERS)
        check_choice("motion_planner", self.motion_planner, MOTION_PLANNERS)
        check_choice("execution", self.execution, EXECUTIONS)
        MAX_TIME.check("max_time", self.max_time)
        SEED.check("seed", self.seed)
        _DURATION.check("gripper_time", self.gripper_time)
        for name, typ in (
            ("grasps", GraspOptions),
            ("sdar", SdarOptions),
            ("trajopt", TrajOptOptions),
        ):
            value = getattr(self, name)
            if not isinstance(value, typ):
                raise ParameterError(f"{name} must be a {typ.__name__}, got {type(value).__name__}")
        owned = {
            "max_time": (self.sdar.max_time != math.inf, "PlannerConfig.max_time"),
            "progress": (self.sdar.progress is not None, "the progress argument of the solve"),
            "one_arm_at_a_time": (
                self.sdar.one_arm_at_a_time,
                "motion_planner='sequential'",
            ),
        }
        for name, (is_set, instead) in owned.items():
            if is_set:
                raise ParameterError(f"sdar.{name} is set by the configuration; use {instead}")

    def replace(self, **changes: Any) -> PlannerConfig:
        """A copy with ``changes``; entries whose value is None are left out."""
        return dataclasses.replace(self, **{k: v for k, v in changes.items() if v is not None})

    def sdar_options(self, progress: Callable[[int, int], None] | None = None) -> SdarOptions:
        """SDAR-M's options for this configuration: ``sdar`` with the run's ``max_time`` and
        ``progress(done, total)``; one arm at a time for the ``sequential`` motion planner
        (the baseline's), and the quick motion stream tried first only under the ``sdar``
        motion planner (it differs from the full one only there)."""
        return dataclasses.replace(
            self.sdar,
            max_time=self.max_time,
            progress=progress,
            one_arm_at_a_time=self.motion_planner == "sequential",
            quick_attempts=self.sdar.quick_attempts if self.motion_planner == "sdar" else 0,
        )
