"""Benchmark: synchronous against asynchronous execution time of SDAR's plans.

Every instance is solved by ``sdar solve``'s code path (or its plan is read from
``--plans DIR/<name>.json``, written there after a solve when ``--save`` is given), then
executed three ways side by side: synchronously, re-timed step by step
(:func:`sdar_tamp.schedule.schedule_async`, ``--execution async``) and with one timeline per
arm (:func:`sdar_tamp.schedule.timelines.schedule_timelines`; ``best`` is what ``--execution
timelines`` returns: the shorter of the two that the replay accepts). Every plan is checked by
the independent replay. Execution time is the plan's duration; a scheduler that finds no
shorter schedule returns the synchronous plan, so every ratio is at most 1. Where the time goes
on the timelines: ``dep`` and ``arms``, the waits [s] (summed over the arms) for the task
order's dependencies and for the other arms' motions, ``tog`` the groups that had to move
together at their synchronous pace (swap halves), ``cut`` the time [s] shortened paths saved.

    python benchmarks/bench_async.py [--suite paper] [--only R4,R6,D5] [--plans DIR] [--save]
                                     [--time-limit 60] [--sync-pace]

``--suite`` may be a suite of the shared table's cells (``table_1arm`` ... ``table_4arm``: each
instance names its cell).
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
import statistics
import time
from pathlib import Path

from _suites import shipped_suite_files, stored_or_solved

from sdar_tamp.app import PlannerCache, PlannerConfig
from sdar_tamp.app.execution import execution_options
from sdar_tamp.replay import validate_plan
from sdar_tamp.schedule import ScheduleOptions, schedule_async
from sdar_tamp.schedule.pieces import arm_blocks
from sdar_tamp.schedule.scheduler import retimer
from sdar_tamp.schedule.timelines import schedule_timelines
from sdar_tamp.world.instance import load_instance
from sdar_tamp.world.scene import load_scene
from sdar_tamp.world.suites import CELL_SUITES, SUITES

#: ``--quick``'s defaults
QUICK = {"only": "R4", "time_limit": 30.0}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", default="paper", choices=(*SUITES, *CELL_SUITES))
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
    files = [p for p in shipped_suite_files(args.suite) if not only or p.stem in only]
    cache = PlannerCache()
    solve_config = PlannerConfig(max_time=args.time_limit, execution="sync")
    rows = []
    print(f"{'instance':>8} {'sync [s]':>9} {'retime':>7} {'lines':>7} {'best':>7} {'ratio':>6} "
          f"{'valid':>5} {'bound':>6} {'dep':>5} {'arms':>5} {'tog':>3} {'cut':>5} "
          f"{'time [s]':>8}  note")  # fmt: skip
    for path in files:
        instance = load_instance(path)
        plan = stored_or_solved(
            path, args.plans, solve_config, cache, save=args.save, refresh=args.save
        )
        if plan is None:
            print(f"{path.stem:>8} not solved")
            continue
        scene = load_scene(instance.scene_path(path))
        options = dataclasses.replace(
            ScheduleOptions() if args.uniform else execution_options(scene),
            retime=not args.sync_pace,
        )
        start = time.perf_counter()
        today = schedule_async(plan, instance, scene, options)
        middle = time.perf_counter()
        lines = schedule_timelines(plan, instance, scene, options)
        elapsed = (middle - start, time.perf_counter() - middle)
        valid_today = validate_plan(instance, today.plan, scene).ok
        valid_lines = validate_plan(instance, lines.plan, scene).ok
        # what `--execution timelines` returns: the shorter of the two the replay accepts
        kept = [r.plan for r, ok in ((today, valid_today), (lines, valid_lines)) if ok]
        best = min((p.duration for p in kept), default=plan.duration)
        # no schedule of these motions beats the busier arm's motions plus its dwells
        bound = max(
            sum(b.motion_ticks * options.tick + options.dwell * (b.event is not None) for b in bs)
            for bs in (
                arm_blocks(plan, scene, i, options.tick, options.retime, retimer(scene, i, options))
                for i in range(len(scene.arms))
            )
        )
        figures = dict(lines.figures)
        rows.append(
            {
                "instance": path.stem,
                "sync": round(plan.duration, 3),
                "async": round(today.plan.duration, 3),
                "timelines": round(lines.plan.duration, 3),
                "best": round(best, 3),
                "ratio": round(today.plan.duration / plan.duration, 4),
                "ratio_timelines": round(best / plan.duration, 4),
                "bound": round(bound, 3),
                "asynchronous": today.asynchronous,
                "timelines_kept": lines.asynchronous,
                "order": today.order,
                "valid": valid_today and valid_lines,
                "schedule_time": round(elapsed[0], 2),
                "timelines_time": round(elapsed[1], 2),
                "checks": today.checks,
                "timelines_checks": lines.checks,
                **{k: round(v, 3) for k, v in figures.items()},
            }
        )
        note = lines.reason[:60]
        dep, arms = figures.get("wait_dependencies", 0.0), figures.get("wait_other_arms", 0.0)
        tog, cut = int(figures.get("together", 0)), figures.get("shortcut_saved", 0.0)
        print(f"{path.stem:>8} {plan.duration:9.2f} {today.plan.duration:7.2f} "
              f"{lines.plan.duration:7.2f} {best:7.2f} {best / plan.duration:6.3f} "
              f"{valid_today and valid_lines!s:>5} {bound:6.2f} {dep:5.1f} {arms:5.1f} {tog:3d} "
              f"{cut:5.2f} {sum(elapsed):8.1f}  {note}", flush=True)  # fmt: skip

    def median(key: str) -> float | None:
        values = [r[key] for r in rows]
        return round(statistics.median(values), 4) if values else None

    ratios = [r["ratio"] for r in rows]
    summary = {
        "benchmark": "async",
        "suite": args.suite,
        "instances": len(rows),
        "retime": not args.sync_pace,
        "timer": "uniform" if args.uniform else "time-optimal",
        "median_sync": median("sync"),
        "median_async": median("async"),
        "median_timelines": median("best"),
        "median_bound": median("bound"),
        "median_ratio": median("ratio"),
        "median_ratio_timelines": median("ratio_timelines"),
        "mean_ratio": round(statistics.fmean(ratios), 4) if ratios else None,
        "timelines_kept": sum(r["timelines_kept"] for r in rows),
        "all_valid": all(r["valid"] for r in rows),
        "rows": rows,
        "quick": args.quick,
    }
    if ratios:
        print(f"median execution [s]: sync {summary['median_sync']}, async (re-timed) "
              f"{summary['median_async']}, timelines {summary['median_timelines']}")  # fmt: skip
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
