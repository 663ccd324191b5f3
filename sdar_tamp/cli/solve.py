"""``sdar solve``: plan one rearrangement instance with SDAR, validate and write the plan."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sdar_tamp.app.config import EXECUTIONS
from sdar_tamp.arguments import COUNT, SEED, TIME_LIMIT, output_file
from sdar_tamp.cli.log_options import FORCE_HELP, JSON_HELP, SCENE_HELP

if TYPE_CHECKING:
    from sdar_tamp.app.config import PlannerConfig


def cmd_solve(args: argparse.Namespace) -> int:
    """Plan a rearrangement instance with SDAR, validate the plan by independent replay and
    write it (JSON, see the README). Exit status 0 only when solved and valid."""
    from sdar_tamp.app.pipeline import solve_instance
    from sdar_tamp.app.summary import format_summary, terminal_progress
    from sdar_tamp.plan_writing import save_plan

    if args.output is not None:
        output_file(args.output, suffixes=(".json",), force=args.force)
    if args.stream:
        return _solve_streamed(args)
    bar = terminal_progress(f"{args.instance.stem}") if not (args.quiet or args.json) else None
    try:
        outcome = solve_instance(
            args.instance,
            _config(args, args.execution or "async"),
            progress=bar,
            stage=bar.stage if bar is not None else None,
            scene=args.scene,
        )
    finally:
        if bar is not None:
            bar.close()
    written = None
    if outcome.plan is not None and args.output is not None:
        written = save_plan(outcome.plan, args.output)
    if args.json:
        from sdar_tamp.app.summary import summary_record

        record = summary_record(outcome, plan_file=written)
        print(json.dumps(record, sort_keys=True))
    else:
        print(format_summary(outcome))
        if written is not None:
            print(f"wrote {written}")
    return 0 if outcome.success else 1


def _config(args: argparse.Namespace, execution: str) -> PlannerConfig:
    """The planner configuration of the command's options."""
    import dataclasses

    from sdar_tamp.app.config import PlannerConfig

    config = PlannerConfig(
        task_planner=args.task_planner,
        motion_planner=args.motion_planner,
        max_time=args.time_limit,
        seed=args.seed,
        execution=execution,
    )
    if args.grasps is not None:
        config = config.replace(sdar=dataclasses.replace(config.sdar, grasps=args.grasps))
    return config


def _solve_streamed(args: argparse.Namespace) -> int:
    """``sdar solve --stream``: the header, each step and the end as JSON lines on stdout,
    the progress and the summary on stderr."""
    import sys

    from sdar_tamp.app.stream_records import end_record, header_record, step_record
    from sdar_tamp.app.streaming import StepRejected, solve_stream
    from sdar_tamp.app.summary import format_summary, terminal_progress
    from sdar_tamp.errors import ParameterError
    from sdar_tamp.plan_writing import save_plan

    if args.json:
        raise ParameterError("--json: --stream writes JSON lines already (the end line: status)")
    if args.execution not in (None, "sync"):
        raise ParameterError(
            f"--stream emits the synchronous timing (--execution sync); --execution "
            f"{args.execution} re-times the whole plan once it is complete"
        )

    def emit(record: dict[str, Any]) -> None:
        sys.stdout.write(json.dumps(record, allow_nan=False) + "\n")
        sys.stdout.flush()

    bar = terminal_progress(f"{args.instance.stem}") if not args.quiet else None
    try:
        stream = solve_stream(args.instance, _config(args, "sync"), progress=bar, scene=args.scene)
        emit(header_record(stream.header))
        try:
            for step in stream:
                emit(step_record(step))
        except StepRejected as err:
            emit(end_record("rejected", None, None, False, str(err.violation.message)))
            print(f"{args.instance.stem}: {err}", file=sys.stderr)
            return 1
    finally:
        if bar is not None:
            bar.close()
    outcome = stream.outcome
    assert outcome is not None
    written = None
    if outcome.plan is not None and args.output is not None:
        written = save_plan(outcome.plan, args.output)
    emit(
        end_record(
            outcome.status,
            stream.last_part,
            outcome.plan,
            outcome.valid,
            outcome.violation,
            outcome.diagnosis,
        )
    )
    print(format_summary(outcome), file=sys.stderr)
    if written is not None:
        print(f"wrote {written}", file=sys.stderr)
    return 0 if outcome.success else 1


def add_solve_parser(sub: argparse._SubParsersAction[Any]) -> None:
    """Register ``sdar solve``."""
    solve = sub.add_parser(
        "solve", help="plan a rearrangement instance with SDAR", description=cmd_solve.__doc__
    )
    solve.add_argument("instance", type=Path, help="instance YAML")
    solve.add_argument("-o", "--output", type=Path, default=None, help="plan file (.json)")
    solve.add_argument("--scene", type=Path, default=None, help=SCENE_HELP)
    solve.add_argument("--force", action="store_true", help=FORCE_HELP)
    solve.add_argument(
        "--time-limit", type=TIME_LIMIT.parse, default=60.0, help="seconds (default: 60)"
    )
    solve.add_argument("--seed", type=SEED.parse, default=0, help="random seed (default: 0)")
    solve.add_argument(
        "--task-planner", choices=("sdar", "baseline"), default="sdar", help="(default: sdar)"
    )
    solve.add_argument(
        "--motion-planner",
        choices=("sdar", "plain", "sequential"),
        default="sdar",
        help="sdar: optimisation, untangling, one arm at a time; plain: optimisation only; "
        "sequential: one arm at a time (default: sdar)",
    )
    solve.add_argument(
        "--grasps",
        type=COUNT.parse,
        default=None,
        help="grasps tried per object, in the grasp set's order (default: 6)",
    )
    solve.add_argument(
        "--stream",
        action="store_true",
        help="emit each step as soon as it is planned and checked: one JSON object per line "
        "on stdout (a header, the steps, the end), the progress and the summary on stderr; "
        "the synchronous timing (see docs/streaming.md)",
    )
    solve.add_argument(
        "--execution",
        choices=EXECUTIONS,
        default=None,
        help="sync: every arm on one synchronous timeline; async: each arm on its own, "
        "the synchronous steps re-timed for itself; timelines: one timeline per arm, each "
        "arm's next motion started as soon as it is done, against the other arms' committed "
        "motions (the shorter of it and async); assigned: the plan's moves assigned anew to "
        "whichever arm is free, each with a motion planned for it (the shortest of the three); "
        "async modes are kept only when shorter and "
        "valid (default: async, sync with --stream; see docs/execution.md)",
    )
    solve.add_argument("--json", action="store_true", help=JSON_HELP + " (implies -q)")
    solve.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    solve.set_defaults(func=cmd_solve)
