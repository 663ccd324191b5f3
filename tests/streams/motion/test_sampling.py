"""The sampling-based transfer (OMPL RRTConnect): collision-free, validated, optional."""

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.collision import ObjectBox
from streams.context import WorldContext
from streams.motion import sampling
from streams.motion.exact_check import configure_world, validate_trajectory
from streams.motion.ladder import plan_dual_motion
from streams.motion.planner import MotionPlanner
from streams.motion.records import MotionRequest, MotionTally
from streams.motion.sampling import (
    OmplUnavailableError,
    SampledStrategy,
    SamplingOptions,
    sample_path,
)

# Two grasp configurations in M1 whose straight synchronous transfer is blocked (as in
# test_motion_planner.py).
BLOCKED_START = np.array([-0.9597713794940521, -1.487539072672206, 2.2951842532166142,
    -2.3784415073393053, -1.5707963267948966, 0.6482225313692203, -0.5339339743344569,
    -0.675777200007472, 1.1304521182278542, -1.6688772479994611, -0.8550081079150917,
    -0.5163163995987907])  # fmt: skip
BLOCKED_GOAL = np.array([0.04376532233356345, -0.9655976891109983, 1.5288636436242042,
    -2.1340622813081023, -1.5707963267948966, 1.221061045296719, 0.2352577772079112,
    -1.4271827367975796, 2.22417797686042, -2.3677915668577363, -1.5707963267948966,
    1.0782072680107593])  # fmt: skip

needs_ompl = pytest.mark.skipif(not sampling.ompl_available(), reason="OMPL not installed")


def _blocked(objects: dict[str, ObjectBox]) -> MotionRequest:
    # the fixed 8 cm lift the blocked configurations were found with
    return MotionRequest(BLOCKED_START, BLOCKED_GOAL, objects, retreat=(True, True),
                         approach=(True, True), lift=0.08)  # fmt: skip


def _blocked_transfer(
    ctx: WorldContext, planner: MotionPlanner, objects: dict[str, ObjectBox]
) -> tuple[MotionRequest, np.ndarray, np.ndarray]:
    """The blocked request with both worlds configured, and its transfer's ends (after the
    retreat, before the approach)."""
    request = _blocked(objects)
    configure_world(ctx, planner.world, objects, {}, BLOCKED_START)
    configure_world(ctx, planner.margin_world, objects, {}, BLOCKED_START)
    retreat, approach = planner.phases(request) or (None, None)
    assert retreat is not None and approach is not None
    return request, retreat[-1][-1], approach[0][0]


@needs_ompl
def test_sampled_path_is_collision_free_where_the_straight_line_is_not(
    ctx: WorldContext, planner: MotionPlanner, objects: dict[str, ObjectBox]
) -> None:
    _, q_a, q_b = _blocked_transfer(ctx, planner, objects)
    straight = np.linspace(0.0, 1.0, 30)[:, None] * (q_b - q_a)[None] + q_a[None]
    assert not validate_trajectory(ctx, planner.world, straight).ok
    W = sample_path(planner.transfers(), q_a, q_b)
    assert W is not None and len(W) >= 3
    np.testing.assert_allclose(W[[0, -1]], np.stack([q_a, q_b]))
    for k in range(len(W)):  # every waypoint is clear, with the margin
        assert not planner.margin_world.in_collision(W[k])
    # a waiting arm stays where it is
    layout = ctx.layout
    q_b2 = layout.replace(q_b, "left", layout.part(q_a, "left"))
    W2 = sample_path(planner.transfers(), q_a, q_b2)
    assert W2 is not None and np.allclose(layout.part(W2, "left"), layout.part(q_a, "left"))
    # a goal in collision ends at once (RRTConnect alone would wait for a valid goal)
    q_bad = layout.replace(q_b, "right", layout.part(q_a, "right"))
    assert planner.margin_world.in_collision(q_bad)
    assert sample_path(planner.transfers(), q_a, q_bad) is None


