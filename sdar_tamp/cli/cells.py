"""``sdar cells``: list the shipped cells (scene files), or check one cell file."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any


def cmd_cells(args: argparse.Namespace) -> int:
    """List the shipped cells: name, scene file and description. With a scene file, load and
    check it (robot descriptions, frames, joints, limits, grippers) and print its arms."""
    from sdar_tamp.world.cells import shipped_cells
    from sdar_tamp.world.scene import load_scene

    if args.scene is None:
        for cell in shipped_cells():
            print(f"{cell.name:<16} {cell.path}")
            print(f"{'':<16} {cell.description}")
        return 0
    scene = load_scene(args.scene)
    print(f"{args.scene}: a valid cell, workspace x {list(scene.workspace.x)} y "
          f"{list(scene.workspace.y)}")  # fmt: skip
    for arm in scene.arms:
        g = arm.gripper
        print(
            f"  {arm.name}: {arm.urdf.name}, {arm.dof} joints {arm.base_frame} -> "
            f"{arm.tool_frame} ({', '.join(arm.joint_names)}); gripper opening "
            f"{g.max_opening:g} m, fingers {g.finger_depth:g} m deep, {g.finger_width:g} m wide"
        )
    if args.reach is not None:
        check_reach(scene, Path(args.scene), args.reach, args.every_arm)
    return 0


def check_reach(scene: Any, path: Path, step: float, every_arm: bool = False) -> None:
    """Raise a located error at the file's ``workspace`` naming the first point (and how many
    more) no arm grasps top-down on a ``step`` [m] grid (``every_arm``: that some arm does not
    grasp); print the count checked and how many points each arm grasps."""
    from sdar_tamp.world.cell_reach import grid, uncovered_points, unreached_points
    from sdar_tamp.world.errors import SceneError

    if not step > 0.0:
        raise SceneError(f"--reach: expected a grid step > 0 [m], got {step}")
    missed = unreached_points(scene, step)
    n = len(grid(scene.workspace.x, scene.workspace.y, step))
    if every_arm:
        for arm, points in missed.items():
            if len(points):
                _reach_error(path, points, f"arm {arm!r} does not grasp", step)
    elif len(lost := uncovered_points(missed)):
        _reach_error(path, lost, "no arm grasps", step)
    if all(len(points) == 0 for points in missed.values()):
        print(f"  reach: every arm grasps all {n} workspace points top-down (grid {step:g} m)")
        return
    counts = ", ".join(f"{arm} {n - len(points)}" for arm, points in missed.items())
    print(
        f"  reach: each of the {n} workspace points is grasped top-down by at least one arm "
        f"(grid {step:g} m; points per arm: {counts})"
    )


def _reach_error(path: Path, points: Any, what: str, step: float) -> None:
    """Raise the located error of :func:`check_reach` for the missed ``points`` ``(k, 2)``."""
    from sdar_tamp.world._yaml import read_yaml
    from sdar_tamp.world.errors import SceneError

    root = read_yaml(path, SceneError)
    node = root.mapping([], list(root.value))["workspace"]  # type: ignore[call-overload]
    x, y = points[0]
    more = f" and {len(points) - 1} more point(s)" if len(points) > 1 else ""
    raise SceneError(
        f"workspace: {what} ({x:.3f}, {y:.3f}) m top-down at every yaw within its limits"
        f"{more} (grid {step:g} m); narrow the workspace or move the arm",
        node.location,
    )


def add_cells_parser(sub: argparse._SubParsersAction[Any]) -> None:
    """Register ``sdar cells``."""
    cells = sub.add_parser(
        "cells",
        help="list the shipped cells, or check a cell file",
        description=cmd_cells.__doc__,
    )
    cells.add_argument(
        "scene", type=Path, nargs="?", default=None, help="a scene file to check (optional)"
    )
    cells.add_argument(
        "--reach",
        type=float,
        default=None,
        metavar="STEP",
        help="also check that every workspace point of a STEP [m] grid is grasped top-down "
        "at every yaw by at least one arm (numeric IK, limits, self and table collisions)",
    )
    cells.add_argument(
        "--every-arm",
        action="store_true",
        help="with --reach: ask every arm to grasp every point (as in the paper cell)",
    )
    cells.set_defaults(func=cmd_cells)
