"""Asynchronous execution: schedules of solved instances replay as valid, are never longer
than the synchronous plan, and the separation the scheduler keeps is needed (without it the
validator rejects the plan)."""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.app import execution
from sdar_tamp.app.execution import execution_options, schedule_and_validate, schedule_plan
from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import GRIPPER_DWELL, PlanFile
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_rules import STILL_TOL, check_timeline
from sdar_tamp.plan_writing import save_plan
from sdar_tamp.replay import ReplayReport, validate_plan
from sdar_tamp.replay_sampling import tcp_subdivisions
from sdar_tamp.schedule import ScheduleOptions, schedule_async
from sdar_tamp.schedule import sweep as sweep_module
from sdar_tamp.schedule.pieces import arm_blocks, arm_columns, on_ticks
from sdar_tamp.schedule.scheduler import Placement, Schedule, groups
from sdar_tamp.schedule.spline import ClampedSpline, retime
from sdar_tamp.schedule.sweep import Conflict, TimedEvent, WorldSweep
from sdar_tamp.world.instance import Instance, load_instance
from sdar_tamp.world.suites import shipped_suite_dir
from sdar_tamp.world.transforms import FloatArray
from streams.context import WorldContext


@dataclass(frozen=True)
class Solved:
    ctx: WorldContext
    instance: Instance
    plan: PlanFile


#: The synchronous SDAR plans these tests schedule, solved once and shipped (see
#: ``solved/regenerate.py``): the scheduler is under test here, not the planner.
SOLVED = Path(__file__).resolve().parent / "solved"


def _solved(ctx: WorldContext, name: str) -> Solved:
    instance = load_instance(shipped_suite_dir("paper") / f"{name}.yaml")
    plan = load_plan(SOLVED / f"{name}.plan.json")
    assert validate_plan(instance, plan, ctx.scene).ok  # still a plan of today's instance
    return Solved(ctx, instance, plan)


@pytest.fixture(scope="module")
def uneven(ctx: WorldContext) -> Solved:
    """Five independent objects of the paper suite (four paired moves, then one arm alone):
    the arms' motions differ in length, so running each arm on its own timeline saves time."""
    return _solved(ctx, "R5")


@pytest.fixture(scope="module")
def swap(ctx: WorldContext) -> Solved:
    """Five objects of the paper suite, two swaps among them: the arms cross each other's
    paths holding objects, so they must move at the same time."""
    return _solved(ctx, "D5")


def _dwell_overlaps(plan: PlanFile) -> int:
    """Events during whose dwell the other arm moves (impossible in a synchronous plan)."""
    count = 0
    for e in plan.events:
        other = arm_columns(plan, 1 - plan.arm_names.index(e.arm))
        inside = (plan.t >= e.t) & (plan.t <= e.t + GRIPPER_DWELL)
        count += bool(np.abs(np.diff(plan.q[inside][:, other], axis=0)).max() > STILL_TOL)
    return count


# -- the schedule -----------------------------------------------------------------------------
def test_an_async_plan_validates_and_is_shorter(uneven: Solved, tmp_path: Path) -> None:
    scene = uneven.ctx.scene
    s = schedule_async(uneven.plan, uneven.instance, scene, execution_options(scene))
    assert s.asynchronous, s.reason
    assert s.async_duration is not None and s.async_duration < s.sync_duration
    assert s.plan.duration == pytest.approx(s.async_duration)
    assert s.plan.metrics.execution == "async"
    assert s.plan.metrics.execution_time == pytest.approx(s.plan.duration)
    assert _dwell_overlaps(s.plan) >= 1  # one arm moves while the other's gripper acts
    assert _dwell_overlaps(uneven.plan) == 0
    # the same events per object, in the same order per object
    for name in uneven.instance.names:
        sync = [(e.arm, e.type) for e in uneven.plan.events if e.object == name]
        assert [(e.arm, e.type) for e in s.plan.events if e.object == name] == sync
    report = validate_plan(uneven.instance, s.plan, uneven.ctx.scene)
    assert report.ok, report.violation
    path = save_plan(s.plan, tmp_path / "async.json")  # the file format round trip
    assert validate_plan(uneven.instance, load_plan(path), uneven.ctx.scene).ok


