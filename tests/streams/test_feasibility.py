"""Infeasibility proofs: objects boxed in at their starts (never picked first) or at their goals
(never placed last) are found and named; dense but solvable scenes are not refused."""

from __future__ import annotations

import math

import pytest

from sdar_tamp.world.generators import GeneratorOptions, generate_instance
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D
from sdar_tamp.world.scene import Workspace
from sdar_tamp.world.suites import load_suite, suite_members
from streams.context import WorldContext
from streams.feasibility import (
    PLANNER_MARGIN,
    VALIDATOR_MARGIN,
    ProofCheck,
    prove_infeasible,
    prove_unplannable,
)
from streams.stream_map import IK_MARGIN

SIZE = (0.08, 0.04, 0.05)  # closes along y only (0.08 m is wider than the gripper opens)
WORKSPACE = Workspace((-0.25, 0.25), (-0.30, 0.30))
#: Three objects side by side along their closing axis, 5 mm apart: a finger needs 2.2 cm.
TRIO = (Pose2D(0.0, -0.045, 0.0), Pose2D(0.0, 0.0, 0.0), Pose2D(0.0, 0.045, 0.0))
SPREAD = (Pose2D(-0.15, -0.2, 0.0), Pose2D(0.0, -0.2, 0.0), Pose2D(0.15, -0.2, 0.0))


def _instance(starts: tuple[Pose2D, ...], goals: tuple[Pose2D, ...]) -> Instance:
    objects = tuple(
        ObjectSpec(f"o{i}", SIZE, s, g) for i, (s, g) in enumerate(zip(starts, goals, strict=True))
    )
    return Instance("hand", WORKSPACE, objects)


def test_a_trio_boxed_in_at_the_start_can_never_be_picked_first(ctx: WorldContext) -> None:
    proof = prove_infeasible(ctx, _instance(TRIO, SPREAD))
    assert proof is not None and proof.phase == "start"
    assert set(proof.objects) == {"o0", "o1", "o2"}
    by_name = {s.name: s for s in proof.stuck}
    assert by_name["o1"].neighbours == ("o0", "o2")  # boxed in on both closing sides
    assert by_name["o0"].neighbours == ("o1",) and by_name["o2"].neighbours == ("o1",)
    lines = proof.lines()
    assert "can ever be picked first" in lines[0]
    assert "o1: no grasp clear of o0, o2" in lines


def test_a_trio_boxed_in_at_the_goal_can_never_be_placed_last(ctx: WorldContext) -> None:
    proof = prove_infeasible(ctx, _instance(SPREAD, TRIO))
    assert proof is not None and proof.phase == "goal"
    assert set(proof.objects) == {"o0", "o1", "o2"}
    assert "placed last" in proof.summary()


def test_boxed_in_objects_that_never_need_to_move_prove_nothing(ctx: WorldContext) -> None:
    assert prove_infeasible(ctx, _instance(TRIO, TRIO)) is None
    # turned by a full turn: still its start
    turned = tuple(Pose2D(p.x, p.y, p.yaw + 2 * math.pi) for p in TRIO)
    assert prove_infeasible(ctx, _instance(TRIO, turned)) is None


def test_a_dense_scene_freed_in_order_is_not_refused(ctx: WorldContext) -> None:
    """o0 is boxed in by o1 standing 5 mm beside it, across its closing axis; o1 (turned a
    quarter) closes along x and is free: taking o1 away first frees o0."""
    from sdar_tamp.world.collision import ObjectBox
    from sdar_tamp.world.transforms import pose_xyz_yaw
    from streams.feasibility import remove_graspable
    from streams.grasps import sample_grasps

    starts = (Pose2D(0.0, 0.0, 0.0), Pose2D(0.0, 0.065, math.pi / 2))
    goals = (Pose2D(0.0, -0.2, 0.0), Pose2D(0.15, 0.2, 0.0))
    inst = _instance(starts, goals)
    boxes = {
        o.name: ObjectBox(pose_xyz_yaw(o.start.x, o.start.y, SIZE[2] / 2, o.start.yaw), SIZE)
        for o in inst.objects
    }
    width = ctx.scene.grasp_limits
    removal = remove_graspable(ctx, boxes, {n: sample_grasps(SIZE, width) for n in boxes})
    assert removal.rounds == (("o1",), ("o0",)) and removal.stuck == ()
    assert prove_infeasible(ctx, inst) is None


def test_an_object_out_of_reach_is_named(ctx: WorldContext) -> None:
    far = Pose2D(0.0, 0.95, 0.0)  # beyond both arms
    inst = _instance((far,), (Pose2D(0.0, 0.0, 0.0),))
    proof = prove_infeasible(ctx, inst)
    assert proof is not None and proof.objects == ("o0",)
    assert not proof.stuck[0].reachable
    assert proof.stuck[0].reason() == "o0: no grasp within reach of any arm"


@pytest.mark.parametrize("name", ["R12", "S12", "D12", "M1", "M5", "M10"])
def test_solvable_paper_instances_are_not_refused(ctx: WorldContext, name: str) -> None:
    (inst,) = [i for i in load_suite("paper") if i.name == name]
    assert prove_unplannable(ctx, inst) is None


def test_the_stress_suite_is_generated_without_provably_unsolvable_instances(
    ctx: WorldContext,
) -> None:
    check = ProofCheck(ctx)
    shipped = load_suite("stress")
    assert all(check(inst) is None for inst in shipped)
    (m,) = [m for m in suite_members("stress") if m.name == "D20"]
    options = GeneratorOptions(gap=m.gap or 0.0)
    first = generate_instance(m.family, m.n_objects, m.seed, options, name=m.name)
    reason = check(first)  # the first sample of this seed boxes objects in at their starts
    assert reason is not None and "picked first" in reason and "o7" in reason
    accepted = generate_instance(m.family, m.n_objects, m.seed, options, m.name, accept=check)
    assert accepted == shipped[[i.name for i in shipped].index("D20")]


def test_the_dense_suite_is_generated_without_provably_unsolvable_instances(
    ctx: WorldContext,
) -> None:
    check = ProofCheck(ctx)
    shipped = load_suite("dense")
    assert all(check(inst) is None for inst in shipped)
    m = suite_members("dense")[0]
    first = generate_instance(m.family, m.n_objects, m.seed, name=m.name)
    reason = check(first)  # packed at the paper's clearance: the first sample boxes o0 in
    assert reason is not None and "picked first" in reason and "o0" in reason
    assert generate_instance(m.family, m.n_objects, m.seed, name=m.name, accept=check) == shipped[0]


def test_too_little_room_for_the_planner_is_told_apart_from_no_plan_at_all(
    ctx: WorldContext,
) -> None:
    """2.3 cm between neighbours: a finger (2.2 cm beside the object) fits within the
    validator's tolerance, not within the planner's 3 mm IK clearance."""
    trio = tuple(Pose2D(0.0, k * 0.063, 0.0) for k in (-1, 0, 1))
    inst = _instance(trio, SPREAD)
    assert prove_infeasible(ctx, inst, margin=VALIDATOR_MARGIN) is None
    proof = prove_unplannable(ctx, inst)
    assert proof is not None and proof.margin == PLANNER_MARGIN == IK_MARGIN
    assert "with the planner's 3 mm grasp clearance" in proof.summary()
    assert "o1" in proof.objects
    # boxed in for any plan: the stronger proof is the one returned
    strict = prove_unplannable(ctx, _instance(TRIO, SPREAD))
    assert strict is not None and strict.margin == VALIDATOR_MARGIN
    assert "clearance" not in strict.summary()
