from pathlib import Path

import numpy as np

from sdar_tamp.language.pddl import parse_domain
from sdar_tamp.language.streams import parse_stream_file
from sdar_tamp.world.instance import Instance, Pose2D
from streams.context import WorldContext
from streams.motion import DualMotionPlanner
from streams.stream_map import STREAM_KINDS, ArmConf, make_stream_map

DOMAIN = Path(__file__).resolve().parents[2] / "domains" / "dual_arm_rearrangement"


def test_stream_file_parses_and_every_stream_is_bound(ctx: WorldContext) -> None:
    domain = parse_domain((DOMAIN / "domain.pddl").read_text(encoding="utf-8"))
    streams = parse_stream_file((DOMAIN / "stream.pddl").read_text(encoding="utf-8"), domain)
    names = {s.name for s in streams.streams}
    stream_map = make_stream_map(ctx)
    assert names == set(stream_map) == set(STREAM_KINDS)
    overlap = next(s for s in streams.streams if s.name == "test-overlap")
    assert overlap.outputs == ()


def test_overlap_grasp_and_ik_streams(ctx: WorldContext, instance: Instance) -> None:
    o = instance.objects[0]
    sm = make_stream_map(ctx, {x.name: x.size for x in instance.objects})
    assert sm["test-overlap"](o.name, o.start, "x", Pose2D(o.start.x + 0.02, o.start.y, 0.0))
    assert not sm["test-overlap"](o.name, o.start, "x", Pose2D(o.start.x + 0.3, o.start.y, 0.0))
    grasps = [g for (g,) in sm["sample-grasp"](o.name)]
    assert len(grasps) == 6 and grasps[0].is_top_down
    fluents = [("atpose", x.name, x.start) for x in instance.objects]
    confs = [c for (c,) in sm["inverse-kinematics"]("left", o.name, o.start, grasps[0], fluents)]
    T_obj = np.eye(4)
    T_obj[:3, :3] = [[np.cos(o.start.yaw), -np.sin(o.start.yaw), 0],
                     [np.sin(o.start.yaw), np.cos(o.start.yaw), 0], [0, 0, 1]]  # fmt: skip
    T_obj[:3, 3] = (o.start.x, o.start.y, o.size[2] / 2)
    for c in confs:
        tcp = ctx.kinematics["left"].fk_tcp(np.array(c.q))
        np.testing.assert_allclose(tcp, T_obj @ grasps[0].T_object_tcp, atol=1e-9)
    buffers = [p for (p,), _ in zip(sm["sample-buffer"](o.name, fluents), range(3), strict=False)]
    assert len(buffers) == 3


def test_motion_stream_plans_a_validated_place(
    ctx: WorldContext, instance: Instance, planner: DualMotionPlanner
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
