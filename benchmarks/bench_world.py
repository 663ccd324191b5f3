"""Benchmark of the dual-arm world: batched IK, collision checks, dependency graphs, and the
exact minimum feedback vertex set SDAR-T computes on a dense 24-object cycle component.

Prints a small table, then as its last line one JSON object with the figures.
Run: ``python benchmarks/bench_world.py``.
"""

from __future__ import annotations

import json
import random
import time

import numpy as np

from sdar_tamp.graph import DependencyGraph
from sdar_tamp.world.collision import CollisionWorld, ObjectBox
from sdar_tamp.world.dependency import instance_dependency_graph
from sdar_tamp.world.generators import generate_instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import load_scene
from sdar_tamp.world.transforms import FloatArray, pose_xyz_yaw, top_down_pose
from solvers.sdar.buffer_sets import feedback_vertex_set


def _best_rate(fn: object, count: int, repeats: int = 5) -> float:
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()  # type: ignore[operator]
        best = min(best, time.perf_counter() - t0)
    return count / best


def bench_ik(kin: ArmKinematics, rng: np.random.Generator, n: int = 5000) -> float:
    """Tool poses per second, all 8 branches plus limit filtering, batched."""
    T = top_down_pose(
        rng.uniform(-0.25, 0.25, n), rng.uniform(-0.3, 0.3, n), rng.uniform(0.02, 0.3, n),
        rng.uniform(-np.pi, np.pi, n),
    )  # fmt: skip
    return _best_rate(lambda: kin.ik_tcp(T), n)


def realistic_configurations(
    scene_kins: list[ArmKinematics], rng: np.random.Generator, n: int
) -> FloatArray:
    """Dual-arm configurations ``(n, 12)``: both tools top-down above random table points."""
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


def bench_collision(world: CollisionWorld, Q: FloatArray) -> tuple[float, float]:
    """Dual-arm checks per second and the fraction found colliding."""
    hits = [world.in_collision(q) for q in Q]
    rate = _best_rate(lambda: [world.in_collision(q) for q in Q], len(Q), 3)
    return rate, float(np.mean(hits))


def dense_cycle_component(n: int, extra: int, seed: int) -> DependencyGraph:
    """A ring of ``n`` objects plus up to ``extra`` random edges per object: one component."""
    rng = random.Random(seed)
    edges = {(i, (i + 1) % n) for i in range(n)}
    for i in range(n):
        edges |= {(i, j) for j in rng.sample(range(n), extra) if j != i}
    return DependencyGraph(tuple(f"o{i}" for i in range(n)), tuple(sorted(edges)))


def main() -> None:
    rng = np.random.default_rng(0)
    scene = load_scene()
    kins = [ArmKinematics.from_scene(scene, a) for a in scene.arm_names]
    ik_rate = bench_ik(kins[0], rng)

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
    Q = realistic_configurations(kins, rng, 3000)
    coll_rate, coll_frac = bench_collision(world, Q)

    big = generate_instance("R", 24, seed=24)
    t_graph = 1.0 / _best_rate(lambda: instance_dependency_graph(big), 1, 20)

    scc = dense_cycle_component(24, 2, seed=3)
    t_fvs = 1.0 / _best_rate(lambda: feedback_vertex_set(scc), 1, 3)

    rows = [
        ("IK poses/s (8 branches, batched, 1 core)", f"{ik_rate:,.0f}", ">= 20,000"),
        ("dual-arm collision checks/s (12 objects)", f"{coll_rate:,.0f}", ">= 20,000"),
        ("  fraction of checked configurations colliding", f"{coll_frac:.2f}", ""),
        ("dependency graph, 24 objects [ms]", f"{1e3 * t_graph:.3f}", ""),
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
            }
        )
    )


if __name__ == "__main__":
    main()
