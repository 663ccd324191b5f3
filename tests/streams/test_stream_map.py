import dataclasses
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.streams import parse_stream_file
from sdar_tamp.world.errors import ArmLayoutError
from sdar_tamp.world.instance import Instance, Pose2D
from streams.context import WorldContext
from streams.stream_map import RearrangementStreams, make_stream_map
from streams.stream_types import STREAM_KINDS, ArmConf, CellConf

DOMAIN = Path(__file__).resolve().parents[2] / "domains" / "dual_arm_rearrangement"


def test_stream_file_parses_and_every_stream_is_bound(ctx: WorldContext) -> None:
    domain = parse_domain((DOMAIN / "domain.pddl").read_text(encoding="utf-8"))
    streams = parse_stream_file((DOMAIN / "stream.pddl").read_text(encoding="utf-8"), domain)
    names = {s.name for s in streams.streams} | {f.name for f in streams.functions}
    stream_map = make_stream_map(ctx)
    assert names == {n.lower() for n in stream_map} == {n.lower() for n in STREAM_KINDS}
    overlap = next(s for s in streams.streams if s.name == "test-overlap")
    assert overlap.outputs == ()


def test_overlap_grasp_and_ik_streams(ctx: WorldContext, instance: Instance) -> None:
    o = instance.objects[0]
    sm = make_stream_map(ctx, {x.name: x.size for x in instance.objects})
    assert sm["test-overlap"](o.name, o.start, "x", Pose2D(o.start.x + 0.02, o.start.y, 0.0))
    assert not sm["test-overlap"](o.name, o.start, "x", Pose2D(o.start.x + 0.3, o.start.y, 0.0))
    grasps = [g for (g,) in sm["sample-grasp"](o.name)]
    # the grasp set (top-down, then 45 degrees either way), then the pair grasps (20 and 30)
    assert len(grasps) == 6 + 8 and grasps[0].is_top_down
    tilts = [round(float(np.degrees(abs(g.tilt)))) for g in grasps]
    assert tilts == [0, 0, 45, 45, 45, 45, 20, 20, 20, 20, 30, 30, 30, 30]
    fluents = [("atpose", x.name, x.start) for x in instance.objects]
    confs = [c for (c,) in sm["inverse-kinematics"]("left", o.name, o.start, grasps[0], fluents)]
    T_obj = np.eye(4)
    T_obj[:3, :3] = [[np.cos(o.start.yaw), -np.sin(o.start.yaw), 0],
                     [np.sin(o.start.yaw), np.cos(o.start.yaw), 0], [0, 0, 1]]  # fmt: skip
    T_obj[:3, 3] = (o.start.x, o.start.y, o.size[2] / 2)
    assert len(confs) == 2  # the grasp's own configuration, then its half-turn twin's
    for c, g in zip(confs, grasps[:2], strict=True):
        tcp = ctx.kinematics["left"].fk_tcp(np.array(c.q))
        np.testing.assert_allclose(tcp, T_obj @ g.T_object_tcp, atol=1e-9)
    buffers = [p for (p,), _ in zip(sm["sample-buffer"](o.name, fluents), range(3), strict=False)]
    assert len(buffers) == 3


def test_cfree_is_the_complement_of_overlap(ctx: WorldContext, instance: Instance) -> None:
    o = instance.objects[0]
    sm = make_stream_map(ctx, {x.name: x.size for x in instance.objects})
    near, far = Pose2D(o.start.x + 0.02, o.start.y, 0.0), Pose2D(o.start.x + 0.3, o.start.y, 0.0)
    assert not sm["test-cfree"](o.name, o.start, "x", near)
    assert sm["test-cfree"](o.name, o.start, "x", far)
    assert not sm["test-cfree"](o.name, o.start, o.name, far)  # an object and itself


