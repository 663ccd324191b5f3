"""Moves assigned anew to the arms (:mod:`sdar_tamp.schedule.assignment`): a free arm takes
the next ready move, the moves' order is kept, a contact forces a wait, rotations go through a
buffer, and every schedule replays.

The motions come from :class:`StraightMoves`: the streams' grasps and inverse kinematics
(:class:`~sdar_tamp.app.move_planning.StreamMovePlanner`) with straight joint-space segments
through the pre-grasps and the arm's home in place of the motion planner (fast, clear of the
resting objects; the sweep still checks them)."""

from __future__ import annotations

import dataclasses
import itertools
import math
import time
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from sdar_tamp.app.execution import SCHEDULERS, execution_options
from sdar_tamp.app.move_planning import StreamMovePlanner
from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_rules import check_timeline
from sdar_tamp.replay import validate_plan
from sdar_tamp.schedule.assignment import (
    FINGER_ROOM,
    POLICIES,
    Assignment,
    AssignmentOptions,
    PlannedMove,
    Stand,
    schedule_assigned,
)
from sdar_tamp.schedule.moves import CyclicMoves, Move, break_cycles, plan_moves, stuck_moves
from sdar_tamp.schedule.room import block_of, rest_to_rest
from sdar_tamp.schedule.scheduler import Entry, NoPlacement, retimer
from sdar_tamp.schedule.sweep import WorldSweep
from sdar_tamp.world.collision import CollisionWorld
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


def _solved(name: str) -> tuple[Instance, PlanFile]:
    return load_instance(shipped_suite_dir("paper") / f"{name}.yaml"), load_plan(
        SOLVED / f"{name}.plan.json"
    )


def _search(
    ctx: WorldContext, instance: Instance, plan: PlanFile, planner: StraightMoves
) -> Assignment:
    options = execution_options(ctx.scene)
    sweep = WorldSweep(instance, ctx.scene, options.max_tcp_step)
    moves = break_cycles(plan_moves(plan, instance, sweep, FINGER_ROOM), planner.buffer)
    retimers = [retimer(ctx.scene, i, options) for i in range(len(ctx.scene.arms))]
    return Assignment(plan, sweep, options, moves, planner, retimers, AssignmentOptions())


@pytest.fixture(scope="module")
def r5(ctx: WorldContext) -> tuple[Instance, PlanFile, StraightMoves]:
    instance, plan = _solved("R5")
    return instance, plan, StraightMoves(instance, ctx.scene)


def test_the_moves_of_a_plan_chain_each_object_from_start_to_goal(ctx: WorldContext) -> None:
    instance, plan = _solved("M2")
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
    instance, plan = _solved("D5")
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
        search = _search(ctx, instance, plan, alone)
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
    search = _search(ctx, instance, plan, planner)
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


def _first_move(search: Assignment, planner: StraightMoves, arm: int) -> Move:
    stand = search.stand[arm]
    return next(
        m for m in search.moves if not m.blockers and m.previous is None
        and planner.estimate(arm, stand, m) is not None
    )  # fmt: skip


