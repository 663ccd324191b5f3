import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.collision import ObjectBox
from streams.context import WorldContext
from streams.grasps import pregrasp_offset, sample_grasps
from streams.ik import (
    GraspIK,
    IKRequest,
    SceneCache,
    collision_free_candidates,
    compatible_pairs,
    iter_collision_free_candidates,
    solve_ik_candidates,
)


def _requests(
    ctx: WorldContext, objects: dict[str, ObjectBox], names: list[str]
) -> list[IKRequest]:
    grasps = sample_grasps(objects[names[0]].size, ctx.scene.grasp_limits)
    return [IKRequest(a, o, objects[o], grasps) for a in ctx.arm_names for o in names]


def test_candidates_reproduce_the_grasp_pose_and_are_ranked(
    ctx: WorldContext, objects: dict[str, ObjectBox]
) -> None:
    world = ctx.new_world()
    names = list(objects)[:3]
    home = {a: ctx.home(a) for a in ctx.arm_names}
    cands = solve_ik_candidates(ctx, world, objects, _requests(ctx, objects, names), home)
    assert cands
    assert [c.cost for c in cands] == sorted(c.cost for c in cands)
    for c in cands:
        kin = ctx.kinematics[c.arm]
        T = objects[c.obj].T_world_obj @ c.grasp.T_object_tcp
        np.testing.assert_allclose(kin.fk_tcp(c.q), T, atol=1e-9)
        np.testing.assert_allclose(kin.fk_tcp(c.q_pre), pregrasp_offset(T, 0.08), atol=1e-9)
        lo, hi = kin.spec.lower_array, kin.spec.upper_array
        assert np.all(c.q >= lo - 1e-12) and np.all(c.q <= hi + 1e-12)
        # the pre-grasp never collides with anything
        other = ctx.other(c.arm)
        qs = {c.arm: c.q_pre, other: ctx.home(other)}
        assert not world.in_collision(ctx.layout.join(qs))


def test_ranking_for_two_arms_two_objects_six_grasps_is_repeatable(
    ctx: WorldContext, objects: dict[str, ObjectBox]
) -> None:
    # Its time is measured by benchmarks/bench_motion.py (ik_ranking_median_s).
    world = ctx.new_world()
    reqs = _requests(ctx, objects, list(objects)[:2])
    home = {a: ctx.home(a) for a in ctx.arm_names}
    first = solve_ik_candidates(ctx, world, objects, reqs, home)
    again = solve_ik_candidates(ctx, world, objects, reqs, home)
    assert first and len(first) == len(again)
    for a, b in zip(first, again, strict=True):
        assert (a.arm, a.obj, a.cost) == (b.arm, b.obj, b.cost)
        np.testing.assert_array_equal(a.q, b.q)


def test_compatible_pairs_are_jointly_collision_free(
    ctx: WorldContext, objects: dict[str, ObjectBox]
) -> None:
    world = ctx.new_world()
    names = list(objects)
    home = {a: ctx.home(a) for a in ctx.arm_names}
    grasps = sample_grasps(objects[names[0]].size, ctx.scene.grasp_limits)
    left = solve_ik_candidates(
        ctx, world, objects, [IKRequest("left", names[0], objects[names[0]], grasps)], home
    )
    right = solve_ik_candidates(
        ctx, world, objects, [IKRequest("right", names[1], objects[names[1]], grasps)], home
    )
    pairs = compatible_pairs(ctx, world, objects, left, right, limit=3)
    assert pairs
    for a, b in pairs:
        assert a.arm == "left" and b.arm == "right"
        assert not world.in_collision(ctx.layout.join({a.arm: a.q_pre, b.arm: b.q_pre}))


