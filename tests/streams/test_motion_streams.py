"""The motion streams (``plan-dual-motion``, its quick variant, the duration functions) as the
stream map binds them."""

from typing import Any

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.instance import Instance, Pose2D
from streams import motion_streams
from streams.context import WorldContext
from streams.motion.planner import MotionPlanner
from streams.motion.records import MotionResult
from streams.stream_map import make_stream_map
from streams.stream_types import ArmConf, CellConf


def test_motion_stream_plans_a_validated_place(
    ctx: WorldContext, instance: Instance, planner: MotionPlanner
) -> None:
    sizes = {x.name: x.size for x in instance.objects}
    sm = make_stream_map(ctx, sizes, planner=planner)
    o = instance.objects[3]
    grasp = next(g for (g,) in sm["sample-grasp"](o.name))
    fluents = [("atpose", x.name, x.start) for x in instance.objects if x.name != o.name]
    pick = next(c for (c,) in sm["inverse-kinematics"]("left", o.name, o.start, grasp, fluents))
    place_pose = next(p for (p,) in sm["sample-buffer"](o.name, fluents))
    place = next(c for (c,) in sm["inverse-kinematics"]("left", o.name, place_pose, grasp, fluents))
    home_right = ArmConf("right", tuple(ctx.home("right")))
    (q1,) = next(sm["combine-confs"]("left", pick, "right", home_right))
    (q2,) = next(sm["combine-confs"]("right", home_right, "left", place))
    holding = [("holding", "left", o.name, grasp)]
    (result,) = next(sm["plan-dual-motion"](q1, q2, fluents + holding))
    assert result.success and result.trajectory is not None
    q = result.trajectory.q
    np.testing.assert_allclose(q[0], q1.q, atol=1e-9)
    np.testing.assert_allclose(q[-1], q2.q, atol=1e-9)
    assert np.allclose(q[:, 6:], q1.q[6:])  # the right arm waits at home


def test_distance_estimates_a_rest_to_rest_time(ctx: WorldContext) -> None:
    sm = make_stream_map(ctx)
    home = {a: ArmConf(a, tuple(ctx.home(a))) for a in ctx.arm_names}
    d0 = CellConf(home["left"], home["right"])
    moved = list(home["left"].q)
    moved[0] += 1.0
    d1 = CellConf(ArmConf("left", tuple(moved)), home["right"])
    assert sm["Distance"](d0, d0) == 0.0
    t = sm["Distance"](d0, d1)
    v = ctx.scene.arm("left").velocity_limit[0]
    assert 1.0 / v < t < 1.0 / v + 2.0  # slower than the velocity limit allows, not absurd


def test_unknown_motion_planner_is_refused(ctx: WorldContext) -> None:
    with pytest.raises(ParameterError, match="motion planner must be one of sdar, plain"):
        make_stream_map(ctx, motion="fast")


@pytest.mark.parametrize("sampling", [False, True])
def test_the_full_motion_skips_the_rung_the_quick_stream_failed(
    ctx: WorldContext, planner: MotionPlanner, monkeypatch: pytest.MonkeyPatch, sampling: bool
) -> None:
    """The quick stream is the ladder's first rung alone (deterministic): after it failed on
    a motion, the full stream starts that same motion at the second rung."""
    if sampling and not motion_streams.ompl_available():
        pytest.skip("OMPL not installed")
    calls: list[tuple[bool, tuple[str, ...] | None]] = []

    def failing(planner: Any, request: Any, fallbacks: bool = True, sequential_only: bool = False,
                strategies: Any = None) -> MotionResult:  # fmt: skip
        calls.append((fallbacks, None if strategies is None else tuple(s.name for s in strategies)))
        return MotionResult(False, None, None, 0.0, 0.0, ("plain: optimisation failed",),
                            reason="plain: optimisation failed")  # fmt: skip

    monkeypatch.setattr(motion_streams, "plan_dual_motion", failing)
    sm = make_stream_map(ctx, planner=planner, sampling=sampling)
    home = [ArmConf(a, tuple(float(x) for x in ctx.home(a))) for a in ctx.arm_names]
    d1 = CellConf(*home)
    d2 = CellConf(ArmConf(home[0].arm, tuple(x + 0.1 for x in home[0].q)), home[1])
    here = [("atpose", "o", Pose2D(0.1, 0.0, 0.0))]
    there = [("atpose", "o", Pose2D(0.2, 0.0, 0.0))]
    assert not list(sm["plan-dual-motion-quick"](d1, d2, here))
    assert not list(sm["plan-dual-motion"](d1, d2, here))
    assert not list(sm["plan-dual-motion"](d1, d2, there))  # another motion: the whole ladder
    if sampling:  # the ladder is passed: its first rung has the sampled warm start
        ladder = ("plain", "untangle", "sequential")
        assert calls == [(False, ("plain",)), (True, ladder[1:]), (True, ladder)]
    else:
        assert calls == [(False, None), (True, ("untangle", "sequential")), (True, None)]
