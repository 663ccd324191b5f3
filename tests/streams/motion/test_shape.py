"""Motion shape: lift height from clearance, rounded corners, the straight-end check."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.transforms import pose_xyz_yaw
from streams.context import WorldContext
from streams.motion.cartesian import straight_tool_move
from streams.motion.shape import (
    ShapeOptions,
    clearance_lift,
    footprint_distance,
    footprint_distances,
    round_corner,
    straight_end_deviation,
)

OPTS = ShapeOptions()
#: The shipped gripper's finger envelope (the cell's ``gripper.envelope``; the test of
#: ``tests/world/test_gripper.py`` reads it back from the URDF).
ENVELOPE = np.array(
    [[x, y, z] for x in (-0.011, 0.011) for y in (-0.042, 0.042) for z in (-0.048, 0.017)]
)
SIZE = (0.08, 0.04, 0.05)


def _top_down(x: float, y: float, z: float) -> np.ndarray:
    T = pose_xyz_yaw(x, y, z, 0.0)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])  # tool z down
    return T


def _box(x: float, y: float, height: float = 0.05) -> ObjectBox:
    return ObjectBox(pose_xyz_yaw(x, y, height / 2, 0.0), (0.08, 0.04, height))


def test_lone_object_gets_the_least_lift() -> None:
    # the grasped object itself: fingertips 17 mm below the TCP at its centre must clear its top
    T = _top_down(0.0, 0.0, 0.025)
    lift = clearance_lift(T, ENVELOPE, {"o": _box(0.0, 0.0)}, None, OPTS)
    tip = float(ENVELOPE[:, 2].max())
    assert lift == pytest.approx(max(OPTS.min_lift, 0.05 + OPTS.lift_margin - (0.025 - tip)))


def test_lift_follows_the_tallest_neighbour() -> None:
    T = _top_down(0.0, 0.0, 0.025)
    held = _box(0.0, 0.0)  # held: its bottom rests on the table
    low = clearance_lift(T, ENVELOPE, {"n": _box(0.0, 0.1, 0.05)}, held, OPTS)
    tall = clearance_lift(T, ENVELOPE, {"n": _box(0.0, 0.1, 0.09)}, held, OPTS)
    assert low == pytest.approx(0.05 + OPTS.lift_margin)
    assert tall == pytest.approx(0.09 + OPTS.lift_margin)
    far = clearance_lift(T, ENVELOPE, {"n": _box(0.0, 0.4, 0.09)}, held, OPTS)
    assert far == pytest.approx(OPTS.min_lift)  # not a neighbour ...
    toward = clearance_lift(
        T, ENVELOPE, {"n": _box(0.0, 0.4, 0.09)}, held, OPTS, np.array([0.0, 0.6])
    )
    assert toward == pytest.approx(tall)  # ... unless the motion passes it
    huge = clearance_lift(T, ENVELOPE, {"n": _box(0.0, 0.1, 0.5)}, held, OPTS)
    assert huge == OPTS.max_lift


def test_side_grasp_keeps_the_fixed_lift() -> None:
    T = pose_xyz_yaw(0.0, 0.0, 0.025, 0.0)
    T[:3, :3] = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # tool z along x
    assert clearance_lift(T, ENVELOPE, {}, None, OPTS) is None


def test_footprint_distance() -> None:
    box = ObjectBox(pose_xyz_yaw(0.0, 0.0, 0.025, np.pi / 2), SIZE)  # 0.04 along x, 0.08 along y
    assert footprint_distance(box, np.array([0.0, 0.0])) == 0.0
    assert footprint_distance(box, np.array([0.05, 0.0])) == pytest.approx(0.03)
    assert footprint_distance(box, np.array([0.0, 0.05])) == pytest.approx(0.01)


@pytest.mark.parametrize(
    ("field", "value"),
    [("straight", 0.0), ("grasp_speed", -1.0), ("lift_margin", -0.01), ("near", math.nan),
     ("max_lift", 0.01), ("step", math.inf)],
)  # fmt: skip
def test_bad_options_name_the_parameter(field: str, value: float) -> None:
    with pytest.raises(ParameterError, match=field):
        ShapeOptions(**{field: value})


def test_round_corner_keeps_the_straight_part_and_the_ends() -> None:
    before = np.stack([np.zeros(2), [0.0, 0.01], [0.0, 0.02], [0.0, 0.05], [0.0, 0.08]])
    after = np.stack([[0.0, 0.08], [0.1, 0.08], [0.2, 0.08], [0.3, 0.08]])
    path = round_corner(before, 2, after, max_after=1.0)
    np.testing.assert_array_equal(path[:3], before[:3])
    np.testing.assert_array_equal(path[-1], after[-1])
    assert not any(np.allclose(p, before[-1]) for p in path)  # the corner itself is cut
    assert np.all(np.diff(path[:, 0]) >= 0.0) and np.all(np.diff(path[:, 1]) >= 0.0)
    # at most max_after of the transfer is taken
    short = round_corner(before, 2, after, max_after=0.1)
    np.testing.assert_array_equal(short[-3:], after[-3:])


def test_straight_end_deviation(ctx: WorldContext) -> None:
    kin = ctx.kinematics["left"]
    q = ctx.home("left")
    q_grasp = straight_tool_move(kin, q, 0.20)
    assert q_grasp is not None
    grasp = q_grasp[-1]
    up = straight_tool_move(kin, grasp, -0.05, 0.002)
    assert up is not None
    lateral, angle = straight_end_deviation(kin, up, grasp, 0.02)
    assert lateral < 1e-4 and angle < 1e-4
    cut = np.linspace(grasp, q, 40)  # a joint-space line: leaves the tool axis at once
    lateral, angle = straight_end_deviation(kin, cut, grasp, 0.02)
    assert lateral > 0.002 or angle > np.radians(2.0)
    assert straight_end_deviation(kin, up[:3], grasp, 0.02) == (math.inf, math.inf)


def test_footprint_distances_match_one_point_at_a_time() -> None:
    box = ObjectBox(pose_xyz_yaw(0.1, -0.05, 0.025, 0.7), (0.08, 0.04, 0.05))
    pts = np.random.default_rng(3).uniform(-0.3, 0.3, (50, 2))
    expected = [footprint_distance(box, p) for p in pts]
    np.testing.assert_allclose(footprint_distances(box, pts), expected, atol=1e-12)
    assert footprint_distances(box, np.array([[0.1, -0.05]]))[0] == 0.0
