"""Synchronous motions: limits, exact collision freedom, fallbacks."""

import dataclasses
from dataclasses import dataclass

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.collision import ObjectBox
from streams.context import WorldContext
from streams.grasps import sample_grasps
from streams.ik import IKRequest, compatible_pairs, solve_ik_candidates
from streams.motion.cartesian import tool_pose_ik
from streams.motion.exact_check import configure_world, validate_trajectory
from streams.motion.ladder import default_strategies, plan_dual_motion
from streams.motion.optimiser_cache import OptimiserCache
from streams.motion.optimiser_records import TransferQuery
from streams.motion.planner import MotionPlanner
from streams.motion.records import MotionRequest, TransferProblem
from streams.motion.shape import ShapeOptions, straight_end_deviation
from streams.motion.strategies import SequentialStrategy, UntangleStrategy
from streams.motion.timing import spline_curve
from streams.motion.waypoints import straight_line

# Two grasp configurations in M1 whose straight synchronous transfer is blocked (found by search).
BLOCKED_START = np.array([-0.9597713794940521, -1.487539072672206, 2.2951842532166142,
    -2.3784415073393053, -1.5707963267948966, 0.6482225313692203, -0.5339339743344569,
    -0.675777200007472, 1.1304521182278542, -1.6688772479994611, -0.8550081079150917,
    -0.5163163995987907])  # fmt: skip
BLOCKED_GOAL = np.array([0.04376532233356345, -0.9655976891109983, 1.5288636436242042,
    -2.1340622813081023, -1.5707963267948966, 1.221061045296719, 0.2352577772079112,
    -1.4271827367975796, 2.22417797686042, -2.3677915668577363, -1.5707963267948966,
    1.0782072680107593])  # fmt: skip


def _pick_goal(ctx: WorldContext, objects: dict[str, ObjectBox], a: str, b: str) -> np.ndarray:
    world = ctx.new_world()
    home = {x: ctx.home(x) for x in ctx.arm_names}
    g = sample_grasps(objects[a].size, ctx.scene.grasp_limits)
    left = solve_ik_candidates(ctx, world, objects, [IKRequest("left", a, objects[a], g)], home)
    right = solve_ik_candidates(ctx, world, objects, [IKRequest("right", b, objects[b], g)], home)
    pairs = compatible_pairs(ctx, world, objects, left, right)
    assert pairs
    return np.concatenate([pairs[0][0].q, pairs[0][1].q])


def _check(
    ctx: WorldContext, traj_t: np.ndarray, traj_q: np.ndarray, request: MotionRequest
) -> None:
    v = np.concatenate([ctx.scene.arm(a).velocity_limit for a in ctx.arm_names])
    acc = np.concatenate([ctx.scene.arm(a).acceleration_limit for a in ctx.arm_names])
    dt = np.diff(traj_t)
    assert dt.max() <= 0.02 + 1e-12
    vel = np.diff(traj_q, axis=0) / dt[:, None]
    assert np.all(np.abs(vel) <= v * 1.001)
    a = np.diff(vel, axis=0) / (0.5 * (dt[1:] + dt[:-1]))[:, None]
    assert np.all(np.abs(a) <= acc * 1.05)
    np.testing.assert_allclose(traj_q[0], request.q_start, atol=1e-9)
    np.testing.assert_allclose(traj_q[-1], request.q_goal, atol=1e-9)
    world = ctx.new_world()  # an independent world, finer resolution
    configure_world(ctx, world, request.objects, request.held, request.q_start)
    assert validate_trajectory(ctx, world, traj_q, max_tcp_step=0.005).ok


def test_plain_pick_motion_is_valid(
    ctx: WorldContext, planner: MotionPlanner, objects: dict[str, ObjectBox]
) -> None:
    names = list(objects)
    q_goal = _pick_goal(ctx, objects, names[0], names[5])
    request = MotionRequest(_home12(ctx), q_goal, objects, approach=(True, True))
    result = plan_dual_motion(planner, request)
    assert result.success and result.level == "plain" and result.trajectory is not None
    assert result.validation is not None and result.validation.ok
    _check(ctx, result.trajectory.t, result.trajectory.q, request)


