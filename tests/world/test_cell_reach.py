"""The top-down reach check of a cell's arms (:mod:`sdar_tamp.world.cell_reach`)."""

from __future__ import annotations

import numpy as np
import pytest

from sdar_tamp.world._pin import PinRobot, chain_to, colliding_configurations
from sdar_tamp.world.cell_reach import (
    ReachArm,
    grid,
    largest_rectangle,
    reached,
    solve_top_down,
)
from sdar_tamp.world.errors import KinematicsError
from sdar_tamp.world.numeric_ik import chain_fk
from sdar_tamp.world.scene import domain_path
from sdar_tamp.world.transforms import pose_xyz_yaw

PANDA = domain_path("robots/panda_hand.urdf")
READY = np.array([0.0, -np.pi / 4, 0.0, -3 * np.pi / 4, 0.0, np.pi / 2, np.pi / 4])


@pytest.fixture(scope="module")
def panda() -> ReachArm:
    robot = PinRobot.load(PANDA)
    lo, hi = robot.model.lowerPositionLimit.copy(), robot.model.upperPositionLimit.copy()
    return ReachArm(robot, pose_xyz_yaw(-0.5, 0.0, 0.0, 0.0), "tool0", 0.1034, lo, hi, READY)


def test_collisions_with_itself_and_the_table(panda: ReachArm) -> None:
    robot = panda.robot
    assert colliding_configurations(robot, READY[None], 0.0).tolist() == [False]
    folded = READY.copy()
    folded[3] = -3.0  # elbow fully bent, forearm into the upper arm's links
    folded[5] = 0.0
    down = np.array([0.0, 1.5, 0.0, -0.5, 0.0, 2.0, np.pi / 4])  # stretched: tcp 0.02 m under
    assert colliding_configurations(robot, np.stack([folded, down]), 0.0).tolist() == [True, True]
    # the same stretched pose is free above a table 1 m lower
    assert colliding_configurations(robot, down[None], -1.0).tolist() == [False]


def test_solutions_reach_the_poses(panda: ReachArm) -> None:
    xy = np.array([[0.0, 0.0], [0.1, 0.2], [-0.1, -0.15]])
    sol = solve_top_down(panda, xy, 0.025, 0.3)
    assert sol.ok.all()
    assert np.all((sol.q >= panda.lower) & (sol.q <= panda.upper))
    _, T_base_tool0 = chain_fk(chain_to(panda.robot, "tool0"), sol.q)
    T_world_tcp = panda.T_world_base @ T_base_tool0
    tcp = T_world_tcp[:, :3, :3] @ np.array([0.0, 0.0, 0.1034]) + T_world_tcp[:, :3, 3]
    np.testing.assert_allclose(tcp[:, :2], xy, atol=1e-6)
    np.testing.assert_allclose(tcp[:, 2], 0.025, atol=1e-6)
    np.testing.assert_allclose(T_world_tcp[:, :3, 2], [[0.0, 0.0, -1.0]] * 3, atol=1e-6)


def test_near_points_are_reached_far_ones_not(panda: ReachArm) -> None:
    # 0.5 m in front of the base: reached; 1.2 m: beyond the Panda's 0.855 m; on the base: no
    xy = np.array([[0.0, 0.0], [0.7, 0.0], [-0.5, 0.0]])
    assert reached(panda, xy, 0.025).tolist() == [True, False, False]


def test_narrowed_limits_are_kept(panda: ReachArm) -> None:
    lo, hi = READY - 0.05, READY + 0.05  # about the ready pose only: its hand 0.5 m high
    narrow = ReachArm(panda.robot, panda.T_world_base, "tool0", 0.1034, lo, hi, READY)
    xy = np.array([[0.0, 0.0]])
    assert reached(panda, xy, 0.025).tolist() == [True]
    assert reached(narrow, xy, 0.025).tolist() == [False]


def test_bad_arguments_are_errors(panda: ReachArm) -> None:
    short = ReachArm(panda.robot, panda.T_world_base, "tool0", 0.1, panda.lower[:6],
                     panda.upper[:6], READY[:6])  # fmt: skip
    with pytest.raises(KinematicsError, match="7 joints to 'tool0', limits for 6"):
        solve_top_down(short, np.zeros((1, 2)), 0.025, 0.0)
    with pytest.raises(KinematicsError, match="grid step must be > 0"):
        grid((0.0, 1.0), (0.0, 1.0), 0.0)


def test_grid_includes_both_edges() -> None:
    pts = grid((-0.25, 0.25), (-0.3, 0.3), 0.02)
    assert len(pts) == 26 * 31
    assert pts.min(axis=0).tolist() == [-0.25, -0.3] and pts.max(axis=0).tolist() == [0.25, 0.3]


def test_largest_rectangle() -> None:
    ok = np.array(
        [
            [0, 1, 1, 1, 0],
            [1, 1, 1, 1, 0],
            [1, 1, 1, 1, 1],
            [0, 0, 1, 1, 1],
        ],
        dtype=bool,
    )
    xs, ys = np.arange(4.0), np.arange(5.0)
    assert largest_rectangle(ok, xs, ys) == ((0.0, 2.0), (1.0, 3.0))
    assert largest_rectangle(np.zeros((2, 2), dtype=bool), xs[:2], ys[:2]) is None
