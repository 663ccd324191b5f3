"""SDAR-M synchronous motion of k arms with fallbacks (the paper's Alg. 2): the ladder.

A synchronous segment takes the arms (one to any number, placed anywhere around the table)
from ``q_start`` to ``q_goal`` (``(dof,)`` [rad]) with the held objects fixed for the whole
segment (gripper actions happen between segments):

1. retreat: arms flagged ``retreat`` first move their tool straight back along the tool axis
   (IK interpolation), every such arm at once, by a lift [m] chosen per grasp from the clearance
   of its neighbours (:func:`streams.motion.shape.clearance_lift`; or the request's fixed
   ``lift``), see :mod:`streams.motion.phases`;
2. transfer: between the two lifted (pre-grasp) configurations, produced by a *strategy*
   (:mod:`streams.motion.strategies`);
3. approach: arms flagged ``approach`` move straight down the tool axis to the goal.

The motion is first shaped as one blended path (:mod:`streams.motion.assembly`,
:mod:`streams.motion.shape`): only the first and last ``straight`` centimetres stay
straight, the corners at the lifted configurations are rounded into the transfer, and the
path is timed as one, without stopping at the pre-grasp points. If that path leaves the
straight tool axis or fails the exact check, the unblended motion is used: every phase and
stage timed rest to rest (:mod:`streams.motion.timing`). Either way the whole trajectory is
checked exactly with coal (:mod:`streams.motion.exact_check`), and only a trajectory that
passes is returned as a success. Strategies are tried in order until one passes: ``plain``,
``untangle``, ``sequential``.

``plan_dual_motion(..., fallbacks=False)`` is the paper's "plain" planner (no fallbacks);
``sequential_only=True`` is the baseline motion planner
(:class:`~streams.motion.strategies.OneArmStrategy`: the arms move one after the other;
SDAR-M then also keeps the idle arms at home, so that one arm works while the others wait at
their retract poses).

The name says "dual" for history: a request of k arms (``q_start``/``q_goal`` over the scene's
:class:`~sdar_tamp.world.layout.ArmLayout`, ``held`` per arm, ``retreat``/``approach`` per-arm
tuples) is planned the same way, the optimiser keeping every pair of arms apart.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from sdar_tamp.world.transforms import FloatArray
from streams.motion.exact_check import ValidationReport, validate_trajectory
from streams.motion.planner import MotionPlanner
from streams.motion.records import MotionRequest, MotionResult, MotionTally
from streams.motion.strategies import (
    OneArmStrategy,
    PlainStrategy,
    SequentialStrategy,
    TransferStrategy,
    UntangleStrategy,
)
from streams.motion.timing import TimedTrajectory


def default_strategies(
    fallbacks: bool = True, sequential_only: bool = False
) -> tuple[TransferStrategy, ...]:
    """The ladder of Alg. 2: plain, untangle, sequential (or a part of it).
    ``sequential_only``: the baseline motion planner (:class:`OneArmStrategy`). The ladder
    with a sampled first rung is :func:`streams.motion.sampling.sampled_strategies`."""
    if sequential_only:
        return (OneArmStrategy(),)
    if not fallbacks:
        return (PlainStrategy(),)
    return (PlainStrategy(), UntangleStrategy(), SequentialStrategy())


def _clear_phases(
    planner: MotionPlanner, request: MotionRequest, one_at_a_time: bool
) -> tuple[list[FloatArray], list[FloatArray]] | str:
    """Retreat and approach that are collision-free on their own (every strategy shares
    them): synchronised, else one arm after the other, else with the retreat one arm after
    the other in the reverse order (the mirror of an approach made one arm at a time, which
    may be how the arms came down where they are); or why there are none."""
    reason = "approach or retreat unreachable"
    lifts = (None,) if request.lift is not None else (None, planner.shape.default_lift)
    orders = [(one_at_a_time, False), (True, False)]
    if sum(map(bool, request.retreat)) > 1:
        orders.append((True, True))
    for lift in lifts:  # the clearance lifts, then the fixed default
        for chained, last_first in dict.fromkeys(orders):
            phases = planner.phases(
                request, one_at_a_time=chained, lift=lift, last_first=last_first
            )
            if phases is None:
                break
            for label, paths in zip(("retreat", "approach"), phases, strict=True):
                report = validate_trajectory(
                    planner.ctx, planner.world, np.concatenate(paths), near=planner.near_world
                )
                if not report.ok:
                    reason = f"{label} collides ({report.reason})"
                    break
            else:
                return phases
    return reason


def plan_dual_motion(
    planner: MotionPlanner,
    request: MotionRequest,
    fallbacks: bool = True,
    sequential_only: bool = False,
    strategies: Sequence[TransferStrategy] | None = None,
) -> MotionResult:
    """Plan one synchronous segment; see the module docstring."""
    t0 = time.perf_counter()
    tally = MotionTally()
    ladder = tuple(strategies) if strategies is not None else default_strategies(
        fallbacks, sequential_only)  # fmt: skip
    ctx = planner.ctx
    planner.configure(request)
    phases = _clear_phases(planner, request, sequential_only and strategies is None)
    if isinstance(phases, str):
        return MotionResult(False, None, None, 0.0, time.perf_counter() - t0, (),
                            reason=phases)  # fmt: skip
    retreat, approach = phases
    problem = planner.transfer_problem(request, retreat[-1][-1], approach[0][0])
    transfers = planner.transfers(tally)
    assembly = planner.assembly
    attempts: list[str] = []
    report: ValidationReport | None = None

    def succeeded(
        level: str, traj: TimedTrajectory, valid: ValidationReport, blended: bool
    ) -> MotionResult:
        return MotionResult(True, level, traj, tally.optimisation_time,
                            time.perf_counter() - t0, tuple(attempts), valid,
                            ipopt_solves=tally.ipopt_solves, direct_paths=tally.direct_paths,
                            sampled_paths=tally.sampled_paths, blended=blended)  # fmt: skip

    for strategy in ladder:
        stages = strategy(transfers, problem)
        if stages is None:
            attempts.append(f"{strategy.name}: optimisation failed")
            continue
        blended = assembly.blend(request, retreat, stages, approach)
        if blended is not None:
            report = validate_trajectory(
                ctx, planner.world, blended.q, blended.t, near=planner.near_world
            )
            if report.ok:
                attempts.append(f"{strategy.name}: ok (blended)")
                return succeeded(strategy.name, blended, report, blended=True)
        traj = assembly.assemble(retreat, stages, approach)
        report = validate_trajectory(ctx, planner.world, traj.q, traj.t, near=planner.near_world)
        if report.ok:
            attempts.append(f"{strategy.name}: ok")
            return succeeded(strategy.name, traj, report, blended=False)
        attempts.append(
            f"{strategy.name}: validation failed ({report.reason} at sample {report.index}"
            + "".join(f", {p.first}-{p.second}" for p in report.pairs[:2])
            + ")"
        )
    return MotionResult(False, None, None, tally.optimisation_time, time.perf_counter() - t0,
                        tuple(attempts), report, reason="; ".join(attempts),
                        ipopt_solves=tally.ipopt_solves,
                        direct_paths=tally.direct_paths,
                        sampled_paths=tally.sampled_paths)  # fmt: skip
