"""Compatible IK tuples for cells of more than two arms (a three-arm test cell)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.transforms import pose_xyz_yaw
from streams.context import WorldContext
from streams.grasps import sample_grasps
from streams.ik import IKRequest, compatible_tuples, solve_ik_candidates

CELL = Path(__file__).parents[1] / "sdar" / "data" / "cells" / "three_arms.yaml"
SIZE = (0.08, 0.04, 0.05)


def test_compatible_tuples_are_jointly_collision_free_and_cheapest_first() -> None:
    ctx = WorldContext.load(CELL)
    world = ctx.new_world()
    places = {"o0": (0.1, -0.15, 0.0), "o1": (-0.1, -0.15, 1.57), "o2": (0.0, 0.15, 0.0)}
    objects = {
        o: ObjectBox(pose_xyz_yaw(x, y, SIZE[2] / 2, yaw), SIZE)
        for o, (x, y, yaw) in places.items()
    }
    home = {a: ctx.home(a) for a in ctx.arm_names}
    grasps = sample_grasps(SIZE, ctx.scene.grasp_limits)
    per_arm = [
        solve_ik_candidates(ctx, world, objects, [IKRequest(a, o, objects[o], grasps)], home)
        for a, o in zip(ctx.arm_names, ("o0", "o2", "o1"), strict=True)
    ]
    assert all(per_arm)
    found = compatible_tuples(ctx, world, objects, per_arm, limit=4)
    assert found
    totals = [sum(c.cost for c in combo) for combo in found]
    assert totals == sorted(totals)
    cheapest = sum(min(c.cost for c in cands) for cands in per_arm)
    assert totals[0] >= cheapest - 1e-12
    for combo in found:
        assert [c.arm for c in combo] == list(ctx.arm_names)
        for qs in ([c.q for c in combo], [c.q_pre for c in combo]):
            q = ctx.layout.join({c.arm: x for c, x in zip(combo, qs, strict=True)})
            if world.in_collision(q):  # only grippers touching what they grasp
                for p in world.report():
                    pair = {p.first, p.second}
                    assert any(f"object:{c.obj}" in pair for c in combo)
    assert compatible_tuples(ctx, world, objects, [*per_arm[:2], []]) == []
    two = compatible_tuples(ctx, world, objects, per_arm[:2], limit=1)
    assert two and len(two[0]) == 2  # the third arm waits at home
    assert np.isfinite(totals[0])


def test_compatible_tuples_refuse_bad_limits() -> None:
    ctx = WorldContext.load(CELL)
    with pytest.raises(ParameterError, match="limit"):
        compatible_tuples(ctx, ctx.new_world(), {}, [[]], limit=0)
