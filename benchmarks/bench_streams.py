"""Benchmark: the four stream planning algorithms on the teaching TAMP domains.

For every domain (pick_place_2d, kitchen, dual_arm_swap, infeasible) and every algorithm
(incremental, focused, binding, adaptive): status, wall time [s], stream calls, plan cost and
length. Each run builds a fresh problem from the same seed. Then, per algorithm, how far a run
overshoots ``max_time`` on a problem that never ends by itself (an infinite sampler whose values
a test always rejects): ``overrun`` = wall time / max_time - 1. Prints a table, then one JSON line.

With ``--call-modes threaded inline`` every run is made once per way of calling user code
(``solve(enforce_max_time=True/False)``), side by side, plus a micro-benchmark of one call's
cost in each mode; ``cpu`` is the process time [s] of a run (all threads).

    python benchmarks/bench_streams.py [--max-time 30] [--seed 0] [--domains kitchen ...]
        [--limit-probe 1.5]                       # the full run
    python benchmarks/bench_streams.py --quick    # seconds

Then the 2-D kitchen (``domains/kitchen_2d``: two cups from a counter to a shelf, in
PDDLStream's idiom) in its variants: a 1.0 m shelf (feasible) or a 0.5 m one (infeasible), a
finite grid pose sampler or an endless random one, with or without ``StreamInfo(negate=True)``
on the collision test; every algorithm on ``--kitchen-seeds`` seeds each, a run limited to
``--kitchen-max-time``. A feasible row is met when every seed is solved within
``FEASIBLE_SECONDS``; an infeasible one (finite samplers only: an endless sampler can prove
nothing) when every seed ends ``infeasible`` within ``INFEASIBLE_SECONDS`` with the failing
collision test named in the diagnosis. ``--kitchen-seeds 0`` skips these rows. Each row also
gives the median and largest CPU time of its runs (``median_cpu``, ``max_cpu``: what a loaded
machine does not inflate; for continuous_tamp, the whole example process's).

Then PDDLStream's own continuous_tamp (its ``tight`` problem, two blocks), unmodified, through
the alias (``benchmarks/bench_pddlstream_compat.py`` runs it, one process a run, seeding Python's
and NumPy's generators): every algorithm (``-a``) on ``--tamp-seeds`` seeds; a row is met when
every seed finds a plan that passes the re-check within ``FEASIBLE_SECONDS`` of solve time (the
example wraps its solve in its own profiler, as in PDDLStream). It needs a PDDLStream checkout
(``--pddlstream PATH`` or ``$PDDLSTREAM_PATH``; without one the rows are skipped and the JSON
says why); ``--tamp-seeds 0`` skips them. Their rows also give the CPU time of the solve calls
alone, per seed (``solve_cpus``, ``median_solve_cpu``, ``max_solve_cpu``).

``--quick`` changes only the defaults: every algorithm on kitchen, dual_arm_swap and infeasible
(pick_place_2d, the slow one, left out), the 2-D kitchen on 2 seeds (3 s a run),
continuous_tamp on 1 seed, a 0.2 s
overrun probe and 2,000 calls for the call overhead; the JSON keys are the same, plus
``"quick": true``.
"""

from __future__ import annotations

import argparse
import importlib
import itertools
import json
import logging
import math
import os
import time
from pathlib import Path
from typing import Any

from _tamp_rows import tamp_rows

from domains.kitchen_2d import samplers as kitchen_2d
from sdar_tamp.language.generators import from_sampler, from_test
from sdar_tamp.language.problem import PDDLProblem
from solvers.solve import solve
from solvers.stream_planning.calls import CallRunner
from solvers.stream_planning.policies import ALGORITHMS

DOMAINS = ("pick_place_2d", "kitchen", "dual_arm_swap", "infeasible")
EXPECTED = {"infeasible": "infeasible"}  # every other domain: solved


