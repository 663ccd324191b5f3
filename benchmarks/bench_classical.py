"""Benchmark: our classical planner against pyperplan, GBFS + h_FF, side by side.

Runs both planners in this process on the same PDDL files: seeded blocksworld problems with
6 to 20 blocks and the teaching problems pyperplan can read (STRIPS + typing). Parsing is timed
apart; "ground" and "search" are the planners' own phases. Prints a table, then one JSON line.

    python benchmarks/bench_classical.py [--sizes 6 8 12] [--time-limit 60]
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import re
import signal
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _blocksworld import blocksworld_problem

from sdar_tamp.language import parse_domain, parse_problem
from solvers.classical import plan, task_from_problem

DOMAINS = Path(__file__).resolve().parents[1] / "domains"
TEACHING = [
    ("blocksworld", "sussman"),
    ("blocksworld", "reverse4"),
    ("logistics", "two-cities"),
    ("logistics", "three-cities"),
]


class _Expansions(logging.Handler):
    """Reads pyperplan's "<n> Nodes expanded" log line."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.count: int | None = None

    def emit(self, record: logging.LogRecord) -> None:
        match = re.match(r"(\d+) Nodes expanded", record.getMessage())
        if match:
            self.count = int(match.group(1))


@contextmanager
def _alarm(seconds: float) -> Iterator[None]:
    def expire(signum: int, frame: object) -> None:
        raise TimeoutError

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def run_ours(
    domain_file: Path, problem_file: Path, time_limit: float, lazy: bool = False
) -> dict[str, Any]:
    start = time.perf_counter()
    domain = parse_domain(domain_file.read_text(), str(domain_file))
    problem = parse_problem(problem_file.read_text(), domain, str(problem_file))
    parse_time = time.perf_counter() - start
    result = plan(
        task_from_problem(domain, problem),
        search="gbfs",
        heuristic="ff",
        lazy=lazy,
        time_limit=time_limit,
    )
    stats = result.statistics
    return {
        "status": result.status.value,
        "parse": parse_time,
        "ground": stats.grounding_time,
        "search": stats.search_time,
        "length": len(result.plan) if result.plan is not None else None,
        "expanded": stats.expanded,
    }


def run_pyperplan(domain_file: Path, problem_file: Path, time_limit: float) -> dict[str, Any]:
    from pyperplan import grounding
    from pyperplan.heuristics.relaxation import hFFHeuristic
    from pyperplan.pddl.parser import Parser
    from pyperplan.search import greedy_best_first_search

    handler = _Expansions()
    logger = logging.getLogger()
    logger.addHandler(handler)
    level = logger.level
    logger.setLevel(logging.INFO)
    result: dict[str, Any] = {
        "status": "timeout",
        "parse": None,
        "ground": None,
        "search": None,
        "length": None,
        "expanded": None,
    }
    try:
        with _alarm(time_limit):
            start = time.perf_counter()
            parser = Parser(str(domain_file), str(problem_file))
            problem = parser.parse_problem(parser.parse_domain())
            parsed = time.perf_counter()
            task = grounding.ground(problem)
            grounded = time.perf_counter()
            solution = greedy_best_first_search(task, hFFHeuristic(task))
            searched = time.perf_counter()
        result.update(
            status="solved" if solution is not None else "unsolvable",
            parse=parsed - start,
            ground=grounded - parsed,
            search=searched - grounded,
            length=len(solution) if solution is not None else None,
            expanded=handler.count,
        )
    except TimeoutError:
        pass
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)
    return result


def _geomean(values: list[float]) -> float:
    return math.exp(sum(math.log(v) for v in values) / len(values)) if values else math.nan


