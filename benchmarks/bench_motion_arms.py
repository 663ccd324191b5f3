"""Benchmark: the trajectory optimiser per call for 1 to 4 arms around one table, side by side.

The cell (``--scene``, default the four-arm test cell ``tests/streams/motion/data/
table_4arm.yaml``: a 1.2 m x 1.0 m table, arms S, N, W, E) is cut to its first k arms for
every k of ``--arms`` (default ``1,2,3,4``), so every k plans on the same table among the same
objects. Per k, ``--calls`` transfers (seeded, the same object layouts for every k): every
arm goes from the pre-grasp above one resting object to the pre-grasp above another (IK
candidates of the grasp set, the first whose two configurations are collision-free with the
objects and each other). Each transfer is one call of the optimiser
(:meth:`streams.motion.optimiser.TrajectoryOptimiser.solve`, straight-line warm start; no
direct paths, no fallbacks), timed in CPU seconds of the process (the machine may be shared)
and in wall seconds; its result is re-checked with coal along the optimised knots' curve.

The NLP's size is reported per k: collision rows per knot are ``k (k - 1) / 2`` arm-arm
blocks of the pair's arm-arm slots, plus an arm-obstacle and an arm-table block per arm.
Derivatives are CasADi's own evaluation unless ``--compiled`` (then each k's library is
compiled first, which takes minutes of CPU once and is cached).

    python benchmarks/bench_motion_arms.py [--calls 30] [--arms 1,2,3,4] [--seed 0]
    python benchmarks/bench_motion_arms.py --quick        # 2 calls per k: seconds

Prints one line per k, then one JSON object on the last line (``--quick`` adds
``"quick": true``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import time
from pathlib import Path

import numpy as np

from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.scene import Scene, load_scene
from sdar_tamp.world.transforms import pose_xyz_yaw
from streams.context import WorldContext
from streams.grasps import sample_grasps
from streams.ik import IKRequest, solve_ik_candidates
from streams.motion import codegen
from streams.motion.exact_check import configure_world, validate_trajectory
from streams.motion.optimiser import TrajectoryOptimiser
from streams.motion.optimiser_records import TrajOptOptions, TransferQuery
from streams.motion.phases import OBSTACLE_SPHERES
from streams.motion.sphere_pairs import HeldSpheres, arm_pairs
from streams.motion.spheres import object_spheres
from streams.motion.timing import spline_curve

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SCENE = ROOT / "tests/streams/motion/data/table_4arm.yaml"
QUICK = {"calls": 2}
SIZE = (0.08, 0.04, 0.05)
OBJECTS = 8


def _layout(scene: Scene, rng: np.random.Generator) -> dict[str, ObjectBox]:
    """``OBJECTS`` boxes in the workspace, centres at least 0.12 m apart."""
    ws = scene.workspace
    out: dict[str, ObjectBox] = {}
    while len(out) < OBJECTS:
        x, y = rng.uniform(*ws.x), rng.uniform(*ws.y)
        if all(np.hypot(x - b.T_world_obj[0, 3], y - b.T_world_obj[1, 3]) >= 0.12
               for b in out.values()):  # fmt: skip
            yaw = float(rng.uniform(-np.pi / 2, np.pi / 2))
            out[f"o{len(out)}"] = ObjectBox(pose_xyz_yaw(x, y, SIZE[2] / 2, yaw), SIZE)
    return out


def _pregrasps(
    ctx: WorldContext, objects: dict[str, ObjectBox]
) -> dict[str, dict[str, list[np.ndarray]]]:
    """Per arm, per object, its pre-grasp configurations (cheapest first)."""
    world = ctx.new_world()
    configure_world(ctx, world, objects, {}, ctx.scene.home)
    home = {a: ctx.home(a) for a in ctx.arm_names}
    grasps = sample_grasps(SIZE, ctx.scene.grasp_limits)
    out: dict[str, dict[str, list[np.ndarray]]] = {}
    for arm in ctx.arm_names:
        out[arm] = {}
        for name, box in objects.items():
            found = solve_ik_candidates(ctx, world, objects, [IKRequest(arm, name, box, grasps)],
                                        home)  # fmt: skip
            if found:
                out[arm][name] = [c.q_pre for c in found[:3]]
    return out


def _transfer(
    ctx: WorldContext, objects: dict[str, ObjectBox], pre: dict[str, dict[str, list[np.ndarray]]],
    rng: np.random.Generator, tries: int = 200,
) -> tuple[np.ndarray, np.ndarray] | None:  # fmt: skip
    """Ends of a transfer: each arm from above one object to above another, both ends free."""
    world = ctx.new_world()
    configure_world(ctx, world, objects, {}, ctx.scene.home)
    for _ in range(tries):
        ends: list[dict[str, np.ndarray]] = [{}, {}]
        for arm in ctx.arm_names:
            names = sorted(pre[arm])
            if len(names) < 2:
                return None
            a, b = rng.choice(len(names), 2, replace=False)
            for end, obj in zip(ends, (names[a], names[b]), strict=True):
                options = pre[arm][obj]
                end[arm] = options[int(rng.integers(len(options)))]
        q_a, q_b = ctx.join(ends[0]), ctx.join(ends[1])
        if not world.in_collision(q_a) and not world.in_collision(q_b):
            return q_a, q_b
    return None


def _obstacles(objects: dict[str, ObjectBox]) -> tuple[np.ndarray, np.ndarray]:
    cs, rs = zip(*(object_spheres(b.size, b.T_world_obj, OBSTACLE_SPHERES)
                   for b in objects.values()), strict=True)  # fmt: skip
    return np.concatenate(cs), np.concatenate(rs)


def run_k(scene: Scene, k: int, calls: int, seed: int, compiled: bool) -> dict[str, object]:
    """Times ``calls`` optimiser calls for the first ``k`` arms of ``scene``."""
    ctx = WorldContext.load(dataclasses.replace(scene, arms=scene.arms[:k]))
    options = TrajOptOptions(compiled=compiled)
    t = time.process_time()
    opt = TrajectoryOptimiser(ctx, options)
    build = time.process_time() - t
    if compiled:
        opt.request_compiled()
    rng = np.random.default_rng(seed)
    world = ctx.new_world()
    cpu, wall, ipopt_cpu, iterations = [], [], [], []
    ok = valid = ipopt = skipped = 0
    held = tuple(HeldSpheres.empty() for _ in range(k))
    v, a = ctx.scene.joint_array("velocity_limit"), ctx.scene.joint_array("acceleration_limit")
    while len(cpu) < calls and skipped < 10 * calls:
        objects = _layout(ctx.scene, rng)
        ends = _transfer(ctx, objects, _pregrasps(ctx, objects), rng)
        if ends is None:
            skipped += 1
            continue
        q_a, q_b = ends
        d = np.abs(q_b - q_a)
        duration = float(2.0 * np.maximum(d / v + v / a, 2.0 * np.sqrt(d / a)).max() + 0.5)
        query = TransferQuery(q_a, q_b, held, _obstacles(objects), duration)
        t_cpu, t_wall = time.process_time(), time.perf_counter()
        result = opt.solve(query)
        cpu.append(time.process_time() - t_cpu)
        wall.append(time.perf_counter() - t_wall)
        iterations.append(result.iterations)
        if result.rounds > 0:
            ipopt += 1
            ipopt_cpu.append(cpu[-1])
        if result.success:
            ok += 1
            configure_world(ctx, world, objects, {}, q_a)
            curve = spline_curve(result.path, 4 * len(result.path))
            valid += int(validate_trajectory(ctx, world, curve).ok)
    n = len(cpu)
    o = options
    per_knot = sum(opt.pair_slots) + k * (o.obstacle_slots + o.table_slots)
    return {
        "arms": list(ctx.arm_names),
        "calls": n,
        "build_cpu_s": build,
        "collision_rows_per_knot": per_knot,
        "arm_arm_blocks": len(arm_pairs(k)),
        "success_rate": ok / n if n else 0.0,
        "exact_check_passed": valid,
        "ipopt_calls": ipopt,
        "median_cpu_s": float(np.median(cpu)) if cpu else None,
        "p90_cpu_s": float(np.percentile(cpu, 90)) if cpu else None,
        "median_wall_s": float(np.median(wall)) if wall else None,
        "median_cpu_s_ipopt_calls": float(np.median(ipopt_cpu)) if ipopt_cpu else None,
        "median_iterations": float(np.median(iterations)) if iterations else None,
        "compiled": opt.compiled,
    }


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--scene", type=Path, default=DEFAULT_SCENE, help="a cell of 4 arms or more")
    ap.add_argument("--arms", default="1,2,3,4", help="arm counts, comma-separated")
    ap.add_argument("--calls", type=int, default=30, help="optimiser calls per arm count")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--compiled", action="store_true", help="compiled derivatives (see above)")
    ap.add_argument("--quick", action="store_true", help="2 calls per arm count: seconds")
    args = ap.parse_args(argv)
    if args.quick:  # explicit options still win
        ap.set_defaults(**QUICK)
        args = ap.parse_args(argv)
    if not args.compiled:
        os.environ[codegen.ENV_SWITCH] = "0"
    scene = load_scene(args.scene)
    counts = [int(k) for k in args.arms.split(",")]
    bad = [k for k in counts if not 1 <= k <= len(scene.arms)]
    if bad:
        ap.error(f"--arms: expected counts in 1..{len(scene.arms)} (the cell's arms), got {bad}")
    rows = {}
    for k in counts:
        if args.compiled:
            _wait_compiled(scene, k)
        row = run_k(scene, k, args.calls, args.seed, args.compiled)
        rows[str(k)] = row
        print(f"{k} arm(s): {row['calls']} calls, median {row['median_cpu_s']:.3f} s CPU "
              f"({row['ipopt_calls']} with IPOPT: median {row['median_cpu_s_ipopt_calls']} s), "
              f"success {row['success_rate']:.2f}, rows/knot {row['collision_rows_per_knot']}",
              flush=True)  # fmt: skip
    out: dict[str, object] = {"benchmark": "bench_motion_arms", "scene": str(args.scene),
                              "seed": args.seed, "by_arms": rows}  # fmt: skip
    if args.quick:
        out["quick"] = True
    print(json.dumps(out))


def _wait_compiled(scene: Scene, k: int, limit: float = 1800.0) -> None:
    """Compile the derivatives of the ``k``-arm optimiser (or find them cached), waiting up to
    ``limit`` [s] for the background compile."""
    ctx = WorldContext.load(dataclasses.replace(scene, arms=scene.arms[:k]))
    opt = TrajectoryOptimiser(ctx, TrajOptOptions())
    opt.request_compiled()
    library = opt.library
    start = time.perf_counter()
    while library is not None and not library.is_file() and time.perf_counter() - start < limit:
        time.sleep(2.0)


if __name__ == "__main__":
    main()
