"""What the assignment tests share (:mod:`tests.plan.test_assignment`,
:mod:`tests.plan.test_assignment_policies`): the planner :class:`StraightMoves` (the streams'
grasps and inverse kinematics, :class:`~sdar_tamp.app.move_planning.StreamMovePlanner`, with
straight joint-space segments through the pre-grasps and the arm's home in place of the motion
planner: fast, clear of the resting objects; the sweep still checks them), the solved paper
plans and a search set up on one of them."""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from sdar_tamp.app.execution import execution_options
from sdar_tamp.app.move_planning import StreamMovePlanner
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.schedule.assignment import FINGER_ROOM, Assignment, AssignmentOptions, Stand
from sdar_tamp.schedule.moves import Move, break_cycles, plan_moves
from sdar_tamp.schedule.scheduler import retimer
from sdar_tamp.schedule.sweep import WorldSweep
from sdar_tamp.world.instance import Instance, load_instance
from sdar_tamp.world.suites import shipped_suite_dir
from sdar_tamp.world.transforms import FloatArray
from streams.context import WorldContext
from streams.stream_types import ArmConf

SOLVED = Path(__file__).resolve().parent / "solved"


class StraightMoves(StreamMovePlanner):
    """The streams' grasps and IK, straight joint-space motions (see the module docstring);
    ``unable``: arms that can do no move."""

    unable: frozenset[int] = frozenset()

    def estimate(self, arm: int, stand: Stand, move: Move) -> float | None:
        return None if arm in self.unable else super().estimate(arm, stand, move)

    def motion(
        self,
        name: str,
        q1: ArmConf,
        q2: ArmConf,
        fluents: Sequence[tuple[Any, ...]],
        standing: Mapping[str, FloatArray] | None = None,
    ) -> tuple[FloatArray, FloatArray] | None:
        points = [q1.q, *(() if q1.pre is None else (q1.pre,)), tuple(self.ctx.home(name))]
        points += [*(() if q2.pre is None else (q2.pre,)), q2.q]
        rows = [np.array(points[0])]
        for a, b in itertools.pairwise(points):
            n = max(2, int(np.ceil(np.abs(np.subtract(b, a)).max() / 0.01)))
            rows.extend(np.linspace(a, b, n + 1)[1:])
        q = np.array(rows)
        return np.linspace(0.0, 0.05 * len(q), len(q)), q  # slow: the re-timing takes over


def solved(name: str) -> tuple[Instance, PlanFile]:
    return load_instance(shipped_suite_dir("paper") / f"{name}.yaml"), load_plan(
        SOLVED / f"{name}.plan.json"
    )


def new_search(
    ctx: WorldContext, instance: Instance, plan: PlanFile, planner: StraightMoves
) -> Assignment:
    options = execution_options(ctx.scene)
    sweep = WorldSweep(instance, ctx.scene, options.max_tcp_step)
    moves = break_cycles(plan_moves(plan, instance, sweep, FINGER_ROOM), planner.buffer)
    retimers = [retimer(ctx.scene, i, options) for i in range(len(ctx.scene.arms))]
    return Assignment(plan, sweep, options, moves, planner, retimers, AssignmentOptions())


def first_move(search: Assignment, planner: StraightMoves, arm: int) -> Move:
    stand = search.stand[arm]
    return next(
        m for m in search.moves if not m.blockers and m.previous is None
        and planner.estimate(arm, stand, m) is not None
    )  # fmt: skip


def pre_grasps(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> tuple[FloatArray, FloatArray]:
    """Both arms' pre-grasps of the same object (close to each other)."""
    instance, plan, planner = r5
    probe = new_search(ctx, instance, plan, planner)
    m = first_move(probe, planner, 0)
    resting = {**probe.rest, m.obj: m.start}
    pre = []
    for a in (0, 1):
        stand = next(planner.plan(a, probe.stand[a], m, resting)).end
        assert stand.pre is not None
        pre.append(stand.pre)
    return pre[0], pre[1]