def _cell(value: Any) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return "nan" if math.isnan(value) else f"{value:.3f}"
    return str(value)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="*", default=[6, 8, 10, 12, 14, 16, 18, 20])
    parser.add_argument("--seed", type=int, default=0, help="added to the size to seed a problem")
    parser.add_argument(
        "--time-limit", type=float, default=120.0, help="per planner and problem [s]"
    )
    args = parser.parse_args(argv)

    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as tmp:
        cases: list[tuple[str, Path, Path]] = []
        bw_domain = DOMAINS / "blocksworld" / "domain.pddl"
        for size in args.sizes:
            path = Path(tmp) / f"bw-{size}.pddl"
            path.write_text(blocksworld_problem(size, seed=size + args.seed))
            cases.append((f"blocksworld-{size}", bw_domain, path))
        for domain, problem in TEACHING:
            folder = DOMAINS / domain
            cases.append(
                (
                    f"{domain}/{problem}",
                    folder / "domain.pddl",
                    folder / "problems" / f"{problem}.pddl",
                )
            )
        for name, domain_file, problem_file in cases:
            ours = run_ours(domain_file, problem_file, args.time_limit)
            lazy = run_ours(domain_file, problem_file, args.time_limit, lazy=True)
            theirs = run_pyperplan(domain_file, problem_file, args.time_limit)
            ours_total = ours["ground"] + ours["search"]
            if theirs["status"] == "timeout":  # the speedup is then a lower bound
                theirs_total = args.time_limit
            else:
                theirs_total = theirs["ground"] + theirs["search"]
            rows.append(
                {
                    "problem": name,
                    "ours": ours,
                    "ours_lazy": lazy,
                    "pyperplan": theirs,
                    "speedup": theirs_total / ours_total if ours_total > 0 else math.inf,
                }
            )

    header = (
        f"{'problem':<24} | {'ours: ground':>12} {'search':>7} {'len':>4} {'exp':>5} | "
        f"{'lazy: total':>11} {'len':>4} | "
        f"{'pyperplan: ground':>17} {'search':>7} {'len':>4} {'exp':>6} | {'speedup':>7}"
    )
    print(header)
    print("-" * len(header))
    for row in rows:
        o, z, p = row["ours"], row["ours_lazy"], row["pyperplan"]
        print(
            f"{row['problem']:<24} | {_cell(o['ground']):>12} {_cell(o['search']):>7} "
            f"{_cell(o['length']):>4} {_cell(o['expanded']):>5} | "
            f"{_cell(z['ground'] + z['search']):>11} {_cell(z['length']):>4} | "
            f"{_cell(p['ground']):>17} {_cell(p['search']):>7} {_cell(p['length']):>4} "
            f"{_cell(p['expanded']):>6} | "
            f"{'>' if p['status'] == 'timeout' else ' '}{row['speedup']:>6.1f}x"
        )
    print(
        "speedup = pyperplan (ground + search) / ours (ground + search), both GBFS + h_FF; "
        "ours: eager with preferred operators (the default); lazy: same with lazy=True; "
        f"'>': pyperplan hit the {args.time_limit:g} s limit"
    )

    speedups = [row["speedup"] for row in rows]
    both = [r for r in rows if r["ours"]["length"] is not None and r["pyperplan"]["length"]]
    bw12 = next((r for r in rows if r["problem"] == "blocksworld-12"), None)
    summary = {
        "benchmark": "classical_gbfs_ff",
        "problems": len(rows),
        "solved_ours": sum(r["ours"]["status"] == "solved" for r in rows),
        "solved_pyperplan": sum(r["pyperplan"]["status"] == "solved" for r in rows),
        "pyperplan_time_limit_s": args.time_limit,
        "speedup_geomean": _geomean(speedups),
        "speedup_min": min(speedups),
        "plans_equal_or_shorter": sum(
            r["ours"]["length"] <= r["pyperplan"]["length"] for r in both
        ),
        "plans_compared": len(both),
        "plan_length_total_ours": sum(r["ours"]["length"] for r in both),
        "plan_length_total_pyperplan": sum(r["pyperplan"]["length"] for r in both),
        "speedup_geomean_blocksworld": _geomean(
            [r["speedup"] for r in rows if r["problem"].startswith("blocksworld-")]
        ),
        "lazy_seconds_total": sum(
            r["ours_lazy"]["ground"] + r["ours_lazy"]["search"] for r in rows
        ),
        "ours_seconds_total": sum(r["ours"]["ground"] + r["ours"]["search"] for r in rows),
        "blocksworld12_ours_seconds": (
            bw12["ours"]["ground"] + bw12["ours"]["search"] if bw12 else None
        ),
        "rows": [
            {
                "problem": r["problem"],
                "ours": {
                    k: r["ours"][k] for k in ("status", "ground", "search", "length", "expanded")
                },
                "pyperplan": {
                    k: r["pyperplan"][k]
                    for k in ("status", "ground", "search", "length", "expanded")
                },
                "speedup": r["speedup"],
            }
            for r in rows
        ],
    }
    print(json.dumps(summary))
    return summary


if __name__ == "__main__":
    main()
