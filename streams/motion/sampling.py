"""Sampling-based synchronous transfers of k arms: OMPL's RRTConnect in their joint space.

An optional extra (``pip install sdar-tamp[ompl]``). The planner samples every arm's joints
within their limits; a state is valid when the planner's ``margin_world`` (resting and held
objects grown by the direct-path margin, see :class:`streams.motion.planner.MotionPlanner`)
reports no collision, and OMPL checks edges every ``resolution`` [rad] of joint-space
length. The path found is shortcut by OMPL's simplifier, then the curve that
:func:`streams.motion.timing.time_parameterize` follows through its waypoints is checked exactly
(5 mm of TCP travel) in the same world; if the spline bulges into an obstacle, the path is
densified once and checked again. The motion is then assembled, timed and validated like
any other strategy's (:func:`streams.motion.ladder.plan_dual_motion`).

Work is bounded by counts, not seconds (``max_checks`` state checks for planning,
``simplify_checks`` for shortcutting), and every query restarts OMPL's process-wide seed
sequence from a seed made of ``seed`` and the query's end configurations: a query gives the
same path whatever the process planned before it (a benchmark worker that solves several
instances in turn, in any order). OMPL's console output is lowered to warnings during each
query (silenced while the seed is set) and restored.

:class:`SampledStrategy` is a :class:`streams.motion.strategies.TransferStrategy`; with
``refine=True`` the trajectory optimiser is warm-started from the sampled path and its
result kept when it executes faster.
"""

from __future__ import annotations

import functools
import importlib.util
import threading
import zlib
from dataclasses import dataclass
from typing import Any

import numpy as np

from sdar_tamp.errors import ParameterError, SdarError
from sdar_tamp.world.transforms import FloatArray
from streams.motion.exact_check import validate_trajectory
from streams.motion.records import TransferProblem
from streams.motion.strategies import (
    PlainStrategy,
    SequentialStrategy,
    TransferStrategy,
    UntangleStrategy,
)
from streams.motion.timing import spline_curve, time_parameterize
from streams.motion.transfers import Transfers
from streams.motion.waypoints import densify


class OmplUnavailableError(SdarError):
    """The ``ompl`` package is not installed (``pip install sdar-tamp[ompl]``)."""


def ompl_available() -> bool:
    """True when the ``ompl`` Python package can be imported."""
    return importlib.util.find_spec("ompl") is not None


@dataclass(frozen=True)
class SamplingOptions:
    """Budgets and resolution of one sampled transfer."""

    max_checks: int = 20_000  # state validity checks while planning
    simplify_checks: int = 4_000  # state validity checks while shortcutting
    resolution: float = 0.02  # [rad] joint-space length between edge checks
    range: float = 0.0  # [rad] RRTConnect's step (0: OMPL's default, a fifth of the extent)
    curve_samples: int = 24  # samples of the timed curve handed to the exact check
    seed: int = 0  # mixed with each query's end configurations into OMPL's seed

    def __post_init__(self) -> None:
        for name in ("max_checks", "simplify_checks", "curve_samples"):
            if getattr(self, name) < 1:
                raise ParameterError(f"{name} must be >= 1, got {getattr(self, name)}")
        if not self.resolution > 0.0:
            raise ParameterError(f"resolution must be > 0 [rad], got {self.resolution}")
        if self.seed < 0:
            raise ParameterError(f"seed must be >= 0, got {self.seed}")
        if self.range < 0.0:
            raise ParameterError(f"range must be >= 0 [rad], got {self.range}")


_SEED_LOCK = threading.Lock()  # OMPL's seed sequence is process-wide


def query_seed(seed: int, q_a: FloatArray, q_b: FloatArray) -> int:
    """OMPL's seed for one query: ``seed`` mixed with the end configurations (rounded to
    1e-9 rad), in [1, 2**31 - 1] (OMPL refuses 0)."""
    ends = np.round(np.concatenate([np.ravel(q_a), np.ravel(q_b)]), 9) + 0.0  # no -0.0
    return zlib.crc32(ends.astype("<f8").tobytes(), seed & 0xFFFFFFFF) % (2**31 - 1) + 1


def _ompl() -> tuple[Any, Any, Any]:
    if not ompl_available():
        raise OmplUnavailableError(
            "the sampling-based motion planner needs OMPL: pip install 'sdar-tamp[ompl]'"
        )
    from ompl import base, geometric, util

    return base, geometric, util


