"""Benchmark: synchronous against asynchronous execution time of SDAR's plans.

Every instance is solved by ``sdar solve``'s code path (or its plan is read from
``--plans DIR/<name>.json``, written there after a solve when ``--save`` is given), then
re-scheduled for asynchronous execution (:func:`sdar_tamp.schedule.schedule_async`), and the
asynchronous plan is checked by the independent replay. Execution time is the plan's duration;
the asynchronous figure is the plan the scheduler returns (the synchronous one when no shorter
schedule was found, so the ratio is at most 1).

    python benchmarks/bench_async.py [--suite paper] [--only R4,R6,D5] [--plans DIR] [--save]
                                     [--time-limit 60] [--sync-pace]
    python benchmarks/bench_async.py --quick    # R4 alone: seconds

Prints one row per instance (``bound``: the busier arm's motions and dwells, a lower bound
for any schedule of these motions), the median ratio, then one JSON object on the last line.

``--quick`` changes only the defaults: ``--only R4`` (4 objects, in the ``paper`` suite),
solved with a 30 s time limit; the JSON keys are the same, plus ``"quick": true``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import re
import statistics
import time
from pathlib import Path

from sdar_tamp.app import PlannerCache, solve_instance
from sdar_tamp.app.execution import execution_options
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_writing import save_plan
from sdar_tamp.replay import validate_plan
from sdar_tamp.resources import domain_file
from sdar_tamp.schedule import ScheduleOptions, schedule_async
from sdar_tamp.schedule.pieces import arm_blocks
from sdar_tamp.schedule.scheduler import retimer
from sdar_tamp.world.instance import load_instance
from sdar_tamp.world.scene import load_scene
from sdar_tamp.world.suites import SUITES


def _suite_files(suite: str) -> list[Path]:
    folder = domain_file("dual_arm_rearrangement", "domain.pddl").parent / "suites" / suite

    def key(p: Path) -> tuple[str, int]:
        digits = re.sub(r"\D", "", p.stem)
        return (p.stem[0], int(digits) if digits else 0)

    return sorted(folder.glob("*.yaml"), key=key)


def _plan(path: Path, args: argparse.Namespace, cache: PlannerCache) -> PlanFile | None:
    stored = args.plans / f"{path.stem}.json" if args.plans else None
    if stored is not None and stored.exists() and not args.save:
        return load_plan(stored)
    outcome = solve_instance(path, time_limit=args.time_limit, execution="sync", cache=cache)
    if not outcome.success or outcome.plan is None:
        return None
    if stored is not None and args.save:
        save_plan(outcome.plan, stored)
    return outcome.plan


#: ``--quick``'s defaults
QUICK = {"only": "R4", "time_limit": 30.0}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", default="paper", choices=SUITES)
    ap.add_argument("--only", default="", help="comma-separated instance names")
    ap.add_argument("--plans", type=Path, default=None, help="folder of plan files <name>.json")
    ap.add_argument("--save", action="store_true", help="solve and write the plans to --plans")
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--sync-pace", action="store_true", help="motions keep their synchronous pace")
    ap.add_argument(
        "--uniform",
        action="store_true",
        help="re-time each arm's motions uniformly faster (no time-optimal path timing)",
    )
    ap.add_argument("--quick", action="store_true", help="one small instance (R4): seconds")
    args = ap.parse_args(argv)
    if args.quick:  # explicit options still win
        ap.set_defaults(**QUICK)
        args = ap.parse_args(argv)
    only = {s for s in args.only.split(",") if s}
    files = [p for p in _suite_files(args.suite) if not only or p.stem in only]
    cache = PlannerCache()
    rows = []
    print(f"{'instance':>8} {'sync [s]':>9} {'async [s]':>9} {'ratio':>6} {'order':>8} "
          f"{'valid':>5} {'time [s]':>8} {'bound [s]':>9}  note")  # fmt: skip
    for path in files:
        instance = load_instance(path)
        plan = _plan(path, args, cache)
        if plan is None:
            print(f"{path.stem:>8} not solved")
            continue
        scene = load_scene(instance.scene_path(path))
        options = dataclasses.replace(
            ScheduleOptions() if args.uniform else execution_options(scene),
            retime=not args.sync_pace,
        )
        start = time.perf_counter()
        result = schedule_async(plan, instance, scene, options)
        elapsed = time.perf_counter() - start
        valid = validate_plan(instance, result.plan, scene).ok
        # no schedule of these motions beats the busier arm's motions plus its dwells
        bound = max(
            sum(b.motion_ticks * options.tick + options.dwell * (b.event is not None) for b in bs)
            for bs in (
                arm_blocks(plan, scene, i, options.tick, options.retime, retimer(scene, i, options))
                for i in (0, 1)
            )
        )
        ratio = result.plan.duration / plan.duration
        rows.append(
            {
                "instance": path.stem,
                "sync": round(plan.duration, 3),
                "async": round(result.plan.duration, 3),
                "ratio": round(ratio, 4),
                "bound": round(bound, 3),
                "asynchronous": result.asynchronous,
                "order": result.order,
                "valid": valid,
                "schedule_time": round(elapsed, 2),
                "checks": result.checks,
            }
        )
        note = result.reason[:70]
        order = result.order or "-"
        print(f"{path.stem:>8} {plan.duration:9.2f} {result.plan.duration:9.2f} {ratio:6.3f} "
              f"{order:>8} {valid!s:>5} {elapsed:8.1f} {bound:9.2f}  {note}")  # fmt: skip
    ratios = [r["ratio"] for r in rows]
    summary = {
        "benchmark": "async",
        "suite": args.suite,
        "instances": len(rows),
        "retime": not args.sync_pace,
        "timer": "uniform" if args.uniform else "time-optimal",
        "median_ratio": round(statistics.median(ratios), 4) if ratios else None,
        "mean_ratio": round(statistics.fmean(ratios), 4) if ratios else None,
        "all_valid": all(r["valid"] for r in rows),
        "rows": rows,
        "quick": args.quick,
    }
    if ratios:
        print(f"median async/sync execution time: {summary['median_ratio']:.3f}")
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
