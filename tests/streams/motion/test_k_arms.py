"""The motion level for one to four arms placed around one table (the test cells in ``data/``:
``table_1arm.yaml`` .. ``table_4arm.yaml``, arms S, N, W, E; fixtures in ``conftest.py``): park
poses and reach depths by each arm's base pose, the sequential fallback's order, and planned
motions checked exactly with coal (the optimiser's rows and the checks: ``test_k_arm_rows.py``)."""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping
from types import ModuleType

import numpy as np
import pytest

from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.errors import ArmLayoutError
from sdar_tamp.world.transforms import inverse, pose_xyz_yaw
from streams.context import WorldContext
from streams.grasps import sample_grasps
from streams.ik import IKCandidate, IKRequest, solve_ik_candidates
from streams.motion.cartesian import tool_pose_ik
from streams.motion.exact_check import HeldObject, configure_world, validate_trajectory
from streams.motion.ladder import plan_dual_motion
from streams.motion.optimiser_cache import OptimiserCache
from streams.motion.planner import MotionPlanner
from streams.motion.records import MotionRequest, MotionResult, MotionTally, TransferProblem
from streams.motion.sphere_pairs import HeldSpheres
from streams.motion.strategies import SequentialStrategy, UntangleStrategy
from streams.motion.transfers import Transfers
from streams.motion.waypoints import straight_line

SIZE = (0.08, 0.04, 0.05)
NO_OBSTACLES = (np.zeros((0, 3)), np.zeros(0))

# Four-arm pre-grasp configurations (S above (-0.2, -0.04) -> above (0.2, -0.04); N above
# (0.2, 0.04) -> above (-0.2, 0.04); W and E at home) whose straight joint-space line makes the
# wrists of S and N meet (found by search over the IK candidates of those objects).
CROSS_START = np.array([0.12792838602664558, -1.354183341187614, 1.8744530296194277,
    -2.09106601522671, -1.5707963267948966, 0.12792838602664558, 0.12792838602664514,
    -1.354183341187614, 1.874453029619428, -2.09106601522671, -1.5707963267948966,
    0.12792838602664514, 0.0, -2.2, 1.9, -1.383, -1.57, 0.0, 0.0, -2.2, 1.9, -1.383, -1.57,
    0.0])  # fmt: skip
CROSS_GOAL = np.array([-0.6195252539044604, -1.354183341187614, 1.8744530296194273,
    -2.09106601522671, -1.5707963267948966, -0.6195252539044609, -0.6195252539044613,
    -1.354183341187614, 1.8744530296194277, -2.09106601522671, -1.5707963267948966,
    -0.6195252539044613, 0.0, -2.2, 1.9, -1.383, -1.57, 0.0, 0.0, -2.2, 1.9, -1.383, -1.57,
    0.0])  # fmt: skip


def _boxes(poses: Mapping[str, tuple[float, float, float]]) -> dict[str, ObjectBox]:
    return {n: ObjectBox(pose_xyz_yaw(x, y, SIZE[2] / 2, yaw), SIZE) for n, (x, y, yaw) in
            poses.items()}  # fmt: skip


def _candidates(
    ctx: WorldContext, objects: dict[str, ObjectBox], arm: str, obj: str, box: ObjectBox
) -> list[IKCandidate]:
    world = ctx.new_world()
    configure_world(ctx, world, objects, {}, ctx.scene.home)
    home = {a: ctx.home(a) for a in ctx.arm_names}
    grasps = sample_grasps(SIZE, ctx.scene.grasp_limits)
    return solve_ik_candidates(ctx, world, objects, [IKRequest(arm, obj, box, grasps)], home)


def _independent_check(ctx: WorldContext, result: MotionResult, request: MotionRequest) -> None:
    """Success, the ends of the request, and an exact coal replay in a world of its own."""
    assert result.success and result.trajectory is not None, result.reason
    traj = result.trajectory
    np.testing.assert_allclose(traj.q[0], request.q_start, atol=1e-9)
    np.testing.assert_allclose(traj.q[-1], request.q_goal, atol=1e-9)
    world = ctx.new_world()
    configure_world(ctx, world, request.objects, request.held, request.q_start)
    assert validate_trajectory(ctx, world, traj.q, traj.t).ok


# -- untangling geometry and the sequential order ------------------------------------------------