def sample_path(
    transfers: Transfers,
    q_a: FloatArray,
    q_b: FloatArray,
    options: SamplingOptions | None = None,
) -> FloatArray | None:
    """Collision-free waypoints ``(k, dof)`` from ``q_a`` to ``q_b`` (``transfers.margin_world``
    configured for the segment), shortcut; None when the budget runs out."""
    o = options or SamplingOptions()
    ob, og, ou = _ompl()
    ctx, world = transfers.ctx, transfers.margin_world
    lo, hi = ctx.scene.joint_array("lower"), ctx.scene.joint_array("upper")
    q_a, q_b = np.asarray(q_a, dtype=np.float64), np.asarray(q_b, dtype=np.float64)
    # arms that do not move are pinned: zero-width bounds keep them at their start
    still = [bool(np.allclose(q_a[sl], q_b[sl])) for sl in ctx.layout.slices]
    lo, hi = np.minimum(lo, np.minimum(q_a, q_b)), np.maximum(hi, np.maximum(q_a, q_b))
    for sl, pinned in zip(ctx.layout.slices, still, strict=True):
        if pinned:
            lo[sl] = hi[sl] = q_a[sl]
    free = np.flatnonzero(hi > lo)
    if len(free) == 0:
        return np.stack([q_a, q_b])
    level = ou.getLogLevel()
    with _SEED_LOCK:
        try:
            # setting the seed again restarts the sequence (OMPL logs an error that it is
            # no longer the first seed: expected here, so silenced)
            ou.setLogLevel(ou.LOG_NONE)
            ou.RNG.setSeed(query_seed(o.seed, q_a, q_b))
            ou.setLogLevel(ou.LOG_WARN)
            return _plan(ob, og, world, q_a, q_b, lo, hi, free, o)
        finally:
            ou.setLogLevel(level)


def _plan(
    ob: Any,
    og: Any,
    world: Any,
    q_a: FloatArray,
    q_b: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    free: Any,
    o: SamplingOptions,
) -> FloatArray | None:
    n = len(free)
    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    for k, j in enumerate(free):
        bounds.setLow(k, float(lo[j]))
        bounds.setHigh(k, float(hi[j]))
    space.setBounds(bounds)
    setup = og.SimpleSetup(space)
    q = q_a.copy()
    checks = [0]

    def full(state: Any) -> FloatArray:
        out = q.copy()
        out[free] = [state[k] for k in range(n)]
        return out

    def valid(state: Any) -> bool:
        checks[0] += 1
        x = full(state)
        return not world.in_collision(x)

    if not valid(_state(space, q_a, free)) or not valid(_state(space, q_b, free)):
        return None  # RRTConnect would wait for a valid start or goal
    setup.setStateValidityChecker(valid)
    info = setup.getSpaceInformation()
    info.setStateValidityCheckingResolution(o.resolution / space.getMaximumExtent())
    setup.setStartAndGoalStates(_state(space, q_a, free), _state(space, q_b, free))
    rrt = og.RRTConnect(info)
    if o.range > 0.0:
        rrt.setRange(o.range)
    setup.setPlanner(rrt)
    polls = [0]  # the condition also counts its own polls: planning ends even without checks

    def spent(limit: int) -> bool:
        polls[0] += 1
        return checks[0] >= limit or polls[0] >= 10 * limit

    budget = ob.PlannerTerminationCondition(lambda: spent(o.max_checks))
    solved = setup.solve(budget)
    if not setup.haveExactSolutionPath() or not bool(solved):
        return None
    path = setup.getSolutionPath()
    limit = checks[0] + o.simplify_checks
    polls[0] = 0
    simplifier = og.PathSimplifier(info)
    simplifier.simplify(path, ob.PlannerTerminationCondition(lambda: spent(limit)))
    W = np.stack([full(path.getState(k)) for k in range(path.getStateCount())])
    W[0], W[-1] = q_a, q_b
    return W


def _state(space: Any, q: FloatArray, free: Any) -> Any:
    state = space.allocState()
    for k, j in enumerate(free):
        state[k] = float(q[j])
    return state


