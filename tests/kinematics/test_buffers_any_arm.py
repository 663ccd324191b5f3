"""The buffer pool of a numeric-IK arm checks the reach of the poses it meets, not the pool's."""

import numpy as np

from streams.buffers import GRASP_CORRIDOR, REACH_CHUNK, BufferPool, reachable_top_down
from streams.context import WorldContext


def test_pool_checks_the_reach_of_a_numeric_arm_lazily(ctx7: WorldContext) -> None:
    size = (0.08, 0.04, 0.05)
    pool = BufferPool(ctx7, size, seed=0, count=512)
    assert not ctx7.kinematics["left"].closed_form
    assert not pool.known("left").any()  # nothing computed up front
    clear = pool.clearance({})
    got = pool.take("left", clear, 3, seed=1, margin=GRASP_CORRIDOR)
    assert len(got) == 3
    poses = np.array([p.as_tuple() for p in got])
    assert reachable_top_down(ctx7, "left", poses, size).all()
    known = pool.known("left")
    assert 0 < known.sum() < len(known)  # only the poses met, a chunk at a time
    assert known.sum() % REACH_CHUNK == 0 or known.sum() == len(known)
    # what it learnt is the reach of those poses
    idx = np.flatnonzero(known)[:8]
    assert (
        pool.reach["left"][idx] == reachable_top_down(ctx7, "left", pool.poses[idx], size)
    ).all()
    assert got == pool.take("left", clear, 3, seed=1, margin=GRASP_CORRIDOR)  # same again
    assert got != pool.take("left", clear, 3, seed=2, margin=GRASP_CORRIDOR)


def test_pool_of_a_closed_form_arm_knows_every_pose(ctx: WorldContext) -> None:
    pool = BufferPool(ctx, (0.08, 0.04, 0.05), seed=0, count=64)
    for arm in ctx.arm_names:
        assert pool.known(arm).all()
        assert (pool.reach[arm] == reachable_top_down(ctx, arm, pool.poses, pool.size)).all()
