"""The values the trajectory optimiser takes and returns: its options (one NLP per distinct
value), one transfer query and the optimised result."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.transforms import FloatArray
from streams.motion.sphere_pairs import HeldSpheres, arm_pairs


@dataclass(frozen=True)
class TrajOptOptions:
    """Shape and solver settings; one NLP is built per distinct value."""

    knots: int = 10
    held_slots: int = 4  # spheres per held object
    #: per pair of arms; None: from the two arms' coarse sphere models (``slots_per_sphere``)
    arm_arm_slots: int | None = None
    #: arm-arm slots per coarse sphere, of the geometric mean of the pair's two counts
    #: (rounded down): 24 for two UR5e arms (25 coarse spheres each), 33 for two Pandas (35)
    slots_per_sphere: float = 0.96
    obstacle_slots: int = 12  # per arm
    table_slots: int = 6  # per arm
    margin: float = 0.015  # [m] clearance asked of the spheres
    select_distance: float = 0.10  # [m] pairs closer than this along the path get a slot
    w_length: float = 0.05
    max_iter: int = 25
    tol: float = 1e-3
    active_set_rounds: int = 2
    compiled: bool = True  # derivatives compiled where a C compiler is (streams.motion.codegen)

    def __post_init__(self) -> None:
        if self.arm_arm_slots is not None and self.arm_arm_slots < 1:
            raise ParameterError(f"arm_arm_slots must be at least 1, got {self.arm_arm_slots}")
        if not (math.isfinite(self.slots_per_sphere) and self.slots_per_sphere > 0.0):
            raise ParameterError(
                f"slots_per_sphere must be a finite number > 0, got {self.slots_per_sphere}"
            )

    def pair_slots(self, coarse: tuple[int, ...]) -> tuple[int, ...]:
        """Arm-arm slots of every pair of arms (:func:`~streams.motion.sphere_pairs.arm_pairs`
        order) whose arms have ``coarse`` coarse spheres each (scene order): ``arm_arm_slots``
        when set, else ``slots_per_sphere`` times the geometric mean of the pair's counts,
        rounded down, at least one. The slots cover the pairs that may come close; an arm
        cut into more spheres has more close pairs where two links meet."""
        if self.arm_arm_slots is not None:
            return tuple(self.arm_arm_slots for _ in arm_pairs(len(coarse)))
        return tuple(
            max(1, int(self.slots_per_sphere * math.sqrt(coarse[i] * coarse[j]) + 1e-9))
            for i, j in arm_pairs(len(coarse))
        )


@dataclass(frozen=True)
class TransferQuery:
    """One transfer: end configurations ``(dof,)`` [rad], held spheres per arm (scene order),
    obstacle spheres ``(m, 3)``, ``(m,)`` [m] and the nominal duration ``T`` [s]."""

    q_start: FloatArray
    q_goal: FloatArray
    held: tuple[HeldSpheres, ...]
    obstacles: tuple[FloatArray, FloatArray]
    duration: float
    fixed: tuple[bool, ...] = ()  # per arm (scene order): it must wait at its start


@dataclass(frozen=True)
class TrajOptResult:
    """The optimised knots ``(K, dof)``; ``success`` means IPOPT converged (or stopped at a
    feasible point) and every sphere pair keeps its clearance on a dense check of the path."""

    path: FloatArray
    success: bool
    status: str
    iterations: int
    solve_time: float  # [s] wall time of the whole call
    rounds: int = 1
    min_clearance: float = field(default=float("nan"))  # [m] over all sphere pairs
