"""The assignment's options, its wall-clock cap, motions that pause on the way
(:mod:`sdar_tamp.schedule.move_commit`) and the policies searched in turn
(:mod:`sdar_tamp.schedule.assignment`); the motions come from
:class:`~tests.plan.assignment_base.StraightMoves`."""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
import pytest

from sdar_tamp.app.execution import execution_options
from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_rules import check_timeline
from sdar_tamp.replay import validate_plan
from sdar_tamp.schedule.assignment import (
    POLICIES,
    AssignmentOptions,
    schedule_assigned,
)
from sdar_tamp.schedule.room import block_of, rest_to_rest
from sdar_tamp.schedule.scheduler import Entry, NoPlacement
from sdar_tamp.world.instance import Instance
from streams.context import WorldContext
from tests.plan.assignment_base import (
    StraightMoves,
    first_move,
    new_search,
    pre_grasps,
    solved,
)


@pytest.fixture(scope="module")
def r5(ctx: WorldContext) -> tuple[Instance, PlanFile, StraightMoves]:
    instance, plan = solved("R5")
    return instance, plan, StraightMoves(instance, ctx.scene)


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
    assert AssignmentOptions().policies == POLICIES[:3]  # ``own-first`` on request


def test_a_search_past_its_wall_clock_cap_gives_no_schedule(
    ctx: WorldContext, r5: tuple[Instance, PlanFile, StraightMoves]
) -> None:
    """A search whose deadline has passed stops at its next decision; with the cap spent
    before a policy starts, that policy is not tried and the synchronous plan is kept."""
    instance, plan, planner = r5
    search = new_search(ctx, instance, plan, planner)
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
    pre = pre_grasps(ctx, r5)
    ends = []
    for pauses in (False, True):
        search = new_search(ctx, instance, plan, planner)
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
        search = new_search(ctx, instance, plan, planner)
        search.policy = policy
        search.moves = (first_move(search, planner, 0),)
        result = search.run()
        assert dict(search.figures())["retreats"] == retreats
        arm = next(iter(search.carrier.values()))
        assert (search.stand[arm].pre is None) == (policy == "clear")
        report = validate_plan(instance, result, ctx.scene)
        assert report.violation is None or report.violation.kind == "goal", report.violation
