"""The continuous_tamp rows of ``bench_streams.py``: PDDLStream's own continuous_tamp example
(its ``tight`` problem, two blocks), unmodified, through the alias, one process a run
(``bench_pddlstream_compat.py`` runs it, seeding Python's and NumPy's generators)."""

from __future__ import annotations

import importlib.util
import resource
import sys
from pathlib import Path
from typing import Any


def _compat_bench() -> Any:
    """``bench_pddlstream_compat.py`` beside this file (the runner of PDDLStream's examples)."""
    path = Path(__file__).with_name("bench_pddlstream_compat.py")
    spec = importlib.util.spec_from_file_location("bench_pddlstream_compat", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # (its dataclasses look their module up)
    spec.loader.exec_module(module)
    return module


#: [s] a continuous_tamp run's process is stopped after this (the example's own limit is 30 s)
TAMP_TIMEOUT = 60.0


def _children_cpu() -> float:
    """CPU time [s] of this process's finished child processes (user + system)."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def tamp_rows(
    checkout: Path, algorithms: list[str], seeds: int, seconds: float
) -> list[dict[str, Any]]:
    """PDDLStream's continuous_tamp through the alias: per algorithm, the seeds solved within
    ``seconds`` of solve time (its plans re-checked by the runner)."""
    bench = _compat_bench()
    rows = []
    for algorithm in algorithms:
        example = bench.Example(
            "continuous_tamp", "examples.continuous_tamp.run", args=("-a", algorithm)
        )
        runs = []
        for seed in range(seeds):
            before = _children_cpu()
            run = bench.run_example(checkout, example, TAMP_TIMEOUT, seed=seed)
            runs.append({**run, "cpu": round(_children_cpu() - before, 3)})
        times = sorted(float(r["solve_seconds"]) for r in runs)
        cpus = sorted(float(r["cpu"]) for r in runs)
        solve_cpus = sorted(float(r.get("solve_cpu", 0.0)) for r in runs)
        rows.append(
            {
                "variant": "continuous_tamp (alias)",
                "algorithm": algorithm,
                "expected": "solved",
                "seeds": seeds,
                "met": sum(bool(r["passed"]) and r["solve_seconds"] <= seconds for r in runs),
                "statuses": [str(r["result"]) for r in runs],
                "median_time": times[len(times) // 2],
                "max_time": times[-1],
                # the whole process's (start-up and the example's own drawing included)
                "median_cpu": cpus[len(cpus) // 2],
                "max_cpu": cpus[-1],
                "rounds_per_s": None,
                "solve_seconds": [r["solve_seconds"] for r in runs],
                "cpus": [r["cpu"] for r in runs],  # per seed, the example's process
                # per seed, the CPU time of the solve calls alone (a loaded machine stretches
                # the wall time, hardly this)
                "solve_cpus": [r.get("solve_cpu", 0.0) for r in runs],
                "median_solve_cpu": solve_cpus[len(solve_cpus) // 2],
                "max_solve_cpu": solve_cpus[-1],
            }
        )
    return rows
