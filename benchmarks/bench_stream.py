"""Benchmark: streaming (``sdar solve --stream``) against the batch solve, side by side.

For each instance and run, in one process (imports done once, a fresh world and motion
planner for every solve: a ``PlannerCache`` per solve, as in a new ``sdar solve``), the
batch solve (``solve_instance(..., execution="sync")``, the plan a stream concatenates to)
and the stream (``solve_stream``) are timed one after the other, their order alternating from
run to run:

* ``first_step_s``: from the ``solve_stream`` call (the instance read, the world built, the
  optimiser's compiled library started in the background) to the first step yielded,
  planned and checked; ``first_step_after_load_s``: from the call's return (the instance
  loaded, the world and the problem built) to the first step;
* ``stream_total_s``: from that call to the last step yielded (planning finished);
  ``stream_done_s`` also holds the end (the whole plan's replay and the figures);
* ``batch_total_s``: the ``solve_instance`` call, start to return (planning, the plan file,
  its replay);
* ``*_cpu_s``: the same spans in CPU time of the process (every thread: the optimiser's
  build included), less sensitive than wall time to a loaded machine;
* ``same_plan``: the streamed plan equals the batch plan (every field but the run's timings).

    python benchmarks/bench_stream.py [--instances M1 D4] [--runs 3] [--seed 0]
    python benchmarks/bench_stream.py --quick    # one run on D4: seconds

Prints one row per solve, then one JSON object on the last line: per instance the medians over
the runs, and the medians over the instances (``first_step_s``, ``stream_total_s``,
``batch_total_s``, ...). ``--quick`` changes only the defaults (``--instances D4 --runs 1``)
and adds ``"quick": true``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path
from typing import Any

from sdar_tamp.app.cache import PlannerCache
from sdar_tamp.app.pipeline import solve_instance
from sdar_tamp.app.streaming import solve_stream
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_writing import plan_to_dict
from sdar_tamp.resources import domain_file

#: The plan file's metrics that time the run (they differ between any two runs).
TIMING = {"planning_time", "planning_time_selection", "planning_time_motion", "step_time_median"}
KEYS = ("first_step_s", "stream_total_s", "stream_done_s", "batch_total_s", "steps",
        "first_step_cpu_s", "stream_total_cpu_s", "batch_total_cpu_s",
        "first_step_after_load_s", "first_step_after_load_cpu_s")  # fmt: skip


def same_plan(a: PlanFile, b: PlanFile) -> bool:
    """Every field equal, the metrics but the run's timings."""
    x, y = plan_to_dict(a), plan_to_dict(b)
    for d in (x, y):
        d["metrics"] = {k: v for k, v in d["metrics"].items() if k not in TIMING}
    return x == y


def batch(path: Path, seed: int, time_limit: float) -> tuple[dict[str, float], PlanFile | None]:
    start, cpu = time.perf_counter(), time.process_time()
    outcome = solve_instance(
        path, seed=seed, time_limit=time_limit, execution="sync", cache=PlannerCache()
    )
    figures = {
        "batch_total_s": time.perf_counter() - start,
        "batch_total_cpu_s": time.process_time() - cpu,
    }
    return figures, outcome.plan if outcome.success else None


def stream(path: Path, seed: int, time_limit: float) -> tuple[dict[str, float], PlanFile | None]:
    start, cpu = time.perf_counter(), time.process_time()
    planned = solve_stream(path, seed=seed, time_limit=time_limit, cache=PlannerCache())
    loaded = (time.perf_counter() - start, time.process_time() - cpu)
    times = [(time.perf_counter() - start, time.process_time() - cpu) for _ in planned]
    done = time.perf_counter() - start
    outcome = planned.outcome
    first, last = (times[0], times[-1]) if times else ((done, 0.0), (done, 0.0))
    figures = {
        "first_step_s": first[0],
        "first_step_cpu_s": first[1],
        "first_step_after_load_s": first[0] - loaded[0],
        "first_step_after_load_cpu_s": first[1] - loaded[1],
        "stream_total_s": last[0],
        "stream_total_cpu_s": last[1],
        "stream_done_s": done,
        "steps": float(len(times)),
    }
    return figures, outcome.plan if outcome is not None and outcome.success else None


def run_instance(name: str, runs: int, seed: int, time_limit: float) -> dict[str, Any]:
    path = domain_file("dual_arm_rearrangement", f"suites/paper/{name}.yaml")
    rows = []
    for k in range(runs):
        order = ("batch", "stream") if k % 2 == 0 else ("stream", "batch")
        row: dict[str, Any] = {}
        plans: dict[str, PlanFile | None] = {}
        for which in order:
            run = batch if which == "batch" else stream
            figures, plans[which] = run(path, seed, time_limit)
            row.update(figures)
        a, b = plans["stream"], plans["batch"]
        row["same_plan"] = a is not None and b is not None and same_plan(a, b)
        shown = " ".join(f"{k} {row[k]:.3f}" for k in KEYS if k != "steps")
        print(f"{name} run {k}: {shown} steps {int(row['steps'])} same_plan {row['same_plan']}")
        rows.append(row)
    out: dict[str, Any] = {k: round(statistics.median(r[k] for r in rows), 3) for k in KEYS}
    out["same_plan"] = all(r["same_plan"] for r in rows)
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--instances", nargs="+", default=None, help="paper suite (default: M1)")
    ap.add_argument("--runs", type=int, default=None, help="runs per instance (default: 3)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--time-limit", type=float, default=600.0, help="[s] (default: 600)")
    ap.add_argument("--quick", action="store_true", help="D4, one run")
    args = ap.parse_args(argv)
    instances = args.instances or (["D4"] if args.quick else ["M1"])
    runs = args.runs or (1 if args.quick else 3)
    per = {name: run_instance(name, runs, args.seed, args.time_limit) for name in instances}
    summary: dict[str, Any] = {
        "benchmark": "stream",
        "instances": len(per),
        "runs": runs,
        "seed": args.seed,
        "load_average": [round(x, 2) for x in os.getloadavg()],
        **{k: round(statistics.median(p[k] for p in per.values()), 3) for k in KEYS},
        "first_step_target_s": 0.5,
        "all_same_plan": all(p["same_plan"] for p in per.values()),
        "per_instance": per,
    }
    if args.quick:
        summary["quick"] = True
    print(json.dumps(summary, sort_keys=True))


if __name__ == "__main__":
    main()
