"""Benchmark: deferred tests and functions against evaluating every combination.

The 2-D house (``domains/nav_manip_2d``): a path stream between sampled navigation poses, an
endless placement stream, a 4-argument collision test used through a derived predicate and a
4-argument cost function, solved as a PDDLStream program solves it:
``solve_adaptive(problem, stream_info=..., search_sample_ratio=0.5, planner="ff-astar",
max_planner_time=30)`` through ``sdar_tamp.compat.pddlstream``. Three ways, side by side in one
run, on the same seeds:

- ``eager``: ``StreamInfo(eager=True, negate=True)`` on the test and ``FunctionInfo(eager=True)``
  on both costs: every instance is evaluated as soon as its inputs exist (what the solver did
  with every test and function before they were deferred);
- ``negate``: ``StreamInfo(eager=False, negate=True)`` on the test (the navigation project's
  idiom): the test and the costs are evaluated for the candidate plans' instances only;
- ``auto``: no stream options; the test is negated automatically (PDDLStream's namo idiom).

Per run: status, wall time [s], plan cost, and calls per stream. The samplers here take
microseconds; ``--call-ms`` makes each collision test and handling cost spend that long, as a
real geometric check would. Prints a table, then one JSON line.

    python benchmarks/bench_deferred.py [--seeds 3] [--max-time 120] [--clutter 3] [--call-ms 0]
    python benchmarks/bench_deferred.py --quick    # one seed, two clutter objects
"""

from __future__ import annotations

import argparse
import json
import logging
import statistics
import time
from typing import Any

from domains.nav_manip_2d.samplers import MODES, make_problem, stream_info
from sdar_tamp.compat.pddlstream.algorithms.focused import solve_adaptive

TEST = "test-collision-free"
COST = "handlingcost"
QUICK = {"seeds": 1, "clutter": 2, "max_time": 120.0}


def run(
    mode: str, seed: int, clutter: int, max_time: float, call_ms: float = 0.0
) -> dict[str, Any]:
    problem = make_problem(seed=seed, clutter=clutter, call_seconds=call_ms / 1000)
    start = time.perf_counter()
    solution = solve_adaptive(
        problem,
        stream_info=stream_info(mode),
        search_sample_ratio=0.5,
        planner="ff-astar",
        max_planner_time=30,
        max_time=max_time,
        verbose=False,
        seed=seed,
    )
    elapsed = time.perf_counter() - start
    return {
        "mode": mode,
        "seed": seed,
        "status": solution.status.value,
        "time": round(elapsed, 3),
        "cost": None if solution.plan is None else round(solution.cost, 4),
        "length": None if solution.plan is None else len(solution.plan),
        "calls": {name: s.calls for name, s in sorted(solution.streams.items())},
    }


def summary(rows: list[dict[str, Any]], mode: str) -> dict[str, Any]:
    mine = [r for r in rows if r["mode"] == mode]
    return {
        "solved": sum(r["status"] == "solved" for r in mine),
        "runs": len(mine),
        "median_time": round(statistics.median(r["time"] for r in mine), 3),
        "test_calls": sum(r["calls"].get(TEST, 0) for r in mine),
        "cost_calls": sum(r["calls"].get(COST, 0) for r in mine),
        "all_calls": sum(sum(r["calls"].values()) for r in mine),
    }


def table(rows: list[dict[str, Any]]) -> str:
    streams = sorted({name for r in rows for name in r["calls"]})
    head = ["mode", "seed", "status", "time [s]", "cost", *streams]
    lines = [" | ".join(head), " | ".join("---" for _ in head)]
    for r in rows:
        cells = [r["mode"], str(r["seed"]), r["status"], f"{r['time']:.2f}", str(r["cost"])]
        cells += [str(r["calls"].get(name, 0)) for name in streams]
        lines.append(" | ".join(cells))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--clutter", type=int, default=3, help="objects already on the shelf")
    parser.add_argument("--max-time", type=float, default=120.0, help="[s] per run")
    parser.add_argument("--modes", nargs="+", choices=MODES, default=list(MODES))
    parser.add_argument(
        "--call-ms", type=float, default=0.0, help="[ms] each test and cost call spends"
    )
    parser.add_argument("--quick", action="store_true", help="one seed, a smaller shelf")
    args = parser.parse_args(argv)
    if args.quick:
        args.seeds, args.clutter, args.max_time = (
            QUICK["seeds"],
            int(QUICK["clutter"]),
            QUICK["max_time"],
        )
    logging.basicConfig(level=logging.ERROR)
    rows = [
        run(mode, seed, args.clutter, args.max_time, args.call_ms)
        for seed in range(args.seeds)
        for mode in args.modes
    ]
    print(table(rows))
    result: dict[str, Any] = {
        "benchmark": "deferred",
        "clutter": args.clutter,
        "seeds": args.seeds,
        "max_time": args.max_time,
        "call_ms": args.call_ms,
        "runs": rows,
        "modes": {mode: summary(rows, mode) for mode in args.modes},
    }
    if args.quick:
        result["quick"] = True
    print(json.dumps(result, separators=(",", ":")))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