def test_scene_cache_keeps_one_world_per_arrangement(
    ctx: WorldContext, objects: dict[str, ObjectBox]
) -> None:
    cache = SceneCache(ctx, margin=0.003, capacity=2)
    names = list(objects)
    fewer = {k: v for k, v in objects.items() if k != names[0]}
    a = cache.world("all", objects)
    assert cache.world("all", objects) is a and (cache.builds, cache.hits) == (1, 1)
    assert set(a.objects) == set(objects)
    b = cache.world("fewer", fewer)
    assert b is not a and set(b.objects) == set(fewer) and cache.builds == 2
    # a third arrangement reuses the least recently used world ("all")
    c = cache.world("one", {names[0]: objects[names[0]]})
    assert c is a and set(c.objects) == {names[0]} and cache.builds == 3
    assert cache.world("fewer", fewer) is b and cache.hits == 2
    # the world of "all" now serves "one": a holder of it must ask again
    assert cache.holds("one", a) and not cache.holds("all", a) and cache.holds("fewer", b)


def test_scene_cache_refuses_no_capacity(ctx: WorldContext) -> None:
    with pytest.raises(ParameterError, match="capacity must be >= 1, got 0"):
        SceneCache(ctx, margin=0.003, capacity=0)


def test_one_grasp_ik_table_serves_every_arrangement(
    ctx: WorldContext, objects: dict[str, ObjectBox]
) -> None:
    """The closed-form IK of a pose, computed once, filtered by each arrangement's collisions,
    gives what a fresh solve gives; an object put where the gripper goes removes candidates."""
    world = ctx.new_world()
    name = next(iter(objects))
    box = objects[name]
    grasps = sample_grasps(box.size, ctx.scene.grasp_limits)
    home = {a: ctx.home(a) for a in ctx.arm_names}
    table = GraspIK(ctx, "left", name, box, grasps)
    fresh = solve_ik_candidates(ctx, world, objects, [IKRequest("left", name, box, grasps)], home)
    kept = collision_free_candidates(ctx, world, objects, table, home)
    assert fresh and [(c.grasp.index, c.branch) for c in kept] == [
        (c.grasp.index, c.branch) for c in fresh
    ]
    one = collision_free_candidates(ctx, world, objects, table, home, (fresh[0].grasp.index,))
    assert {c.grasp.index for c in one} == {fresh[0].grasp.index}
    # a tall box over the object's top leaves no top-down grasp
    T = box.T_world_obj.copy()
    T[2, 3] += 0.12
    crowded = {**objects, "lid": ObjectBox(T, (0.06, 0.06, 0.05))}
    blocked = collision_free_candidates(ctx, world, crowded, table, home)
    assert len(blocked) < len(kept)
    assert not any(c.grasp.is_top_down for c in blocked)


def test_candidates_one_at_a_time_check_only_what_is_asked_for(
    ctx: WorldContext, objects: dict[str, ObjectBox]
) -> None:
    """The lazy candidates are the list's, in its order; taking the first one checks fewer
    configurations than the list; a world used for another arrangement in between is given
    the candidates' objects back before the next check."""
    name = next(iter(objects))
    arm = ctx.arm_names[0]
    grasps = sample_grasps(objects[name].size, ctx.scene.grasp_limits)
    table = GraspIK(ctx, arm, name, objects[name], grasps)
    home = {a: ctx.home(a) for a in ctx.arm_names}
    world = ctx.new_world()
    calls = [0]
    check = world.in_collision

    def counted(q: np.ndarray | None = None) -> bool:
        calls[0] += 1
        return check(q)

    world.in_collision = counted  # type: ignore[method-assign]
    every = collision_free_candidates(ctx, world, objects, table, home)
    assert len(every) >= 2
    all_checks, calls[0] = calls[0], 0
    lazy = iter_collision_free_candidates(ctx, lambda: world, objects, table, home)
    first = next(lazy)
    assert calls[0] < all_checks
    assert (first.grasp, first.branch, first.cost) == (
        every[0].grasp,
        every[0].branch,
        every[0].cost,
    )
    world.set_objects({})  # the scratch world serves another arrangement meanwhile
    rest = list(lazy)
    assert world.objects.keys() == objects.keys()
    assert [(c.grasp, c.branch) for c in rest] == [(c.grasp, c.branch) for c in every[1:]]