def checked_waypoints(transfers: Transfers, W: FloatArray, samples: int) -> FloatArray | None:
    """``W`` (or ``W`` densified) whose timed curve passes the exact check in
    ``transfers.margin_world``; None if neither does."""
    for waypoints in (W, densify(W, 4)):
        curve = spline_curve(waypoints, max(samples, 2 * len(waypoints)))
        if validate_trajectory(transfers.ctx, transfers.margin_world, curve).ok:
            return waypoints
    return None


@dataclass(frozen=True)
class SampledStrategy:
    """One transfer sampled by RRTConnect and shortcut (see the module docstring); with
    ``refine``, the optimiser warm-started from it, kept when it executes faster."""

    name: str = "sampled"
    options: SamplingOptions = SamplingOptions()
    refine: bool = False

    def __call__(self, transfers: Transfers, problem: TransferProblem) -> list[FloatArray] | None:
        if self.refine and transfers.direct:
            direct = transfers.direct_path(problem.q_from, problem.q_to)
            if direct is not None:
                transfers.tally.direct_paths += 1
                return [transfers.refine_direct(problem, direct)]
        W = _checked_sample(transfers, problem, self.options)
        if W is None:
            return None
        if self.refine:
            refined = _optimised_along(transfers, problem, W, self.options)
            if refined is not None and _duration(transfers, refined) < _duration(transfers, W):
                return [refined]
        return [W]


def sampled_warm_start(
    transfers: Transfers, problem: TransferProblem, options: SamplingOptions | None = None
) -> FloatArray | None:
    """The optimiser's transfer warm-started from a sampled path (:func:`sample_path`, its
    timed curve checked), kept only when the optimiser succeeds and the optimised path's
    timed curve passes the same check; None otherwise. The first rung of SDAR-M's ladder
    (:class:`streams.motion.strategies.PlainStrategy`) tries it after the straight line."""
    o = options or SamplingOptions()
    W = _checked_sample(transfers, problem, o)
    return None if W is None else _optimised_along(transfers, problem, W, o)


def _checked_sample(
    transfers: Transfers, problem: TransferProblem, o: SamplingOptions
) -> FloatArray | None:
    """A sampled path for ``problem`` (counted in ``transfers.tally.sampled_paths``) whose
    timed curve passes the exact check (:func:`checked_waypoints`), or None."""
    W = sample_path(transfers, problem.q_from, problem.q_to, o)
    transfers.tally.sampled_paths += int(W is not None)
    return None if W is None else checked_waypoints(transfers, W, o.curve_samples)


def _optimised_along(
    transfers: Transfers, problem: TransferProblem, W: FloatArray, o: SamplingOptions
) -> FloatArray | None:
    """The optimiser's path warm-started along ``W``, if it succeeds and its timed curve
    passes the same check; else None."""
    path = transfers.optimise(problem, problem.q_from, problem.q_to, transfers.warm_start_along(W))
    if path is None or checked_waypoints(transfers, path, o.curve_samples) is None:
        return None
    return path


def warm_started_strategies(
    fallbacks: bool = True, options: SamplingOptions | None = None
) -> tuple[TransferStrategy, ...]:
    """SDAR-M's ladder (:func:`streams.motion.ladder.default_strategies`) whose first rung tries a
    sampled path's warm start (:func:`sampled_warm_start` with ``options``) after the
    straight line's and before the lifted via-point's; the first rung alone unless
    ``fallbacks``."""
    plain = PlainStrategy(rescue=functools.partial(sampled_warm_start, options=options))
    return (plain,) if not fallbacks else (plain, UntangleStrategy(), SequentialStrategy())


def _duration(transfers: Transfers, path: FloatArray) -> float:
    v, a = transfers.limits
    return time_parameterize(path, v, a).duration


def sampled_strategies(fallbacks: bool = True) -> tuple[TransferStrategy, ...]:
    """The ladder of Alg. 2 with a sampled first rung (needs OMPL): when the straight or
    lightly bent path is not clear, a sampled path (RRTConnect, shortcut) warm-starts the
    optimiser instead of the straight line (the sampled path itself is kept when the optimiser
    does not shorten it), then untangling and one arm at a time (``fallbacks``)."""
    sampled = SampledStrategy(name="plain", refine=True)
    return (sampled,) if not fallbacks else (sampled, UntangleStrategy(), SequentialStrategy())
