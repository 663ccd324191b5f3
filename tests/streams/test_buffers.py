import numpy as np
import pytest

from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.footprint import clearance, corners, inside_rectangle, overlap_matrix
from sdar_tamp.world.instance import Instance, Pose2D
from streams.buffers import GRASP_CORRIDOR, BufferPool, reachable_top_down, sample_buffers
from streams.context import WorldContext
from streams.stream_map import make_stream_map


def test_buffers_are_free_disjoint_inside_and_reachable(
    ctx: WorldContext, instance: Instance
) -> None:
    size = instance.objects[0].size
    occupied = np.concatenate(
        [corners(instance.start_poses(), instance.sizes()[:, :2]),
         corners(instance.goal_poses(), instance.sizes()[:, :2])]
    )  # fmt: skip
    buffers = sample_buffers(ctx, "left", size, occupied, 5, seed=3)
    assert 1 <= len(buffers) <= 5
    poses = np.array([b.as_tuple() for b in buffers])
    rect = corners(poses, np.broadcast_to(size[:2], (len(poses), 2)))
    assert inside_rectangle(rect, ctx.scene.workspace.x, ctx.scene.workspace.y).all()
    assert not overlap_matrix(rect, occupied).any()
    pair = overlap_matrix(rect, rect)
    assert not pair[~np.eye(len(rect), dtype=bool)].any()
    assert reachable_top_down(ctx, "left", poses, size).all()


def test_buffers_are_seeded(ctx: WorldContext) -> None:
    empty = np.zeros((0, 4, 2))
    a = sample_buffers(ctx, "right", (0.08, 0.04, 0.05), empty, 4, seed=11)
    b = sample_buffers(ctx, "right", (0.08, 0.04, 0.05), empty, 4, seed=11)
    c = sample_buffers(ctx, "right", (0.08, 0.04, 0.05), empty, 4, seed=12)
    assert a == b and a != c and len(a) == 4


