"""The streams and the optimiser with a 7-DoF arm: grasp candidates from the IK stream, a
straight approach by the numeric IK, one free-space transfer optimised."""

from __future__ import annotations

import numpy as np

from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.transforms import pose_xyz_yaw
from streams.context import WorldContext
from streams.grasps import pregrasp_offset, sample_grasps
from streams.ik import GraspIK, IKRequest, solve_ik_candidates
from streams.motion.cartesian import straight_tool_move, straight_tool_moves, tool_pose_ik
from streams.motion.optimiser import TrajectoryOptimiser
from streams.motion.optimiser_records import TrajOptOptions, TransferQuery
from streams.motion.sphere_pairs import HeldSpheres

SIZE = (0.08, 0.04, 0.05)


def _objects() -> dict[str, ObjectBox]:
    return {
        "a": ObjectBox(pose_xyz_yaw(-0.15, 0.1, SIZE[2] / 2, 0.3), SIZE),
        "b": ObjectBox(pose_xyz_yaw(0.15, -0.1, SIZE[2] / 2, -0.2), SIZE),
    }


def test_ik_stream_yields_grasp_candidates(ctx7: WorldContext) -> None:
    objects = _objects()
    grasps = sample_grasps(SIZE, ctx7.scene.grasp_limits)
    requests = [IKRequest(a, o, objects[o], grasps) for a in ctx7.arm_names for o in objects]
    home = {a: ctx7.home(a) for a in ctx7.arm_names}
    cands = solve_ik_candidates(ctx7, ctx7.new_world(), objects, requests, home)
    assert {(c.arm, c.obj) for c in cands} == {(a, o) for a in ctx7.arm_names for o in objects}
    assert [c.cost for c in cands] == sorted(c.cost for c in cands)
    for c in cands:
        kin = ctx7.kinematics[c.arm]
        assert c.q.shape == (7,)
        T = objects[c.obj].T_world_obj @ c.grasp.T_object_tcp
        np.testing.assert_allclose(kin.fk_tcp(c.q), T, atol=1e-5)
        np.testing.assert_allclose(kin.fk_tcp(c.q_pre), pregrasp_offset(T, 0.08), atol=1e-5)
        lo, hi = kin.spec.lower_array, kin.spec.upper_array
        assert np.all(c.q >= lo) and np.all(c.q <= hi)
    table = GraspIK(ctx7, "left", "a", objects["a"], ())
    assert table.q.shape == (0, 4, 7) and table.ok.shape == (0, 4)


def test_straight_approach_by_the_numeric_ik(ctx7: WorldContext) -> None:
    kin = ctx7.kinematics["left"]
    home = ctx7.home("left")
    path = straight_tool_move(kin, home, -0.06, step=0.015)
    assert path is not None and path.shape == (5, 7)
    start = kin.fk_tcp(home)
    end = kin.fk_tcp(path[-1])
    np.testing.assert_allclose(end[:3, 3], start[:3, 3] - 0.06 * start[:3, 2], atol=1e-5)
    np.testing.assert_allclose(end[:3, :3], start[:3, :3], atol=1e-5)
    assert np.abs(np.diff(path, axis=0)).max() < 0.3
    far = kin.fk_tcp(home)
    far[:3, 3] = [1.5, 0.0, 0.3]
    assert tool_pose_ik(kin, far, home) is None
    assert straight_tool_move(kin, home, 2.0, step=0.5) is None  # leaves the reach


def test_straight_moves_in_one_batch_are_the_moves_one_by_one(
    ctx7: WorldContext, ctx: WorldContext
) -> None:
    for c, arm in ((ctx7, "left"), (ctx, "right")):  # numeric IK, then the closed form
        kin = c.kinematics[arm]
        home = c.home(arm)
        starts = np.stack([home, home + 0.1, home - 0.1])
        for distance in (-0.06, 2.0):  # the second leaves the reach
            batch = straight_tool_moves(kin, starts, distance, step=0.015)
            single = [straight_tool_move(kin, q, distance, step=0.015) for q in starts]
            assert len(batch) == 3
            for b, s in zip(batch, single, strict=True):
                assert (b is None) == (s is None)
                if b is not None and s is not None:
                    np.testing.assert_allclose(b, s, atol=1e-12)
        assert straight_tool_moves(kin, np.zeros((0, kin.dof)), -0.06) == []
    assert straight_tool_moves(ctx7.kinematics["left"], ctx7.home("left")[None], 2.0) == [None]


def test_tool_pose_ik_of_a_numeric_arm_starts_from_the_near_configuration(
    ctx7: WorldContext,
) -> None:
    kin = ctx7.kinematics["left"]
    home = ctx7.home("left")
    T = kin.fk_tcp(home)
    T[:3, 3] += [0.05, 0.03, 0.1]
    q = tool_pose_ik(kin, T, home)
    assert q is not None
    np.testing.assert_allclose(kin.fk_tcp(q), T, atol=1e-5)
    every = kin.ik_tcp(T[None])  # no branch of the cold solve is nearer the start
    d = np.linalg.norm(every.q[0][every.valid[0]] - home, axis=1)
    assert np.linalg.norm(q - home) <= d.min() + 1e-6
    lo, hi = kin.spec.lower_array, kin.spec.upper_array
    assert np.all(q >= lo) and np.all(q <= hi)


def test_optimiser_solves_a_free_space_transfer(ctx7: WorldContext) -> None:
    """The left arm's TCP crosses from y = 0.25 to y = -0.25 past an obstacle sphere on the
    straight line: IPOPT bends the path round it."""
    kin = ctx7.kinematics["left"]
    home = ctx7.home("left")
    ends = []
    for y in (0.25, -0.25):
        T = kin.fk_tcp(home)
        T[:3, 3] = [-0.2, y, 0.1]
        q, ok = kin.ik_tcp(T[None]).closest(home)
        assert ok[0]
        ends.append(ctx7.join({"left": q[0], "right": ctx7.home("right")}))
    q_start, q_goal = ends
    obstacle = (np.array([[-0.2, 0.0, 0.1]]), np.array([0.06]))
    optimiser = TrajectoryOptimiser(ctx7, TrajOptOptions(compiled=False))
    held = (HeldSpheres.empty(), HeldSpheres.empty())
    result = optimiser.solve(TransferQuery(q_start, q_goal, held, obstacle, 3.0))
    assert result.success and result.status == "Solve_Succeeded", result.status
    assert result.iterations > 0 and result.min_clearance > 0.0
    assert result.path.shape == (10, 14)
    np.testing.assert_allclose(result.path[[0, -1]], [q_start, q_goal])
    lo, hi = ctx7.scene.joint_array("lower"), ctx7.scene.joint_array("upper")
    assert np.all(result.path >= lo - 1e-9) and np.all(result.path <= hi + 1e-9)
    tcp = ctx7.fk["left"].tcp_positions(result.path[:, :7])
    assert np.linalg.norm(tcp - obstacle[0], axis=1).min() > 0.06  # round the obstacle
    assert ctx7.fk["right"].dof == 7
