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
from sdar_tamp.app.replan_moving import Arrival, improve, replan_while_moving
from sdar_tamp.app.replan_starts import Start, at_grasps, next_start
from sdar_tamp.app.replanning import Fresh, ReplanOutcome, replan
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_state import Cut, cut_point
from sdar_tamp.replay import validate_plan
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.observed import ObservedState
from sdar_tamp.world.scene import load_scene
from tests.app.conftest import CONFIG, O4_AT, o4_nudged

AT = O4_AT


@pytest.fixture(scope="module")
def repaired(d5: tuple[Instance, PlanFile], cache: PlannerCache) -> ReplanOutcome:
    out = replan(*d5, AT, o4_nudged(d5), config=CONFIG, cache=cache, compare=False)
    assert out.status == "repaired" and out.changed and out.valid is True
    return out


def test_with_time_to_spare_the_fresh_continuation_from_the_cut_replaces_the_repair(
    d5: tuple[Instance, PlanFile], cache: PlannerCache, repaired: ReplanOutcome
) -> None:
    """The arms reach the cut long after the solve ends: the fresh continuation starts at the
    cut itself, the same plan as the comparison before returning keeps."""
    later = Arrival(time.perf_counter() + 1000.0, repaired.resume)
    better = improve(d5[0], repaired, later, config=CONFIG, cache=cache)
    synchronous = replan(*d5, AT, o4_nudged(d5), config=CONFIG, cache=cache)
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


def test_a_solve_out_of_time_is_tried_again_from_a_later_start(
    d5: tuple[Instance, PlanFile], cache: PlannerCache, repaired: ReplanOutcome,
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    """The arms far away, each solve limited by the re-plan's time limit: the next starts
    later (a clear cut not at grasps, or a braked stop), from a state no try had: at most
    ``TRIES`` solves in all, until no start is left with a grasp after it."""
    calls: list[tuple[float, float]] = []
    _out_of_time(monkeypatch, calls)
    later = Arrival(time.perf_counter() + 1000.0, repaired.resume)
    assert improve(d5[0], repaired, later, config=CONFIG, cache=cache) is None
    assert 1 < len(calls) <= replan_moving.TRIES
    assert repaired.plan is not None
    ends = [c[0] for c in calls]  # the end of each try's prefix
    assert ends == sorted(ends) and len(set(ends)) == len(ends)
    clear = [float(c.prefix.t[-1]) for c in _starts(d5[0], repaired)]
    assert ends[0] == clear[0] and set(clear) <= set(ends) | {e for e in clear if e > ends[-1]}
    assert all(0.0 < budget <= CONFIG.max_time for _, budget in calls)


def test_a_later_try_leaves_twice_the_time_per_object(
    d5: tuple[Instance, PlanFile], cache: PlannerCache, repaired: ReplanOutcome,
    monkeypatch: pytest.MonkeyPatch,
) -> None:  # fmt: skip
    """The arms on their way now (the repair given at once, in no time: no expected time
    yet; a clock that stands still): the first solve starts where they arrive
    ``MIN_BUDGET`` + ``RESERVE`` from now (a braked stop on their way to o1 and o4), each
    next one, later, where they leave at least twice the time per object the last had."""
    calls: list[tuple[float, float]] = []
    _out_of_time(monkeypatch, calls)
    now = dataclasses.replace(repaired, latency=0.0)
    frozen = CONFIG.replace(sdar=dataclasses.replace(CONFIG.sdar, clock=lambda: 100.0))
    moving = Arrival(100.0, repaired.resume)  # on a clock that stands still
    assert improve(d5[0], now, moving, config=frozen, cache=cache) is None
    assert 2 <= len(calls) <= replan_moving.TRIES
    assert repaired.plan is not None
    budgets = [c[1] for c in calls]
    assert 0.99 * replan_moving.MIN_BUDGET <= budgets[0] < 1.0
    assert calls[0][0] < 6.99  # before the grasps of o1 and o4
    left = [replan_moving._left(repaired.plan, c[0]) for c in calls]
    per_object = [b / n for b, n in zip(budgets, left, strict=True)]
    assert all(b >= 0.99 * 2.0 * a for a, b in itertools.pairwise(per_object))
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
    ``replan(..., compare=False)``); each next one, if any, a valid plan shorter than the one
    before it (its ``alternative``), with the same executed prefix; an unchanged plan
    (nothing observed) gives one outcome only."""
    outs = list(replan_while_moving(*d5, AT, o4_nudged(d5), config=CONFIG, cache=cache,
                                    look=0.0))  # fmt: skip
    assert outs[0].status == "repaired" and outs[0].changed and outs[0].valid is True
    first = outs[0].plan
    assert first is not None
    for before, out in itertools.pairwise(outs):
        assert out.status == "replanned" and out.valid is True and out.plan is not None
        assert before.plan is not None and out.alternative == before.plan.duration
        assert out.plan.duration < 0.99 * before.plan.duration
        assert out.latency >= before.latency
        assert np.array_equal(out.plan.q[out.plan.t <= out.resume],
                              first.q[first.t <= out.resume])  # fmt: skip
    same = list(replan_while_moving(*d5, AT, ObservedState(), config=CONFIG, cache=cache))
    assert len(same) == 1 and same[0].status == "repaired" and not same[0].changed


def test_no_fresh_solve_starts_where_the_arms_stand_at_grasps(
    d5: tuple[Instance, PlanFile], repaired: ReplanOutcome
) -> None:
    """The repaired plan's cut points include instants of grasps (arms at rest, fingers open
    around the objects); the clear cuts a fresh continuation starts from are the others."""
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
    chosen = [s.t for s in _starts(d5[0], repaired)]
    assert chosen == [c.t for c in raw if not at_grasps(plan, c)] and chosen


def _starts(instance: Instance, repaired: ReplanOutcome) -> list[Start]:
    """The clear cuts a fresh continuation of ``repaired`` may start from."""
    assert repaired.plan is not None
    instance_starts = {o.name: o.start.as_tuple() for o in instance.objects}
    scene = load_scene()
    kins = {a: ArmKinematics.from_scene(scene, a) for a in scene.arm_names}
    chosen: list[Start] = []
    t = repaired.resume
    while (nxt := next_start(repaired.plan, t, instance_starts, scene, kins,
                             brakes=False)) is not None:  # fmt: skip
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
    outs = list(replan_while_moving(*d5, AT, o4_nudged(d5), config=frozen, cache=cache))
    assert [o.status for o in outs] == ["repaired", "replanned"]
    assert [o.latency for o in outs] == [0.0, 0.0]
    assert outs[1].plan is not None and outs[1].valid is True
    synchronous = replan(*d5, AT, o4_nudged(d5), config=CONFIG, cache=cache)
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
    nudged = o4_nudged(d5)
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