def test_combine_confs_rejects_arms_in_collision(ctx: WorldContext) -> None:
    sm = make_stream_map(ctx)
    home = {a: ArmConf(a, tuple(ctx.home(a))) for a in ctx.arm_names}
    assert list(sm["combine-confs"]("left", home["left"], "right", home["right"]))
    assert not list(sm["combine-confs"]("left", home["left"], "left", home["left"]))
    # a left configuration whose gripper touches the right arm's gripper at home
    crossing = ArmConf("left", (-2.781, -3.068, 0.89, 2.288, -0.423, 0.863))
    pairs = ctx.new_world().report(CellConf(crossing, home["right"]).q)
    assert any(p.first.startswith("left") and p.second.startswith("right") for p in pairs)
    assert not list(sm["combine-confs"]("left", crossing, "right", home["right"]))


def test_buffers_keep_clear_of_reserved_goals(ctx: WorldContext, instance: Instance) -> None:
    sizes = {x.name: x.size for x in instance.objects}
    goals = {x.name: x.goal for x in instance.objects}
    sm = make_stream_map(ctx, sizes, reserved=goals)
    o = instance.objects[0]
    fluents = [("atpose", x.name, x.start) for x in instance.objects]
    for (p,) in sm["sample-buffer"](o.name, fluents):
        for x in instance.objects:
            if x.name != o.name:
                assert sm["test-cfree"](o.name, p, x.name, x.goal)
                assert sm["test-cfree"](o.name, p, x.name, x.start)


def test_ik_queries_of_one_arrangement_share_one_collision_world(
    ctx: WorldContext, instance: Instance
) -> None:
    sm_obj = RearrangementStreams(ctx, {x.name: x.size for x in instance.objects})
    fluents = [("atpose", x.name, x.start) for x in instance.objects]
    grasps = [g for (g,) in sm_obj.sample_grasp(instance.objects[0].name)]
    for o in instance.objects[:4]:  # picks of four objects where they rest, two grasps, both arms
        for arm in ctx.arm_names:
            for g in grasps[:2]:
                list(sm_obj.inverse_kinematics(arm, o.name, o.start, g, fluents))
    assert sm_obj.scenes.builds == 1 and sm_obj.scenes.hits == 15
    # a place of the first object elsewhere is another arrangement: one more world
    o = instance.objects[0]
    after = [f for f in fluents if f[1] != o.name]
    list(sm_obj.inverse_kinematics("left", o.name, o.goal, grasps[0], after))
    list(sm_obj.inverse_kinematics("right", o.name, o.goal, grasps[0], after))
    assert sm_obj.scenes.builds == 2 and sm_obj.scenes.hits == 16


def test_dual_conf_holds_every_arm_in_layout_order(ctx: WorldContext) -> None:
    home = {a: ArmConf(a, tuple(ctx.home(a))) for a in ctx.arm_names}
    d = CellConf(*(home[a] for a in ctx.arm_names))
    assert d.arms == (home["left"], home["right"]) and d.arm("right") is home["right"]
    np.testing.assert_array_equal(d.q, ctx.scene.home)
    combine = make_stream_map(ctx)["combine-confs"]
    ((combined,),) = list(combine("right", home["right"], "left", home["left"]))
    assert combined == d  # arms in layout order whatever order the stream got them in
    with pytest.raises(ParameterError, match="CellConf: expected one ArmConf per arm, got none"):
        CellConf()
    with pytest.raises(ParameterError, match=r"arm must be one of \['left', 'right'\]; got 'up'"):
        d.arm("up")


def test_other_arm_needs_two_arms(ctx: WorldContext) -> None:
    assert ctx.other("left") == "right" and ctx.other("right") == "left"
    with pytest.raises(ArmLayoutError, match="unknown arm 'up'"):
        ctx.other("up")
    third = dataclasses.replace(ctx.scene.arms[0], name="middle")
    three = WorldContext(dataclasses.replace(ctx.scene, arms=(*ctx.scene.arms, third)), {}, {})
    with pytest.raises(ParameterError, match="other: defined for two arms, the scene has 3"):
        three.other("left")
    assert three.split(np.arange(18.0))["middle"].tolist() == list(range(12, 18))