def test_park_and_depth_of_two_arms_facing_across_x(planner: MotionPlanner) -> None:
    ctx = planner.ctx
    transfers = planner.transfers()
    for arm, x in (("left", -0.15), ("right", 0.15)):
        q_goal = ctx.kinematics[arm].fk_tcp(ctx.home(arm))
        park = transfers.park(arm, ctx.home(arm))
        assert park is not None
        T = ctx.kinematics[arm].fk_tcp(park)
        y = float(np.clip(q_goal[1, 3], *ctx.scene.workspace.y))
        np.testing.assert_allclose(T[:3, 3], [x, y, 0.30], atol=1e-6)
    q = ctx.scene.home
    tcp = [ctx.kinematics[a].fk_tcp(ctx.layout.part(q, a))[0, 3] for a in ctx.arm_names]
    np.testing.assert_array_equal(transfers.depth(q), [tcp[0], -tcp[1]])


def test_park_and_depth_of_arms_around_the_table(
    cells: dict[int, WorldContext], k_optimisers: OptimiserCache
) -> None:
    ctx = cells[4]
    transfers = MotionPlanner(ctx, optimisers=k_optimisers).transfers()
    ws = ctx.scene.workspace
    reach = {"south": (0.10, 0.12), "north": (-0.05, -0.10), "west": (0.05, 0.08),
             "east": (-0.02, -0.12)}  # fmt: skip
    q = ctx.scene.home.copy()
    for arm, (x, y) in reach.items():
        T = ctx.kinematics[arm].fk_tcp(ctx.home(arm))
        T[:3, 3] = (x, y, 0.12)
        T[:3, :3] = np.diag([1.0, -1.0, -1.0])  # pointing down
        q_arm = tool_pose_ik(ctx.kinematics[arm], T, ctx.home(arm))
        assert q_arm is not None, arm
        q = ctx.layout.replace(q, arm, q_arm)
        park = transfers.park(arm, q_arm)
        assert park is not None, arm
        P = ctx.kinematics[arm].fk_tcp(park)[:3, 3]
        want = {"south": (x, -0.15), "north": (x, 0.15), "west": (-0.30, y),
                "east": (0.30, y)}[arm]  # fmt: skip
        want = (float(np.clip(want[0], *ws.x)), float(np.clip(want[1], *ws.y)))
        np.testing.assert_allclose(P, [*want, 0.30], atol=1e-6)
    # past the table centre along each arm's facing direction
    np.testing.assert_allclose(transfers.depth(q), [0.12, 0.10, 0.05, 0.02], atol=1e-6)


class _OneArmAtATime(Transfers):
    """Transfers that refuse every stage moving more than one arm (straight lines else)."""

    def optimise_or_lift(
        self, problem: TransferProblem, q_a: np.ndarray, q_b: np.ndarray,
        fixed: tuple[bool, ...] = (),
    ) -> np.ndarray | None:  # fmt: skip
        moving = [not np.allclose(q_a[sl], q_b[sl]) for sl in self.ctx.layout.slices]
        return np.stack([q_a, q_b]) if sum(moving) <= 1 else None


def _moving(stage: np.ndarray, ctx: WorldContext) -> list[str]:
    return [a for a in ctx.arm_names if not np.allclose(ctx.layout.part(stage[0], a),
                                                        ctx.layout.part(stage[-1], a))]  # fmt: skip


@pytest.mark.parametrize("k", [2, 3])
def test_sequential_moves_the_deepest_arm_home_first(
    k: int, ctx: WorldContext, cells: dict[int, WorldContext], k_optimisers: OptimiserCache
) -> None:
    world = ctx if k == 2 else cells[k]
    planner = MotionPlanner(world, optimisers=k_optimisers)
    transfers = _OneArmAtATime(world, planner.build, planner.margin_world, MotionTally())
    q_from = world.scene.home + 0.05
    q_to = world.scene.home - 0.05
    problem = TransferProblem(q_from, q_to, tuple(HeldSpheres.empty() for _ in range(k)),
                              NO_OBSTACLES)  # fmt: skip
    order = [world.arm_names[int(i)] for i in np.argsort(-transfers.depth(q_from))]
    stages = SequentialStrategy()(transfers, problem)
    if k == 2:  # the other arm's stage moves one arm: allowed
        assert stages is not None and [_moving(s, world) for s in stages] == [
            [order[0]], [order[1]], [order[0]]]  # fmt: skip
    else:  # together refused: one at a time, deepest first
        assert stages is not None
        assert [_moving(s, world) for s in stages] == [[order[0]], [order[1]], [order[2]],
                                                       [order[0]]]  # fmt: skip
    np.testing.assert_allclose(stages[0][-1][world.layout.slice(order[0])],
                               world.home(order[0]))  # fmt: skip
    np.testing.assert_allclose(stages[-1][-1], q_to)
    for a, b in itertools.pairwise(stages):
        np.testing.assert_allclose(a[-1], b[0])


