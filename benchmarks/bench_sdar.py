"""Benchmark: SDAR end to end on a suite of rearrangement instances.

Every instance is solved by ``sdar solve``'s code path (SDAR-T + SDAR-M, a time limit per
instance), and every plan is checked by the independent replay (``sdar validate``); a plan
that does not validate counts as a failure. Planning time per synchronous step is the paper's
figure: a step is one synchronous dual-arm motion; its time is the motion's planning time plus
an equal share of its task's selection time (IK, grasps, buffers, ranking). The motion
planner's one-off set-up (building the optimiser) is excluded and printed separately.

    python benchmarks/bench_sdar.py [--suite paper] [--max-objects 12] [--time-limit 60]
                                    [--task-planner sdar] [--motion-planner sdar] [--only M1,R4]
    python benchmarks/bench_sdar.py --quick    # R4 alone: seconds
    python benchmarks/bench_sdar.py --scene CELL.yaml [--folder SUITE_DIR]   # another cell

``--scene`` solves in that cell (a scene file, e.g. of ``sdar cells``) instead of the
instances' own; ``--folder`` takes the instances of a folder (e.g. a suite generated for the
cell by ``sdar generate --suite paper --scene CELL.yaml``) instead of a shipped suite.

``--suite table_1arm`` ... ``table_4arm``: the ``families`` suite shipped for the cells of the
shared table (each instance names its cell). ``--bound-only`` solves nothing: it prints each
instance's lower bound (with ``--min-objects 24``, say).

Every row shows the execution time against its lower bound
(:mod:`sdar_tamp.world.execution_bound`: ``bound`` [s] and ``x``, execution over bound); the
JSON holds their medians (``execution_time_median``, ``bound_median``,
``execution_over_bound_median``) and per instance (``per_instance``).

Prints one row per instance, a summary, then one JSON object on the last line.

``--cpu-clock``: the time limit counts this process's CPU seconds (``time.process_time``, the
solver's budget clock ``SdarOptions.clock``) instead of wall-clock seconds, so that on a machine
shared with other jobs a run plans about as far as it would alone (the anytime finish starts when
the measured pace says; its wall-clock time is then longer). Figures taken so say so (the JSON's
``clock``).

``--quick`` changes only the defaults: ``--only R4`` (4 objects, in the ``paper`` suite)
with a 30 s time limit; the JSON keys are the same, plus ``"quick": true``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

from _suites import shipped_suite_files, suite_order

from sdar_tamp.app.cache import PlannerCache
from sdar_tamp.app.config import PlannerConfig
from sdar_tamp.app.pipeline import solve_instance
from sdar_tamp.app.records import SolveOutcome
from sdar_tamp.world.instance import load_instance
from sdar_tamp.world.suites import CELL_SUITES, SUITES
from solvers.sdar.options import SdarOptions


def _folder_files(folder: Path) -> list[Path]:
    """The instance files of ``folder``, by family then object count."""
    return sorted(Path(folder).glob("*.yaml"), key=suite_order)


#: ``--quick``'s defaults
QUICK = {"only": "R4", "time_limit": 30.0}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", default="paper", choices=(*SUITES, *CELL_SUITES))
    ap.add_argument("--max-objects", type=int, default=None)
    ap.add_argument("--min-objects", type=int, default=None)
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--task-planner", default="sdar", choices=("sdar", "baseline"))
    ap.add_argument("--motion-planner", default="sdar", choices=("sdar", "plain", "sequential"))
    ap.add_argument("--only", default="", help="comma-separated instance names")
    ap.add_argument("--scene", type=Path, default=None, help="a cell replacing the instances'")
    ap.add_argument("--folder", type=Path, default=None, help="instances of this folder instead")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument(
        "--compare-adaptive",
        action="store_true",
        help="instead: the generic adaptive algorithm against sdar on a one-object instance",
    )
    ap.add_argument(
        "--bound-only",
        action="store_true",
        help="instead: the execution-time bound of every instance, nothing solved",
    )
    ap.add_argument(
        "--cpu-clock",
        action="store_true",
        help="the time limit counts CPU seconds of this process, not wall-clock seconds",
    )
    ap.add_argument("--quick", action="store_true", help="one small instance (R4): seconds")
    args = ap.parse_args(argv)
    if args.quick:  # explicit options still win
        ap.set_defaults(**QUICK)
        args = ap.parse_args(argv)
    if args.compare_adaptive:
        compare_adaptive(args.time_limit, args.quick)
        return
    files = shipped_suite_files(args.suite) if args.folder is None else _folder_files(args.folder)
    files = [p for p in files if _wanted(p, args)]
    if args.bound_only:
        bounds_only(files, args)
        return

    cache = PlannerCache()
    config = PlannerConfig(sdar=SdarOptions(clock=time.process_time)) if args.cpu_clock else None
    rows = []
    step_times: list[float] = []
    step_selection: list[float] = []
    step_motion: list[float] = []
    start = time.perf_counter()
    print(f"{'instance':>9} {'n':>3} {'ok':>3} {'actions':>7} {'steps':>5} {'exec s':>7} "
          f"{'bound s':>7} {'x':>5} {'plan s':>7} {'step med':>8} {'levels'}")  # fmt: skip
    for path in files:
        outcome = solve_instance(
            path,
            config,
            time_limit=args.time_limit,
            seed=args.seed,
            task_planner=args.task_planner,
            motion_planner=args.motion_planner,
            cache=cache,
            scene=args.scene,
        )
        n = len(outcome.instance.objects)
        f = outcome.figures
        row = {
            "instance": outcome.instance.name,
            "objects": n,
            "status": outcome.status,
            "valid": outcome.valid,
            "success": outcome.success,
            "planning_time": f.planning_time,
            "selection_time": f.selection_time,
            "motion_time": f.motion_time,
            "bound": None if outcome.bound is None else outcome.bound.seconds,
            "execution_over_bound": outcome.execution_over_bound,
            "reason": None if outcome.success else failure_reason(outcome),
        }
        if outcome.plan is not None:
            m = outcome.plan.metrics
            row.update(
                actions=m.actions,
                steps=m.steps,
                dual_arm_steps=m.dual_arm_steps,
                execution_time=m.execution_time,
                step_time_median=f.step_time_median,
                levels=dict(f.levels),
                buffer_moves=f.buffer_moves,
            )
        rows.append(row)
        print(
            f"{row['instance']:>9} {n:>3} {'yes' if row['success'] else 'NO':>3} "
            f"{row.get('actions', '-'):>7} {row.get('steps', '-'):>5} "
            f"{float(row.get('execution_time', 0.0)):>7.1f} {_num(row['bound'], 7, 1)} "
            f"{_num(row['execution_over_bound'], 5, 2)} {row['planning_time']:>7.2f} "
            f"{float(row.get('step_time_median', 0.0)):>8.3f} {row.get('levels', '')}"
            + ("" if row["success"] else f"  {row['reason']}"),
            flush=True,
        )
        for record in _steps(outcome):
            step_selection.append(record[0])
            step_motion.append(record[1])
            step_times.append(record[0] + record[1])
    solved = [r for r in rows if r["success"]]
    # the paper's "per step" figure: an instance's whole planning time over its steps
    per_instance = [float(r["planning_time"]) / int(r["steps"]) for r in solved if r["steps"]]
    executions = [float(r["execution_time"]) for r in solved]
    bounds = [float(r["bound"]) for r in rows if r["bound"] is not None]
    ratios = [float(r["execution_over_bound"]) for r in solved if r["execution_over_bound"]]
    summary = {
        "benchmark": "sdar",
        "suite": args.suite if args.folder is None else str(args.folder),
        "scene": None if args.scene is None else str(args.scene),
        "task_planner": args.task_planner,
        "motion_planner": args.motion_planner,
        "time_limit": args.time_limit,
        "clock": "cpu" if args.cpu_clock else "wall",
        "instances": len(rows),
        "success": len(solved),
        "success_rate": len(solved) / len(rows) if rows else 0.0,
        "steps": len(step_times),
        "step_time_median": statistics.median(step_times) if step_times else None,
        "step_time_p90": _quantile(step_times, 0.9),
        "step_selection_median": statistics.median(step_selection) if step_selection else None,
        "step_motion_median": statistics.median(step_motion) if step_motion else None,
        "instance_step_time_median": statistics.median(per_instance) if per_instance else None,
        "execution_time_median": statistics.median(executions) if executions else None,
        "bound_median": statistics.median(bounds) if bounds else None,
        "execution_over_bound_median": statistics.median(ratios) if ratios else None,
        "execution_over_bound_min": min(ratios) if ratios else None,
        "per_instance": {
            r["instance"]: {
                "execution_time": r.get("execution_time"),
                "bound": r["bound"],
                "execution_over_bound": r["execution_over_bound"],
            }
            for r in rows
        },
        "planning_time_total": sum(r["planning_time"] for r in rows),
        "wall_time": time.perf_counter() - start,
        "failures": [r["instance"] for r in rows if not r["success"]],
        "failure_reasons": {r["instance"]: r["reason"] for r in rows if not r["success"]},
        "quick": args.quick,
    }
    print(
        f"success {summary['success']}/{summary['instances']}; step planning time median "
        f"{_fmt(summary['step_time_median'])} s (selection {_fmt(summary['step_selection_median'])}"
        f" s, motion {_fmt(summary['step_motion_median'])} s), p90 "
        f"{_fmt(summary['step_time_p90'])} s over {summary['steps']} steps; planning time over "
        f"steps per instance, median {_fmt(summary['instance_step_time_median'])} s; execution "
        f"time median {_fmt(summary['execution_time_median'])} s, execution over bound median "
        f"{_fmt(summary['execution_over_bound_median'])}"
    )
    print(json.dumps(summary))


def failure_reason(outcome: SolveOutcome) -> str:
    """Why an instance counts as a failure: the solver's status and diagnosis when it returned
    no plan (e.g. ``timeout: max_time reached with 3 object(s) left``), else the replay's
    violation."""
    if outcome.plan is None:
        why = "; ".join(outcome.diagnosis) or outcome.violation
        return f"{outcome.status}: {why}"
    return f"invalid: {outcome.violation}"


def _wanted(path: Path, args: argparse.Namespace) -> bool:
    """Whether ``--only``, ``--max-objects`` and ``--min-objects`` keep the instance file."""
    wanted = {s for s in args.only.split(",") if s}
    if wanted and path.stem not in wanted:
        return False
    n = len(load_instance(path).objects)
    too_many = args.max_objects is not None and n > args.max_objects
    return not too_many and (args.min_objects is None or n >= args.min_objects)


def bounds_only(files: list[Path], args: argparse.Namespace) -> None:
    """The lower bound of every instance in its cell (or ``--scene``), nothing solved: one
    row per instance, then the medians as one JSON object."""
    from sdar_tamp.app.bound import instance_bound
    from sdar_tamp.world.scene import load_scene

    start = time.perf_counter()
    rows = {}
    print(f"{'instance':>9} {'n':>3} {'arms':>4} {'bound s':>7} {'sum/k s':>7} {'max c s':>7}")
    for path in files:
        instance = load_instance(path)
        scene = load_scene(args.scene or instance.scene_path(path))
        b = instance_bound(scene, instance)
        rows[instance.name] = {
            "bound": b.seconds, "sum_over_arms": b.total / b.arms, "longest_object": b.longest,
            "arms": b.arms, "relays": sum(o.relay for o in b.objects),
        }  # fmt: skip
        print(
            f"{instance.name:>9} {len(instance.objects):>3} {b.arms:>4} {b.seconds:>7.2f} "
            f"{b.total / b.arms:>7.2f} {b.longest:>7.2f}",
            flush=True,
        )
    values = [r["bound"] for r in rows.values()]
    summary = {
        "benchmark": "sdar-bound",
        "suite": args.suite if args.folder is None else str(args.folder),
        "scene": None if args.scene is None else str(args.scene),
        "instances": len(rows),
        "bound_median": statistics.median(values) if values else None,
        "per_instance": rows,
        "wall_time": time.perf_counter() - start,
        "quick": args.quick,
    }
    print(json.dumps(summary))


def compare_adaptive(time_limit: float, quick: bool = False) -> None:
    """The same PDDL domain solved by the generic ``adaptive`` algorithm and by ``sdar``."""
    from sdar_tamp.app.problem import rearrangement_problem
    from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D
    from sdar_tamp.world.scene import Workspace
    from solvers.solve import solve
    from streams.context import WorldContext
    from streams.motion.planner import MotionPlanner

    ctx = WorldContext.load()
    planner = MotionPlanner(ctx)
    size = (0.08, 0.04, 0.05)
    one = Instance(
        "one",
        Workspace((-0.25, 0.25), (-0.30, 0.30)),
        (ObjectSpec("a", size, Pose2D(-0.1, 0.15, 0.0), Pose2D(-0.1, -0.15, 0.3)),),
    )
    results = {}
    for algorithm in ("sdar", "adaptive"):
        problem = rearrangement_problem(one, ctx, planner=planner).problem
        start = time.perf_counter()
        solution = solve(problem, algorithm=algorithm, max_time=time_limit, verbose=False)
        elapsed = time.perf_counter() - start
        actions = [a.name for a in solution.plan or []]
        results[algorithm] = {"status": solution.status.value, "time": elapsed, "plan": actions}
        print(f"{algorithm:>9}: {solution.status.value} in {elapsed:.2f} s, plan {actions}")
    print(json.dumps({"benchmark": "sdar-vs-adaptive", "objects": 1, **results, "quick": quick}))


def _steps(outcome: SolveOutcome) -> list[tuple[float, float]]:
    return [(step.selection, step.motion) for step in outcome.figures.step_times]


def _quantile(values: list[float], q: float) -> float | None:
    if not values:
        return None
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


def _num(value: float | None, width: int, digits: int) -> str:
    return f"{'-':>{width}}" if value is None else f"{value:>{width}.{digits}f}"


def _fmt(value: object) -> str:
    return "-" if value is None else f"{float(str(value)):.3f}"


if __name__ == "__main__":
    main()
