"""``sdar export``: a plan file to a ROS-style joint trajectory, a CSV table or URScript.

The writers are in :mod:`sdar_tamp.export`; NumPy and the writers are imported when the
command runs (the CLI starts fast).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from sdar_tamp.arguments import FPS, Real
from sdar_tamp.cli.log_options import FORCE_HELP
from sdar_tamp.errors import ParameterError
from sdar_tamp.export.formats import CSV_RATE, FORMATS

_SECONDS = Real(0.0, unit="s")
_GAIN = Real(0.0)


def cmd_export(args: argparse.Namespace) -> int:
    """Write a plan file as a ROS trajectory_msgs/JointTrajectory-shaped JSON per arm with the
    gripper commands (joint-trajectory), a CSV table at 50 Hz (csv) or one URScript program per
    arm (urscript: servoj stream, gripper calls, the base-to-base transform in the header).
    Without -o the output goes next to the plan (PLAN.trajectory.json, PLAN.csv, folder
    PLAN.urscript); existing files are refused unless --force. URScript is for UR arms only:
    an arm that is not one is refused (by the robot description of --scene, else by its joint
    names)."""
    from sdar_tamp.export.plan_files import export_plan_file
    from sdar_tamp.export.urscript import ServoSettings

    servo_options = {"period": args.period, "lookahead": args.lookahead, "gain": args.gain}
    given = [k for k, v in servo_options.items() if v is not None]
    if given and args.format != "urscript":
        raise ParameterError(f"--{given[0]} applies to --format urscript only")
    if args.rate is not None and args.format != "csv":
        raise ParameterError("--rate applies to --format csv only")
    servo = ServoSettings(**{k: v for k, v in servo_options.items() if v is not None})
    rate = CSV_RATE if args.rate is None else args.rate
    scene = None
    if args.scene is not None:
        from sdar_tamp.world.scene import load_scene

        scene = load_scene(args.scene)
    paths = export_plan_file(
        args.plan, args.format, args.output, force=args.force, servo=servo, rate=rate, scene=scene
    )
    for path in paths:
        print(f"wrote {path}")
    return 0


def add_export_parser(sub: argparse._SubParsersAction[Any]) -> None:
    """Register ``sdar export``."""
    export = sub.add_parser(
        "export",
        help="write a plan for ROS, a spreadsheet or UR controllers",
        description=cmd_export.__doc__,
    )
    export.add_argument("plan", type=Path, help="plan JSON")
    export.add_argument("--format", choices=FORMATS, required=True, help="output format")
    export.add_argument(
        "-o",
        "--output",
        type=Path,
        default=None,
        help="file (.json, .csv), or folder for urscript (default: next to the plan)",
    )
    export.add_argument("--force", action="store_true", help=FORCE_HELP)
    export.add_argument(
        "--scene",
        type=Path,
        default=None,
        help="the plan's cell (scene YAML): its arms are checked against the plan's, and "
        "urscript checks their robot descriptions (default: none)",
    )
    export.add_argument(
        "--rate", type=FPS.parse, default=None, help=f"csv rows per second (default: {CSV_RATE:g})"
    )
    export.add_argument(
        "--period",
        type=_SECONDS.parse,
        default=None,
        help="urscript: servoj t, seconds between targets, >= 0.002 (default: 0.008)",
    )
    export.add_argument(
        "--lookahead",
        type=_SECONDS.parse,
        default=None,
        help="urscript: servoj lookahead_time [s] in [0.03, 0.2] (default: 0.1)",
    )
    export.add_argument(
        "--gain",
        type=_GAIN.parse,
        default=None,
        help="urscript: servoj gain in [100, 2000] (default: 300)",
    )
    export.set_defaults(func=cmd_export)