def test_unreachable_pose_is_reported(ctx: WorldContext, objects: dict[str, ObjectBox]) -> None:
    far = np.array([[3.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    assert reachable_top_down(ctx, "left", far, (0.08, 0.04, 0.05)).tolist() == [False, True]


def _gap(a: Pose2D, sa: tuple[float, ...], b: Pose2D, sb: tuple[float, ...]) -> float:
    """The largest margin [m] by which ``a``'s footprint grows and stays clear of ``b``'s
    (bisection on the exact overlap test: the reference for :func:`clearance`)."""
    rect_b = corners(np.array([b.as_tuple()]), np.array([sb[:2]]))
    lo, hi = -0.05, 0.05
    for _ in range(40):
        mid = (lo + hi) / 2
        grown = corners(np.array([a.as_tuple()]), np.array([sa[:2]]) + 2 * mid)
        lo, hi = (lo, mid) if overlap_matrix(grown, rect_b)[0, 0] else (mid, hi)
    return (lo + hi) / 2


def test_clearance_is_the_margin_at_which_footprints_meet() -> None:
    size = (0.08, 0.04, 0.05)
    a = Pose2D(0.0, 0.0, 0.0)
    side = Pose2D(0.08 + 0.03, 0.0, 0.0)  # 3 cm gap end to end
    turned = Pose2D(0.0, 0.1, 0.7)
    far = Pose2D(0.2, 0.2, 0.0)
    rect = corners(np.array([a.as_tuple()]), np.array([size[:2]]))
    others = corners(np.array([side.as_tuple(), turned.as_tuple(), far.as_tuple()]),
                     np.broadcast_to(size[:2], (3, 2)))  # fmt: skip
    got = [float(clearance(rect, others[k : k + 1], 0.05)[0]) for k in range(3)]
    assert got[0] == pytest.approx(0.03, abs=1e-9)
    assert got[1] == pytest.approx(_gap(a, size, turned, size), abs=1e-6)
    assert got[2] == np.inf  # farther than the reach
    assert float(clearance(rect, others, 0.05)[0]) == pytest.approx(min(got), abs=1e-9)
    assert clearance(rect, np.zeros((0, 4, 2)), 0.05).tolist() == [np.inf]


def test_clearance_agrees_with_the_grown_overlap_test() -> None:
    rng = np.random.default_rng(5)
    poses = np.c_[rng.uniform(-0.3, 0.3, (400, 2)), rng.uniform(-3, 3, 400)]
    sizes = rng.uniform(0.02, 0.1, (400, 2))
    others = corners(np.c_[rng.uniform(-0.3, 0.3, (30, 2)), rng.uniform(-3, 3, 30)],
                     rng.uniform(0.02, 0.1, (30, 2)))  # fmt: skip
    c = clearance(corners(poses, sizes), others, 0.03)
    for margin in (0.0, 0.01, 0.025):
        grown_clear = ~overlap_matrix(corners(poses, sizes + 2 * margin), others).any(axis=1)
        assert ((c > margin + 1e-9) == grown_clear).all()
    assert (c <= 0).sum() > 0 and np.isinf(c).sum() > 0  # overlapping and far poses both met


def test_pool_buffers_keep_the_grasp_corridor_when_there_is_room(
    ctx: WorldContext, instance: Instance
) -> None:
    size = instance.objects[0].size
    occupied = corners(instance.start_poses(), instance.sizes()[:, :2])
    pool = BufferPool(ctx, size, seed=0)
    clear = pool.clearance({k: occupied[k] for k in range(len(occupied))})
    got = pool.take("left", clear, 4, seed=1, margin=GRASP_CORRIDOR)
    assert len(got) == 4
    poses = np.array([p.as_tuple() for p in got])
    grown = corners(poses, np.broadcast_to(np.array(size[:2]) + 2 * GRASP_CORRIDOR, (4, 2)))
    assert not overlap_matrix(grown, occupied).any()  # 2.5 cm from every footprint
    assert not overlap_matrix(grown, grown)[~np.eye(4, dtype=bool)].any()
    assert reachable_top_down(ctx, "left", poses, size).all()
    assert got == pool.take("left", clear, 4, seed=1, margin=GRASP_CORRIDOR)  # seeded
    assert got != pool.take("left", clear, 4, seed=2, margin=GRASP_CORRIDOR)


def test_pool_refuses_bad_values(ctx: WorldContext) -> None:
    with pytest.raises(ValueError, match="count must be >= 1, got 0"):
        BufferPool(ctx, (0.08, 0.04, 0.05), seed=0, count=0)
    pool = BufferPool(ctx, (0.08, 0.04, 0.05), seed=0, count=16)
    clear = pool.clearance({})
    with pytest.raises(ValueError, match="k must be >= 0, got -1"):
        pool.take("left", clear, -1, seed=0, margin=0.01)
    with pytest.raises(ValueError, match=r"margin must be in \[0, 0.025\] \[m\], got 0.1"):
        pool.take("left", clear, 1, seed=0, margin=0.1)


def test_stream_buffers_fall_back_from_the_corridor_to_the_margin(ctx: WorldContext) -> None:
    """A buffer that only fits 1 cm from a wall of objects (a 2.5 cm corridor does not fit)
    is still found; with room, the stream's buffers keep the corridor."""
    size = (0.08, 0.04, 0.05)
    ws = ctx.scene.workspace
    # rows of objects end to end, 7.5 cm apart: a 4 cm wide buffer fits between two rows
    # with 1 cm to spare on each side, not with 2.5 cm
    xs = np.arange(ws.x[0] - 0.04, ws.x[1] + 0.08, 0.08)
    ys = np.arange(ws.y[0] + 0.02, ws.y[1] + 0.115, 0.04 + 0.075)
    grid = [Pose2D(float(x), float(y), 0.0) for x in xs for y in ys]
    names = [f"w{k}" for k in range(len(grid))]
    sm = make_stream_map(ctx, {n: size for n in [*names, "o"]})
    fluents = [("atpose", n, p) for n, p in zip(names, grid, strict=True)]
    crowded = [p for (p,) in sm["sample-buffer"]("o", fluents)]
    assert crowded, "a 1 cm buffer exists between the rows"
    walls = corners(
        np.array([p.as_tuple() for p in grid]), np.broadcast_to(size[:2], (len(grid), 2))
    )
    rect = corners(
        np.array([p.as_tuple() for p in crowded]), np.broadcast_to(size[:2], (len(crowded), 2))
    )
    c = clearance(rect, walls, GRASP_CORRIDOR)
    assert (c > 0.01).all() and (c <= GRASP_CORRIDOR).any()  # the 1 cm tier
    roomy = [p for (p,) in sm["sample-buffer"]("o", fluents[:2])]
    rect = corners(
        np.array([p.as_tuple() for p in roomy]), np.broadcast_to(size[:2], (len(roomy), 2))
    )
    assert (clearance(rect, walls[:2], GRASP_CORRIDOR) > GRASP_CORRIDOR).all()
