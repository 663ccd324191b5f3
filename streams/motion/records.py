"""The values of one synchronous motion: the request, the transfer problem the strategies
solve, the per-call counters, and the result."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.transforms import FloatArray
from streams.motion.exact_check import HeldObject, ValidationReport
from streams.motion.sphere_pairs import HeldSpheres
from streams.motion.timing import TimedTrajectory


@dataclass(frozen=True)
class MotionRequest:
    """One synchronous segment. Arms are in the scene's order (its layout); ``retreat`` and
    ``approach`` say per arm whether it leaves or reaches a grasp (missing entries: no)."""

    q_start: FloatArray  # (dof,) [rad]
    q_goal: FloatArray  # (dof,) [rad]
    objects: Mapping[str, ObjectBox]  # resting objects
    held: Mapping[str, HeldObject] = field(default_factory=dict)  # arm -> held object
    retreat: tuple[bool, ...] = ()
    approach: tuple[bool, ...] = ()
    lift: float | None = None  # [m] fixed for every grasp; None: per grasp from clearance


@dataclass(frozen=True)
class MotionResult:
    """``level`` is the strategy that produced the motion (None on failure)."""

    success: bool
    level: str | None
    trajectory: TimedTrajectory | None
    optimisation_time: float  # [s] spent in the trajectory optimiser, all attempts
    planning_time: float  # [s] wall time of the whole call
    attempts: tuple[str, ...]  # "level: outcome" for every strategy tried
    validation: ValidationReport | None = None
    reason: str = ""
    blended: bool = False  # retreat, transfer and approach timed as one blended path
    ipopt_solves: int = 0  # optimiser calls that ran IPOPT (a feasible straight line needs none)
    direct_paths: int = 0  # transfers (or stages) taken straight or lightly bent, not optimised
    sampled_paths: int = 0  # transfers found by the sampling-based planner (OMPL)


@dataclass(frozen=True)
class TransferProblem:
    """The transfer between the lifted configurations, with everything a strategy needs."""

    q_from: FloatArray  # (dof,)
    q_to: FloatArray  # (dof,)
    held: tuple[HeldSpheres, ...]  # per arm
    obstacles: tuple[FloatArray, FloatArray]


@dataclass
class MotionTally:
    """What one :func:`streams.motion.ladder.plan_dual_motion` call spent, counted as it goes
    (each call has its own; strategies add to it through
    :class:`streams.motion.transfers.Transfers`)."""

    optimisation_time: float = 0.0  # [s] spent in the trajectory optimiser, all attempts
    ipopt_solves: int = 0  # optimiser calls that ran IPOPT
    direct_paths: int = 0  # transfers (or stages) taken straight or lightly bent
    sampled_paths: int = 0  # transfers found by the sampling-based planner (OMPL)


def flag(flags: tuple[bool, ...], i: int) -> bool:
    """Entry ``i`` of a per-arm flag tuple (missing entries are False)."""
    return i < len(flags) and flags[i]