@needs_ompl
def test_a_query_gives_the_same_path_whatever_ran_before_it(
    ctx: WorldContext, planner: MotionPlanner, objects: dict[str, ObjectBox]
) -> None:
    configure_world(ctx, planner.margin_world, objects, {}, BLOCKED_START)
    retreat, approach = planner.phases(_blocked(objects)) or (None, None)
    assert retreat is not None and approach is not None
    q_a, q_b = retreat[-1][-1], approach[0][0]
    first = sample_path(planner.transfers(), q_a, q_b)
    other = sample_path(planner.transfers(), q_b, q_a)  # advances OMPL's process-wide sequence
    again = sample_path(planner.transfers(), q_a, q_b)
    assert first is not None and other is not None and again is not None
    np.testing.assert_array_equal(first, again)
    reseeded = sample_path(planner.transfers(), q_a, q_b, SamplingOptions(seed=1))
    assert reseeded is not None and not np.array_equal(reseeded, first)
    assert sampling.query_seed(0, q_a, q_b) == sampling.query_seed(0, q_a.copy(), q_b.copy())
    assert sampling.query_seed(0, q_a, q_b) != sampling.query_seed(0, q_b, q_a)
    assert all(1 <= sampling.query_seed(s, q_a, q_b) < 2**31 for s in (0, 1, 2**40))


@needs_ompl
def test_sampled_strategy_plans_a_validated_motion(
    ctx: WorldContext, planner: MotionPlanner, objects: dict[str, ObjectBox]
) -> None:
    request = _blocked(objects)
    result = plan_dual_motion(planner, request, strategies=[SampledStrategy()])
    assert result.success and result.level == "sampled" and result.sampled_paths == 1
    assert result.ipopt_solves == 0 and result.trajectory is not None
    check = ctx.new_world()
    configure_world(ctx, check, objects, {}, BLOCKED_START)
    assert validate_trajectory(ctx, check, result.trajectory.q).ok
    ladder = sampling.sampled_strategies()
    assert [s.name for s in ladder] == ["plain", "untangle", "sequential"]
    assert isinstance(ladder[0], SampledStrategy) and ladder[0].refine
    combined = plan_dual_motion(planner, request, strategies=ladder)
    assert combined.success and combined.trajectory is not None
    assert combined.direct_paths + combined.sampled_paths >= 1


def test_sampling_options_are_checked() -> None:
    with pytest.raises(ParameterError, match="max_checks must be >= 1, got 0"):
        SamplingOptions(max_checks=0)
    with pytest.raises(ParameterError, match=r"resolution must be > 0 \[rad\], got 0.0"):
        SamplingOptions(resolution=0.0)
    with pytest.raises(ParameterError, match=r"range must be >= 0 \[rad\]"):
        SamplingOptions(range=-1.0)
    with pytest.raises(ParameterError, match="seed must be >= 0"):
        SamplingOptions(seed=-1)