MODES = {"threaded": True, "inline": False}
#: ``--quick``'s defaults
QUICK = {
    "domains": ["kitchen", "dual_arm_swap", "infeasible"],
    "limit_probe": 0.2,
    "overhead_calls": 2_000,
    "kitchen_seeds": 2,
    "kitchen_max_time": 3.0,
    "tamp_seeds": 1,
}
#: The 2-D kitchen's variants: name -> (shelf width [m], pose sampler, negate the test)
KITCHEN_VARIANTS: dict[str, tuple[float, str, bool]] = {
    "feasible-grid": (1.0, "grid", False),
    "feasible-grid-negate": (1.0, "grid", True),
    "feasible-random": (1.0, "random", False),
    "feasible-random-negate": (1.0, "random", True),
    "infeasible-grid": (0.5, "grid", False),
    "infeasible-grid-negate": (0.5, "grid", True),
}
FEASIBLE_SECONDS = 2.0  # [s] a feasible kitchen variant is solved within this, every seed
INFEASIBLE_SECONDS = 5.0  # [s] an infeasible one is proved so within this, every seed


def run(
    domain: str, algorithm: str, max_time: float, seed: int, mode: str = "threaded"
) -> dict[str, Any]:
    make_problem = importlib.import_module(f"domains.{domain}.samplers").make_problem
    problem = make_problem(seed=seed)
    start = time.perf_counter()
    cpu = time.process_time()
    solution = solve(
        problem,
        algorithm=algorithm,
        max_time=max_time,
        seed=seed,
        verbose=False,
        enforce_max_time=MODES[mode],
    )
    elapsed = time.perf_counter() - start
    return {
        "domain": domain,
        "algorithm": algorithm,
        "calls_mode": mode,
        "cpu": round(time.process_time() - cpu, 3),
        "status": solution.status.value,
        "expected": EXPECTED.get(domain, "solved"),
        "time": round(elapsed, 3),
        "stream_calls": sum(s.calls for s in solution.streams.values()),
        "cost": round(solution.cost, 6) if math.isfinite(solution.cost) else None,
        "length": len(solution.plan) if solution.plan is not None else None,
        "iterations": int(solution.statistics.get("iterations", 0)),
    }


def kitchen_run(variant: str, algorithm: str, seed: int, max_time: float) -> dict[str, Any]:
    """One solve of a 2-D kitchen variant."""
    width, sampler, negate = KITCHEN_VARIANTS[variant]
    problem = kitchen_2d.make_problem(width, sampler, seed)
    start = time.perf_counter()
    cpu = time.process_time()
    solution = solve(
        problem,
        algorithm=algorithm,
        stream_info=kitchen_2d.stream_info(negate),
        max_time=max_time,
        seed=seed,
        verbose=False,
    )
    elapsed = time.perf_counter() - start
    iterations = int(solution.statistics.get("iterations", 0))
    return {
        "status": solution.status.value,
        "time": round(elapsed, 3),
        "cpu": round(time.process_time() - cpu, 3),
        "iterations": iterations,
        "rounds_per_s": round(iterations / elapsed, 1) if elapsed > 0 else None,
        "stream_calls": sum(s.calls for s in solution.streams.values()),
        "names_test": any("test-cfree" in reason for reason in solution.diagnosis),
    }


