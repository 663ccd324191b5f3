"""Benchmark: the four stream planning algorithms on the teaching TAMP domains.

For every domain (pick_place_2d, kitchen, dual_arm_swap, infeasible) and every algorithm
(incremental, focused, binding, adaptive): status, wall time [s], stream calls, plan cost and
length. Each run builds a fresh problem from the same seed. Prints a table, then one JSON line.

    python benchmarks/bench_streams.py [--max-time 30] [--seed 0] [--domains kitchen ...]
"""

from __future__ import annotations

import argparse
import importlib
import json
import logging
import math
import time
from typing import Any

from solvers.solve import solve
from solvers.stream_planning.algorithms import ALGORITHMS

DOMAINS = ("pick_place_2d", "kitchen", "dual_arm_swap", "infeasible")
EXPECTED = {"infeasible": "infeasible"}  # every other domain: solved


def run(domain: str, algorithm: str, max_time: float, seed: int) -> dict[str, Any]:
    make_problem = importlib.import_module(f"domains.{domain}.samplers").make_problem
    problem = make_problem(seed=seed)
    start = time.perf_counter()
    solution = solve(problem, algorithm=algorithm, max_time=max_time, seed=seed, verbose=False)
    elapsed = time.perf_counter() - start
    return {
        "domain": domain,
        "algorithm": algorithm,
        "status": solution.status.value,
        "expected": EXPECTED.get(domain, "solved"),
        "time": round(elapsed, 3),
        "stream_calls": sum(s.calls for s in solution.streams.values()),
        "cost": round(solution.cost, 6) if math.isfinite(solution.cost) else None,
        "length": len(solution.plan) if solution.plan is not None else None,
        "iterations": int(solution.statistics.get("iterations", 0)),
    }


def table(rows: list[dict[str, Any]]) -> str:
    header = (
        f"{'domain':<14} {'algorithm':<12} {'status':<11} {'time[s]':>8} {'calls':>7} "
        f"{'cost':>8} {'length':>6}  ok"
    )
    lines = [header, "-" * len(header)]
    for row in rows:
        cost = f"{row['cost']:.3f}" if row["cost"] is not None else "-"
        length = str(row["length"]) if row["length"] is not None else "-"
        ok = "yes" if row["status"] == row["expected"] else "NO"
        lines.append(
            f"{row['domain']:<14} {row['algorithm']:<12} {row['status']:<11} "
            f"{row['time']:>8.3f} {row['stream_calls']:>7d} {cost:>8} {length:>6}  {ok}"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-time", type=float, default=30.0, help="[s] per run")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--domains", nargs="+", choices=DOMAINS, default=list(DOMAINS))
    parser.add_argument("--algorithms", nargs="+", choices=ALGORITHMS, default=list(ALGORITHMS))
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    rows = [
        run(domain, algorithm, args.max_time, args.seed)
        for domain in args.domains
        for algorithm in args.algorithms
    ]
    print(table(rows))
    summary = {
        "benchmark": "stream_planning",
        "max_time": args.max_time,
        "seed": args.seed,
        "all_expected": all(r["status"] == r["expected"] for r in rows),
        "runs": rows,
    }
    print(json.dumps(summary, separators=(",", ":")))
    return 0 if summary["all_expected"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