def test_the_synchronous_pace_and_every_ordering_validate(uneven: Solved) -> None:
    for options in (
        ScheduleOptions(retime=False),
        ScheduleOptions(orders=("events",)),
        ScheduleOptions(orders=("objects",)),
    ):
        s = schedule_async(uneven.plan, uneven.instance, uneven.ctx.scene, options)
        assert s.plan.duration <= uneven.plan.duration
        if s.asynchronous:
            assert s.order in options.orders
            report = validate_plan(uneven.instance, s.plan, uneven.ctx.scene)
            assert report.ok, (options, report.violation)


def test_a_crossing_swap_keeps_its_arms_apart(swap: Solved) -> None:
    """The two arms cross each other's paths: the schedule is never longer and valid."""
    s = schedule_async(swap.plan, swap.instance, swap.ctx.scene)
    assert s.plan.duration <= swap.plan.duration
    assert validate_plan(swap.instance, s.plan, swap.ctx.scene).ok


class _Blind(WorldSweep):
    """A mutant of the scheduler's replay that sees no conflict (no separation kept)."""

    def run(self, k0: int, q: FloatArray, events: list[TimedEvent]) -> Conflict | None:  # type: ignore[override]
        return None


@pytest.fixture(scope="module")
def crowded(ctx: WorldContext) -> Solved:
    """Twelve objects of the paper suite (mixed family): the arms work close to each other."""
    return _solved(ctx, "M2")


def test_without_the_separation_the_validator_rejects_the_schedule(crowded: Solved) -> None:
    """With a replay that sees no conflict, the scheduler pulls the arms' blocks together
    until they touch; the validator's replay sees it."""
    scene, options = crowded.ctx.scene, ScheduleOptions()
    blocks = [arm_blocks(crowded.plan, scene, i, options.tick) for i in range(2)]
    blind = _Blind(crowded.instance, scene, options.max_tcp_step)
    mutant = Placement(crowded.plan, blocks, blind, options, "objects").run()
    assert check_timeline(mutant, scene) is None  # limits and dwells still hold
    report = validate_plan(crowded.instance, mutant, scene)
    assert not report.ok and report.violation is not None
    assert report.violation.kind == "collision"
    names = report.violation.message
    assert "left" in names and "right" in names  # the two arms (or what they hold) touch


def test_a_per_arm_dwell_violation_is_rejected(uneven: Solved) -> None:
    scene = uneven.ctx.scene
    plan = schedule_async(uneven.plan, uneven.instance, scene, execution_options(scene)).plan
    e = next(
        e
        for e in plan.events
        if np.abs(
            np.diff(
                plan.q[(plan.t >= e.t) & (plan.t <= e.t + GRIPPER_DWELL)][
                    :, arm_columns(plan, 1 - plan.arm_names.index(e.arm))
                ],
                axis=0,
            )
        ).max()
        > STILL_TOL
    )
    k = int(np.searchsorted(plan.t, e.t))
    mine = arm_columns(plan, plan.arm_names.index(e.arm))
    q = np.array(plan.q)
    bump = 1e-4 * np.sin(np.linspace(0.0, np.pi, 26)) ** 2
    q[k : k + 26, mine.start] += bump  # the arm of the event moves during its dwell
    report = validate_plan(uneven.instance, dataclasses.replace(plan, q=q), uneven.ctx.scene)
    assert not report.ok and report.violation is not None
    assert report.violation.kind == "dwell" and e.arm in report.violation.message
    assert validate_plan(uneven.instance, plan, uneven.ctx.scene).ok  # the other arm moving is fine


