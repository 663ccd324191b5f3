"""Re-planning while the arms move (``sdar_tamp.app.replan_moving``) on D5 of the paper suite
and its stored plan (``conftest.py``): the repair is given first, a shorter fresh
continuation replaces it only when it is found before the arms reach the cut point it starts
from."""

from __future__ import annotations

import dataclasses
import itertools
import time

import numpy as np
import pytest

from sdar_tamp.app import replan_moving
from sdar_tamp.app.cache import PlannerCache
from sdar_tamp.app.replan_moving import Arrival, at_grasps, improve, replan_while_moving
from sdar_tamp.app.replanning import Fresh, ReplanOutcome, replan
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_state import Cut, cut_point, state_at
from sdar_tamp.replay import validate_plan
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.observed import ObservedState, parse_observed
from sdar_tamp.world.scene import load_scene
from tests.app.conftest import CONFIG

AT = 5.116  # o4 resting, its task still to come


def _o4_nudged(d5: tuple[Instance, PlanFile]) -> ObservedState:
    """o4 nudged: the repair plans its task again (13.70 s in all), a fresh continuation from
    the same cut ends 0.5 s earlier (``test_replanning.py``)."""
    instance, plan = d5
    starts = {o.name: o.start.as_tuple() for o in instance.objects}
    x, y, yaw = state_at(plan, starts, load_scene(), AT).resting["o4"]
    text = f"poses: [{{name: o4, pose: [{x + 0.0052}, {y + 0.0173}, {yaw - 0.1559}]}}]"
    return parse_observed(text, "obs.yaml")


@pytest.fixture(scope="module")
def repaired(d5: tuple[Instance, PlanFile], cache: PlannerCache) -> ReplanOutcome:
    out = replan(*d5, AT, _o4_nudged(d5), config=CONFIG, cache=cache, compare=False)
    assert out.status == "repaired" and out.changed and out.valid is True
    return out


def test_with_time_to_spare_the_fresh_continuation_from_the_cut_replaces_the_repair(
    d5: tuple[Instance, PlanFile], cache: PlannerCache, repaired: ReplanOutcome
) -> None:
    """The arms reach the cut long after the solve ends: the fresh continuation starts at the
    cut itself, the same plan as the comparison before returning keeps."""
    later = Arrival(time.perf_counter() + 1000.0, repaired.resume)
    better = improve(d5[0], repaired, later, config=CONFIG, cache=cache)
    synchronous = replan(*d5, AT, _o4_nudged(d5), config=CONFIG, cache=cache)
    assert better is not None and better.status == "replanned" and better.valid is True
    assert synchronous.status == "replanned" and synchronous.plan is not None
    assert better.plan is not None and repaired.plan is not None
    assert validate_plan(d5[0], better.plan, load_scene()).ok
    assert np.array_equal(better.plan.q, synchronous.plan.q)
    assert better.alternative == pytest.approx(repaired.plan.duration)
    assert better.cut == repaired.cut and better.resume == repaired.resume
    assert better.plan.duration < 0.99 * repaired.plan.duration


def test_no_time_left_keeps_the_repair(
    d5: tuple[Instance, PlanFile], cache: PlannerCache, repaired: ReplanOutcome
) -> None:
    """The arms are past every cut point of the repair before a solve could end: none."""
    gone = Arrival(time.perf_counter() - 1000.0, repaired.resume)
    assert improve(d5[0], repaired, gone, config=CONFIG, cache=cache) is None


def _out_of_time(
    monkeypatch: pytest.MonkeyPatch, calls: list[tuple[float, float]]
) -> None:  # fmt: skip
    """Every fresh solve made to run out of its time; ``calls``: (start, budget) of each."""

    def out_of_time(world, config, instance, prefix, *a, **k):  # type: ignore[no-untyped-def]
        calls.append((float(prefix.t[-1]), config.max_time))
        return Fresh(None, (), "timeout")

    monkeypatch.setattr(replan_moving, "fresh_continuation", out_of_time)


