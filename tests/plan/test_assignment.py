"""Moves assigned anew to the arms (:mod:`sdar_tamp.schedule.assignment`): a free arm takes
the next ready move, the moves' order is kept, a contact forces a wait, rotations go through a
buffer, arms retreat and motions are planned against the others, and every schedule replays.
The motions come from :class:`~tests.plan.assignment_base.StraightMoves`; the options, the
wall-clock cap, pauses and policies are in :mod:`tests.plan.test_assignment_policies`."""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Iterator, Mapping, Sequence
from typing import Any

import numpy as np
import pytest

from sdar_tamp.app.execution import SCHEDULERS, execution_options
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_rules import check_timeline
from sdar_tamp.replay import validate_plan
from sdar_tamp.schedule.assignment import (
    PlannedMove,
    Stand,
    schedule_assigned,
)
from sdar_tamp.schedule.moves import CyclicMoves, Move, break_cycles, plan_moves, stuck_moves
from sdar_tamp.schedule.sweep import WorldSweep
from sdar_tamp.world.collision import CollisionWorld
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.transforms import FloatArray
from streams.context import WorldContext
from streams.stream_types import ArmConf
from tests.plan.assignment_base import StraightMoves, first_move, new_search, solved


@pytest.fixture(scope="module")
def r5(ctx: WorldContext) -> tuple[Instance, PlanFile, StraightMoves]:
    instance, plan = solved("R5")
    return instance, plan, StraightMoves(instance, ctx.scene)


def test_the_moves_of_a_plan_chain_each_object_from_start_to_goal(ctx: WorldContext) -> None:
    instance, plan = solved("M2")
    moves = plan_moves(plan, instance, WorldSweep(instance, ctx.scene, 0.005))
    assert [m.index for m in moves] == list(range(len(moves)))
    for o in instance.objects:
        chain = [m for m in moves if m.obj == o.name]
        if not chain:
            continue
        assert np.allclose(chain[0].start, o.start.as_tuple(), atol=1e-6)
        assert np.allclose(chain[-1].end[:2], o.goal.as_tuple()[:2], atol=1e-3)
        assert chain[0].previous is None
        assert [m.previous for m in chain[1:]] == [m.index for m in chain[:-1]]
    assert any(m.blockers for m in moves) and not stuck_moves(moves)
    for m in moves:  # a blocker is lifted from a pose the released object covers
        assert all(moves[b].obj != m.obj for b in m.blockers)


def test_a_rotation_goes_through_a_buffer_and_without_one_is_refused(ctx: WorldContext) -> None:
    instance, plan = solved("D5")
    moves = plan_moves(plan, instance, WorldSweep(instance, ctx.scene, 0.005))
    assert stuck_moves(moves)  # objects trading places, held at once
    with pytest.raises(CyclicMoves, match="no buffer"):
        break_cycles(moves, lambda m, ms: None)
    spot = (0.0, -0.3, 0.0)
    broken = break_cycles(moves, lambda m, ms: spot)
    assert not stuck_moves(broken)
    split = [m for m in broken if m.end == spot]
    assert split and len(broken) == len(moves) + len(split)
    for first in split:
        (second,) = (m for m in broken if m.previous == first.index)
        assert second.start == spot and not first.blockers
        assert second.end == next(m.end for m in moves if m.index == first.index)


