"""Shortcuts of the start-time search that must not change its answer: starts passed over
(:meth:`~sdar_tamp.schedule.scheduler.Placement.skipped`), a paused attempt's motion put
back as it was (:meth:`~sdar_tamp.schedule.move_commit.MoveCommit.put_back`) and the world
after the same events set at once (:meth:`~sdar_tamp.schedule.sweep.WorldSweep.reset`)."""

from __future__ import annotations

import numpy as np
import pytest

from sdar_tamp.plan_file import PlanFile
from sdar_tamp.schedule.assignment import Assignment
from sdar_tamp.schedule.room import block_of
from sdar_tamp.schedule.scheduler import Entry, Placement
from sdar_tamp.schedule.sweep import TimedEvent, WorldSweep
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.transforms import FloatArray
from streams.context import WorldContext
from tests.plan.assignment_base import (
    StraightMoves,
    new_search,
    pre_grasps,
    solved,
)


@pytest.fixture(scope="module")
def r5(ctx: WorldContext) -> tuple[Instance, PlanFile, StraightMoves]:
    instance, plan = solved("R5")
    return instance, plan, StraightMoves(instance, ctx.scene)


def _left_visits(search: Assignment, pre: FloatArray) -> None:
    """The left arm waits 1 s at home, goes over the object (2 s), stays 1 s, goes home."""
    home = np.array(search.stand[0].q)
    search.traj[0].extend([search.traj[0][-1]] * 50)
    there = search.retimers[0].retime(
        np.linspace(0.0, 2.0, 50), np.linspace(home, pre, 50), False, False
    )
    search.place([Entry(0, block_of(0, there), there, 0)])
    search.traj[0].extend([search.traj[0][-1]] * 50)
    back = np.array(there[::-1])
    search.place([Entry(0, block_of(0, back), back, 0)])


def test_starts_passed_over_all_fail_and_the_start_found_is_the_same(
    ctx: WorldContext,
    r5: tuple[Instance, PlanFile, StraightMoves],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The right arm goes over the same object while the left arm visits it: from early
    starts it arrives first and stands in the left arm's way (a conflict after its motion),
    so the starts up to the one that arrives at the conflict's tick are passed over. The start
    found and the schedule are those of the search that tries every start, with fewer
    replays."""
    instance, plan, planner = r5
    pre = pre_grasps(ctx, r5)
    results = []
    passed: list[int] = []
    real = Placement.skipped

    def counting(self: Placement, entries: list[Entry], s: int, tick: int) -> int:
        n = real(self, entries, s, tick)
        passed.append(n)
        return n

    for skipping in (True, False):
        if skipping:
            monkeypatch.setattr(Placement, "skipped", counting)
        else:
            monkeypatch.setattr(Placement, "skipped", lambda *_: 0)
        search = new_search(ctx, instance, plan, planner)
        search.max_wait = 600
        _left_visits(search, pre[0])
        home = np.array(search.stand[1].q)
        q = search.retimers[1].retime(
            np.linspace(0.0, 1.0, 30), np.linspace(home, pre[1], 30), False, False
        )
        runs = search.sweep.checks
        search.place([Entry(1, block_of(1, q), q, 0)])
        results.append((np.array(search.traj[1]), search.delay, search.sweep.checks - runs))
    assert any(n > search.stride for n in passed)  # starts were passed over
    (with_skips, delay, checks), (every, delay_every, checks_every) = results
    assert delay == delay_every > 0  # it waited for the left arm, the same start
    np.testing.assert_array_equal(with_skips, every)
    assert checks < checks_every


def test_a_paused_attempt_that_ends_no_earlier_puts_the_motion_back_as_it_was(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    """A pause that does not end the motion earlier than ``end`` is taken back and the whole
    motion committed again: the same samples, events and steps as before the attempt."""
    instance, plan, planner = r5
    pre = pre_grasps(ctx, r5)
    search = new_search(ctx, instance, plan, planner)
    _left_visits(search, pre[0])
    home = np.array(search.stand[1].q)
    q = search.retimers[1].retime(
        np.linspace(0.0, 1.0, 30), np.linspace(home, pre[1], 30), False, False
    )
    mark = search.mark()
    search.place([Entry(1, block_of(1, q), q, 0)])
    before = ([np.array(t) for t in search.traj], list(search.events), list(search.steps))
    delay = (search.delay, search.delayed_by)
    assert not search.paused_motion(1, q, None, False, len(q) // 2, 0, mark)  # never earlier
    for traj, kept in zip(search.traj, before[0], strict=True):
        np.testing.assert_array_equal(np.array(traj), kept)
    assert search.events == before[1] and search.steps == before[2]
    assert (search.delay, search.delayed_by) == delay


def _timed(plan: PlanFile) -> list[TimedEvent]:
    """The plan's events at their ticks with their arms' configurations."""
    out = []
    for e in plan.events:
        row = int(np.argmin(np.abs(plan.t - e.t)))
        arm = plan.arm_names.index(e.arm)
        out.append(TimedEvent(row, e, np.array(plan.q[row, plan.layout.slice(arm)])))
    return out


def _state(sweep: WorldSweep) -> tuple[object, ...]:
    held = {a: (o, T.tobytes()) for a, (o, T) in sweep.held.items()}
    exempt = {a: (o, q.tobytes()) for a, (o, q) in sweep.exempt.items()}
    return sweep.world.arrangement_key(), list(sweep.rest.items()), held, exempt


def test_a_reset_to_the_same_events_again_sets_the_same_world(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    """Resetting to events just replayed (remembered) gives the world a fresh sweep builds
    from them: the same resting boxes in the same order, held objects at the same grasps, the
    same exempt contacts and the same collision answers; after other events, a third reset
    still does."""
    instance, plan, _ = r5
    events = _timed(plan)
    held_at = next(i for i, e in enumerate(events) if e.event.type == "grasp") + 1
    fresh = WorldSweep(instance, ctx.scene, 0.005)
    for n in (held_at, len(events) // 2, len(events)):
        fresh.reset(events[:n])
        want = _state(fresh)
        sweep = WorldSweep(instance, ctx.scene, 0.005)
        sweep.reset(events[:n])
        sweep.run(0, plan.q[:40], events[:0])  # a replay changes nothing remembered
        if n < len(events):
            sweep.apply(events[n], check=False)
        sweep.reset(events[:n])  # remembered
        assert _state(sweep) == want
        sweep.reset(events[:1])
        sweep.reset(events[:n])
        assert _state(sweep) == want
        q = plan.q[:: max(1, len(plan.q) // 50)]
        assert [sweep.world.in_collision(x) for x in q] == [fresh.world.in_collision(x) for x in q]