def kitchen_rows(algorithms: list[str], seeds: int, max_time: float) -> list[dict[str, Any]]:
    """Per variant and algorithm: how many seeds ended as expected, and the times."""
    rows = []
    for variant, (width, _, _) in KITCHEN_VARIANTS.items():
        feasible = width >= 2 * kitchen_2d.CUP
        for algorithm in algorithms:
            runs = [kitchen_run(variant, algorithm, seed, max_time) for seed in range(seeds)]
            if feasible:
                met = [r["status"] == "solved" and r["time"] <= FEASIBLE_SECONDS for r in runs]
            else:
                met = [
                    r["status"] == "infeasible"
                    and r["time"] <= INFEASIBLE_SECONDS
                    and r["names_test"]
                    for r in runs
                ]
            times = sorted(r["time"] for r in runs)
            cpus = sorted(r["cpu"] for r in runs)
            rates = [r["rounds_per_s"] for r in runs if r["rounds_per_s"] is not None]
            rows.append(
                {
                    "variant": variant,
                    "algorithm": algorithm,
                    "expected": "solved" if feasible else "infeasible",
                    "seeds": seeds,
                    "met": sum(met),
                    "statuses": [r["status"] for r in runs],
                    "median_time": times[len(times) // 2],
                    "max_time": times[-1],
                    "median_cpu": cpus[len(cpus) // 2],
                    "max_cpu": cpus[-1],
                    "rounds_per_s": round(sum(rates) / len(rates), 1) if rates else None,
                    "stream_calls": [r["stream_calls"] for r in runs],
                    # per seed, in seed order: wall and CPU time [s]
                    "times": [r["time"] for r in runs],
                    "cpus": [r["cpu"] for r in runs],
                }
            )
    return rows


def kitchen_table(rows: list[dict[str, Any]]) -> str:
    header = (
        f"{'kitchen_2d variant':<24} {'algorithm':<12} {'expected':<10} {'met':>5} "
        f"{'median[s]':>9} {'max[s]':>7} {'cpu med':>7} {'rounds/s':>8}"
    )
    lines = [header, "-" * len(header)]
    for row in rows:
        rate = f"{row['rounds_per_s']:.1f}" if row["rounds_per_s"] is not None else "-"
        lines.append(
            f"{row['variant']:<24} {row['algorithm']:<12} {row['expected']:<10} "
            f"{row['met']:>2}/{row['seeds']:<2} {row['median_time']:>9.3f} "
            f"{row['max_time']:>7.3f} {row['median_cpu']:>7.3f} {rate:>8}"
        )
    return "\n".join(lines)


_ENDLESS_DOMAIN = """(define (domain endless) (:requirements :strips)
  (:predicates (block ?b) (pose ?b ?p) (ok ?b ?p) (placed ?b))
  (:action place :parameters (?b ?p) :precondition (and (pose ?b ?p) (ok ?b ?p))
     :effect (placed ?b)))"""
_ENDLESS_STREAMS = """(define (stream endless)
  (:stream sample-pose :inputs (?b) :domain (block ?b) :outputs (?p) :certified (pose ?b ?p))
  (:stream test-ok :inputs (?b ?p) :domain (pose ?b ?p) :certified (ok ?b ?p)))"""


def limit_overrun(algorithm: str, max_time: float) -> dict[str, Any]:
    """Solve a problem with an endless sampler and a test that always fails; time the run."""
    values = itertools.count()
    problem = PDDLProblem(
        _ENDLESS_DOMAIN,
        {},
        _ENDLESS_STREAMS,
        {
            "sample-pose": from_sampler(lambda b: (float(next(values)),)),
            "test-ok": from_test(lambda b, p: False),
        },
        init=[("block", "a")],
        goal=("placed", "a"),
    )
    start = time.perf_counter()
    solution = solve(problem, algorithm=algorithm, max_time=max_time, verbose=False)
    elapsed = time.perf_counter() - start
    return {
        "algorithm": algorithm,
        "status": solution.status.value,
        "max_time": max_time,
        "time": round(elapsed, 3),
        "overrun": round(elapsed / max_time - 1.0, 4),
    }


def call_overhead(mode: str, calls: int = 20_000) -> float:
    """[us] the cost of one trivial user call through a :class:`CallRunner` in ``mode``."""
    runner = CallRunner(time.perf_counter() + 3600, threaded=MODES[mode])
    start = time.perf_counter()
    for _ in range(calls):
        runner.call(int, str)
    elapsed = time.perf_counter() - start
    runner.close()
    return 1e6 * elapsed / calls


def table(rows: list[dict[str, Any]]) -> str:
    header = (
        f"{'domain':<14} {'algorithm':<12} {'calls via':<9} {'status':<11} {'time[s]':>8} "
        f"{'cpu[s]':>7} {'calls':>7} {'cost':>8} {'length':>6}  ok"
    )
    lines = [header, "-" * len(header)]
    for row in rows:
        cost = f"{row['cost']:.3f}" if row["cost"] is not None else "-"
        length = str(row["length"]) if row["length"] is not None else "-"
        ok = "yes" if row["status"] == row["expected"] else "NO"
        lines.append(
            f"{row['domain']:<14} {row['algorithm']:<12} {row['calls_mode']:<9} "
            f"{row['status']:<11} {row['time']:>8.3f} {row['cpu']:>7.3f} "
            f"{row['stream_calls']:>7d} {cost:>8} {length:>6}  {ok}"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-time", type=float, default=30.0, help="[s] per run")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--domains", nargs="+", choices=DOMAINS, default=list(DOMAINS))
    parser.add_argument("--algorithms", nargs="+", choices=ALGORITHMS, default=list(ALGORITHMS))
    parser.add_argument(
        "--limit-probe", type=float, default=1.5, help="[s] max_time of the overrun probe; 0: skip"
    )
    parser.add_argument(
        "--call-modes",
        nargs="+",
        choices=tuple(MODES),
        default=["threaded"],
        help="ways of calling user code to run side by side (default: %(default)s)",
    )
    parser.add_argument(
        "--overhead-calls", type=int, default=20_000, help="calls timed for the call overhead"
    )
    parser.add_argument(
        "--kitchen-seeds", type=int, default=8, help="seeds per 2-D kitchen row; 0: skip them"
    )
    parser.add_argument(
        "--kitchen-max-time", type=float, default=10.0, help="[s] per 2-D kitchen run"
    )
    parser.add_argument(
        "--pddlstream",
        default=os.environ.get("PDDLSTREAM_PATH"),
        help="a PDDLStream checkout, for the continuous_tamp rows (default: $PDDLSTREAM_PATH)",
    )
    parser.add_argument(
        "--tamp-seeds", type=int, default=8, help="seeds per continuous_tamp row; 0: skip them"
    )
    parser.add_argument("--quick", action="store_true", help="the fast domains, short probes")
    args = parser.parse_args(argv)
    if args.quick:  # explicit options still win
        parser.set_defaults(**QUICK)
        args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    rows = [
        run(domain, algorithm, args.max_time, args.seed, mode)
        for domain in args.domains
        for algorithm in args.algorithms
        for mode in args.call_modes
    ]
    print(table(rows))
    kitchen = (
        kitchen_rows(args.algorithms, args.kitchen_seeds, args.kitchen_max_time)
        if args.kitchen_seeds > 0
        else []
    )
    if kitchen:
        print(kitchen_table(kitchen))
    tamp: list[dict[str, Any]] = []
    tamp_skipped = None
    if args.tamp_seeds > 0:
        checkout = Path(args.pddlstream) if args.pddlstream else None
        if checkout is None or not (checkout / "examples" / "continuous_tamp").is_dir():
            tamp_skipped = f"no PDDLStream checkout (--pddlstream or $PDDLSTREAM_PATH): {checkout}"
            print(f"continuous_tamp rows skipped: {tamp_skipped}")
        else:
            tamp = tamp_rows(checkout.resolve(), args.algorithms, args.tamp_seeds, FEASIBLE_SECONDS)
            print(kitchen_table(tamp))
            for row in tamp:  # per seed: solve time and its CPU time [s]
                pairs = zip(row["solve_seconds"], row["solve_cpus"], strict=True)
                print(
                    f"{row['algorithm']:<12} solve [s] / its CPU [s] per seed: "
                    + " ".join(f"{t:.2f}/{c:.2f}" for t, c in pairs)
                )
    probes = (
        [limit_overrun(algorithm, args.limit_probe) for algorithm in args.algorithms]
        if args.limit_probe > 0
        else []
    )
    for probe in probes:
        print(
            f"max_time {probe['max_time']:.2f} s, {probe['algorithm']:<12} {probe['status']:<9} "
            f"ran {probe['time']:.3f} s (overrun {probe['overrun']:+.1%})"
        )
    overhead = {
        mode: round(call_overhead(mode, args.overhead_calls), 2) for mode in args.call_modes
    }
    if len(args.call_modes) > 1:
        print("one trivial user call [us]: " + ", ".join(f"{m} {v}" for m, v in overhead.items()))
        for mode in args.call_modes:
            mine = [r for r in rows if r["calls_mode"] == mode]
            print(
                f"{mode}: total time {sum(r['time'] for r in mine):.3f} s, "
                f"cpu {sum(r['cpu'] for r in mine):.3f} s"
            )
    summary = {
        "benchmark": "stream_planning",
        "max_time": args.max_time,
        "seed": args.seed,
        "call_overhead_us": overhead,
        "all_expected": all(r["status"] == r["expected"] for r in rows),
        "runs": rows,
        "kitchen_2d": kitchen,
        "kitchen_2d_met": sum(r["met"] for r in kitchen),
        "kitchen_2d_runs": sum(r["seeds"] for r in kitchen),
        "continuous_tamp": tamp,
        "continuous_tamp_met": sum(r["met"] for r in tamp),
        "continuous_tamp_runs": sum(r["seeds"] for r in tamp),
        "continuous_tamp_skipped": tamp_skipped,
        "max_time_probes": probes,
        "max_time_overrun_max": max((p["overrun"] for p in probes), default=None),
        "quick": args.quick,
    }
    print(json.dumps(summary, separators=(",", ":")))
    return 0 if summary["all_expected"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
