import dataclasses

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.graspability import TABLE_CLEARANCE, GraspLimits, fingertip_drop
from sdar_tamp.world.shipped_cell import SHIPPED_GRASP
from sdar_tamp.world.transforms import pose_xyz_yaw
from streams.context import WorldContext
from streams.grasps import GraspOptions, pregrasp_offset, sample_grasps
from streams.ik import IKRequest, solve_ik_candidates


def wide(width: float) -> GraspLimits:
    """The shipped gripper's fingers with a graspable width of ``width`` [m]."""
    return dataclasses.replace(SHIPPED_GRASP, max_width=width)


def test_default_object_gives_the_six_grasp_set_top_down_first() -> None:
    grasps = sample_grasps((0.08, 0.04, 0.05), wide(0.075))
    assert len(grasps) == 6  # 1 graspable side x 2 yaws (flips) x {0, +45, -45}
    assert [g.tilt for g in grasps[:2]] == [0.0, 0.0]
    assert grasps[2].tilt == pytest.approx(np.pi / 4) and grasps[4].tilt == pytest.approx(
        -np.pi / 4
    )
    for g in grasps:
        R = g.T_object_tcp[:3, :3]
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0)
        assert g.closing_axis == 1 and g.width == pytest.approx(0.04)
        np.testing.assert_allclose(abs(R[:, 1] @ np.array([0, 1.0, 0])), 1.0)  # closes along y
        # approach tilted by |tilt| from straight down, in the plane perpendicular to y
        assert np.arccos(-g.approach[2]) == pytest.approx(abs(g.tilt))
        assert g.approach[1] == pytest.approx(0.0)


def test_both_sides_graspable_short_side_first_and_more_angles() -> None:
    grasps = sample_grasps((0.05, 0.03, 0.05), wide(0.075), tilts=(np.pi / 6, np.pi / 3))
    assert len(grasps) == 2 * 2 * 5
    assert grasps[0].closing_axis == 1 and grasps[2].closing_axis == 0
    tilts = [abs(g.tilt) for g in grasps]
    assert tilts == sorted(tilts)


def test_too_wide_object_is_rejected() -> None:
    assert sample_grasps((0.09, 0.08, 0.05), wide(0.075)) == ()
    with pytest.raises(ValueError):
        sample_grasps((0.05, 0.03, 0.05), wide(0.075), tilts=(2.0,))


def test_pregrasp_backs_off_along_the_approach() -> None:
    g = sample_grasps((0.08, 0.04, 0.05), wide(0.075))[2]
    pre = pregrasp_offset(g.T_object_tcp, 0.08)
    np.testing.assert_allclose(pre[:3, 3] - g.T_object_tcp[:3, 3], -0.08 * g.approach)


def test_a_side_equal_to_the_graspable_width_is_graspable(ctx: WorldContext) -> None:
    """0.06 - 0.01 is 0.049999999999999996: a 0.05 m cube still fits (one shared tolerance)."""
    width = ctx.scene.grasp_limits
    assert width.max_width < 0.05
    assert len(sample_grasps((0.05, 0.05, 0.05), width)) == 12
    assert sample_grasps((0.0501, 0.0501, 0.05), width) == ()


def test_a_short_bar_is_held_above_the_table(ctx: WorldContext) -> None:
    """A 3 cm tall bar: the TCP rises so that the fingertips keep the table clearance; the
    grasp is reachable without touching the table, and the fingertips are the closest to it."""
    size = (0.08, 0.04, 0.03)
    grasps = sample_grasps(size, ctx.scene.grasp_limits)
    top = [g for g in grasps if g.is_top_down]
    assert len(top) == 2
    z_tcp = size[2] / 2 + top[0].T_object_tcp[2, 3]  # above the table [m]
    assert z_tcp == pytest.approx(ctx.scene.grasp_limits.finger_depth + TABLE_CLEARANCE)
    box = ObjectBox(pose_xyz_yaw(0.0, 0.1, size[2] / 2, 0.0), size)
    world = ctx.new_world(margin=0.0)
    home = {a: ctx.home(a) for a in ctx.arm_names}
    cands = solve_ik_candidates(
        ctx, world, {"bar": box}, [IKRequest("left", "bar", box, tuple(top))], home
    )
    assert cands
    world.set_objects({})
    clearance = world.min_distance(ctx.layout.join({**home, "left": cands[0].q}))
    assert clearance.pair is not None and "table" in (clearance.pair.first, clearance.pair.second)
    assert clearance.distance == pytest.approx(TABLE_CLEARANCE, abs=2e-4)
    # tilted grasps rise further (the tilted finger reaches lower) or are left out
    for g in grasps:
        assert (
            g.T_object_tcp[2, 3] + size[2] / 2
            >= fingertip_drop(ctx.scene.grasp_limits, g.tilt) + TABLE_CLEARANCE - 1e-12
        )


def test_a_bar_too_short_to_hold_gets_no_grasp() -> None:
    assert sample_grasps((0.08, 0.04, 0.01), wide(0.05)) == ()


def test_pair_tilts_come_after_the_grasp_set_each_angle_once() -> None:
    size = (0.08, 0.04, 0.05)
    proper = sample_grasps(size, wide(0.075))
    grasps = sample_grasps(size, wide(0.075), pair_tilts=(np.pi / 6, np.pi / 9, np.pi / 4))
    # the grasp set is a prefix; 45 degrees is not repeated; pair tilts grow, +t then -t
    assert [(g.tilt, g.flipped) for g in grasps[: len(proper)]] == [
        (g.tilt, g.flipped) for g in proper
    ]
    assert [round(float(np.degrees(g.tilt))) for g in grasps[len(proper) :]] == [
        20, 20, -20, -20, 30, 30, -30, -30
    ]  # fmt: skip
    assert [g.index for g in grasps] == list(range(len(grasps)))
    with pytest.raises(ValueError, match="tilts"):
        sample_grasps(size, wide(0.075), pair_tilts=(np.pi / 2,))


def test_grasp_options_reject_pair_tilts_out_of_range() -> None:
    assert GraspOptions().pair_tilts  # moderate tilts by default
    with pytest.raises(ParameterError, match=r"pair_tilts must lie in \(0, pi/2\)"):
        GraspOptions(pair_tilts=(0.0,))