class _RefusingFirstStages(Transfers):
    """Transfers that record the first stage of every untangling attempt and refuse it."""

    def __init__(self, planner: MotionPlanner) -> None:
        super().__init__(planner.ctx, planner.build, planner.margin_world, MotionTally())
        self.tried: list[np.ndarray] = []

    def optimise_or_lift(
        self, problem: TransferProblem, q_a: np.ndarray, q_b: np.ndarray,
        fixed: tuple[bool, ...] = (),
    ) -> np.ndarray | None:  # fmt: skip
        self.tried.append(q_b)
        return None


def test_untangle_tries_the_deepest_arm_first(
    cells: dict[int, WorldContext], k_optimisers: OptimiserCache
) -> None:
    ctx = cells[3]
    planner = MotionPlanner(ctx, optimisers=k_optimisers)
    transfers = _RefusingFirstStages(planner)
    q_from = ctx.scene.home.copy()
    q_from[ctx.layout.slice("west")] += np.array([0.0, 0.5, -0.6, 0.0, 0.0, 0.0])  # reach out
    q_to = ctx.scene.home + 0.05
    problem = TransferProblem(q_from, q_to, tuple(HeldSpheres.empty() for _ in range(3)),
                              NO_OBSTACLES)  # fmt: skip
    assert UntangleStrategy()(transfers, problem) is None
    depth = transfers.depth(q_from)
    order = [ctx.arm_names[int(i)] for i in np.argsort(-depth)]
    assert order[0] == "west"
    parked = [next(a for a in ctx.arm_names if not np.allclose(ctx.layout.part(q, a),
                                                               ctx.layout.part(q_to, a)))
              for q in transfers.tried]  # fmt: skip
    assert parked == order  # one attempt per arm, deepest first


def test_others(ctx: WorldContext, cells: dict[int, WorldContext]) -> None:
    assert ctx.others("left") == ("right",)
    assert cells[4].others("north") == ("south", "west", "east")
    assert cells[1].others("south") == ()
    with pytest.raises(ArmLayoutError, match="unknown arm 'up'"):
        cells[3].others("up")


# -- planned motions, checked exactly -----------------------------------------------------------


def test_three_arms_move_between_pregrasps(
    cells: dict[int, WorldContext], k_optimisers: OptimiserCache
) -> None:
    ctx = cells[3]
    objects = _boxes({"o1": (-0.12, -0.15, 0.0), "o2": (0.12, -0.12, 0.0),
                      "o3": (-0.10, 0.15, 0.0), "o4": (0.12, 0.15, 0.0),
                      "o5": (-0.22, -0.02, 1.57), "o6": (-0.15, 0.06, 1.57)})  # fmt: skip
    moves = {"south": ("o1", "o2"), "north": ("o3", "o4"), "west": ("o5", "o6")}
    cands = {
        arm: [_candidates(ctx, objects, arm, o, objects[o]) for o in pair]
        for arm, pair in moves.items()
    }
    world = ctx.new_world()
    configure_world(ctx, world, objects, {}, ctx.scene.home)
    ends = None
    for s, n, w in itertools.product(*(itertools.product(*cands[a]) for a in moves)):
        q_a = ctx.join({"south": s[0].q_pre, "north": n[0].q_pre, "west": w[0].q_pre})
        q_b = ctx.join({"south": s[1].q_pre, "north": n[1].q_pre, "west": w[1].q_pre})
        if not world.in_collision(q_a) and not world.in_collision(q_b):
            ends = (q_a, q_b)
            break
    assert ends is not None
    request = MotionRequest(ends[0], ends[1], objects)
    for direct in (True, False):  # direct=False: the optimiser's own straight-line test
        planner = MotionPlanner(ctx, optimisers=k_optimisers, direct=direct)
        result = plan_dual_motion(planner, request)
        _independent_check(ctx, result, request)
        assert all(
            not np.allclose(ctx.layout.part(ends[0], a), ctx.layout.part(ends[1], a))
            for a in ctx.arm_names
        )


def test_two_of_four_arms_are_kept_apart(
    cells: dict[int, WorldContext], k_optimisers: OptimiserCache
) -> None:
    ctx = cells[4]
    objects = _boxes({"a": (-0.2, -0.04, 0.0), "b": (0.2, -0.04, 0.0), "c": (0.2, 0.04, 0.0),
                      "d": (-0.2, 0.04, 0.0)})  # fmt: skip
    request = MotionRequest(CROSS_START, CROSS_GOAL, objects)
    planner = MotionPlanner(ctx, optimisers=k_optimisers)
    configure_world(ctx, planner.world, objects, {}, CROSS_START)
    straight = validate_trajectory(ctx, planner.world, straight_line(CROSS_START, CROSS_GOAL, 30))
    assert not straight.ok and straight.reason == "collision"
    assert any(
        {p.first.split("_")[0], p.second.split("_")[0]} == {"south", "north"}
        for p in straight.pairs
    )
    result = plan_dual_motion(planner, request)
    _independent_check(ctx, result, request)
    assert result.direct_paths == 0  # not the straight line, nor a lightly bent one
    q = result.trajectory.q if result.trajectory is not None else None
    assert q is not None
    for arm in ("west", "east"):  # the idle arms stay at home
        np.testing.assert_allclose(ctx.layout.part(q, arm), np.tile(ctx.home(arm), (len(q), 1)))


