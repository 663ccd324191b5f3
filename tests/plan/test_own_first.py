"""The synchronous plan's own motions offered first (:mod:`sdar_tamp.schedule.sync_motions`)
and the ``own-first`` policy (:mod:`sdar_tamp.schedule.own_first`): an arm keeps its own
tasks, an idle arm takes another's only where that ends it earlier, and the schedule replays."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pytest

from sdar_tamp.app.execution import execution_options
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.replay import validate_plan
from sdar_tamp.schedule.assignment import AssignmentOptions, schedule_assigned
from sdar_tamp.schedule.move_records import Stand
from sdar_tamp.schedule.moves import Move, break_cycles, plan_moves
from sdar_tamp.schedule.own_first import STEAL_GAIN, own_first, sync_spans
from sdar_tamp.schedule.sweep import WorldSweep
from sdar_tamp.schedule.sync_motions import SeededPlanner, sync_moves
from sdar_tamp.world.instance import Instance
from streams.context import WorldContext
from tests.plan.assignment_base import StraightMoves, new_search, solved


@pytest.fixture(scope="module")
def r5(ctx: WorldContext) -> tuple[Instance, PlanFile, StraightMoves]:
    instance, plan = solved("R5")
    return instance, plan, StraightMoves(instance, ctx.scene)


def _moves(ctx: WorldContext, instance: Instance, plan: PlanFile) -> tuple[Move, ...]:
    sweep = WorldSweep(instance, ctx.scene, execution_options(ctx.scene).max_tcp_step)
    return plan_moves(plan, instance, sweep, 0.03)


def test_each_move_of_the_plan_has_its_own_synchronous_motion(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    instance, plan, planner = r5
    made = _moves(ctx, instance, plan)
    moves = break_cycles(made, planner.buffer)
    motions = sync_moves(plan, moves, made)
    assert set(motions) == {m.index for m in made}
    for m in made:
        sync = motions[m.index]
        cols = plan.layout.slice(m.arm)
        grasp = next(e for e in plan.events if e.type == "grasp" and e.t == m.sync_t)
        row = int(np.argmin(np.abs(plan.t - grasp.t)))
        assert np.allclose(sync.reach[1][-1], plan.q[row, cols])
        assert np.allclose(sync.carry[1][0], plan.q[row, cols])
        assert sync.reach[0][0] == 0.0 and np.all(np.diff(sync.carry[0]) > 0.0)
        assert np.allclose(sync.T_tcp_object, grasp.T_tcp_object)
        end = sync.end
        assert end.leaving  # its next motion leaves a gripper event
        if end.pre is not None:  # the way back out: the approach backwards
            assert end.back is not None and np.allclose(end.back[-1], end.pre)
            assert np.allclose(end.back[0], end.q)
        else:  # one smooth motion into the release
            assert end.event and end.back is None
        # when the plan released the object; where it had the arm at a time of the reach
        release = next(e for e in plan.events if e.type == "release" and e.t > m.sync_t)
        assert sync.released == pytest.approx(release.t, abs=1e-6)
        q0 = sync.reach[1][0]
        assert sync.until(q0, sync.t0) is None  # there already
        half = sync.until(q0, sync.t0 + 0.5 * float(sync.reach[0][-1]))
        if half is not None:
            assert np.allclose(half[1][0], q0) and len(half[1]) < len(sync.reach[1])
        whole = sync.until(q0, sync.released)
        rest_of = sync.from_stand(q0)
        assert rest_of is not None and whole is not None
        assert len(whole[1]) == len(rest_of.reach[1]) - 1  # short of the grasp
        # from anywhere on the reach: the rest of it; off the path: no option
        mid = len(sync.reach[1]) // 2
        rest = sync.from_stand(sync.reach[1][mid])
        assert rest is not None and np.allclose(rest.reach[1][-1], sync.reach[1][-1])
        assert len(rest.reach[1]) <= len(sync.reach[1]) - mid
        assert sync.from_stand(sync.reach[1][0] + 0.1) is None
    # a move split through a buffer has none
    first = made[0]
    split = (Move(first.index, first.obj, first.start, (0.0, 0.0, 0.0), first.arm,
                  first.sync_t, None, ()),)  # fmt: skip
    assert sync_moves(plan, split, made) == {}


def test_the_seeded_planner_offers_the_plan_s_motion_first_to_its_own_arm_only(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    instance, plan, planner = r5
    made = _moves(ctx, instance, plan)
    first = min(made, key=lambda m: m.index)
    seeded = SeededPlanner(planner, sync_moves(plan, made, made))
    home = Stand(np.array(plan.q[0, plan.layout.slice(first.arm)]))
    resting = {o.name: o.start.as_tuple() for o in instance.objects}
    own = next(seeded.plan(first.arm, home, first, resting))
    assert len(seeded.offered) == 1 and np.allclose(own.reach[1][0], home.q)
    other = 1 - first.arm
    there = Stand(np.array(plan.q[0, plan.layout.slice(other)]))
    planned = next(seeded.plan(other, there, first, resting), None)
    assert len(seeded.offered) == 1  # another arm: the wrapped planner's options only
    assert planned is None or not np.array_equal(planned.reach[1], own.reach[1])
    away = Stand(home.q + 0.2)
    next(seeded.plan(first.arm, away, first, resting), None)
    assert len(seeded.offered) == 1  # off the plan's path: none
    assert seeded.estimate(first.arm, home, first) == planner.estimate(first.arm, home, first)


def test_the_synchronous_spans_add_up_to_each_arm_s_last_release(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    instance, plan, _ = r5
    made = _moves(ctx, instance, plan)
    spans = sync_spans(plan, made)
    for arm, name in enumerate(plan.arm_names):
        last = max((e.t for e in plan.events if e.arm == name and e.type == "release"), default=0)
        assert sum(spans[m.index] for m in made if m.arm == arm) == pytest.approx(last)
        assert all(spans[m.index] > 0.0 for m in made if m.arm == arm)


@dataclass
class FakeSearch:
    """Two moves of arm 0 (one ready), none of arm 1; every estimate ``est`` [s]."""

    est: float | None
    owner_busy: int = 0  # [ticks] where arm 0's timeline ends
    tick: float = 0.1
    dwell: int = 2
    stand: list[Stand] = field(default_factory=lambda: [Stand(np.zeros(6))] * 2)
    carrier: dict[int, int] = field(default_factory=dict)
    spans: dict[int, float] = field(default_factory=lambda: {0: 3.0, 1: 3.0})
    estimated: dict[int, int] = field(default_factory=dict)
    moves: tuple[Move, ...] = (
        Move(0, "a", (0.0, 0.0, 0.0), (0.1, 0.0, 0.0), 0, 0.5, None, ()),
        Move(1, "b", (0.2, 0.0, 0.0), (0.3, 0.0, 0.0), 0, 3.5, None, ()),
    )

    @property
    def planner(self) -> FakeSearch:
        return self

    def estimate(self, arm: int, stand: Stand, move: Move) -> float | None:
        return self.est

    def horizon(self, arm: int) -> int:
        return self.owner_busy if arm == 0 else 0

    def bound(self, m: Move) -> tuple[int, int]:
        return 0, 0


def test_an_idle_arm_takes_another_s_move_only_where_that_ends_it_earlier() -> None:
    fake = FakeSearch(est=1.0)
    # the owner takes its own next move, the first of its moves not committed
    assert own_first(fake, 0, list(fake.moves)) == [fake.moves[0]]  # type: ignore[arg-type]
    assert own_first(fake, 0, [fake.moves[1]]) == []  # type: ignore[arg-type]
    # the idle arm: move 1 ends at 1.5 x 1 s + 0.4 s by it, at 6 s by its owner (after move 0)
    assert own_first(fake, 1, list(fake.moves)) == list(fake.moves)  # type: ignore[arg-type]
    assert fake.estimated[1] == math.ceil((1.5 + 0.2) / 0.1)
    # a slow estimate: move 0 (3 s by its owner) no longer, move 1 (6 s) still
    slow = FakeSearch(est=(3.0 - 0.4 - STEAL_GAIN) / 1.5 + 0.1)
    assert own_first(slow, 1, list(slow.moves)) == [slow.moves[1]]  # type: ignore[arg-type]
    # an arm that cannot do a move does not take it
    assert own_first(FakeSearch(est=None), 1, list(slow.moves)) == []  # type: ignore[arg-type]


def test_the_own_first_policy_keeps_the_plan_s_tasks_and_motions(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    """Each arm carries its own moves of the plan along the plan's own motions, in the plan's
    order per arm; what is returned replays (the synchronous plan when the search is stuck:
    here the last move waits for an arm standing at its spot)."""
    instance, plan, planner = r5
    options = AssignmentOptions(policies=("own-first",), max_seconds=math.inf)
    s = schedule_assigned(plan, instance, ctx.scene, execution_options(ctx.scene), planner, options)
    figures = dict(s.figures)
    assert figures["sync_motions"] >= 4 and figures["reassigned"] == 0.0
    assert validate_plan(instance, s.plan, ctx.scene).ok
    assert s.asynchronous == (s.async_duration is not None and s.async_duration < plan.duration)
    search = new_search(ctx, instance, plan, planner)
    search.planner = SeededPlanner(planner, sync_moves(plan, search.moves, search.moves))
    search.policy = "own-first"
    arm, ranked = search.free_arm([m for m in search.moves if search.ready_move(m)])
    assert ranked and ranked[0].arm == arm  # its own move first
    order = {a: [m.index for m in search.moves if m.arm == a] for a in search.arms}
    assert ranked[0].index == order[arm][0]
    # without the plan's motions offered, the default policies use none
    plain = schedule_assigned(
        plan, instance, ctx.scene, execution_options(ctx.scene), planner,
        AssignmentOptions(policies=("earliest",), max_seconds=math.inf),
    )  # fmt: skip
    assert dict(plain.figures)["sync_motions"] == 0.0
