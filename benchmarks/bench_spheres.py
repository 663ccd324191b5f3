"""Benchmark of the optimiser's sphere model fitted to collision meshes
(:mod:`streams.motion.sphere_fit`, :func:`streams.motion.spheres.arm_spheres`).

Per model and per fitted link: the spheres' count, their coverage of points drawn uniformly
on the link's collision surface (another seed than anything the fit uses; it uses none), and
the volume of the spheres' union (and their volumes added up) over the convex hull's; per
model: the sphere counts of the fine and the coarse model and the time to build the model:
cold (no cache), from the disk cache (in a temporary folder of its own) and from the
in-memory cache. Models: the test arm of meshes (``tests/streams/motion/meshes``), the
shipped UR5e with every primitive fitted (``fit="all"``; its default model keeps its
primitive spheres), and, when ``example-robot-data`` is installed (or
``EXAMPLE_ROBOT_DATA_SHARE`` names its ``share`` folder), its UR10 and Franka Panda. Prints
a table, then as its last line one JSON object.

    python benchmarks/bench_spheres.py            # 20000 surface points per link
    python benchmarks/bench_spheres.py --quick    # 2000 points, the UR10 skipped: seconds
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from sdar_tamp.world._coal import hull_volume
from sdar_tamp.world.scene import load_scene
from sdar_tamp.world.urdf import example_robot_data_share
from streams._pin_geometry import arm_primitives
from streams.motion import sphere_cache, spheres
from streams.motion.sphere_fit import FitOptions, fit_spheres, surface_points, union_volume

ROOT = Path(__file__).resolve().parent.parent
MESHES = ROOT / "tests" / "streams" / "motion" / "meshes"


def _models(quick: bool) -> list[tuple[str, Path, tuple[Path, ...], str]]:
    scene = load_scene()
    models = [
        ("mesh_arm", MESHES / "mesharm" / "urdf" / "mesh_arm.urdf", (MESHES,), "meshes"),
        ("ur5e_all", scene.robot_urdf, scene.package_dirs, "all"),
    ]
    share = example_robot_data_share()
    if share is not None:
        robots = share / "example-robot-data" / "robots"
        makers = [("panda", "panda_description/urdf/panda.urdf")]
        if not quick:
            makers.insert(0, ("ur10", "ur_description/urdf/ur10_robot.urdf"))
        for name, relative in makers:
            models.append((name, robots / relative, (robots, share), "meshes"))
    return models


def bench_model(
    urdf: Path, package_dirs: tuple[Path, ...], fit: str, points: int, seed: int
) -> dict[str, Any]:
    spheres._arm_spheres.cache_clear()
    t0 = time.perf_counter()
    fine = spheres.arm_spheres(urdf, package_dirs=package_dirs, fit=fit)
    cold = time.perf_counter() - t0
    spheres._arm_spheres.cache_clear()
    t0 = time.perf_counter()
    from_disk = spheres.arm_spheres(urdf, package_dirs=package_dirs, fit=fit)
    disk = time.perf_counter() - t0
    assert np.array_equal(from_disk.centre, fine.centre)
    t0 = time.perf_counter()
    again = spheres.arm_spheres(urdf, package_dirs=package_dirs, fit=fit)
    cached = time.perf_counter() - t0
    assert again is from_disk
    coarse = spheres.arm_spheres(urdf, coarse=True, package_dirs=package_dirs, fit=fit)
    rng = np.random.default_rng(seed)
    links: dict[str, Any] = {}
    prims = [p for p in arm_primitives(urdf, package_dirs) if p.joint != 0]
    for (_, link), group in spheres.fitted_links(prims, fit).items():
        tri, tolerance = spheres.link_surface(group)
        fitted = fit_spheres(tri, FitOptions(), tolerance)
        sample = surface_points(tri, points, rng)
        d = np.linalg.norm(sample[:, None] - fitted.centre[None], axis=-1)
        inside = np.any(d <= fitted.radius[None] + 1e-9, axis=1)
        links[link] = {
            "spheres": len(fitted.radius),
            "coverage": float(inside.mean()),
            "volume_ratio": union_volume(fitted.centre, fitted.radius)
            / hull_volume(tri.reshape(-1, 3)),
            # the spheres' volumes added up (overlaps counted twice) over the hull's
            "summed_ratio": 4.0
            / 3.0
            * np.pi
            * float(np.sum(fitted.radius**3))
            / hull_volume(tri.reshape(-1, 3)),
        }
    return {
        "spheres": len(fine),
        "coarse_spheres": len(coarse),
        "cold_s": cold,
        "disk_s": disk,
        "cached_s": cached,
        "links": links,
        "min_coverage": min(v["coverage"] for v in links.values()),
        "max_volume_ratio": max(v["volume_ratio"] for v in links.values()),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="2000 points per link: seconds")
    ap.add_argument("--points", type=int, default=20000)
    ap.add_argument("--seed", type=int, default=11)
    args = ap.parse_args()
    n = 2000 if args.quick else args.points
    out: dict[str, Any] = {"points_per_link": n, "models": {}}
    # a disk cache of its own, empty: the first build of each model is cold
    folder = tempfile.TemporaryDirectory(prefix="bench-spheres-")
    os.environ["SDAR_TAMP_CACHE"] = folder.name
    os.environ[sphere_cache.ENV_SWITCH] = "1"
    print(
        f"{'model':9} {'link':20} {'spheres':>7} {'coverage':>9} {'union/hull':>10} {'sum/hull':>8}"
    )
    for name, urdf, package_dirs, fit in _models(args.quick):
        row = bench_model(urdf, package_dirs, fit, n, args.seed)
        out["models"][name] = row
        for link, v in row["links"].items():
            print(
                f"{name:9} {link:20} {v['spheres']:>7} {v['coverage']:>9.4%} "
                f"{v['volume_ratio']:>10.2f} {v['summed_ratio']:>8.2f}"
            )
        print(
            f"{name:9} {'(model)':20} {row['spheres']:>7} fine, {row['coarse_spheres']} coarse; "
            f"cold {row['cold_s']:.2f} s, from disk {row['disk_s'] * 1e3:.1f} ms, "
            f"in memory {row['cached_s'] * 1e3:.2f} ms"
        )
    folder.cleanup()
    if args.quick:
        out["quick"] = True
    print(json.dumps(out))


if __name__ == "__main__":
    main()