def test_a_free_arm_takes_the_next_ready_move_in_the_moves_order(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    instance, plan, planner = r5
    alone = planner
    alone.unable = frozenset({1})  # the right arm can do nothing: the left takes every move
    try:
        search = new_search(ctx, instance, plan, alone)
        result = search.run()
    finally:
        alone.unable = frozenset()
    assert set(search.carrier.values()) == {0}
    figures = dict(search.figures())
    assert figures["moves"] == len(search.moves)
    assert figures["reassigned"] == sum(m.arm == 1 for m in search.moves) > 0
    report = validate_plan(instance, result, ctx.scene)
    assert report.ok, report.violation
    # one arm after the other: each grasp follows the previous release by a dwell at least
    ticks = sorted((search.grasp_tick[i], search.release_tick[i]) for i in search.carrier)
    assert all(g >= r + search.dwell for (_, r), (g, _) in itertools.pairwise(ticks))
    # the moves' order: a release after the blockers' grasps and the earlier neighbours'
    # releases, a move after its object's previous one
    assert any(m.blockers for m in search.moves)
    for m in search.moves:
        grasp, release = search.grasp_tick[m.index], search.release_tick[m.index]
        assert release > grasp
        if m.previous is not None:
            assert grasp >= search.release_tick[m.previous] + search.dwell
        for b in m.blockers:
            assert release >= search.grasp_tick[b] + search.dwell
        for b in m.placed_after:
            assert release >= search.release_tick[b] + search.dwell


def test_a_contact_forces_a_wait(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    """The left arm releases an object and stands there; the right arm, sent to take the same
    object back, finds no start while the left arm's gripper is round it, and one after the
    left arm has gone home."""
    instance, plan, planner = r5
    search = new_search(ctx, instance, plan, planner)
    stand = Stand(np.array(plan.q[0, search.columns[1]]))
    first = next(
        m
        for m in search.moves
        if not m.blockers
        and planner.estimate(0, stand, m) is not None
        and planner.estimate(1, stand, dataclasses.replace(m, start=m.end, end=m.start)) is not None
    )
    assert search.take(0, first)
    back = Move(99, first.obj, first.end, first.start, 1, 0.0, first.index, ())
    search.moves = (*search.moves, back)
    assert not search.take(1, back)  # the left gripper stands round the object
    left_done = search.horizon(0)
    assert search.park(0)
    assert search.take(1, back)
    assert search.grasp_tick[99] > left_done  # waited for the left arm to leave
    report = validate_plan(instance, search.assemble(), ctx.scene)
    # the object is back at its start: not the goal, but no contact and no broken event
    assert report.violation is None or report.violation.kind == "goal", report.violation


def test_a_schedule_is_kept_only_when_shorter(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    instance, plan, planner = r5
    s = schedule_assigned(plan, instance, ctx.scene, execution_options(ctx.scene), planner)
    assert s.order == "assigned"
    if s.asynchronous:
        assert s.async_duration is not None and s.plan.duration < plan.duration
        assert validate_plan(instance, s.plan, ctx.scene).ok
    else:  # the motions through home are slow: the synchronous plan is kept, with the reason
        assert s.plan is plan and s.reason
        assert s.async_duration is None or s.async_duration >= plan.duration
    assert "assigned" in SCHEDULERS


def test_a_planner_that_finds_no_motion_gives_no_schedule(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    instance, plan, _ = r5

    class Nothing(StraightMoves):
        def plan(
            self,
            arm: int,
            stand: Stand,
            move: Move,
            resting: Mapping[str, tuple[float, float, float]],
            others: Sequence[FloatArray] | None = None,
        ) -> Iterator[PlannedMove]:
            return iter(())

    s = schedule_assigned(
        plan, instance, ctx.scene, execution_options(ctx.scene), Nothing(instance, ctx.scene)
    )
    assert not s.asynchronous and s.plan is plan
    assert "no move can be committed" in s.reason


def test_an_arm_that_finished_retreats_along_its_approach(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    """After a release the arm stands at the release configuration; a retreat takes it back
    out along its approach to the pre-grasp (the carry's end played backwards), in less
    time than the way home, and replays without contact."""
    instance, plan, planner = r5
    search = new_search(ctx, instance, plan, planner)
    m = first_move(search, planner, 0)
    assert search.take(0, m)
    stand, released = search.stand[0], search.horizon(0)
    assert stand.pre is not None and stand.back is not None
    assert np.allclose(stand.back[0], stand.q) and np.allclose(stand.back[-1], stand.pre)
    assert search.retreat(0)
    retreat = search.horizon(0) - released
    assert retreat > 0 and np.allclose(search.traj[0][-1], stand.pre, atol=1e-9)
    assert search.stand[0].pre is None and not search.parked[0]
    assert dict(search.figures())["retreats"] == 1.0
    assert not search.retreat(0)  # at no grasp or release: nothing to retreat from
    result = search.assemble()
    assert check_timeline(result, ctx.scene) is None  # from rest to rest, within the limits
    report = validate_plan(instance, result, ctx.scene)
    assert report.violation is None or report.violation.kind == "goal", report.violation
    # the way home from the release configuration takes longer
    home = new_search(ctx, instance, plan, planner)
    assert home.take(0, m) and home.park(0)
    assert home.horizon(0) - released > retreat


def test_a_retreat_the_sweep_refuses_commits_nothing(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    """A retreat into the table is refused: False, the timeline as it was."""
    instance, plan, planner = r5
    search = new_search(ctx, instance, plan, planner)
    m = first_move(search, planner, 0)
    assert search.take(0, m)
    stand, horizon = search.stand[0], search.horizon(0)
    down = np.array(stand.q)
    down[1] += 1.2  # the shoulder drives the arm down through the table
    q = plan.q[0].copy()
    q[search.columns[0]] = down
    assert CollisionWorld(ctx.scene).in_collision(q)
    search.stand[0] = dataclasses.replace(stand, pre=down, back=None)
    assert not search.retreat(0)
    assert search.horizon(0) == horizon and search.stand[0].pre is not None


def test_motions_are_planned_against_the_other_arms_where_they_stand_then_at_home(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    instance, plan, _ = r5

    class Recording(StraightMoves):
        seen: list[dict[str, tuple[float, ...]]]

        def motion(
            self,
            name: str,
            q1: ArmConf,
            q2: ArmConf,
            fluents: Sequence[tuple[Any, ...]],
            standing: Mapping[str, FloatArray] | None = None,
        ) -> tuple[FloatArray, FloatArray] | None:
            self.seen.append({a: tuple(map(float, q)) for a, q in (standing or {}).items()})
            return super().motion(name, q1, q2, fluents, standing)

    planner = Recording(instance, ctx.scene)
    planner.seen = []
    search = new_search(ctx, instance, plan, planner)
    m = first_move(search, planner, 0)
    raised = np.array(search.stand[1].q) + np.array([0.3, -0.2, 0.0, 0.0, 0.0, 0.0])
    others = [np.array(search.stand[0].q), raised]
    resting = {**search.rest, m.obj: m.start}
    planned = list(planner.plan(0, search.stand[0], m, resting, others))
    assert planned
    right = ctx.arm_names[1]
    where = [s[right] for s in planner.seen]
    home = tuple(map(float, ctx.home(right)))
    assert where[0] == tuple(map(float, raised)) and where[-1] == home
    # the other arms at home already: one round only
    planner.seen = []
    list(planner.plan(0, search.stand[0], m, resting, [others[0], ctx.home(right)]))
    assert {s[right] for s in planner.seen} == {home}
