"""Benchmark of the dual-arm world: batched IK, collision checks, dependency graphs, and the
exact minimum feedback vertex set SDAR-T computes on a dense 24-object cycle component.

The dependency graph is timed on the shipped ``stress`` suite's ``R24``: 24 objects fit only at
that suite's 1 cm clearance (at the generator's default 2.6 cm, room for a finger beside every
object, random placement runs out of room after 21 to 23 of them and the generator refuses
24). Prints a small table, then as its last line one JSON object with the figures.

    python benchmarks/bench_world.py            # the full run
    python benchmarks/bench_world.py --quick    # the same measures on small batches, seconds

``--quick``: 500 IK poses, 200 collision checks, the same graphs, a single repeat of each
timing; the figures are rough, the JSON keys the same, plus ``"quick": true``.
"""

from __future__ import annotations

import argparse
import json
import random
import time
from dataclasses import dataclass

import numpy as np

from sdar_tamp.graph import DependencyGraph
from sdar_tamp.world.collision import CollisionWorld, ObjectBox
from sdar_tamp.world.dependency import instance_dependency_graph
from sdar_tamp.world.generators import generate_instance
from sdar_tamp.world.instance import load_instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import load_scene
from sdar_tamp.world.suites import shipped_suite_dir
from sdar_tamp.world.transforms import FloatArray, pose_xyz_yaw, top_down_pose
from solvers.sdar.buffer_sets import feedback_vertex_set


def _best_rate(fn: object, count: int, repeats: int = 5) -> float:
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()  # type: ignore[operator]
        best = min(best, time.perf_counter() - t0)
    return count / best


def bench_ik(
    kin: ArmKinematics, rng: np.random.Generator, n: int = 5000, repeats: int = 5
) -> float:
    """Tool poses per second, all 8 branches plus limit filtering, batched."""
    T = top_down_pose(
        rng.uniform(-0.25, 0.25, n), rng.uniform(-0.3, 0.3, n), rng.uniform(0.02, 0.3, n),
        rng.uniform(-np.pi, np.pi, n),
    )  # fmt: skip
    return _best_rate(lambda: kin.ik_tcp(T), n, repeats)


def realistic_configurations(
    scene_kins: list[ArmKinematics], rng: np.random.Generator, n: int
) -> FloatArray:
    """Dual-arm configurations ``(n, layout.dof)``: both tools top-down above random table
    points."""
    cols = []
    for kin in scene_kins:
        m = 4 * n
        T = top_down_pose(
            rng.uniform(-0.25, 0.25, m), rng.uniform(-0.3, 0.3, m), rng.uniform(0.1, 0.3, m),
            rng.uniform(-np.pi, np.pi, m),
        )  # fmt: skip
        q, ok = kin.ik_tcp(T).closest(np.array(kin.spec.home))
        cols.append(q[ok][:n])
    return np.hstack(cols)


def bench_collision(world: CollisionWorld, Q: FloatArray, repeats: int = 3) -> tuple[float, float]:
    """Dual-arm checks per second and the fraction found colliding."""
    hits = [world.in_collision(q) for q in Q]
    rate = _best_rate(lambda: [world.in_collision(q) for q in Q], len(Q), repeats)
    return rate, float(np.mean(hits))


def dense_cycle_component(n: int, extra: int, seed: int) -> DependencyGraph:
    """A ring of ``n`` objects plus up to ``extra`` random edges per object: one component."""
    rng = random.Random(seed)
    edges = {(i, (i + 1) % n) for i in range(n)}
    for i in range(n):
        edges |= {(i, j) for j in rng.sample(range(n), extra) if j != i}
    return DependencyGraph(tuple(f"o{i}" for i in range(n)), tuple(sorted(edges)))


@dataclass(frozen=True)
class Sizes:
    """How much each measure does: batch sizes and best-of repeats."""

    ik_poses: int
    ik_repeats: int
    configurations: int
    collision_repeats: int
    graph_repeats: int
    fvs_repeats: int


FULL = Sizes(5000, 5, 3000, 3, 20, 3)
QUICK = Sizes(500, 1, 200, 1, 3, 1)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small batches, one repeat: seconds")
    args = ap.parse_args(argv)
    sizes = QUICK if args.quick else FULL
    rng = np.random.default_rng(0)
    scene = load_scene()
    kins = [ArmKinematics.from_scene(scene, a) for a in scene.arm_names]
    ik_rate = bench_ik(kins[0], rng, sizes.ik_poses, sizes.ik_repeats)

    inst = generate_instance("M", 12, seed=1)
    world = CollisionWorld(scene)
    world.set_objects(
        {
            o.name: ObjectBox(
                pose_xyz_yaw(o.start.x, o.start.y, o.size[2] / 2, o.start.yaw), o.size
            )
            for o in inst.objects
        }
    )
    Q = realistic_configurations(kins, rng, sizes.configurations)
    coll_rate, coll_frac = bench_collision(world, Q, sizes.collision_repeats)

    big = load_instance(shipped_suite_dir("stress") / "R24.yaml")
    t_graph = 1.0 / _best_rate(lambda: instance_dependency_graph(big), 1, sizes.graph_repeats)

    scc = dense_cycle_component(24, 2, seed=3)
    t_fvs = 1.0 / _best_rate(lambda: feedback_vertex_set(scc), 1, sizes.fvs_repeats)

    rows = [
        ("IK poses/s (8 branches, batched, 1 core)", f"{ik_rate:,.0f}", ">= 20,000"),
        ("dual-arm collision checks/s (12 objects)", f"{coll_rate:,.0f}", ">= 20,000"),
        ("  fraction of checked configurations colliding", f"{coll_frac:.2f}", ""),
        ("dependency graph, 24 objects (stress R24) [ms]", f"{1e3 * t_graph:.3f}", ""),
        ("exact minimum FVS, 24-object cycle component [ms]", f"{1e3 * t_fvs:.1f}", "< 10,000"),
    ]
    print(f"{'measure':50s} {'value':>12s} {'target':>10s}")
    for name, value, target in rows:
        print(f"{name:50s} {value:>12s} {target:>10s}")
    print(
        json.dumps(
            {
                "ik_poses_per_s_per_core": round(ik_rate),
                "collision_checks_per_s_12_objects": round(coll_rate),
                "collision_fraction": round(coll_frac, 3),
                "dependency_graph_24_objects_ms": round(1e3 * t_graph, 4),
                "exact_fvs_24_object_component_ms": round(1e3 * t_fvs, 2),
                "quick": args.quick,
            }
        )
    )


if __name__ == "__main__":
    main()
