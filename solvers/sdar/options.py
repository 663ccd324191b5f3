"""SDAR-M's budgets and switches (:class:`SdarOptions`), apart so that every part of the solver
can read them without importing the decision loop."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from sdar_tamp.errors import ParameterError
from solvers.sdar.vocabulary import SdarVocabulary


@dataclass(frozen=True)
class Plane:
    """Where poses lie on the table, for SDAR-T's steps of more than two moves (the
    :class:`~solvers.sdar.tasks.Layout` of each view): ``locate`` gives the ``(x, y)`` [m] of a
    pose value (None: a value it does not know), ``bases`` arm -> base ``(x, y)`` [m],
    ``clearance`` [m] the distance under which two objects count as neighbours. Built by the
    app from the scene; the solvers see only these numbers."""

    locate: Callable[[object], tuple[float, float] | None]
    bases: Mapping[str, tuple[float, float]]
    clearance: float = 0.08


@dataclass(frozen=True)
class SdarOptions:
    """Budgets of SDAR-M (see the module docstring)."""

    max_time: float = math.inf  # [s]
    candidates: int = 8  # candidate steps grounded per decision (more if none works)
    choose_among: int = 3  # feasible groundings compared by estimated motion time
    peer_steps: int = 4  # more candidates alike to the task planner (Step.tie) compared so
    grasps: int = 6  # grasps tried per object
    options_per_move: int = 2  # (grasp, pick IK, place IK) options kept per arm and move
    more_options: int = 6  # kept instead when every pair of the first ones makes the arms collide
    pair_grasps: int = 28  # grasps searched per object of a pair_kinds step when no pair of
    # the first options works (a swap of touching objects needs two compatible grasps, often
    # two moderately tilted ones: the grasp stream's pair grasps come after its grasp set)
    pair_kinds: tuple[str, ...] = ("swap",)
    expand_kinds: tuple[str, ...] = ("pair", "swap", "chain", "cycle", "rotate")  # steps of
    # several moves
    assignments: int = 6  # with more than two arms: assignments of arms to a step's moves
    # grounded (the soonest by estimate, among the arms that reach; every one with two arms)
    buffers: int = 4  # buffer poses tried per buffer move
    place_branches: int = 4  # IK solutions at a target compared by the time from the pick
    one_arm_at_a_time: bool = False  # the baseline motion planner (one arm moves at a time)
    quick_attempts: int = 6  # best-ranked groundings tried with the quick motion stream first
    progress: Callable[[int, int], None] | None = None  # (objects at goal, objects) per step
    plane: Plane | None = None  # with more than two arms: where objects are (see Plane)
    fewer_moves_after: tuple[int, int] = (2, 6)  # with more than two arms: failed motions
    # in a decision after which it tries steps of at most two moves (of steps of three moves
    # or more), then of one move (in all); see solvers.sdar.spending
    finish_reserve: float = 2.5  # [s] per remaining object before any decision is measured,
    # and at most: with a finite max_time, once the time left is what the remaining objects
    # need at the run's measured pace (solvers.sdar.budget.Pace) the run finishes with steps of
    # at most finish_moves moves (0: never); the reserve is at most finish_share of max_time
    finish_safety: float = 1.5  # the measured seconds per object are multiplied by this
    finish_moves: int = 1
    finish_gap: float = 0.2  # [m] with more than two arms: the finish also proposes a step of
    # one-object moves with arms whose plane segments stay this far apart (0: never); see
    # solvers.sdar.spending.spread_steps
    finish_share: float = 0.9
    finish_min_time: float = 20.0  # [s] runs of a shorter max_time never finish early (a short
    # budget is a latency budget, e.g. a repair's: its caller falls back itself)
    clock: Callable[[], float] = time.perf_counter  # [s] the budget's clock (tests: a fake one)
    home: object = None  # the cell configuration (a value of the problem) idle arms wait at;
    # None: the initial one (a plan re-planned from arms away from home gives the home)
    vocabulary: SdarVocabulary = field(default_factory=SdarVocabulary)

    def __post_init__(self) -> None:
        few = self.fewer_moves_after
        if len(few) != 2 or not 1 <= few[0] <= few[1]:
            raise ParameterError(
                f"fewer_moves_after must be two counts 1 <= a <= b, got {self.fewer_moves_after}"
            )
        if self.finish_moves < 1:
            raise ParameterError(f"finish_moves must be >= 1, got {self.finish_moves}")
        if not 0 <= self.finish_share <= 1:
            raise ParameterError(f"finish_share must be in [0, 1], got {self.finish_share}")
        if not self.finish_min_time >= 0:
            raise ParameterError(f"finish_min_time must be >= 0 [s], got {self.finish_min_time}")
        if not self.finish_gap >= 0:
            raise ParameterError(f"finish_gap must be >= 0 [m], got {self.finish_gap}")
        if not self.finish_safety >= 1:
            raise ParameterError(f"finish_safety must be >= 1, got {self.finish_safety}")
        if not self.finish_reserve >= 0:
            raise ParameterError(f"finish_reserve must be >= 0 [s], got {self.finish_reserve}")
