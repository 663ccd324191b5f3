"""``sdar validate``: replay a plan file on an instance and print the verdict."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from sdar_tamp.cli.log_options import JSON_HELP, SCENE_HELP


def cmd_validate(args: argparse.Namespace) -> int:
    """Replay a plan file on an instance and check it independently of the planner."""
    from sdar_tamp.plan_reading import load_plan
    from sdar_tamp.replay import validate_plan
    from sdar_tamp.world.instance import load_instance
    from sdar_tamp.world.scene import load_scene

    instance = load_instance(args.instance, grasp=None)
    scene_path = args.scene if args.scene is not None else instance.scene_path(args.instance)
    scene = load_scene(scene_path)
    instance = load_instance(args.instance, scene.grasp_limits)
    plan = load_plan(args.plan, scene.layout)
    report = validate_plan(instance, plan, scene)
    v = report.violation
    if args.json:
        record = {
            "valid": v is None,
            "instance": instance.name,
            "plan": str(args.plan),
            "events": len(plan.events),
            "checks": report.checks,
            "duration": plan.duration,
            "violation": None if v is None else {"t": v.t, "kind": v.kind, "message": v.message},
        }
        print(json.dumps(record, sort_keys=True))
    elif v is None:
        print(
            f"valid: {len(plan.events)} gripper events, {report.checks} collision checks, "
            f"duration {plan.duration:.2f} s"
        )
    else:
        print(f"invalid at t={v.t:.3f}s: {v.kind}: {v.message}")
    return 0 if v is None else 1


def add_validate_parser(sub: argparse._SubParsersAction[Any]) -> None:
    """Register ``sdar validate``."""
    validate = sub.add_parser(
        "validate", help="check a plan file against an instance", description=cmd_validate.__doc__
    )
    validate.add_argument("instance", type=Path, help="instance YAML")
    validate.add_argument("plan", type=Path, help="plan JSON")
    validate.add_argument("--scene", type=Path, default=None, help=SCENE_HELP)
    validate.add_argument("--json", action="store_true", help=JSON_HELP)
    validate.set_defaults(func=cmd_validate)
