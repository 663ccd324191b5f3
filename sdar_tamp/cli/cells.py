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
    return 0


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
    cells.set_defaults(func=cmd_cells)
