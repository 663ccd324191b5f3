"""Benchmark: batched IK of :class:`sdar_tamp.world.kinematics.ArmKinematics` per solver kind.

The planner's IK call (``ik_tcp``: every branch of a batch of TCP poses) for the shipped UR5e
(the closed form, eight branches) and for a 7-DoF arm with the Franka Panda's kinematics
(the shipped Panda cell's left arm; the numeric IK, up to four distinct
solutions from eight seeds). Targets are the forward kinematics of configurations drawn
uniformly inside the limits, so every one is reachable. Measured per arm: the share of poses
with at least one valid branch, the largest pose error of a valid branch (position [m] or
rotation [rad]), poses per second, and the numeric IK's cost relative to the closed form.
Prints a table, then as its last line one JSON object.

    python benchmarks/bench_arm_ik.py            # 2000 poses per arm
    python benchmarks/bench_arm_ik.py --quick    # 100 poses per arm, seconds
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

import numpy as np

from sdar_tamp.world.cells import cell_path
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.numeric_ik import pose_error
from sdar_tamp.world.scene import load_scene


def _arms() -> dict[str, ArmKinematics]:
    """The left arm of the shipped UR5e cell (closed form) and of the Panda cell (numeric)."""
    ur5e = load_scene()
    panda = load_scene(cell_path("panda_facing"))
    return {
        "ur5e": ArmKinematics.from_scene(ur5e, ur5e.arm_names[0]),
        "panda": ArmKinematics.from_scene(panda, panda.arm_names[0]),
    }


def bench_arm(kin: ArmKinematics, n: int, seed: int) -> dict[str, Any]:
    lo, hi = kin.spec.lower_array, kin.spec.upper_array
    q = np.random.default_rng(seed).uniform(lo, hi, (n, kin.dof))
    targets = kin.fk_batch(q) @ kin.T_tool0_tcp
    t0 = time.perf_counter()
    sol = kin.ik_tcp(targets)
    seconds = time.perf_counter() - t0
    rows, branches = np.nonzero(sol.valid)
    reached = kin.fk_batch(sol.q[rows, branches]) @ kin.T_tool0_tcp
    err = np.abs(pose_error(targets[rows], reached))
    return {
        "solver": "closed form" if kin.closed_form else "numeric",
        "dof": kin.dof,
        "branches": int(sol.q.shape[1]),
        "poses": n,
        "success_rate": float(sol.valid.any(axis=1).mean()),
        "mean_valid_branches": float(sol.valid.sum(axis=1).mean()),
        "max_error": float(err.max()) if len(err) else None,
        "poses_per_second": n / seconds,
        "ms_per_pose": 1e3 * seconds / n,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="100 poses per arm: seconds")
    ap.add_argument("--poses", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    n = 100 if args.quick else args.poses
    out: dict[str, Any] = {"arms": {}}
    print(f"{'arm':6} {'solver':12} {'dof':>3} {'poses':>6} {'solved':>8} {'branches':>8} "
          f"{'max err':>9} {'ms/pose':>8}")  # fmt: skip
    for name, kin in _arms().items():
        row = bench_arm(kin, n, args.seed)
        out["arms"][name] = row
        print(
            f"{name:6} {row['solver']:12} {row['dof']:>3} {n:>6} {row['success_rate']:>8.2%} "
            f"{row['mean_valid_branches']:>8.2f} {row['max_error'] or 0.0:>9.1e} "
            f"{row['ms_per_pose']:>8.3f}"
        )
    ratio = out["arms"]["panda"]["ms_per_pose"] / out["arms"]["ur5e"]["ms_per_pose"]
    out["numeric_over_closed_form"] = ratio
    print(f"numeric IK (7-DoF) / closed form (UR5e), time per pose: {ratio:.0f}x")
    if args.quick:
        out["quick"] = True
    print(json.dumps(out))


if __name__ == "__main__":
    main()
