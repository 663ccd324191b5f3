"""The values the trajectory optimiser takes and returns: its options (one NLP per distinct
value), one transfer query and the optimised result."""

from __future__ import annotations

from dataclasses import dataclass, field

from sdar_tamp.world.transforms import FloatArray
from streams.motion.sphere_pairs import HeldSpheres


@dataclass(frozen=True)
class TrajOptOptions:
    """Shape and solver settings; one NLP is built per distinct value."""

    knots: int = 10
    held_slots: int = 4  # spheres per held object
    arm_arm_slots: int = 24  # per pair of arms
    obstacle_slots: int = 12  # per arm
    table_slots: int = 6  # per arm
    margin: float = 0.015  # [m] clearance asked of the spheres
    select_distance: float = 0.10  # [m] pairs closer than this along the path get a slot
    w_length: float = 0.05
    max_iter: int = 25
    tol: float = 1e-3
    active_set_rounds: int = 2
    compiled: bool = True  # derivatives compiled where a C compiler is (streams.motion.codegen)


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
