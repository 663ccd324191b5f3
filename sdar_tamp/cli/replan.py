"""``sdar replan``: re-plan a running plan from an observed state and write the new plan."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from sdar_tamp.arguments import PLAN_TIME, SEED, TIME_LIMIT, output_file
from sdar_tamp.cli.log_options import FORCE_HELP, JSON_HELP, SCENE_HELP


def cmd_replan(args: argparse.Namespace) -> int:
    """Re-plan PLAN of INSTANCE at time --at from the state in --observed: the plan runs on to
    its next point where every arm is at rest with an empty gripper, then a repaired rest of
    the old plan or a fresh continuation follows. The new plan (the executed prefix and the
    continuation, with the observation recorded) is validated by independent replay and
    written with -o. Exit status 0 when re-planned and valid, 1 when no plan (infeasible, with
    the blocking objects) or invalid, 2 for a bad file (an impossible observed state is
    located in its file). With --while-moving the repair is written (and reported) as soon as
    it is valid, and each shorter fresh continuation found before the arms reach its start is
    written over it afterwards (a record each)."""
    from sdar_tamp.app.config import PlannerConfig
    from sdar_tamp.app.replan_moving import replan_while_moving
    from sdar_tamp.app.replanning import replan
    from sdar_tamp.plan_reading import load_plan
    from sdar_tamp.plan_writing import save_plan
    from sdar_tamp.world.instance import load_instance
    from sdar_tamp.world.observed import load_observed
    from sdar_tamp.world.scene import load_scene

    if args.output is not None:
        output_file(args.output, suffixes=(".json",), force=args.force)
    instance = load_instance(args.instance, grasp=None)
    scene_path = args.scene if args.scene is not None else instance.scene_path(args.instance)
    scene = load_scene(scene_path)
    instance = load_instance(args.instance, scene.grasp_limits)
    plan = load_plan(args.plan, scene.layout)
    observed = load_observed(args.observed)
    config = PlannerConfig(max_time=args.time_limit, seed=args.seed)
    if args.while_moving:
        outcomes = replan_while_moving(
            instance, plan, args.at, observed, config=config, scene_path=scene_path
        )
    else:
        outcomes = iter([replan(
            instance, plan, args.at, observed, config=config, scene_path=scene_path,
            repair=not args.fresh, compare=not args.no_compare,
        )])  # fmt: skip
    code = 1
    for outcome in outcomes:
        written = None
        if outcome.plan is not None and args.output is not None:
            written = save_plan(outcome.plan, args.output)
        _report(outcome, written, args.json)
        code = 0 if outcome.plan is not None and outcome.valid else 1
    return code


def _report(outcome: Any, written: Path | None, as_json: bool) -> None:
    if as_json:
        record = {
            "status": outcome.status,
            "valid": outcome.valid,
            "violation": outcome.violation or None,
            "cut": outcome.cut,
            "latency": outcome.latency,
            "execution_time": None if outcome.plan is None else outcome.plan.duration,
            "reasons": list(outcome.reasons),
            "blocking": list(outcome.blocking),
            "moved_away": list(outcome.moved_away),
            "alternative": outcome.alternative,
            "plan_file": None if written is None else str(written),
        }
        print(json.dumps(record, sort_keys=True), flush=True)
    else:
        print(_summary(outcome, written), flush=True)


def _summary(outcome: Any, written: Path | None) -> str:
    lines = [f"{outcome.status}: cut at t = {outcome.cut:.3f} s, {outcome.latency:.3f} s"]
    if outcome.plan is not None:
        verdict = "valid" if outcome.valid else f"INVALID ({outcome.violation})"
        lines.append(f"new plan: {outcome.plan.duration:.2f} s of execution, {verdict}")
    if outcome.alternative is not None:
        lines.append(f"compared with: {outcome.alternative:.2f} s of execution (not kept)")
    if outcome.moved_away:
        lines.append(f"moved away: {', '.join(outcome.moved_away)}")
    if outcome.blocking:
        lines.append(f"blocking: {', '.join(outcome.blocking)}")
    lines += [f"  {r}" for r in outcome.reasons]
    if written is not None:
        lines.append(f"wrote {written}")
    return "\n".join(lines)


def add_replan_parser(sub: argparse._SubParsersAction[Any]) -> None:
    """Register ``sdar replan``."""
    p = sub.add_parser(
        "replan", help="re-plan a running plan from an observed state",
        description=cmd_replan.__doc__,
    )  # fmt: skip
    p.add_argument("instance", type=Path, help="instance YAML")
    p.add_argument("plan", type=Path, help="the plan being executed (JSON)")
    p.add_argument("--at", type=PLAN_TIME.parse, required=True, help="time reached [s]")
    p.add_argument(
        "--observed", type=Path, required=True, help="observed state YAML (docs/replanning.md)"
    )
    p.add_argument("-o", "--output", type=Path, default=None, help="new plan file (.json)")
    p.add_argument("--scene", type=Path, default=None, help=SCENE_HELP)
    p.add_argument("--force", action="store_true", help=FORCE_HELP)
    p.add_argument(
        "--time-limit", type=TIME_LIMIT.parse, default=60.0, help="seconds (default: 60)"
    )
    p.add_argument("--seed", type=SEED.parse, default=0, help="random seed (default: 0)")
    how = p.add_mutually_exclusive_group()
    how.add_argument(
        "--fresh", action="store_true", help="no repair: always a fresh continuation from the cut"
    )
    how.add_argument(
        "--no-compare", action="store_true",
        help="keep a valid repair without solving a fresh continuation to compare it with "
        "(lower latency; the execution may be longer)",
    )  # fmt: skip
    how.add_argument(
        "--while-moving", action="store_true",
        help="write the repair at once, then a shorter fresh continuation over it when one is "
        "found before the arms reach its start (docs/replanning.md)",
    )  # fmt: skip
    p.add_argument("--json", action="store_true", help=JSON_HELP)
    p.set_defaults(func=cmd_replan)
