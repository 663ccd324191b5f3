"""A top-down picture of a cell: table, workspace, each arm's base, its chain at home and
where its tool centre point reaches near the table.

The reach is sampled: configurations drawn uniformly within the arm's joint limits (seeded),
the TCP kept when it lies between the table top and :data:`REACH_HEIGHT` above it. A
workspace corner no sample of an arm comes near is worth a look (``sdar show CELL.yaml``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sdar_tamp.world._pin import PinRobot
from sdar_tamp.world.arm_spec import ArmSpec
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray, inverse, translation

#: Heights [m] above the table top at which the TCP counts as reaching the table.
REACH_HEIGHT = 0.15
#: Configurations sampled per arm.
SAMPLES = 3000
_COLOURS = ("tab:blue", "tab:red", "tab:green", "tab:purple")


def arm_points(
    scene: Scene, arm: ArmSpec, samples: int = SAMPLES, seed: int = 0
) -> tuple[FloatArray, FloatArray]:
    """``(chain, reach)``: the arm's joint origins and TCP at home ``(k, 3)``, and the TCP
    positions ``(m, 3)`` of sampled configurations that lie near the table [m, world]."""
    robot = PinRobot.load(arm.urdf, scene.package_dirs)
    model = robot.model
    q = robot.neutral()
    for name, value in arm.locked_joints:
        q[int(model.idx_qs[model.getJointId(name)])] = value
    index = [int(model.idx_qs[model.getJointId(j)]) for j in arm.joint_names]
    base, tool = robot.frame_id(arm.base_frame), robot.frame_id(arm.tool_frame)
    T_world_root = arm.T_world_base @ inverse(robot.frame_pose(q, base))
    T_tool_tcp = translation(0.0, 0.0, arm.gripper.tcp_offset)
    chain_frames = tuple(robot.frame_id(j) for j in arm.joint_names)
    q[index] = arm.home
    poses = robot.frame_poses(q, (*chain_frames, tool))
    chain = [T_world_root @ T for T in poses] + [T_world_root @ poses[-1] @ T_tool_tcp]
    rng = np.random.default_rng(seed)
    reach = []
    for sample in rng.uniform(arm.lower, arm.upper, (samples, arm.dof)):
        q[index] = sample
        reach.append((T_world_root @ robot.frame_pose(q, tool) @ T_tool_tcp)[:3, 3])
    points = np.array(reach)
    near = points[(points[:, 2] >= 0.0) & (points[:, 2] <= REACH_HEIGHT)]
    return np.array([T[:3, 3] for T in chain]), near


def draw_cell(scene: Scene, path: Path) -> Path:
    """Render the cell ``scene`` top-down to an image file (format from the suffix)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    fig, ax = plt.subplots(figsize=(8, 6))
    tx, ty, _ = scene.table.size
    ax.add_patch(Rectangle((-tx / 2, -ty / 2), tx, ty, facecolor="0.93", edgecolor="0.5"))
    ws = scene.workspace
    w, h = ws.x[1] - ws.x[0], ws.y[1] - ws.y[0]
    ax.add_patch(
        Rectangle((ws.x[0], ws.y[0]), w, h, fill=False, edgecolor="orange", lw=2, label="workspace")
    )
    for k, arm in enumerate(scene.arms):
        colour = _COLOURS[k % len(_COLOURS)]
        chain, near = arm_points(scene, arm)
        ax.scatter(near[:, 0], near[:, 1], s=2, alpha=0.25, color=colour,
                   label=f"{arm.name}: TCP within {REACH_HEIGHT:g} m of the table")  # fmt: skip
        ax.plot(chain[:, 0], chain[:, 1], "-o", color=colour, ms=3, lw=2,
                label=f"{arm.name} at home ({arm.urdf.name}, {arm.dof} joints)")  # fmt: skip
        x, y, _ = arm.base_xyz
        ax.plot([x], [y], "s", color=colour, ms=10)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(Path(scene.file).name)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), fontsize=8, ncol=2)
    fig.tight_layout()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out