def test_one_arm_carries_an_object(
    cells: dict[int, WorldContext], k_optimisers: OptimiserCache
) -> None:
    ctx = cells[1]
    kin = ctx.kinematics["south"]
    objects = _boxes({"o1": (-0.12, -0.10, 0.0), "o2": (0.0, 0.0, 0.3)})
    goal = _boxes({"o1": (0.14, 0.10, 0.5)})["o1"]
    found = None
    at_goal = _candidates(ctx, {"o2": objects["o2"]}, "south", "o1", goal)
    for c in _candidates(ctx, objects, "south", "o1", objects["o1"]):
        same = [g for g in at_goal if g.grasp.index == c.grasp.index]
        if same:
            found = (c, same[0])
            break
    assert found is not None
    pick, place = found
    held = HeldObject("o1", SIZE, inverse(kin.fk_tool0(pick.q)) @ objects["o1"].T_world_obj)
    resting = {"o2": objects["o2"]}
    request = MotionRequest(pick.q, place.q, resting, {"south": held}, retreat=(True,),
                            approach=(True,))  # fmt: skip
    for direct in (True, False):
        planner = MotionPlanner(ctx, optimisers=k_optimisers, direct=direct)
        result = plan_dual_motion(planner, request)
        _independent_check(ctx, result, request)
    # the held object arrives at its goal pose
    T = kin.fk_tool0(place.q) @ held.T_tool0_obj
    np.testing.assert_allclose(T, goal.T_world_obj, atol=1e-6)


def test_benchmark_refuses_more_arms_than_the_cell_has(
    benchmark_script: Callable[[str], ModuleType], capsys: pytest.CaptureFixture[str]
) -> None:
    bench = benchmark_script("bench_motion_arms")
    with pytest.raises(SystemExit):
        bench.main(["--arms", "2,5", "--calls", "1"])
    assert "--arms: expected counts in 1..4 (the cell's arms), got [5]" in capsys.readouterr().err


def test_waiting_arms_are_obstacles_of_the_moving_one(
    cells: dict[int, WorldContext], k_optimisers: OptimiserCache, planner: MotionPlanner
) -> None:
    """South moves past north, which waits in its way (west at home): the transfer is
    optimised for south alone with north's spheres as obstacles, and checked with every arm."""
    ctx = cells[3]
    kin = ctx.kinematics["north"]
    T = kin.fk_tcp(CROSS_START[6:12])
    T[0, 3] = 0.05  # north above the middle of south's way
    north = tool_pose_ik(kin, T, CROSS_START[6:12])
    assert north is not None
    q_a = ctx.layout.join({**{a: ctx.home(a) for a in ctx.arm_names}, "north": north,
                           "south": CROSS_START[:6]})  # fmt: skip
    q_b = ctx.layout.replace(q_a, "south", CROSS_GOAL[:6])
    objects = _boxes({"a": (-0.2, -0.04, 0.0), "b": (0.2, -0.04, 0.0), "c": (0.2, 0.04, 0.0),
                      "d": (-0.2, 0.04, 0.0)})  # fmt: skip
    world = ctx.new_world()
    configure_world(ctx, world, objects, {}, q_a)
    straight = validate_trajectory(ctx, world, straight_line(q_a, q_b, 30))
    assert not straight.ok and {straight.pairs[0].first[:5], straight.pairs[0].second[:5]} == {
        "south", "north"}  # fmt: skip
    moving = MotionPlanner(ctx, optimisers=k_optimisers, direct=False)
    request = MotionRequest(q_a, q_b, objects)
    result = plan_dual_motion(moving, request)
    _independent_check(ctx, result, request)
    assert result.ipopt_solves >= 1 and moving.subsets.sets == ((0,),)
    assert result.trajectory is not None
    for arm in ("north", "west"):
        part = ctx.layout.part(result.trajectory.q, arm)
        np.testing.assert_allclose(part, np.tile(ctx.layout.part(q_a, arm), (len(part), 1)))
    # two arms are always optimised together (the two-arm planner)
    two = planner.transfers()
    assert two.subsets is not None and not two._by_subset(q_a[:12], q_b[:12], (0,))