def test_missing_ompl_is_a_clear_error(
    ctx: WorldContext, planner: MotionPlanner, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(sampling, "ompl_available", lambda: False)
    q = np.concatenate([ctx.home(a) for a in ctx.arm_names])
    with pytest.raises(OmplUnavailableError, match=r"pip install 'sdar-tamp\[ompl\]'"):
        sample_path(planner.transfers(), q, q + 0.1)


@needs_ompl
def test_a_sampled_path_warm_starts_the_optimiser(
    ctx: WorldContext, planner: MotionPlanner, objects: dict[str, ObjectBox]
) -> None:
    request, q_a, q_b = _blocked_transfer(ctx, planner, objects)
    problem = planner.transfer_problem(request, q_a, q_b)
    tally = MotionTally()
    path = sampling.sampled_warm_start(planner.transfers(tally), problem)
    assert path is not None and tally.sampled_paths == 1 and tally.ipopt_solves == 1
    assert path.shape == (planner.build.options.knots, len(BLOCKED_START))
    np.testing.assert_allclose(path[[0, -1]], np.stack([problem.q_from, problem.q_to]))
    # the optimised knots, not the sampled waypoints, and their timed curve is clear
    samples = SamplingOptions().curve_samples
    assert sampling.checked_waypoints(planner.transfers(), path, samples) is not None
    # no sampled path within the budget: nothing, and no optimisation
    tiny = SamplingOptions(max_checks=1)
    tally = MotionTally()
    assert sampling.sampled_warm_start(planner.transfers(tally), problem, tiny) is None
    assert tally.sampled_paths == 0 and tally.ipopt_solves == 0


class _StubPlanner:
    """Records the warm starts the plain rung asks the optimiser for."""

    def __init__(self, succeed_with: str) -> None:
        self.succeed_with = succeed_with
        self.calls: list[str] = []

    def optimise(self, problem: object, q_a: object, q_b: object, warm_start: object = None,
                 fixed: object = ()) -> np.ndarray | None:  # fmt: skip
        kind = "straight" if warm_start is None else str(warm_start)
        self.calls.append(kind)
        return np.zeros((2, 12)) if kind == self.succeed_with else None

    def lifted_via(self, q_a: object, q_b: object) -> str:
        return "lifted"


class _StubProblem:
    q_from = np.zeros(12)
    q_to = np.ones(12)


@pytest.mark.parametrize(
    ("rescue", "succeed_with", "calls"),
    [
        (True, "straight", ["straight"]),
        (True, "sampled", ["straight", "sampled"]),
        (True, "lifted", ["straight", "sampled", "lifted"]),
        (True, "nothing", ["straight", "sampled", "lifted"]),
        (False, "lifted", ["straight", "lifted"]),  # the ladder without OMPL
    ],
)
def test_the_plain_rung_tries_its_rescue_between_straight_and_lifted(
    rescue: bool, succeed_with: str, calls: list[str]
) -> None:
    from streams.motion.strategies import PlainStrategy

    stub = _StubPlanner(succeed_with)

    def sampled(planner: _StubPlanner, problem: object) -> np.ndarray | None:
        return planner.optimise(problem, None, None, "sampled")

    strategy = PlainStrategy(rescue=sampled if rescue else None)  # type: ignore[arg-type]
    result = strategy(stub, _StubProblem())  # type: ignore[arg-type]
    assert stub.calls == calls
    assert (result is None) == (succeed_with == "nothing")


def test_sdar_m_warm_starts_from_a_sampled_path_where_ompl_is_installed(
    ctx: WorldContext, planner: MotionPlanner, monkeypatch: pytest.MonkeyPatch
) -> None:
    from streams import motion_streams, stream_map
    from streams.motion.strategies import PlainStrategy

    ladder = sampling.warm_started_strategies(options=SamplingOptions(seed=3))
    assert [s.name for s in ladder] == ["plain", "untangle", "sequential"]
    first = ladder[0]
    assert isinstance(first, PlainStrategy) and first.rescue is not None
    assert first.rescue.keywords == {"options": SamplingOptions(seed=3)}  # type: ignore[attr-defined]
    assert len(sampling.warm_started_strategies(fallbacks=False)) == 1
    streams = stream_map.RearrangementStreams(ctx, {}, planner=planner)
    assert streams.sampling == sampling.ompl_available()
    assert not stream_map.RearrangementStreams(ctx, {}, planner=planner, sampling=False).sampling
    monkeypatch.setattr(motion_streams, "ompl_available", lambda: False)
    assert not stream_map.RearrangementStreams(ctx, {}, planner=planner).sampling
    with pytest.raises(OmplUnavailableError, match=r"sampling=True: .*pip install"):
        stream_map.RearrangementStreams(ctx, {}, planner=planner, sampling=True)
