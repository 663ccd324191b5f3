"""``sdar demo``: solve the shipped mixed instance M1 and write its plan and pictures."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from sdar_tamp.arguments import TIME_LIMIT, output_folder

DEMO_DOMAIN = "dual_arm_rearrangement"
DEMO_INSTANCE = "suites/paper/M1.yaml"


def cmd_demo(args: argparse.Namespace) -> int:
    """Solve the shipped 12-object mixed instance M1 with SDAR as ``sdar solve`` does
    (asynchronous execution), validate the plan by replay, and write the plan file, the 3-D
    page and the storyboard (default: a folder in the system's temporary directory; nothing
    is written to the working directory)."""
    import tempfile

    from sdar_tamp.app.pipeline import solve_instance
    from sdar_tamp.app.summary import format_summary, terminal_progress
    from sdar_tamp.plan_writing import save_plan
    from sdar_tamp.resources import domain_file
    from sdar_tamp.viewer import write_html, write_storyboard

    instance = domain_file(DEMO_DOMAIN, DEMO_INSTANCE)
    if args.output is None:
        out = Path(tempfile.mkdtemp(prefix="sdar-demo-"))  # a fresh folder per run
    else:
        out = output_folder(args.output, name="--output")
        out.mkdir(parents=True, exist_ok=True)
    print(f"Solving the shipped mixed instance {DEMO_INSTANCE} (12 objects) with SDAR:")
    bar = terminal_progress(instance.stem)
    try:
        outcome = solve_instance(
            instance,
            time_limit=args.time_limit,
            execution="async",  # `sdar solve`'s default
            progress=bar,
            stage=bar.stage if bar is not None else None,
        )
    finally:
        if bar is not None:
            bar.close()
    print(format_summary(outcome))
    if outcome.plan is None:
        return 1
    print(f"wrote {save_plan(outcome.plan, out / 'plan.json')}")
    print(f"wrote {write_html(outcome.instance, outcome.plan, out / 'plan.html')}")
    print(f"wrote {write_storyboard(outcome.instance, outcome.plan, out / 'storyboard.png')}")
    print(f"check it again with: sdar validate {instance} {out / 'plan.json'}")
    return 0 if outcome.success else 1


def add_demo_parser(sub: argparse._SubParsersAction[Any]) -> None:
    """Register ``sdar demo``."""
    demo = sub.add_parser("demo", help="solve a built-in example", description=cmd_demo.__doc__)
    demo.add_argument(
        "--time-limit", type=TIME_LIMIT.parse, default=60.0, help="seconds (default: 60)"
    )
    demo.add_argument(
        "-o",
        "--output",
        "--out",
        dest="output",
        type=Path,
        default=None,
        help="output folder (default: a new folder sdar-demo-* in the temporary directory)",
    )
    demo.set_defaults(func=cmd_demo)
