import numpy as np

from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.footprint import corners, inside_rectangle, overlap_matrix
from sdar_tamp.world.instance import Instance
from streams.buffers import reachable_top_down, sample_buffers
from streams.context import WorldContext


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
