"""Benchmark: what a user waits for, ``sdar solve`` on one instance, process start to exit.

Each run is a fresh ``sdar solve --json`` process (interpreter start, imports, set-up,
planning, the asynchronous schedule, the independent replay, writing the plan), timed from
outside: wall time and the CPU time of the process. Single runs on a shared machine vary by
half again, so the figures are medians over ``--runs`` runs, and ``--against DIR`` times
another checkout of the package in alternation with this one (run k of each one after the
other), the only fair comparison of two versions on a noisy machine.

    python benchmarks/bench_solve.py [--instance suites/paper/M1.yaml] [--runs 5]
                                     [--against /path/to/other/checkout]
    python benchmarks/bench_solve.py --quick    # one run on R4: seconds

Prints one row per run, the medians, then one JSON object on the last line.

``--quick`` changes only the defaults: one run (``--runs 1``) on the 4-object
``suites/paper/R4.yaml``; the JSON keys are the same, plus ``"quick": true``.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from sdar_tamp.resources import domain_file

ROOT = Path(__file__).resolve().parent.parent


def solve_once(instance: Path, code: Path | None, out: Path) -> dict[str, Any]:
    """One ``sdar solve --json`` process (``code``: the checkout to import the package from,
    None for this environment's): wall and CPU time [s] and the summary's figures."""
    env = dict(os.environ)
    if code is not None:
        env["PYTHONPATH"] = os.pathsep.join([str(code), env.get("PYTHONPATH", "")]).rstrip(
            os.pathsep
        )
    command = [sys.executable, "-m", "sdar_tamp.cli", "solve", str(instance), "--json",
               "--force", "-o", str(out)]  # fmt: skip
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"sdar solve failed ({done.returncode}): {done.stderr.strip()[-400:]}")
    summary = json.loads(done.stdout.strip().splitlines()[-1])
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    figures = summary["figures"]
    return {
        "wall_s": wall,
        "cpu_s": cpu,
        "planning_s": figures["planning_time"],
        "schedule_s": figures["schedule_time"],
        "execution_s": summary["metrics"]["execution_time"],
        "valid": summary["valid"],
    }


def medians(runs: list[dict[str, Any]]) -> dict[str, Any]:
    keys = ("wall_s", "cpu_s", "planning_s", "schedule_s")
    out: dict[str, Any] = {k: round(statistics.median(r[k] for r in runs), 3) for k in keys}
    out["wall_range_s"] = [round(min(r["wall_s"] for r in runs), 3),
                           round(max(r["wall_s"] for r in runs), 3)]  # fmt: skip
    out["execution_s"] = sorted({round(r["execution_s"], 4) for r in runs})
    out["all_valid"] = all(r["valid"] for r in runs)
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default = domain_file("dual_arm_rearrangement", "suites/paper/M1.yaml")
    ap.add_argument("--instance", type=Path, default=default)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--against", type=Path, default=None, help="another checkout to compare")
    ap.add_argument("--quick", action="store_true", help="one run on a small instance (R4)")
    args = ap.parse_args(argv)
    if args.quick:  # explicit options still win
        small = domain_file("dual_arm_rearrangement", "suites/paper/R4.yaml")
        ap.set_defaults(runs=1, instance=small)
        args = ap.parse_args(argv)
    if args.runs < 1:
        ap.error(f"--runs: expected a number of runs >= 1, got {args.runs}")
    cli = None if args.against is None else args.against / "sdar_tamp" / "cli"
    if cli is not None and not (
        cli.with_suffix(".py").is_file() or (cli / "__init__.py").is_file()
    ):
        ap.error(f"--against: {args.against} is not a checkout of sdar-tamp (no sdar_tamp/cli)")
    versions: dict[str, Path | None] = {"this": ROOT}
    if args.against is not None:
        versions["against"] = args.against.resolve()
    runs: dict[str, list[dict[str, Any]]] = {name: [] for name in versions}
    with tempfile.TemporaryDirectory(prefix="sdar-bench-solve-") as tmp:
        for k in range(args.runs):
            for name, code in versions.items():
                r = solve_once(args.instance, code, Path(tmp) / f"{name}.json")
                runs[name].append(r)
                print(f"run {k + 1} {name:>7}: wall {r['wall_s']:.2f} s, cpu {r['cpu_s']:.2f} s, "
                      f"planning {r['planning_s']:.2f} s, schedule {r['schedule_s']:.2f} s, "
                      f"execution {r['execution_s']:.2f} s")  # fmt: skip
    result: dict[str, Any] = {"benchmark": "bench_solve", "instance": args.instance.stem,
                              "runs": args.runs}  # fmt: skip
    for name in versions:
        result[name] = medians(runs[name])
        m = result[name]
        print(f"{name:>7}: median wall {m['wall_s']:.2f} s (range {m['wall_range_s'][0]:.2f}-"
              f"{m['wall_range_s'][1]:.2f}), cpu {m['cpu_s']:.2f} s, planning "
              f"{m['planning_s']:.2f} s, schedule {m['schedule_s']:.2f} s")  # fmt: skip
    result["quick"] = args.quick
    print(json.dumps(result))


if __name__ == "__main__":
    main()
