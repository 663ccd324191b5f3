"""Benchmark: synchronous against asynchronous execution time of SDAR's plans.

Every instance is solved by ``sdar solve``'s code path (or its plan is read from
``--plans DIR/<name>.json``, written there after a solve when ``--save`` is given), then
executed three ways side by side: synchronously, re-timed step by step
(:func:`sdar_tamp.schedule.schedule_async`, ``--execution async``) and with one timeline per
arm (:func:`sdar_tamp.schedule.timelines.schedule_timelines`; ``best`` is what ``--execution
timelines`` returns: the shorter of the two that the replay accepts) and with the moves assigned
anew to whichever arm is free (:func:`sdar_tamp.schedule.assignment.schedule_assigned`;
``assign`` is its own schedule, nan when none is found, ``a/sync`` its ratio to the synchronous
time; the ratio after it is what
``--execution assigned`` returns: the shortest of the three the replay accepts; ``--no-assigned``
leaves it out). Every plan is checked by
the independent replay. Execution time is the plan's duration; a scheduler that finds no
shorter schedule returns the synchronous plan, so every ratio is at most 1. Where the time goes
on the timelines: ``dep`` and ``arms``, the waits [s] (summed over the arms) for the task
order's dependencies and for the other arms' motions, ``tog`` the groups that had to move
together at their synchronous pace (swap halves), ``cut`` the time [s] shortened paths saved.

    python benchmarks/bench_async.py [--suite paper] [--only R4,R6,D5] [--plans DIR] [--save]
                                     [--time-limit 60] [--sync-pace] [--assign-seconds 300]
                                     [--policies own-first,earliest,clear,plan-order]
                                     [--no-pauses] [--sync-motions]

``--assign-seconds`` caps the assignment's wall-clock time per instance (the result then
depends on the machine's load), ``--policies`` chooses its policies, ``--no-pauses`` keeps
motions from pausing on the way, ``--sync-motions`` offers a move the synchronous plan's own
motion first (:mod:`sdar_tamp.schedule.sync_motions`; always with ``--policies own-first``);
the note gives each policy's schedule [s].

``--suite`` may be a suite of the shared table's cells (``table_1arm`` ... ``table_4arm``: each
instance names its cell).
    python benchmarks/bench_async.py --quick    # R4 alone: seconds

Prints one row per instance (``bound``: the busier arm's motions and dwells, a lower bound
for any schedule of these motions), the median ratio, then one JSON object on the last line.

``--quick`` changes only the defaults: ``--only R4`` (4 objects, in the ``paper`` suite),
solved with a 30 s time limit, the assignment's ``earliest`` policy alone; the JSON keys are
the same, plus ``"quick": true``.
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
from sdar_tamp.app.move_planning import StreamMovePlanner
from sdar_tamp.replay import validate_plan
from sdar_tamp.schedule import ScheduleOptions, schedule_async
from sdar_tamp.schedule.assignment import schedule_assigned
from sdar_tamp.schedule.move_records import POLICIES, AssignmentOptions
from sdar_tamp.schedule.pieces import arm_blocks
from sdar_tamp.schedule.scheduler import retimer
from sdar_tamp.schedule.timelines import schedule_timelines
from sdar_tamp.world.instance import load_instance
from sdar_tamp.world.scene import load_scene
from sdar_tamp.world.suites import CELL_SUITES, SUITES

#: ``--quick``'s defaults
QUICK = {"only": "R4", "time_limit": 30.0, "policies": "earliest"}


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
    ap.add_argument(
        "--no-assigned", action="store_true", help="leave out the moves assigned anew (slow)"
    )
    ap.add_argument(
        "--assign-seconds",
        type=float,
        default=AssignmentOptions.max_seconds,
        help="wall-clock cap [s] of the assignment search per instance",
    )
    ap.add_argument(
        "--policies",
        default=",".join(AssignmentOptions().policies),
        help=f"the assignment's policies, tried in turn (some of {','.join(POLICIES)})",
    )
    ap.add_argument("--no-pauses", action="store_true", help="motions do not pause on the way")
    ap.add_argument(
        "--sync-motions",
        action="store_true",
        help="offer a move the synchronous plan's own motion first",
    )
    ap.add_argument("--quick", action="store_true", help="one small instance (R4): seconds")
    args = ap.parse_args(argv)
    if args.quick:  # explicit options still win
        ap.set_defaults(**QUICK)
        args = ap.parse_args(argv)
    only = {s for s in args.only.split(",") if s}
    assignment_options = AssignmentOptions(
        max_seconds=args.assign_seconds,
        policies=tuple(p for p in args.policies.split(",") if p),
        pauses=not args.no_pauses,
        sync_motions=args.sync_motions,
    )
    files = [p for p in shipped_suite_files(args.suite) if not only or p.stem in only]
    cache = PlannerCache()
    solve_config = PlannerConfig(max_time=args.time_limit, execution="sync")
    rows = []
    print(f"{'instance':>8} {'sync [s]':>9} {'retime':>7} {'lines':>7} {'best':>7} {'ratio':>6} "
          f"{'assign':>7} {'a/sync':>6} {'ratio':>6} {'valid':>5} {'bound':>6} {'dep':>5} "
          f"{'arms':>5} {'tog':>3} {'cut':>5} {'time [s]':>8}  note")  # fmt: skip
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
        after = time.perf_counter()
        assigned = None
        if not args.no_assigned:
            assigned = schedule_assigned(
                plan,
                instance,
                scene,
                options,
                StreamMovePlanner(instance, scene),
                assignment_options,
            )
        elapsed = (middle - start, after - middle, time.perf_counter() - after)
        valid_today = validate_plan(instance, today.plan, scene).ok
        valid_lines = validate_plan(instance, lines.plan, scene).ok
        valid_assigned = assigned is None or validate_plan(instance, assigned.plan, scene).ok
        # what `--execution timelines` returns: the shorter of the two the replay accepts
        kept = [r.plan for r, ok in ((today, valid_today), (lines, valid_lines)) if ok]
        best = min((p.duration for p in kept), default=plan.duration)
        # and `--execution assigned`: the shortest of the three
        moved = assigned.plan.duration if assigned is not None and valid_assigned else plan.duration
        best_assigned = min(best, moved)
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
                "assigned": None if assigned is None else round(assigned.plan.duration, 3),
                "assigned_found": None if assigned is None else assigned.async_duration,
                "ratio_assigned_own": None
                if assigned is None or assigned.async_duration is None
                else round(assigned.async_duration / plan.duration, 4),
                "assigned_kept": assigned is not None and assigned.asynchronous,
                "assigned_reason": "" if assigned is None else assigned.reason,
                "best_assigned": round(best_assigned, 3),
                "ratio_assigned": round(best_assigned / plan.duration, 4),
                "valid": valid_today and valid_lines and valid_assigned,
                "schedule_time": round(elapsed[0], 2),
                "timelines_time": round(elapsed[1], 2),
                "assigned_time": round(elapsed[2], 2),
                "assigned_checks": None if assigned is None else assigned.checks,
                **(
                    {}
                    if assigned is None
                    else {f"assigned_{k}": round(v, 3) for k, v in assigned.figures}
                ),
                "checks": today.checks,
                "timelines_checks": lines.checks,
                **{k: round(v, 3) for k, v in figures.items()},
            }
        )
        note = lines.reason[:40] + (" | " + assigned.reason[:40] if assigned is not None else "")
        if assigned is not None:  # each policy's schedule [s]
            note += " | " + " ".join(
                f"{k[9:]}={v:.2f}" for k, v in assigned.figures if k.startswith("duration_")
            )
        found = assigned.async_duration if assigned is not None else None
        dep, arms = figures.get("wait_dependencies", 0.0), figures.get("wait_other_arms", 0.0)
        tog, cut = int(figures.get("together", 0)), figures.get("shortcut_saved", 0.0)
        print(f"{path.stem:>8} {plan.duration:9.2f} {today.plan.duration:7.2f} "
              f"{lines.plan.duration:7.2f} {best:7.2f} {best / plan.duration:6.3f} "
              f"{found or float('nan'):7.2f} {(found or float('nan')) / plan.duration:6.3f} "
              f"{best_assigned / plan.duration:6.3f} "
              f"{rows[-1]['valid']!s:>5} {bound:6.2f} {dep:5.1f} {arms:5.1f} {tog:3d} "
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
        "median_assigned": median("best_assigned"),
        "median_ratio_assigned": median("ratio_assigned"),
        "assigned_kept": sum(r["assigned_kept"] for r in rows),
        "mean_ratio": round(statistics.fmean(ratios), 4) if ratios else None,
        "timelines_kept": sum(r["timelines_kept"] for r in rows),
        "all_valid": all(r["valid"] for r in rows),
        "rows": rows,
        "quick": args.quick,
    }
    if ratios:
        print(f"median execution [s]: sync {summary['median_sync']}, async (re-timed) "
              f"{summary['median_async']}, timelines {summary['median_timelines']}, "
              f"assigned {summary['median_assigned']}")  # fmt: skip
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
