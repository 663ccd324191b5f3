"""``sdar export``: a plan file to a ROS-style joint trajectory, a CSV table or URScript.

The command's parser is built here (:func:`add_export_parser`) so that the CLI registers it
with one call. NumPy and the writers are imported when a command runs (the CLI starts fast).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sdar_tamp.arguments import FPS, Real, output_file, output_folder
from sdar_tamp.errors import ParameterError
from sdar_tamp.export.formats import CSV_RATE, FORMATS

if TYPE_CHECKING:
    from sdar_tamp.export.urscript import ServoSettings
    from sdar_tamp.plan_file import PlanFile

#: What ``-o`` names per format, and the default name next to the plan.
_DEFAULT_SUFFIX = {"joint-trajectory": ".trajectory.json", "csv": ".csv", "urscript": ".urscript"}


def default_output(plan_path: Path, fmt: str) -> Path:
    """Where ``fmt`` goes without ``-o``: next to the plan, ``PLAN`` + a suffix
    (``run.json`` -> ``run.trajectory.json``, ``run.csv``, folder ``run.urscript``)."""
    _check_format(fmt)
    plan_path = Path(plan_path)
    stem = plan_path.stem if plan_path.suffix.lower() == ".json" else plan_path.name
    return plan_path.with_name(stem + _DEFAULT_SUFFIX[fmt])


def export_plan(
    plan: PlanFile,
    fmt: str,
    output: Path,
    *,
    servo: ServoSettings | None = None,
    rate: float = CSV_RATE,
) -> list[Path]:
    """Write ``plan`` as ``fmt`` (one of :data:`FORMATS`) to ``output`` (a file; a folder for
    ``urscript``); returns the files written."""
    from sdar_tamp.export.joint_trajectory import write_joint_trajectory
    from sdar_tamp.export.table import write_csv
    from sdar_tamp.export.urscript import write_urscript

    _check_format(fmt)
    if fmt == "joint-trajectory":
        return [write_joint_trajectory(plan, output)]
    if fmt == "csv":
        return [write_csv(plan, output, rate)]
    return write_urscript(plan, output, servo)


def run_export(
    plan_path: Path,
    fmt: str,
    output: Path | None = None,
    *,
    force: bool = False,
    servo: ServoSettings | None = None,
    rate: float = CSV_RATE,
) -> list[Path]:
    """Read ``plan_path``, check where the output goes (existing files are refused unless
    ``force``) and export; returns the files written."""
    from sdar_tamp.export.urscript import script_name
    from sdar_tamp.plan_file import load_plan

    _check_format(fmt)
    plan = load_plan(plan_path)
    target = Path(output) if output is not None else default_output(plan_path, fmt)
    if fmt == "urscript":
        output_folder(target)
        taken = [target / script_name(a) for a in plan.arm_names]
        taken = [p for p in taken if p.exists()]
        if taken and not force:
            raise ParameterError(
                f"--output: {str(taken[0])!r} exists; pass --force to replace it, or choose "
                "another folder"
            )
    else:
        suffix = ".json" if fmt == "joint-trajectory" else ".csv"
        output_file(target, suffixes=(suffix,), force=force)
    return export_plan(plan, fmt, target, servo=servo, rate=rate)


def _check_format(fmt: str) -> None:
    if fmt not in FORMATS:
        raise ParameterError(f"format must be one of {', '.join(FORMATS)}; got {fmt!r}")


# -- the command line ------------------------------------------------------------------------------
_SECONDS = Real(0.0, unit="s")
_GAIN = Real(0.0)


def cmd_export(args: argparse.Namespace) -> int:
    """Write a plan file as a ROS trajectory_msgs/JointTrajectory-shaped JSON per arm with the
    gripper commands (joint-trajectory), a CSV table at 50 Hz (csv) or one URScript program per
    arm (urscript: servoj stream, gripper calls, the base-to-base transform in the header).
    Without -o the output goes next to the plan (PLAN.trajectory.json, PLAN.csv, folder
    PLAN.urscript); existing files are refused unless --force."""
    from sdar_tamp.export.urscript import ServoSettings

    servo_options = {"period": args.period, "lookahead": args.lookahead, "gain": args.gain}
    given = [k for k, v in servo_options.items() if v is not None]
    if given and args.format != "urscript":
        raise ParameterError(f"--{given[0]} applies to --format urscript only")
    if args.rate is not None and args.format != "csv":
        raise ParameterError("--rate applies to --format csv only")
    servo = ServoSettings(**{k: v for k, v in servo_options.items() if v is not None})
    rate = CSV_RATE if args.rate is None else args.rate
    paths = run_export(
        args.plan, args.format, args.output, force=args.force, servo=servo, rate=rate
    )
    for path in paths:
        print(f"wrote {path}")
    return 0


def add_export_parser(sub: argparse._SubParsersAction[Any]) -> None:
    """Register ``sdar export`` on the CLI's subcommands."""
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
    export.add_argument(
        "--force", action="store_true", help="replace output files that exist (default: refuse)"
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