def test_an_arm_that_finished_retreats_along_its_approach(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    """After a release the arm stands at the release configuration; a retreat takes it back
    out along its approach to the pre-grasp (the carry's end played backwards), in less
    time than the way home, and replays without contact."""
    instance, plan, planner = r5
    search = _search(ctx, instance, plan, planner)
    m = _first_move(search, planner, 0)
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
    home = _search(ctx, instance, plan, planner)
    assert home.take(0, m) and home.park(0)
    assert home.horizon(0) - released > retreat


def test_a_retreat_the_sweep_refuses_commits_nothing(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    """A retreat into the table is refused: False, the timeline as it was."""
    instance, plan, planner = r5
    search = _search(ctx, instance, plan, planner)
    m = _first_move(search, planner, 0)
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
    search = _search(ctx, instance, plan, planner)
    m = _first_move(search, planner, 0)
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


def test_assignment_options_are_checked() -> None:
    bad: list[dict[str, Any]] = [
        {"candidates": 0},
        {"stride": True},
        {"max_checks": 1.5},
        {"max_plans": -1},
        {"replans": -1},
        {"max_wait": -0.1},
        {"slack": math.nan},
        {"slack": "1"},
        {"policies": ()},
        {"policies": ("earliest", "fastest")},
        {"policies": "earliest"},
        {"max_seconds": 0.0},
        {"max_seconds": True},
        {"max_seconds": math.nan},
    ]
    for kwargs in bad:
        with pytest.raises(ParameterError, match=next(iter(kwargs))):
            AssignmentOptions(**kwargs)
    assert AssignmentOptions(replans=0, slack=math.inf).replans == 0
    assert AssignmentOptions(policies=("clear",), max_seconds=math.inf).policies == ("clear",)
    assert AssignmentOptions().policies == POLICIES


def test_a_search_past_its_wall_clock_cap_gives_no_schedule(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    """A search whose deadline has passed stops at its next decision; with the cap spent
    before a policy starts, that policy is not tried and the synchronous plan is kept."""
    instance, plan, planner = r5
    search = _search(ctx, instance, plan, planner)
    search.deadline = time.perf_counter() - 1.0
    with pytest.raises(NoPlacement, match="out of time"):
        search.run()
    assert not search.carrier
    s = schedule_assigned(
        plan,
        instance,
        ctx.scene,
        execution_options(ctx.scene),
        planner,
        AssignmentOptions(max_seconds=1e-9),
    )
    assert not s.asynchronous and s.plan is plan and s.async_duration is None
    assert "out of time" in s.reason


def test_a_retreat_cut_out_of_a_motion_still_starts_and_ends_at_rest() -> None:
    """The retreat's path is the end of a carry, moving where it is cut: its times are made
    anew, from rest to rest on a cosine profile of the path's length."""
    q = np.linspace([0.0, 0.0], [0.3, -0.1], 13)
    t = rest_to_rest(q)
    assert t[0] == 0.0 and np.all(np.diff(t) > 0.0) and t[-1] >= 1.0
    v = np.diff(q[:, 0]) / np.diff(t)
    assert abs(v[0]) < abs(v[len(v) // 2]) and abs(v[-1]) < abs(v[len(v) // 2])
    assert np.allclose(rest_to_rest(np.zeros((4, 2))), np.linspace(0.0, 1.0, 4))


def test_a_motion_met_by_another_arm_pauses_on_the_way_and_ends_earlier(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    """The left arm goes to stand over an object for a while, then home; the right arm's
    motion swings away, then comes to the same object. Waiting at its start, it ends when the
    whole motion fits after the left arm has gone; paused on the way (it swings away at once
    and stops short of the left arm), it ends earlier, and the schedule replays."""
    instance, plan, planner = r5
    probe = _search(ctx, instance, plan, planner)
    m = _first_move(probe, planner, 0)
    resting = {**probe.rest, m.obj: m.start}
    pre = []
    for a in (0, 1):
        stand = next(planner.plan(a, probe.stand[a], m, resting)).end
        assert stand.pre is not None
        pre.append(stand.pre)
    ends = []
    for pauses in (False, True):
        search = _search(ctx, instance, plan, planner)
        search.pauses = pauses
        home = [np.array(search.stand[a].q) for a in (0, 1)]
        there = search.retimers[0].retime(
            np.linspace(0.0, 2.0, 50), np.linspace(home[0], pre[0], 50), False, False
        )
        search.place([Entry(0, block_of(0, there), there, 0)])
        search.traj[0].extend([search.traj[0][-1]] * 100)  # stands there 2 s
        back = np.array(there[::-1])
        search.place([Entry(0, block_of(0, back), back, 0)])
        away = home[1].copy()
        away[0] -= 1.0  # the right arm's base turns away first
        path = np.vstack([np.linspace(home[1], away, 50), np.linspace(away, pre[1], 50)[1:]])
        q = search.retimers[1].retime(np.linspace(0.0, 4.0, len(path)), path, False, False)
        delayed = search.place_motion(1, q, None, False, 10)
        assert (delayed is None) == pauses  # paused: no longer delayed at its start
        assert search.paused == int(pauses)
        ends.append(search.horizon(1))
        result = search.assemble()
        assert check_timeline(result, ctx.scene) is None  # every part from rest to rest
        report = validate_plan(instance, result, ctx.scene)
        assert report.violation is None or report.violation.kind == "goal", report.violation
        if pauses:  # the right arm stood still on the way, away from both ends of its path
            right = np.array(search.traj[1])
            still = np.abs(np.diff(right, axis=0)).max(axis=1) < 1e-12
            moving = np.flatnonzero(~still)
            inner = still[moving[0] : moving[-1]]
            assert inner.any()
    assert ends[1] < ends[0]


def test_the_policies_are_searched_in_turn_and_the_shortest_kept(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    instance, plan, planner = r5
    options = AssignmentOptions(policies=("plan-order", "earliest"), max_seconds=math.inf)
    s = schedule_assigned(plan, instance, ctx.scene, execution_options(ctx.scene), planner, options)
    figures = dict(s.figures)
    found = {k[9:]: v for k, v in figures.items() if k.startswith("duration_")}
    assert found and set(found) <= {"plan-order", "earliest"}
    assert s.async_duration == min(found.values())
    assert POLICIES[int(figures["policy"])] == min(
        found, key=lambda p: (found[p], p != "plan-order")
    )
    # an arm of policy ``clear`` leaves the spot it lets go of at once
    for policy, retreats in (("earliest", 0), ("clear", 1)):
        search = _search(ctx, instance, plan, planner)
        search.policy = policy
        search.moves = (_first_move(search, planner, 0),)
        result = search.run()
        assert dict(search.figures())["retreats"] == retreats
        arm = next(iter(search.carrier.values()))
        assert (search.stand[arm].pre is None) == (policy == "clear")
        report = validate_plan(instance, result, ctx.scene)
        assert report.violation is None or report.violation.kind == "goal", report.violation
