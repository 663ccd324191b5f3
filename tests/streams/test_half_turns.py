"""Half-turn twins of grasps, the IK stream's twin configurations and the one-arm time
estimates SDAR-M chooses placements by."""

from __future__ import annotations

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.shipped_cell import SHIPPED_GRASP
from streams.context import WorldContext
from streams.grasps import DEFAULT_PAIR_TILTS, half_turn_twins, sample_grasps
from streams.stream_map import RearrangementStreams, make_stream_map
from streams.stream_types import ArmConf

HALF_TURN = np.diag([-1.0, -1.0, 1.0])  # about the object's vertical axis


def test_twins_hold_the_cuboid_turned_by_half_a_turn() -> None:
    grasps = sample_grasps((0.08, 0.04, 0.05), SHIPPED_GRASP, pair_tilts=DEFAULT_PAIR_TILTS)
    twins = half_turn_twins(grasps)
    assert twins[:6] == (1, 0, 5, 4, 3, 2)  # top-down pair; +45/-45 of opposite flips
    for g, k in zip(grasps, twins, strict=True):
        assert k is not None and twins[k] == g.index  # an involution
        twin = grasps[k]
        np.testing.assert_allclose(HALF_TURN @ g.T_object_tcp[:3, :3], twin.T_object_tcp[:3, :3])
        np.testing.assert_allclose(g.T_object_tcp[:3, 3], twin.T_object_tcp[:3, 3])
        assert twin.tilt == -g.tilt and twin.flipped != g.flipped


def test_without_the_flipped_variants_there_is_no_twin() -> None:
    grasps = sample_grasps((0.08, 0.04, 0.05), SHIPPED_GRASP, symmetric=False)
    assert half_turn_twins(grasps) == (None, None, None)


def test_ik_yields_the_grasps_own_configurations_then_its_twins(
    ctx: WorldContext, instance: Instance
) -> None:
    o = instance.objects[1]
    sizes = {x.name: x.size for x in instance.objects}
    streams = RearrangementStreams(ctx, sizes)
    g, twin = streams.grasps(o.name)[0], streams.grasps(o.name)[1]
    fluents = [("atpose", x.name, x.start) for x in instance.objects]
    both = [c for (c,) in streams.inverse_kinematics("left", o.name, o.start, g, fluents)]
    own = [c for (c,) in RearrangementStreams(ctx, sizes, half_turns=False).inverse_kinematics(
        "left", o.name, o.start, g, fluents)]  # fmt: skip
    kin = ctx.kinematics["left"]
    T_obj = kin.fk_tcp(np.array(own[0].q)) @ np.linalg.inv(g.T_object_tcp)
    assert len(own) >= 1 and len(both) == 2 * len(own)
    assert [c.q for c in both[: len(own)]] == [c.q for c in own]  # the grasp's own first
    for c in both[len(own) :]:
        np.testing.assert_allclose(kin.fk_tcp(np.array(c.q)), T_obj @ twin.T_object_tcp, atol=1e-9)
        # only wrist 3 differs from an own configuration, by half a turn
        match = next(m for m in own if np.allclose(m.q[:5], c.q[:5]))
        assert abs(abs(c.q[5] - match.q[5]) - np.pi) < 1e-9


def test_tilted_grasps_get_no_twin_configurations(ctx: WorldContext, instance: Instance) -> None:
    o = instance.objects[1]
    sizes = {x.name: x.size for x in instance.objects}
    tilted = RearrangementStreams(ctx, sizes).grasps(o.name)[2]
    a = list(RearrangementStreams(ctx, sizes).inverse_kinematics("left", o.name, o.start, tilted))
    b = list(
        RearrangementStreams(ctx, sizes, half_turns=False).inverse_kinematics(
            "left", o.name, o.start, tilted
        )
    )
    assert [c.q for (c,) in a] == [c.q for (c,) in b]


def test_arm_distance_is_the_slowest_joints_rest_to_rest_time(ctx: WorldContext) -> None:
    sm = make_stream_map(ctx)
    home = tuple(ctx.home("left"))
    q0 = ArmConf("left", home)
    q1 = ArmConf("left", (*home[:5], home[5] + 0.8))  # wrist 3 alone: 0.8 rad
    q2 = ArmConf("left", (home[0] + 0.2, *home[1:5], home[5] + 3.0))
    a = ctx.scene.arm("left").acceleration_limit[5]
    v = ctx.scene.arm("left").velocity_limit[5]
    assert sm["ArmDistance"](q0, q0) == 0.0
    assert sm["ArmDistance"](q0, q1) == pytest.approx(2.0 * np.sqrt(0.8 / a))
    assert sm["ArmDistance"](q0, q2) == pytest.approx(3.0 / v + v / a)  # velocity-limited


def test_arm_distance_refuses_two_arms(ctx: WorldContext) -> None:
    sm = make_stream_map(ctx)
    with pytest.raises(ParameterError, match=r"ArmDistance.*'left' and 'right'"):
        sm["ArmDistance"](ArmConf("left", tuple(ctx.home("left"))),
                          ArmConf("right", tuple(ctx.home("right"))))  # fmt: skip


def test_next_motion_penalises_a_wrist_near_its_limits(ctx: WorldContext) -> None:
    sm = make_stream_map(ctx)
    home = tuple(ctx.home("left"))
    a = ctx.scene.arm("left").acceleration_limit[5]

    def at(w3: float) -> float:
        return float(sm["NextMotion"](ArmConf("left", (*home[:5], w3))))

    assert at(0.0) == at(1.5) == at(-1.5) == 0.0
    mean = (2.9**2 + (np.pi - 2.9) ** 2) / (2.0 * np.pi)
    expected = 2.0 * np.sqrt(mean / a) - 2.0 * np.sqrt(np.pi / 4 / a)
    assert at(2.9) == pytest.approx(expected) and at(-2.9) == pytest.approx(expected)
    assert 0.0 < at(2.0) < at(2.9) < at(np.pi)
    assert (
        RearrangementStreams(ctx, {}, half_turns=False).motions.next_motion(
            ArmConf("left", (*home[:5], 2.9))
        )
        == 0.0
    )  # without twins there is no shorter variant to expect
