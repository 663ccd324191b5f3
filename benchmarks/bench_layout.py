"""Benchmark: how well SDAR-T's plane model predicts that two arms meet at two objects.

SDAR-T and SDAR-M, with three arms or more, model an arm reaching for an object as the plane
segment from its base to the object (:class:`solvers.sdar.tasks.Layout`): two arms *cross*
when their segments come closer than the layout's ``clearance`` (0.08 m). This script
measures that model against the exact check. Poses are the starts and goals of a suite of the
cell's table (``--suite``, default ``table_4arm``); ``--poses`` of them are drawn (seeded).
For every arm and pose, the first configuration of the inverse-kinematics stream for each of
the object's first ``--options`` grasps that have one (default 1), on a table without other
objects; for every two arms at two poses at least 0.1 m apart (the other arms at home), the
exact arm-arm check of ``combine-confs`` (coal): the pair collides when every combination of
their options collides. Against the segments' gap (:meth:`~solvers.sdar.tasks.Layout.
arm_gap`): printed per gap band the share of pairs that collide, and per clearance the share
of the pairs it keeps (gap at least the clearance) that collide, and the share of the pairs
that do not collide that it keeps.

    python benchmarks/bench_layout.py [--scene CELL] [--suite table_4arm] [--poses 60]
                                        [--options 1]
    python benchmarks/bench_layout.py --quick     # 12 poses: seconds

One JSON object on the last line (``--quick`` adds ``"quick": true``): ``pairs``,
``collide``, and ``clearances``: clearance -> ``{"collide_kept", "free_kept"}``.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import random
from pathlib import Path

import numpy as np

from sdar_tamp.world.instance import Pose2D, load_instance
from solvers.sdar.tasks import Layout
from streams.context import WorldContext
from streams.stream_map import RearrangementStreams

ROOT = Path(__file__).resolve().parents[1]
CELLS = ROOT / "domains/dual_arm_rearrangement/cells"
SUITES = ROOT / "domains/dual_arm_rearrangement/suites"
QUICK = {"poses": 12}
BANDS = (0.0, 0.04, 0.08, 0.12, 0.16, 0.2, 0.25, 0.3, math.inf)
CLEARANCES = (0.08, 0.12, 0.16, 0.2)
MIN_APART = 0.1  # [m] two poses closer than this are one place


def _poses(suite: str, count: int, seed: int) -> list[tuple[tuple[float, ...], Pose2D]]:
    """``count`` (size, pose) drawn from the starts and goals of the suite's instances."""
    found: list[tuple[tuple[float, ...], Pose2D]] = []
    for path in sorted((SUITES / suite).glob("*.yaml")):
        for o in load_instance(path).objects:
            found += [(tuple(o.size), o.start), (tuple(o.size), o.goal)]
    random.Random(seed).shuffle(found)
    return found[:count]


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", type=Path, default=CELLS / "ur5e_table_4arm.yaml")
    ap.add_argument("--suite", default="table_4arm")
    ap.add_argument("--poses", type=int, default=60)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--options", type=int, default=1, help="grasps with IK per arm and pose")
    ap.add_argument("--quick", action="store_true", help="12 poses")
    args = ap.parse_args(argv)
    if args.quick:
        args.poses = QUICK["poses"]
    ctx = WorldContext.load(args.scene)
    drawn = _poses(args.suite, args.poses, args.seed)
    names = [f"x{k}" for k in range(len(drawn))]
    streams = RearrangementStreams(ctx, {n: s for n, (s, _) in zip(names, drawn, strict=True)})
    arms = ctx.arm_names
    bases = tuple(
        (float(ctx.scene.arm(a).base_xyz[0]), float(ctx.scene.arm(a).base_xyz[1])) for a in arms
    )
    places = {n: ((p.x, p.y), (p.x, p.y)) for n, (_, p) in zip(names, drawn, strict=True)}
    layout = Layout(places, bases)
    confs: dict[tuple[int, int], list[np.ndarray]] = {}
    for k, (n, (_, p)) in enumerate(zip(names, drawn, strict=True)):
        for a, arm in enumerate(arms):
            for (g,) in streams.sample_grasp(n):
                first = next(streams.inverse_kinematics(arm, n, p, g, [("atpose", n, p)]), None)
                if first is not None:
                    confs.setdefault((a, k), []).append(np.array(first[0].q))
                if len(confs.get((a, k), ())) >= args.options:
                    break
    world = ctx.new_world()
    rows: list[tuple[float, bool]] = []
    for (a, i), (b, j) in itertools.combinations(sorted(confs), 2):
        if a == b or math.dist(places[names[i]][0], places[names[j]][0]) < MIN_APART:
            continue
        q = {arm: ctx.home(arm) for arm in arms}
        hit = True
        for qa, qb in itertools.product(confs[a, i], confs[b, j]):
            q[arms[a]], q[arms[b]] = qa, qb
            if not world.in_collision(ctx.join(q)):
                hit = False
                break
        rows.append((layout.arm_gap(a, names[i], b, names[j]), hit))
    print(f"{len(drawn)} poses, {len(rows)} pairs of arms at two poses, "
          f"{sum(h for _, h in rows)} collide")  # fmt: skip
    for lo, hi in itertools.pairwise(BANDS):
        band = [h for gap, h in rows if lo <= gap < hi]
        if band:
            print(f"gap {lo:.2f}-{hi:.2f} m: {len(band):5d} pairs, "
                  f"{sum(band) / len(band):.0%} collide")  # fmt: skip
    free = sum(1 for _, h in rows if not h)
    table: dict[str, dict[str, float]] = {}
    for c in CLEARANCES:
        kept = [h for gap, h in rows if gap >= c]
        collide = sum(kept) / len(kept) if kept else 0.0
        share = (len(kept) - sum(kept)) / free if free else 0.0
        table[f"{c:.2f}"] = {"collide_kept": round(collide, 4), "free_kept": round(share, 4)}
        print(f"clearance {c:.2f} m: {collide:.1%} of the kept pairs collide, "
              f"{share:.0%} of the free pairs kept")  # fmt: skip
    out = {
        "benchmark": "layout",
        "scene": args.scene.name,
        "poses": len(drawn),
        "pairs": len(rows),
        "collide": sum(h for _, h in rows),
        "clearances": table,
    }
    if args.quick:
        out["quick"] = True
    print(json.dumps(out))


if __name__ == "__main__":
    main()
