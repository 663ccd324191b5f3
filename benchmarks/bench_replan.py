"""Benchmark: re-planning from perturbed observed states on the paper suite.

Every instance is solved by ``sdar solve``'s code path with synchronous execution (or its
plan is read from ``--plans DIR/<name>.json`` when it exists, written there after a solve
with ``--save``). Then, at seeded random times ``T`` of its plan, one resting object is
perturbed as a camera would see it: ``nudge`` (moved 1-3 cm in a random direction and turned
5-20 degrees), ``remove`` (gone) or ``add`` (a new object inside the workspace); a
perturbation the observation checks refuse (an overlap, an object in an arm, off the
workspace) is drawn again (``redrawn``). :func:`sdar_tamp.app.replanning.replan` re-plans
(repair first, a fresh SDAR continuation as fallback) and the whole spliced plan is validated
by the independent replay.

Counted apart (not solvable by any re-plan from ``T``): ``cannot_stop``, where the running
plan meets the observed world before its arms reach the next point at which they are at rest
with empty grippers (the cut), and braking on their way does not stop them short of it
either (a gripper acts first, the change is too close, or what an arm holds cannot be put
down).
``success_rate``: valid new plans (the plan finally kept) over the other perturbed
states (every ``infeasible`` or ``timeout`` there counts as a failure).

``--compare`` says when a repair that changed the plan is compared with a fresh continuation:
``moving`` (default) while the arms execute the repair
(:func:`sdar_tamp.app.replan_moving.replan_while_moving`: the repair is given first, each
shorter fresh continuation from a later start, a clear cut or a braked stop, replaces the plan
followed only when found before the arms get there), ``sync`` before ``replan`` returns
(``replan(..., compare=True)``, the measure of the releases before this option), ``none``
never. Latencies, wall time from the call (the observation) on, the final validation of each
plan excluded:
``latency_median_s`` until the first plan, when the arms can move on (with ``sync`` or
``none`` the only plan, as before); ``latency_final_median_s`` until the plan finally kept
(with ``moving``: the last fresh continuation's when one replaced the repair);
``latency_done_median_s`` (and ``latency_done_p90_s``) until the re-plan is over, the
comparison and the validations included (with ``sync``: ``latency``, the old definition, plus
the final validation). ``improved``: re-plans where a fresh continuation found while moving replaced
the repair. ``cpu_median_s``: the process's CPU time of the whole re-plan, the comparison
and validations included (on a loaded machine the wall time grows, the CPU time hardly).
``compared``: the re-plans whose plan kept was compared with another (``alternative``, the
other's execution, known; ``compared_fresh_kept``: those where the fresh one was shorter and
kept). For every nudge re-planned, a fresh
continuation from the same cut (``replan(..., repair=False)``) is planned too:
``nudge_execution_ratio`` is the new plan's execution from the cut over the fresh one's, and
``nudge_latency_median_s`` / ``nudge_fresh_latency_median_s`` the two latencies side by side.

``--clock cpu`` times the re-planner on this process's CPU time instead of the wall time
(``SdarOptions.clock``: the latencies, the solves' limits, and when the arms reach a cut point
while moving): what a machine with a core for the planner would see, when others load this
one (``"clock"`` in the JSON).

    python benchmarks/bench_replan.py [--suite paper] [--only R4,D5] [--per-instance 6]
                                      [--seed 0] [--plans DIR] [--save] [--time-limit 60]
                                      [--solve-time-limit 60]
                                      [--compare moving|sync|none] [--clock wall|cpu]
    python benchmarks/bench_replan.py --quick    # R4, one perturbation of each kind

Prints one row per perturbation, then one JSON object on the last line (``success_rate``,
``latency_median_s``, ``nudge_execution_ratio_median``, counts by kind and status, the load).
``--quick`` changes only the defaults: ``--only R4 --per-instance 3`` with a 30 s time limit;
the JSON keys are the same, plus ``"quick": true``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from _suites import shipped_suite_files, stored_or_solved

from sdar_tamp.app import PlannerCache, PlannerConfig
from sdar_tamp.app.replan_moving import replan_while_moving
from sdar_tamp.app.replanning import ReplanOutcome, replan
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_state import state_at
from sdar_tamp.world.collision import CollisionWorld
from sdar_tamp.world.errors import ObservedStateError
from sdar_tamp.world.instance import Instance, Pose2D, load_instance
from sdar_tamp.world.observed import (
    AddedObject,
    ObservedState,
    Resting,
    check_clear_of_arms,
    observed_arrangement,
)
from sdar_tamp.world.scene import Scene, load_scene
from solvers.sdar.options import SdarOptions

KINDS = ("nudge", "remove", "add")


@dataclass(frozen=True)
class Perturbation:
    kind: str
    at: float
    observed: ObservedState
    what: str
    redrawn: int


def _draw(
    kind: str, instance: Instance, plan: PlanFile, scene: Scene, rng: np.random.Generator,
    world: CollisionWorld,
) -> Perturbation | None:  # fmt: skip
    """A possible perturbation of ``kind`` at a random time (None after 40 refused draws)."""
    starts = {o.name: o.start.as_tuple() for o in instance.objects}
    sizes = {o.name: o.size for o in instance.objects}
    for tries in range(40):
        at = float(rng.uniform(0.0, 0.9 * plan.duration))
        state = state_at(plan, starts, scene, at)
        names = sorted(state.resting)
        if not names:
            continue
        name = names[int(rng.integers(len(names)))]
        x, y, yaw = state.resting[name]
        if kind == "nudge":
            r, a = rng.uniform(0.01, 0.03), rng.uniform(0.0, 2.0 * math.pi)
            turn = math.radians(rng.uniform(5.0, 20.0)) * rng.choice([-1.0, 1.0])
            pose = Pose2D(x + r * math.cos(a), y + r * math.sin(a), yaw + turn)
            observed = ObservedState(poses={name: pose})
            what = f"{name} by {r * 100:.1f} cm, {math.degrees(turn):+.0f} deg"
        elif kind == "remove":
            observed, what = ObservedState(removed=(name,)), name
        else:
            ws = instance.workspace
            size = tuple(float(v) for v in instance.objects[0].size)
            pose = Pose2D(rng.uniform(*ws.x), rng.uniform(*ws.y), rng.uniform(-math.pi, math.pi))
            added = AddedObject("extra", (size[0], size[1], size[2]), pose)
            observed = ObservedState(added=(added,))
            what = f"extra at ({pose.x:.2f}, {pose.y:.2f})"
        try:
            resting = {n: Resting(sizes[n], Pose2D(*p)) for n, p in state.resting.items()}
            arrangement = observed_arrangement(
                observed, resting, state.holder, tuple(sizes), instance.workspace
            )
            check_clear_of_arms(arrangement, scene, state.q, at, observed, world)
        except ObservedStateError:
            continue
        return Perturbation(kind, at, observed, what, tries)
    return None


def _replan(
    compare: str, instance: Instance, plan: PlanFile, p: Perturbation, config: PlannerConfig,
    cache: PlannerCache,
) -> tuple[ReplanOutcome, ReplanOutcome, float]:  # fmt: skip
    """The re-plan's outcome kept, its first one (the arms move again then) and the time [s]
    until it is done (the comparison over), on the configuration's clock."""
    clock = config.sdar.clock
    started = clock()
    if compare != "moving":
        out = replan(instance, plan, p.at, p.observed, config=config, cache=cache,
                     compare=compare == "sync")  # fmt: skip
        return out, out, clock() - started
    outcomes = list(replan_while_moving(instance, plan, p.at, p.observed, config=config,
                                        cache=cache, observed_at=started))  # fmt: skip
    return outcomes[-1], outcomes[0], clock() - started


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", default="paper")
    ap.add_argument("--only", default=None, help="comma-separated instance names")
    ap.add_argument("--per-instance", type=int, default=None, help="perturbations (default 6)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--plans", type=Path, default=None)
    ap.add_argument("--save", action="store_true")
    ap.add_argument("--time-limit", type=float, default=None, help="[s] of a re-plan (60)")
    ap.add_argument("--solve-time-limit", type=float, default=60.0, help="[s] of a first solve")
    ap.add_argument(
        "--compare",
        choices=("moving", "sync", "none"),
        default="moving",
        help="a changed repair compared with a fresh continuation while the arms "
        "execute it (moving), before the re-plan returns (sync), or not",
    )
    ap.add_argument(
        "--clock",
        choices=("wall", "cpu"),
        default="wall",
        help="the re-planner's clock: wall time, or this process's CPU time (as if the "
        "planner had a core of its own on a loaded machine)",
    )
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    only = args.only or ("R4" if args.quick else None)
    per = args.per_instance or (3 if args.quick else 6)
    args.time_limit = args.time_limit or (30.0 if args.quick else 60.0)
    files = [
        p for p in shipped_suite_files(args.suite) if only is None or p.stem in only.split(",")
    ]
    cache = PlannerCache()
    scene = load_scene()
    world = CollisionWorld(scene)
    clock = time.process_time if args.clock == "cpu" else time.perf_counter
    config = PlannerConfig(max_time=args.time_limit, seed=args.seed, sdar=SdarOptions(clock=clock))
    solve_config = PlannerConfig(max_time=args.solve_time_limit, execution="sync")
    rows: list[dict[str, object]] = []
    unsolved: list[str] = []
    started = time.perf_counter()
    for path in files:
        instance = load_instance(path)
        plan = stored_or_solved(
            path, args.plans, solve_config, cache, save=args.save, refresh=False
        )
        if plan is None:
            unsolved.append(path.stem)
            continue
        rng = np.random.default_rng([args.seed, sum(map(ord, path.stem))])
        for k in range(per):
            kind = KINDS[k % len(KINDS)]
            p = _draw(kind, instance, plan, scene, rng, world)
            if p is None:
                continue
            cpu = time.process_time()
            out, first, done = _replan(args.compare, instance, plan, p, config, cache)
            cpu = time.process_time() - cpu  # the final validation included
            row: dict[str, object] = {
                "instance": path.stem, "kind": kind, "at": round(p.at, 3), "what": p.what,
                "redrawn": p.redrawn, "status": out.status, "valid": out.valid,
                "latency": first.latency, "latency_final": out.latency, "latency_done": done,
                "improved": out is not first, "cpu": cpu, "cut": out.cut,
                "cannot_stop": any("before the arms can stop" in r for r in out.reasons),
                "compared": out.alternative is not None,
                "why": out.violation or "; ".join(out.reasons),
            }  # fmt: skip
            if kind == "nudge" and out.plan is not None:
                fresh = replan(instance, plan, p.at, p.observed, config=config, cache=cache,
                               repair=False)  # fmt: skip
                if fresh.plan is not None and fresh.valid:
                    hold = out.cut
                    row["ratio"] = (out.plan.duration - hold) / (fresh.plan.duration - hold)
                    row["fresh_latency"] = fresh.latency
            rows.append(row)
            ratio = (f" ratio {row['ratio']:.3f} (fresh {row['fresh_latency']:.3f} s)"
                     if "ratio" in row else "")  # fmt: skip
            print(f"{path.stem:4s} {kind:6s} t={p.at:6.2f} {p.what:28s} {out.status:10s} "
                  f"valid={out.valid} {first.latency:6.3f} s (final {out.latency:.3f} s, "
                  f"done {done:.3f} s, cpu {cpu:.3f} s){ratio}",
                  flush=True)  # fmt: skip
            if out.valid is not True:
                print(f"     why: {row['why']}", flush=True)
    solvable = [r for r in rows if not r["cannot_stop"]]
    ok = [r for r in solvable if r["valid"] is True]
    latencies = [float(r["latency"]) for r in solvable]  # type: ignore[arg-type]
    ratios = [float(r["ratio"]) for r in rows if "ratio" in r]  # type: ignore[arg-type]

    def median(values: list[float]) -> float | None:
        return round(statistics.median(values), 4) if values else None

    by_kind = {
        kind: {
            "cases": sum(r["kind"] == kind for r in rows),
            "cannot_stop": sum(r["kind"] == kind and bool(r["cannot_stop"]) for r in rows),
            "valid": sum(r["kind"] == kind and r["valid"] is True for r in rows),
            "repaired": sum(r["kind"] == kind and r["status"] == "repaired" for r in rows),
            "latency_median_s": median([float(r["latency"]) for r in solvable  # type: ignore[arg-type]
                                        if r["kind"] == kind]),
        }
        for kind in KINDS
    }  # fmt: skip
    statuses = sorted({str(r["status"]) for r in rows})
    summary = {
        "benchmark": "replan",
        "suite": args.suite,
        "instances": len(files) - len(unsolved),
        "unsolved_instances": unsolved,
        "perturbations": len(rows),
        "cannot_stop": len(rows) - len(solvable),
        "solvable": len(solvable),
        "valid": len(ok),
        "success_rate": round(len(ok) / len(solvable), 4) if solvable else None,
        "latency_median_s": median(latencies),
        "latency_final_median_s": median([float(r["latency_final"]) for r in solvable]),  # type: ignore[arg-type]
        "latency_done_median_s": median([float(r["latency_done"]) for r in solvable]),  # type: ignore[arg-type]
        "latency_done_p90_s": round(float(np.percentile(
            [float(r["latency_done"]) for r in solvable], 90)), 4) if solvable else None,  # type: ignore[arg-type]
        "improved": sum(bool(r["improved"]) for r in rows),
        "compare": args.compare,
        "clock": args.clock,
        "cpu_median_s": median([float(r["cpu"]) for r in solvable]),  # type: ignore[arg-type]
        "latency_p90_s": round(float(np.percentile(latencies, 90)), 4) if latencies else None,
        "nudge_execution_ratio_median": median(ratios),
        "nudge_execution_ratio_max": round(max(ratios), 4) if ratios else None,
        "nudges_compared": len(ratios),
        "nudge_fresh_latency_median_s": median(
            [float(r["fresh_latency"]) for r in rows if "fresh_latency" in r]  # type: ignore[arg-type]
        ),
        "nudge_latency_median_s": median(
            [float(r["latency"]) for r in rows if "fresh_latency" in r]  # type: ignore[arg-type]
        ),
        "compared": sum(bool(r["compared"]) for r in rows),
        "compared_fresh_kept": sum(bool(r["compared"]) and r["status"] == "replanned"
                                   for r in rows),
        "by_kind": by_kind,
        "statuses": {s: sum(r["status"] == s for r in rows) for s in statuses},
        "seconds": round(time.perf_counter() - started, 1),
        "load_average": os.getloadavg()[0],
        "quick": bool(args.quick),
    }  # fmt: skip
    print(f"success {summary['success_rate']} of {len(solvable)} solvable, median latency "
          f"{summary['latency_median_s']} s, nudge ratio {median(ratios)}")  # fmt: skip
    print(json.dumps(summary, sort_keys=True))


if __name__ == "__main__":
    main()