def test_a_solve_out_of_time_is_tried_again_from_a_later_cut_point(
    d5: tuple[Instance, PlanFile], cache: PlannerCache, repaired: ReplanOutcome,
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    """The arms far away, each solve limited by the re-plan's time limit: the next starts from
    a later cut point (one not at grasps), at most ``TRIES`` solves in all."""
    calls: list[tuple[float, float]] = []
    _out_of_time(monkeypatch, calls)
    later = Arrival(time.perf_counter() + 1000.0, repaired.resume)
    assert improve(d5[0], repaired, later, config=CONFIG, cache=cache) is None
    assert 1 < len(calls) <= replan_moving.TRIES
    assert repaired.plan is not None
    last = calls[-1][0]  # the end of the last try's hold: no clear cut point after it, or
    assert len(calls) == replan_moving.TRIES or (  # no more tries
        replan_moving._next_cut(repaired.plan, last + 1e-6, later, 0.0) is None
    )
    starts = [c[0] for c in calls]
    assert starts == sorted(starts) and len(set(starts)) == len(starts)
    assert all(0.0 < budget <= CONFIG.max_time for _, budget in calls)


def test_a_later_try_leaves_twice_the_time(
    d5: tuple[Instance, PlanFile], cache: PlannerCache, repaired: ReplanOutcome,
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    """The arms on their way now (the repair given at once): the first solve starts at the
    first cut point they reach at least ``MIN_BUDGET`` + ``RESERVE`` from now, each next one
    where they leave it twice the time the last had."""
    calls: list[tuple[float, float]] = []
    _out_of_time(monkeypatch, calls)
    now = dataclasses.replace(repaired, latency=0.0)
    moving = Arrival(time.perf_counter(), repaired.resume)
    assert improve(d5[0], now, moving, config=CONFIG, cache=cache) is None
    assert 2 <= len(calls) <= replan_moving.TRIES
    budgets = [c[1] for c in calls]
    assert budgets[0] >= replan_moving.MIN_BUDGET
    assert all(b >= 2.0 * a for a, b in itertools.pairwise(budgets))
    assert [c[0] for c in calls] == sorted(c[0] for c in calls)


@pytest.mark.parametrize("failure", ["infeasible", "longer"])
def test_an_infeasible_or_longer_fresh_continuation_keeps_the_repair(
    d5: tuple[Instance, PlanFile], cache: PlannerCache, repaired: ReplanOutcome,
    monkeypatch: pytest.MonkeyPatch, failure: str,
) -> None:  # fmt: skip
    """No plan (not a timeout: no later try), or one no shorter than the repair: none."""
    assert repaired.plan is not None
    same = Fresh(repaired.plan, ())
    made = Fresh(None, (), "infeasible") if failure == "infeasible" else same
    monkeypatch.setattr(replan_moving, "fresh_continuation", lambda *a, **k: made)
    later = Arrival(time.perf_counter() + 1000.0, repaired.resume)
    assert improve(d5[0], repaired, later, config=CONFIG, cache=cache) is None


def test_the_generator_gives_the_repair_first(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    """The first outcome is the repair without the comparison (its latency that of
    ``replan(..., compare=False)``); a second, if any, a shorter valid plan with the same
    executed prefix; an unchanged plan (nothing observed) gives one outcome only."""
    outs = list(replan_while_moving(*d5, AT, _o4_nudged(d5), config=CONFIG, cache=cache,
                                    look=0.0))  # fmt: skip
    assert 1 <= len(outs) <= 2
    assert outs[0].status == "repaired" and outs[0].changed and outs[0].valid is True
    first = outs[0].plan
    assert first is not None
    for out in outs[1:]:
        assert out.status == "replanned" and out.valid is True and out.plan is not None
        assert out.plan.duration < 0.99 * first.duration
        assert out.latency >= outs[0].latency
        assert np.array_equal(out.plan.q[out.plan.t <= out.resume],
                              first.q[first.t <= out.resume])  # fmt: skip
    same = list(replan_while_moving(*d5, AT, ObservedState(), config=CONFIG, cache=cache))
    assert len(same) == 1 and same[0].status == "repaired" and not same[0].changed


def test_no_fresh_solve_starts_where_the_arms_stand_at_grasps(repaired: ReplanOutcome) -> None:
    """The repaired plan's cut points include instants of grasps (arms at rest, fingers open
    around the objects); the fresh continuations start only at the others."""
    plan = repaired.plan
    assert plan is not None
    raw: list[Cut] = []
    t = repaired.resume
    while (cut := cut_point(plan, t)).t < plan.duration - 1e-9:
        raw.append(cut)
        t = cut.t + 1e-6
    grasping = [c for c in raw if at_grasps(plan, c)]
    assert grasping and all(
        any(e.type == "grasp" and abs(e.t - c.t) < 1e-9 for e in plan.events) for c in grasping
    )
    chosen = _clear_cuts(repaired)
    assert chosen == [c for c in raw if not at_grasps(plan, c)] and chosen


def _clear_cuts(repaired: ReplanOutcome) -> list[Cut]:
    """The cut points a fresh continuation of ``repaired`` may start from, the arms far."""
    assert repaired.plan is not None
    far = Arrival(time.perf_counter() + 1000.0, repaired.resume)
    chosen: list[Cut] = []
    t = repaired.resume
    while (nxt := replan_moving._next_cut(repaired.plan, t, far, 0.0)) is not None:
        chosen.append(nxt)
        t = nxt.t + 1e-6
    return chosen


def test_latencies_and_deadlines_follow_the_configuration_s_clock(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    """A clock that stands still (``config.sdar.clock``): every latency is 0 on it, and the
    arms, timed on it, reach no cut point before a solve ends: the fresh continuation from
    the cut replaces the repair, as with time to spare."""
    frozen = CONFIG.replace(sdar=dataclasses.replace(CONFIG.sdar, clock=lambda: 100.0))
    outs = list(replan_while_moving(*d5, AT, _o4_nudged(d5), config=frozen, cache=cache))
    assert [o.status for o in outs] == ["repaired", "replanned"]
    assert [o.latency for o in outs] == [0.0, 0.0]
    assert outs[1].plan is not None and outs[1].valid is True
    synchronous = replan(*d5, AT, _o4_nudged(d5), config=CONFIG, cache=cache)
    assert synchronous.plan is not None
    assert np.array_equal(outs[1].plan.q, synchronous.plan.q)


def test_arms_standing_at_the_cut_may_wait_the_look_for_a_fresh_continuation(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    """The observation came in 1 s ago (on a clock that stands still), the arms stand at the
    cut: within a look of 10 s the fresh continuation from the cut is given first, instead of
    the repair (the comparison before returning keeps the same plan); when the repair took
    5 s, a look of 1 s is less than a solve of the objects left is expected to take: the
    repair is given first."""
    frozen = CONFIG.replace(sdar=dataclasses.replace(CONFIG.sdar, clock=lambda: 100.0))
    nudged = _o4_nudged(d5)
    outs = list(replan_while_moving(*d5, AT, nudged, config=frozen, cache=cache,
                                    observed_at=99.0, look=10.0))  # fmt: skip
    synchronous = replan(*d5, AT, nudged, config=CONFIG, cache=cache)
    assert [o.status for o in outs] == ["replanned"] and outs[0].latency == 1.0
    assert outs[0].plan is not None and synchronous.plan is not None and outs[0].valid is True
    assert np.array_equal(outs[0].plan.q, synchronous.plan.q)
    late = list(replan_while_moving(*d5, AT, nudged, config=frozen, cache=cache,
                                    observed_at=95.0, look=1.0))  # fmt: skip
    assert late[0].status == "repaired" and late[0].changed
    assert replan_moving._worth_a_look(late[0], 1.0, 10.0)
    assert not replan_moving._worth_a_look(late[0], 5.0, 1.0)
