"""Top-down pictures of a plan: a storyboard (``.png``, one panel per step) or an animation
(``.gif``).

Each picture shows the workspace, every goal as a dashed outline, resting objects (green when at
their goal, grey otherwise), held objects (in the colour of the arm holding them) and every
arm of the cell (one or more) seen from above as thick lines through their link frames, with
the gripper's jaw line. A storyboard panel shows the moment midway through carrying (or the
middle of the step) and the path of each tool centre point during the step.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.viewer._geometry import FINGER_FRAMES
from sdar_tamp.viewer._plan import PlanLike
from sdar_tamp.viewer._timeline import Segment, Timeline, yaw_of
from sdar_tamp.viewer.errors import require
from sdar_tamp.world.footprint import corners
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene, load_scene
from sdar_tamp.world.transforms import FloatArray

#: Storyboard layout: panels per row, panel size [inch] and resolution [dots per inch].
COLUMNS = 4
PANEL_SIZE = (4.0, 2.6)
#: How far past the table's edges the pictures reach [m] (x, y); where an arm's base stands
#: nearer than ``MARGIN[0]`` to the picture's edge, it reaches that far past the base (arms
#: lean out behind their bases).
MARGIN = (0.2, 0.08)
DPI = 100
#: Arm colours (first arm, second arm, ...; repeated past the last), as in the HTML viewer.
ARM_COLOURS = ("#3a74c4", "#d9692a", "#3d9a4c", "#8a5bb8")
SUFFIXES = (".png", ".gif")
#: Tolerances for "at its goal": position [m] and yaw (modulo pi, the cuboid's symmetry) [rad].
GOAL_TOL = (0.005, 0.02)


def write_storyboard(
    instance: Instance,
    plan: PlanLike,
    path: Path,
    scene: Scene | None = None,
    fps: int = 4,
) -> Path:
    """Write a top-down picture of ``plan`` on ``instance`` to ``path`` and return the path.

    ``.png``: a grid of panels, one per synchronous step (``plan.steps``; without steps, one per
    span ending at a release), ``COLUMNS`` panels a row, each ``PANEL_SIZE`` inches.
    ``.gif``: an animation of ``fps`` frames per second of plan time, played in real time.
    """
    out = Path(path)
    suffix = out.suffix.lower()
    if suffix not in SUFFIXES:
        raise ParameterError(
            f"path must end in one of {', '.join(SUFFIXES)} (storyboard or animation), "
            f"got {out.name!r}"
        )
    require("matplotlib", "the storyboard")
    scene = scene if scene is not None else load_scene()
    timeline = Timeline.build(instance, plan, scene)
    out.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".png":
        _storyboard(timeline, scene, out)
    else:
        _animation(timeline, scene, out, fps)
    return out


def arm_colour(index: int) -> str:
    """The colour of the arm at ``index`` (plan order)."""
    return ARM_COLOURS[index % len(ARM_COLOURS)]


def panel_grid(n_panels: int) -> tuple[int, int]:
    """Rows and columns of a storyboard with ``n_panels`` panels."""
    cols = max(1, min(COLUMNS, n_panels))
    return -(-max(n_panels, 1) // cols), cols


@dataclass(frozen=True)
class _Artists:
    """The matplotlib artists of one top-down view, updated in place from frame to frame."""

    ax: Any
    objects: list[Any]
    labels: list[Any]
    arms: list[Any]
    joints: list[Any]
    jaws: list[Any]


def _storyboard(timeline: Timeline, scene: Scene, out: Path) -> None:
    segments = timeline.segments()
    rows, cols = panel_grid(len(segments))
    fig = _figure(cols * PANEL_SIZE[0], rows * PANEL_SIZE[1])
    axes = fig.subplots(rows, cols, squeeze=False)
    for ax in axes.flat[len(segments) :]:
        ax.set_axis_off()
    for seg, ax in zip(segments, axes.flat, strict=False):
        view = _view(ax, timeline, scene)
        t = timeline.snapshot_time(seg)
        _update(view, timeline, t)
        _tcp_paths(ax, timeline, seg)
        ax.set_title(
            f"step {seg.index + 1}: t = {seg.t_start:.1f}–{seg.t_end:.1f} s (at {t:.1f} s)\n"
            f"{_short(seg.label)}",
            fontsize=8,
        )
    height = rows * PANEL_SIZE[1]  # [inch]; room for the title and the panel titles:
    fig.subplots_adjust(
        left=0.04, right=0.99, bottom=0.25 / height, top=1 - 0.75 / height, hspace=0.45
    )
    fig.suptitle(
        f"{timeline.instance.name}: {len(segments)} steps, {timeline.t_end:.1f} s   "
        "(objects: grey resting, green at goal, arm colour held; dashed: goals; "
        "dotted: tool paths)",
        fontsize=10,
    )
    fig.savefig(out, dpi=DPI)


def _animation(timeline: Timeline, scene: Scene, out: Path, fps: int) -> None:
    from matplotlib.animation import PillowWriter

    times = timeline.sample_times(fps)
    fig = _figure(*PANEL_SIZE)
    ax = fig.add_axes((0.09, 0.08, 0.89, 0.82))
    view = _view(ax, timeline, scene)
    writer = PillowWriter(fps=fps)
    with writer.saving(fig, str(out), DPI):
        for t in times:
            _update(view, timeline, float(t))
            ax.set_title(f"{timeline.instance.name}: t = {t:.2f} s", fontsize=9)
            writer.grab_frame()


# -- drawing ----------------------------------------------------------------------------------
def _figure(width: float, height: float) -> Any:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=DPI)
    FigureCanvasAgg(fig)
    return fig


def _view(ax: Any, timeline: Timeline, scene: Scene) -> _Artists:
    from matplotlib.patches import Polygon, Rectangle

    sx, sy, _ = scene.table.size
    ax.add_patch(Rectangle((-sx / 2, -sy / 2), sx, sy, facecolor="#f1e9da", edgecolor="0.6"))
    (x0, x1), (y0, y1) = scene.workspace.x, scene.workspace.y
    ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor="whitesmoke",
                           edgecolor="orange", lw=1.2))  # fmt: skip
    instance = timeline.instance
    sizes = instance.sizes()[:, :2]
    for rect in corners(instance.goal_poses(), sizes):
        ax.add_patch(Polygon(rect, closed=True, fill=False, edgecolor="0.35", ls="--", lw=0.8))
    objects = [
        ax.add_patch(Polygon(rect, closed=True, edgecolor="black", lw=0.8, zorder=3))
        for rect in corners(instance.start_poses(), sizes)
    ]
    labels = [
        ax.text(o.start.x, o.start.y, o.name, ha="center", va="center", fontsize=6, clip_on=True)
        for o in instance.objects
    ]
    arms, joints, jaws = [], [], []
    for a in range(len(timeline.arms)):
        colour = arm_colour(a)
        (line,) = ax.plot([], [], "-", color=colour, lw=6, alpha=0.75, solid_capstyle="round",
                          zorder=5)  # fmt: skip
        (dots,) = ax.plot([], [], "o", color="white", mec=colour, ms=3.5, zorder=6)
        (jaw,) = ax.plot([], [], "-", color="0.2", lw=3, solid_capstyle="butt", zorder=6)
        arms.append(line)
        joints.append(dots)
        jaws.append(jaw)
    ax.set_aspect("equal")
    bases = np.array([a.T_world_base[:2, 3] for a in scene.arms]).reshape(-1, 2)
    reach = MARGIN[0]
    ax.set_xlim(
        min(-sx / 2 - MARGIN[0], float(bases[:, 0].min()) - reach),
        max(sx / 2 + MARGIN[0], float(bases[:, 0].max()) + reach),
    )
    ax.set_ylim(
        min(-sy / 2 - MARGIN[1], float(bases[:, 1].min()) - reach),
        max(sy / 2 + MARGIN[1], float(bases[:, 1].max()) + reach),
    )
    ax.tick_params(labelsize=6)
    return _Artists(ax, objects, labels, arms, joints, jaws)


def _update(view: _Artists, timeline: Timeline, t: float) -> None:
    """Move every artist of ``view`` to the state at time ``t`` [s]."""
    times = np.array([t])
    instance = timeline.instance
    poses, holder = timeline.object_poses(times)
    xy_yaw = np.column_stack([poses[0, :, 0, 3], poses[0, :, 1, 3], yaw_of(poses[0])])
    at_goal = _at_goal(xy_yaw, instance.goal_poses())
    for i, rect in enumerate(corners(xy_yaw, instance.sizes()[:, :2])):
        arm = int(holder[0, i])
        colour = arm_colour(arm) if arm >= 0 else ("#8fd18f" if at_goal[i] else "#c8c8c8")
        view.objects[i].set_xy(rect)
        view.objects[i].set_facecolor(colour)
        view.objects[i].set_alpha(0.6 if arm >= 0 else 0.9)
        view.labels[i].set_position((xy_yaw[i, 0], xy_yaw[i, 1]))
    q = timeline.q_at(times)
    for a, arm_drawing in enumerate(timeline.arms):
        qa = timeline.arm_q(q, a)
        chain = arm_drawing.chain_points(qa)[0, :, :2]
        view.arms[a].set_data(chain[:, 0], chain[:, 1])
        view.joints[a].set_data(chain[1:-2, 0], chain[1:-2, 1])
        if all(arm_drawing.robot.model.existFrame(f) for f in FINGER_FRAMES):
            fingers = arm_drawing.frame_poses(qa, FINGER_FRAMES)[0, :, :2, 3]
            view.jaws[a].set_data(fingers[:, 0], fingers[:, 1])


def _tcp_paths(ax: Any, timeline: Timeline, seg: Segment) -> None:
    times = np.linspace(seg.t_start, seg.t_end, 60).astype(np.float64)
    q = timeline.q_at(times)
    for a, arm in enumerate(timeline.arms):
        tcp = arm.tcp_poses(timeline.arm_q(q, a))[:, :2, 3]
        ax.plot(tcp[:, 0], tcp[:, 1], ":", color=arm_colour(a), lw=1.2, zorder=4)


def _at_goal(xy_yaw: FloatArray, goals: FloatArray) -> Any:
    dist = np.linalg.norm(xy_yaw[:, :2] - goals[:, :2], axis=1)
    dyaw = np.abs((xy_yaw[:, 2] - goals[:, 2] + np.pi / 2) % np.pi - np.pi / 2)
    return (dist <= GOAL_TOL[0]) & (dyaw <= GOAL_TOL[1])


def _short(text: str, limit: int = 48) -> str:
    return text if len(text) <= limit else text[: limit - 1] + "…"