@dataclass(frozen=True)
class StraightLine:
    """A user strategy: the straight joint-space line, not optimised."""

    name: str = "straight"

    def __call__(self, planner: MotionPlanner, problem: TransferProblem) -> list[np.ndarray]:
        return [straight_line(problem.q_from, problem.q_to, 10)]


def test_blocked_straight_line_is_detected_and_a_fallback_takes_over(
    ctx: WorldContext, planner: MotionPlanner, objects: dict[str, ObjectBox]
) -> None:
    request = MotionRequest(BLOCKED_START, BLOCKED_GOAL, objects, retreat=(True, True),
                            approach=(True, True))  # fmt: skip
    configure_world(ctx, planner.world, objects, {}, BLOCKED_START)
    retreat, approach = planner.phases(request) or (None, None)
    assert retreat is not None and approach is not None
    straight = straight_line(retreat[-1][-1], approach[0][0], 30)
    assert not validate_trajectory(ctx, planner.world, straight).ok  # detected

    only_straight = plan_dual_motion(planner, request, strategies=[StraightLine()])
    assert not only_straight.success and only_straight.trajectory is None
    (attempt,) = only_straight.attempts
    assert attempt.startswith("straight: validation failed (collision at sample ")
    ladder = [StraightLine(), UntangleStrategy(), SequentialStrategy()]
    result = plan_dual_motion(planner, request, strategies=ladder)
    assert result.success and result.level in ("untangle", "sequential")
    assert result.trajectory is not None
    _check(ctx, result.trajectory.t, result.trajectory.q, request)
    # the default ladder (optimised plain first) solves it too
    assert plan_dual_motion(planner, request).success


def test_sequential_only_moves_one_arm_at_a_time(
    ctx: WorldContext, planner: MotionPlanner, objects: dict[str, ObjectBox]
) -> None:
    names = list(objects)
    q_goal = _pick_goal(ctx, objects, names[2], names[7])
    request = MotionRequest(_home12(ctx), q_goal, objects)
    result = plan_dual_motion(planner, request, sequential_only=True)
    assert result.success and result.level == "one-arm" and result.trajectory is not None
    q = result.trajectory.q
    moving = np.abs(np.diff(q, axis=0)) > 1e-9
    assert not np.any(moving[:, :6].any(axis=1) & moving[:, 6:].any(axis=1))
    _check(ctx, result.trajectory.t, q, request)
    # back: both arms retreat from their picks and go home, still one at a time, the arm
    # reaching deeper into the other's half first
    back = MotionRequest(q_goal, _home12(ctx), objects, retreat=(True, True))
    result = plan_dual_motion(planner, back, sequential_only=True)
    assert result.success and result.trajectory is not None
    q = result.trajectory.q
    moving = np.abs(np.diff(q, axis=0)) > 1e-9
    assert not np.any(moving[:, :6].any(axis=1) & moving[:, 6:].any(axis=1))
    assert moving[:, :6].any() and moving[:, 6:].any()
    _check(ctx, result.trajectory.t, q, back)


def test_strategy_ladders() -> None:
    assert [s.name for s in default_strategies()] == ["plain", "untangle", "sequential"]
    assert [s.name for s in default_strategies(fallbacks=False)] == ["plain"]
    assert [s.name for s in default_strategies(sequential_only=True)] == ["one-arm"]


def test_optimiser_is_reused_and_deterministic(
    ctx: WorldContext, planner: MotionPlanner, objects: dict[str, ObjectBox]
) -> None:
    names = list(objects)
    q_goal = _pick_goal(ctx, objects, names[1], names[4])
    problem = planner.transfer_problem(
        MotionRequest(_home12(ctx), q_goal, objects), _home12(ctx), q_goal
    )
    query = TransferQuery(_home12(ctx), q_goal, problem.held, problem.obstacles, 3.0)
    solver = planner.trajopt._solver
    a = planner.trajopt.solve(query)
    b = planner.trajopt.solve(query)
    assert planner.trajopt._solver is solver
    np.testing.assert_allclose(a.path, b.path)
    lo = np.concatenate([ctx.scene.arm(x).lower_array for x in ctx.arm_names])
    hi = np.concatenate([ctx.scene.arm(x).upper_array for x in ctx.arm_names])
    assert a.success and np.all(a.path >= lo - 1e-9) and np.all(a.path <= hi + 1e-9)