# -- the parts --------------------------------------------------------------------------------
def test_spline_bounds_are_the_true_peaks() -> None:
    t = np.linspace(0.0, 1.0, 25)
    q = np.stack([np.sin(3 * t), t**3 - t], axis=1)
    q[0], q[-1] = q[0], q[-1]
    s = ClampedSpline.fit(t, q)
    x = np.linspace(0.0, 1.0, 200_001)
    y = s(x)
    h = x[1] - x[0]
    v = np.abs(np.diff(y, axis=0) / h).max(axis=0)
    a = np.abs(np.diff(y, 2, axis=0) / h**2).max(axis=0)
    assert np.allclose(s(t), q)
    assert np.allclose(v, s.peak_velocity(), rtol=1e-4)
    assert np.allclose(a, s.peak_acceleration(), rtol=1e-3)


def _divided_differences(x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Velocities and accelerations as the plan rules measure them (at rest outside)."""
    h = np.diff(x)
    vel = np.diff(y, axis=0) / h[:, None]
    rest = np.zeros((1, y.shape[1]))
    h_ext = np.concatenate([h[:1], h, h[-1:]])
    acc = np.diff(np.concatenate([rest, vel, rest]), axis=0)
    return vel, acc / (0.5 * (h_ext[1:] + h_ext[:-1]))[:, None]


def test_retimed_samples_meet_the_limits_on_any_grid() -> None:
    t = np.linspace(0.0, 2.0, 101)
    q = np.stack([0.5 * (1 - np.cos(np.pi * t / 2.0)), 0.1 * np.sin(np.pi * t / 2.0) ** 2], 1)
    v_max, a_max = np.array([1.0, 1.0]), np.array([2.0, 2.0])
    out = retime(t, q, v_max, a_max, 0.02)
    assert np.array_equal(out[0], q[0]) and np.array_equal(out[-1], q[-1])
    assert len(out) - 1 < 100  # faster than the original 2 s
    vel, acc = _divided_differences(np.arange(len(out)) * 0.02, out)
    use = max((np.abs(vel) / v_max).max(), np.sqrt((np.abs(acc) / a_max).max()))
    assert use == pytest.approx(1.0, rel=0.05)  # one limit is (nearly) reached
    spline = ClampedSpline.fit(t, q)
    T = (len(out) - 1) * 0.02
    rng = np.random.default_rng(0)
    for x in (
        np.union1d(np.arange(0.0, T, 0.013), [T]),
        np.union1d(np.sort(rng.uniform(0.0, T, 400)), [0.0, T]),
    ):
        y = spline(x * spline.duration / T)  # the same motion sampled on another grid
        vel, acc = _divided_differences(x, y)
        assert np.all(np.abs(vel) <= v_max * (1 + 1e-6))
        assert np.all(np.abs(acc) <= a_max * (1 + 1e-6))
    slow = retime(t, q, v_max, a_max, 0.02, max_rate=1.0)
    assert len(slow) - 1 == 100  # never faster than the original


def test_on_ticks_keeps_the_samples_when_no_step_exceeds_the_tick() -> None:
    t = np.array([0.0, 0.019, 0.038, 0.057])
    q = np.arange(24.0).reshape(4, 6)
    assert np.array_equal(on_ticks(t, q, 0.02, np.ones(6), np.ones(6)), q)


def test_options_are_checked() -> None:
    for kwargs in (
        {"tick": 0.0},
        {"tick": 0.03},
        {"max_tcp_step": 0.0},
        {"dwell": -1.0},
        {"max_wait": float("nan")},
        {"orders": ()},
        {"orders": ("fifo",)},
        {"max_checks": 0},
        {"max_checks": True},
        {"straight": 0.0},
        {"grasp_speed": float("inf")},
    ):
        with pytest.raises(ParameterError):
            ScheduleOptions(**kwargs)  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match="tick"):
        retime(np.array([0.0, 1.0]), np.zeros((2, 1)), np.ones(1), np.ones(1), -1.0)
    with pytest.raises(ParameterError, match="increasing"):
        ClampedSpline.fit(np.array([0.0, 0.0]), np.zeros((2, 1)))


# -- per-arm time-optimal re-timing, the group search, the fallbacks ------------------------
def test_the_time_optimal_schedule_is_valid_and_beats_the_uniform_one(uneven: Solved) -> None:
    scene = uneven.ctx.scene
    fast = schedule_plan(uneven.plan, uneven.instance, scene)
    uniform = schedule_async(uneven.plan, uneven.instance, scene)
    assert fast.asynchronous, fast.reason
    assert fast.plan.duration < uniform.plan.duration <= uneven.plan.duration
    report = validate_plan(uneven.instance, fast.plan, scene)
    assert report.ok, report.violation
    assert _dwell_overlaps(fast.plan) >= 1


def test_a_crowded_schedule_is_never_longer_and_keeps_the_arms_apart(crowded: Solved) -> None:
    """Twelve objects, the arms close together: whatever the search falls back to, the plan
    is never longer than the synchronous one and the replay finds no collision."""
    s = schedule_plan(crowded.plan, crowded.instance, crowded.ctx.scene)
    assert s.plan.duration <= crowded.plan.duration
    report = validate_plan(crowded.instance, s.plan, crowded.ctx.scene)
    assert report.ok, report.violation


def test_groups_hold_the_blocks_that_overlapped(uneven: Solved) -> None:
    options = execution_options(uneven.ctx.scene)
    blocks = [arm_blocks(uneven.plan, uneven.ctx.scene, i, options.tick) for i in range(2)]
    found = groups(blocks)
    assert sorted(id(b) for g in found for b in g) == sorted(id(b) for a in blocks for b in a)
    for g in found:  # in the order they ended in the synchronous plan
        assert [b.sync_key for b in g] == sorted(b.sync_key for b in g)
    for a, b in itertools.pairwise(found):  # in time order, apart
        assert max(x.sync_key for x in a) < min(x.sync_start for x in b)
    assert any(len({b.arm for b in g}) == 2 for g in found)  # both arms moved together


def test_past_the_search_budget_the_steps_keep_their_synchronous_pace(uneven: Solved) -> None:
    scene = uneven.ctx.scene
    full = schedule_async(uneven.plan, uneven.instance, scene, execution_options(scene))
    options = dataclasses.replace(execution_options(scene), max_checks=1)
    s = schedule_async(uneven.plan, uneven.instance, scene, options)
    assert s.checks < full.checks
    assert s.plan.duration <= uneven.plan.duration
    assert s.async_duration is not None and s.async_duration > full.plan.duration
    assert validate_plan(uneven.instance, s.plan, scene).ok


def test_a_schedule_the_replay_rejects_is_dropped(
    uneven: Solved, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A scheduler whose result moves an arm during its own dwell: the application replays
    it, keeps the synchronous plan and says why."""
    scene = uneven.ctx.scene
    good = schedule_plan(uneven.plan, uneven.instance, scene)
    e = good.plan.events[0]
    k = int(np.searchsorted(good.plan.t, e.t))
    q = np.array(good.plan.q)
    q[k + 1 : k + 5, arm_columns(good.plan, good.plan.arm_names.index(e.arm)).start] += 1e-3
    bad = dataclasses.replace(good, plan=dataclasses.replace(good.plan, q=q))

    def broken(*args: object, **kwargs: object) -> Schedule:
        return bad

    monkeypatch.setattr("sdar_tamp.app.execution.schedule_async", broken)
    s = schedule_plan(uneven.plan, uneven.instance, scene)
    assert not s.asynchronous and s.plan is uneven.plan
    assert "replay rejects" in s.reason
    # with its report: the one on the synchronous plan kept, which the replay accepts
    replayed: list[PlanFile] = []
    real = execution.validate_plan

    def counting(instance: Instance, plan: PlanFile, *args: object) -> ReplayReport:
        replayed.append(plan)
        return real(instance, plan, *args)  # type: ignore[arg-type]

    monkeypatch.setattr("sdar_tamp.app.execution.validate_plan", counting)
    s, report = schedule_and_validate(uneven.plan, uneven.instance, scene)
    assert s.plan is uneven.plan and report.ok
    assert replayed == [bad.plan, uneven.plan]


def test_a_kept_schedule_is_replayed_once_and_its_report_returned(uneven: Solved) -> None:
    stages: list[str] = []
    s, report = schedule_and_validate(
        uneven.plan, uneven.instance, uneven.ctx.scene, stage=stages.append
    )
    assert s.asynchronous and report.ok and stages == ["validating"]
    assert report.checks > 0


def test_replaying_known_events_skips_the_free_spot_test_a_new_release_takes(
    uneven: Solved,
) -> None:
    """``reset`` replays events already placed (valid by construction) without testing their
    landing spots again; a release checked in a stretch still has its spot tested."""
    scene, plan = uneven.ctx.scene, uneven.plan
    sweep = WorldSweep(uneven.instance, scene, ScheduleOptions().max_tcp_step)

    def timed(event_index: int, q_from: int | None = None) -> TimedEvent:
        e = plan.events[event_index]
        k = int(np.searchsorted(plan.t, (plan.events[q_from] if q_from is not None else e).t))
        return TimedEvent(k, e, scene.layout.part(plan.q[k], e.arm))

    # left grasps o2, then "releases" it with its arm where it later grasps o0 (o0 rests there)
    grasp = timed(0)
    later = next(i for i, e in enumerate(plan.events) if e.arm == "left" and e.object == "o0")
    onto_o0 = timed(2, q_from=later)
    sweep.reset([])
    assert sweep.apply(grasp) is None
    conflict = sweep.apply(onto_o0)
    assert conflict is not None and conflict.kind == "release"
    assert "o2 released onto o0" in conflict.message
    sweep.reset([grasp, onto_o0])  # no test: the world takes the events as given
    assert "o2" in sweep.rest and "o2" not in {o for o, _ in sweep.held.values()}


def test_the_sweep_remembers_collision_answers_per_arrangement(
    uneven: Solved, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A configuration checked again in the same arrangement is not checked again; after an
    event changes the arrangement it is, and a reset to an earlier arrangement reuses that
    arrangement's answers."""
    scene, plan = uneven.ctx.scene, uneven.plan
    sweep = WorldSweep(uneven.instance, scene, ScheduleOptions().max_tcp_step)
    asked: list[bytes] = []
    real = sweep.world.in_collision

    def counting(q: FloatArray | None = None) -> bool:
        asked.append(np.asarray(q).tobytes())
        return real(q)

    monkeypatch.setattr(sweep.world, "in_collision", counting)
    e = plan.events[0]
    k = int(np.searchsorted(plan.t, e.t))
    grasp = TimedEvent(k, e, scene.layout.part(plan.q[k], e.arm))
    q = plan.q[k - 10]
    sweep.reset([])
    first = sweep.collide(q, 0)
    sweep.collide(q, 0)
    assert len(asked) == 1 and sweep.checks == 2  # the second answer from memory, still counted
    assert sweep.apply(grasp) is None  # o2 now held: another arrangement
    sweep.collide(q, 0)
    assert len(asked) == 2
    sweep.reset([])  # back to the first arrangement: its answers are remembered
    assert sweep.collide(q, 0) == first
    assert len(asked) == 2


def test_the_sweep_subdivides_as_the_replay_and_remembers_intervals(uneven: Solved) -> None:
    """The sweep's subdivision of a stretch is the replay's (:func:`tcp_subdivisions`), also
    for a stretch overlapping one replayed before (its intervals then come from memory), and
    once the memory is full and starts again."""
    scene = uneven.ctx.scene
    sweep = WorldSweep(uneven.instance, scene, 0.005)
    q = uneven.plan.q
    for a, b in ((0, 120), (60, 200), (0, 200)):
        stretch = q[a:b]
        expected = tcp_subdivisions(stretch, sweep.kins, scene.layout, 0.005)
        assert sweep.subdivisions(stretch) == expected.tolist()
    assert len(sweep._intervals) == len({q[k : k + 2].tobytes() for k in range(199)})
    small = sweep_module.SWEEP_INTERVALS
    try:
        sweep_module.SWEEP_INTERVALS = 150
        expected = tcp_subdivisions(q[150:300], sweep.kins, scene.layout, 0.005)
        assert sweep.subdivisions(q[150:300]) == expected.tolist()
        assert len(sweep._intervals) <= 150
    finally:
        sweep_module.SWEEP_INTERVALS = small
