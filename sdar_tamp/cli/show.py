"""``sdar show``: draw an instance, or a plan on it, to a picture file."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from sdar_tamp.arguments import FPS, output_file
from sdar_tamp.cli.log_options import FORCE_HELP
from sdar_tamp.errors import ParameterError

#: What a cell picture may be written to (matplotlib's formats).
CELL_SUFFIXES = (".png", ".pdf", ".svg", ".jpg")


def cmd_show(args: argparse.Namespace) -> int:
    """Draw an instance, or a plan on it.

    Without a plan: .png (or another matplotlib format) draws start and goal top-down with the
    dependency graph; .html is an interactive 3-D view of the start. With a plan: .html is an
    interactive 3-D replay (plotly, works offline), .png a storyboard with one panel per step,
    .gif a top-down animation. A scene file (cell) instead of an instance: a top-down
    picture of the cell (.png, .pdf, .svg, .jpg) with its workspace, the arms at home and
    where each arm's tool reaches near the table."""
    from sdar_tamp.viewer.pictures import check_output, show
    from sdar_tamp.world.cells import is_cell_file

    if args.plan is None and is_cell_file(args.instance):
        from sdar_tamp.world.draw_cell import draw_cell
        from sdar_tamp.world.scene import load_scene

        if args.output.suffix.lower() not in CELL_SUFFIXES:
            raise ParameterError(
                f"output: a cell is drawn to one of {', '.join(CELL_SUFFIXES)}, got "
                f"{args.output.name!r}"
            )
        output_file(args.output, force=args.force)
        print(f"wrote {draw_cell(load_scene(args.instance), args.output)}")
        return 0

    check_output(args.output, args.plan is not None)
    output_file(args.output, force=args.force)
    print(f"wrote {show(args.instance, args.plan, args.output, args.fps)}")
    return 0


def add_show_parser(sub: argparse._SubParsersAction[Any]) -> None:
    """Register ``sdar show``."""
    show = sub.add_parser(
        "show",
        help="draw an instance, or replay a plan",
        description=cmd_show.__doc__,
    )
    show.add_argument("instance", type=Path, help="instance YAML (or a scene file: the cell)")
    show.add_argument("plan", type=Path, nargs="?", default=None, help="plan JSON (optional)")
    show.add_argument(
        "-o",
        "--output",
        type=Path,
        required=True,
        help="picture: .png or .html (also .pdf, .svg, .jpg without a plan, .gif with one)",
    )
    show.add_argument("--force", action="store_true", help=FORCE_HELP)
    show.add_argument(
        "--fps",
        type=FPS.parse,
        default=None,
        help="animation frames per second of plan time (default: 10 for .html, 4 for .gif)",
    )
    show.set_defaults(func=cmd_show)