def _home12(ctx: WorldContext) -> np.ndarray:
    return np.concatenate([ctx.home(a) for a in ctx.arm_names])


def test_a_colliding_retreat_fails_at_once_without_optimising(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    """Every strategy shares the straight retreat and approach: when they collide (here a
    box right above the left tool) the motion fails before any optimisation."""
    q_home = _home12(ctx)
    tcp = ctx.kinematics["left"].fk_tcp(q_home[:6])
    lid = np.eye(4)
    lid[:3, :3] = tcp[:3, :3]
    lid[:3, 3] = tcp[:3, 3] - 0.05 * tcp[:3, 2]  # 5 cm back along the tool axis
    objects = {"lid": ObjectBox(lid, (0.12, 0.12, 0.01))}
    q_goal = q_home.copy()
    q_goal[6] += 0.3  # the right arm turns a little
    request = MotionRequest(q_home, q_goal, objects, retreat=(True, False))
    result = plan_dual_motion(planner, request)
    assert not result.success and result.attempts == ()
    assert result.reason.startswith("retreat collides") and result.optimisation_time == 0.0


def test_a_clear_straight_transfer_is_taken_without_optimising(
    ctx: WorldContext,
    planner: MotionPlanner,
    objects: dict[str, ObjectBox],
    optimisers: OptimiserCache,
) -> None:
    names = list(objects)
    q_goal = _pick_goal(ctx, objects, names[0], names[5])
    request = MotionRequest(_home12(ctx), q_goal, objects, approach=(True, True))
    result = plan_dual_motion(planner, request)
    assert result.success and result.direct_paths == 1 and result.ipopt_solves == 0
    assert result.optimisation_time == 0.0 and result.trajectory is not None
    _check(ctx, result.trajectory.t, result.trajectory.q, request)
    # the same transfer through the optimiser (direct paths off) is no faster to execute
    optimised = MotionPlanner(ctx, direct=False, optimisers=optimisers)
    assert optimised.trajopt is planner.trajopt  # one optimiser per scene and options
    again = plan_dual_motion(optimised, request)
    assert again.success and again.direct_paths == 0 and again.trajectory is not None
    assert result.trajectory.duration <= again.trajectory.duration + 1e-6


def test_direct_paths_need_the_margin_and_keep_waiting_arms_still(
    ctx: WorldContext, planner: MotionPlanner, objects: dict[str, ObjectBox]
) -> None:
    request = MotionRequest(BLOCKED_START, BLOCKED_GOAL, objects, retreat=(True, True),
                            approach=(True, True))  # fmt: skip
    configure_world(ctx, planner.world, objects, {}, BLOCKED_START)
    configure_world(ctx, planner.margin_world, objects, {}, BLOCKED_START)
    retreat, approach = planner.phases(request) or (None, None)
    assert retreat is not None and approach is not None
    q_a, q_b = retreat[-1][-1], approach[0][0]
    path = planner.transfers().direct_path(q_a, q_b)
    if path is not None:  # a bent path: it passes the check with the margin
        assert len(path) == 3
        curve = spline_curve(path, 64)
        assert validate_trajectory(ctx, planner.margin_world, curve).ok
    # an arm told to wait cannot reach a different goal directly
    assert planner.transfers().direct_path(q_a, q_b, fixed=(True, False)) is None
    # a waiting arm stays put on the bent paths too
    q_b2 = q_b.copy()
    q_b2[:6] = q_a[:6]
    moved = planner.transfers().direct_path(q_a, q_b2, fixed=(True, False))
    if moved is not None:
        assert np.allclose(moved[:, :6], q_a[:6])


def test_direct_margin_must_not_be_negative(ctx: WorldContext) -> None:
    with pytest.raises(ParameterError, match="direct_margin must be >= 0"):
        MotionPlanner(ctx, direct_margin=-0.001)


def test_blended_pick_motion_is_valid_and_ends_straight(
    ctx: WorldContext,
    planner: MotionPlanner,
    objects: dict[str, ObjectBox],
    optimisers: OptimiserCache,
) -> None:
    names = list(objects)
    q_goal = _pick_goal(ctx, objects, names[0], names[5])
    request = MotionRequest(_home12(ctx), q_goal, objects, approach=(True, True))
    result = plan_dual_motion(planner, request)
    assert result.success and result.blended and result.trajectory is not None
    traj = result.trajectory
    _check(ctx, traj.t, traj.q, request)
    unblended = MotionPlanner(ctx, shape=ShapeOptions(blend=False), optimisers=optimisers)
    slow = plan_dual_motion(unblended, request)
    assert slow.success and not slow.blended and slow.trajectory is not None
    assert traj.duration < slow.trajectory.duration  # no stop at the pre-grasp points
    # one rest-to-rest piece: the robot is at rest only at its two ends
    speed = np.abs(np.diff(traj.q, axis=0)).max(axis=1) / np.diff(traj.t)
    assert speed[1:-1].min() > 1e-3
    straight = planner.shape.straight
    for arm in ctx.arm_names:
        kin, sl = ctx.kinematics[arm], ctx.layout.slice(arm)
        lateral, angle = straight_end_deviation(kin, traj.q[::-1, sl], q_goal[sl], straight)
        assert lateral <= 0.002 and angle <= np.radians(2.0)
        # TCP speed on the final straight centimetres within the shape's grasp speed
        p = np.stack([kin.fk_tcp(q)[:3, 3] for q in traj.q[:, sl]])
        near = np.linalg.norm(p[1:] - p[-1], axis=1) < straight - 1e-3
        v = np.linalg.norm(np.diff(p, axis=0), axis=1) / np.diff(traj.t)
        assert v[near].max() <= planner.shape.grasp_speed * 1.05
        # a mutant that cuts the final straight approach: in from the side (3 cm along the
        # tool's x axis, 3 cm back), straight in joint space, is caught by the check
        T = kin.fk_tcp(q_goal[sl])
        T[:3, 3] += 0.03 * T[:3, 0] - 0.03 * T[:3, 2]
        q_side = tool_pose_ik(kin, T, q_goal[sl])
        assert q_side is not None
        mutant = np.linspace(q_side, q_goal[sl], 30)
        bad_lateral, bad_angle = straight_end_deviation(kin, mutant[::-1], q_goal[sl], straight)
        assert bad_lateral > 0.002 or bad_angle > np.radians(2.0)


def test_lift_follows_clearance(
    ctx: WorldContext, planner: MotionPlanner, objects: dict[str, ObjectBox]
) -> None:
    names = list(objects)
    q_goal = _pick_goal(ctx, objects, names[0], names[5])
    request = MotionRequest(_home12(ctx), q_goal, objects, approach=(True, True))
    _, down = planner.lifts(request)
    # a tall object next to the left arm's grasp raises its lift (and only its)
    kin, sl = ctx.kinematics["left"], ctx.layout.slice("left")
    x, y = kin.fk_tcp(q_goal[sl])[:2, 3]
    tall = ObjectBox(objects[names[0]].T_world_obj.copy(), (0.04, 0.04, 0.14))
    tall.T_world_obj[:3, 3] = [x, y + 0.07, 0.07]
    _, raised = planner.lifts(MotionRequest(_home12(ctx), q_goal, {**objects, "tall": tall},
                                            approach=(True, True)))  # fmt: skip
    assert raised[0] == pytest.approx(min(0.14 + planner.shape.lift_margin - 0.008,
                                          planner.shape.max_lift), abs=2e-3)  # fmt: skip
    assert raised[0] > down[0] and raised[1] == down[1]
    assert planner.lifts(request, 0.08) == ([0.08, 0.08], [0.08, 0.08])


# The lifted ends of a one-arm transfer in M1 whose straight line is blocked and whose direct
# path is bent (found by search; the right arm waits at home).
BENT_FROM = np.array([-0.7061157420693194, -0.9699969278267897, 1.5874309412084284,
    -2.138845293039127, -0.7866195915128875, -0.06986945144194401, 0.0, -2.2, 1.9, -1.383,
    -1.57, 0.0])  # fmt: skip
BENT_TO = np.array([-0.011385690495040901, -1.480127490251257, 2.0947252727854395,
    -2.1853941093290796, -1.5707963267948966, 0.23378877419044874, 0.0, -2.2, 1.9, -1.383,
    -1.57, 0.0])  # fmt: skip


def _bent_transfer(
    ctx: WorldContext, planner: MotionPlanner, objects: dict[str, ObjectBox]
) -> tuple[TransferProblem, np.ndarray]:
    """The transfer between BENT_FROM and BENT_TO, and its bent direct path (3 waypoints)."""
    for world in (planner.world, planner.margin_world):
        configure_world(ctx, world, objects, {}, BENT_FROM)
    bent = planner.transfers().direct_path(BENT_FROM, BENT_TO)
    assert bent is not None and len(bent) == 3, "the case needs a bent direct path"
    request = MotionRequest(BENT_FROM, BENT_TO, objects)
    return planner.transfer_problem(request, BENT_FROM, BENT_TO), bent


def _duration(planner: MotionPlanner, path: np.ndarray) -> float:
    v, a = planner.limits
    from streams.motion.timing import time_parameterize

    return time_parameterize(path, v, a).duration


def test_a_bent_direct_path_is_refined_when_the_optimiser_makes_it_faster(
    ctx: WorldContext, objects: dict[str, ObjectBox], optimisers: OptimiserCache
) -> None:
    planner = MotionPlanner(ctx, optimisers=optimisers)
    assert planner.refine_bent
    problem, bent = _bent_transfer(ctx, planner, objects)
    refined = planner.transfers().refine_direct(problem, bent)
    assert refined is not bent and len(refined) > 3
    assert _duration(planner, refined) < _duration(planner, bent)
    assert np.allclose(refined[0], bent[0]) and np.allclose(refined[-1], bent[-1])
    curve = spline_curve(refined, 128)
    assert validate_trajectory(ctx, planner.margin_world, curve).ok
    # off: the bent path as it is; a straight path is never handed to the optimiser
    plain = MotionPlanner(ctx, refine_bent=False, optimisers=optimisers)
    assert plain.transfers().refine_direct(problem, bent) is bent
    straight = np.stack([bent[0], bent[-1]])
    assert planner.transfers().refine_direct(problem, straight) is straight


def test_a_refinement_that_collides_or_is_slower_keeps_the_bent_path(
    ctx: WorldContext,
    objects: dict[str, ObjectBox],
    monkeypatch: pytest.MonkeyPatch,
    optimisers: OptimiserCache,
) -> None:
    planner = MotionPlanner(ctx, optimisers=optimisers)
    problem, bent = _bent_transfer(ctx, planner, objects)
    solve = planner.trajopt.solve

    def through_the_table(query: TransferQuery, warm: np.ndarray | None = None) -> object:
        # faster than the bent path but blocked: the straight line the bent path avoids
        result = solve(query, warm)
        return dataclasses.replace(result, path=straight_line(bent[0], bent[-1], 20))

    straight = straight_line(bent[0], bent[-1], 20)
    assert _duration(planner, straight) < _duration(planner, bent)
    assert not validate_trajectory(ctx, planner.margin_world, spline_curve(straight, 128)).ok
    monkeypatch.setattr(planner.trajopt, "solve", through_the_table)
    assert planner.transfers().refine_direct(problem, bent) is bent

    def slower(query: TransferQuery, warm: np.ndarray | None = None) -> object:
        result = solve(query, warm)
        return dataclasses.replace(result, path=densify_slow(bent))

    def densify_slow(path: np.ndarray) -> np.ndarray:
        # the same curve with a detour back and forth: longer to execute
        return np.concatenate([path[:2], path[:1], path])

    monkeypatch.setattr(planner.trajopt, "solve", slower)
    assert planner.transfers().refine_direct(problem, bent) is bent
