"""Benchmark of the batched numeric IK (:mod:`sdar_tamp.world.numeric_ik`) on reachable poses.

Targets are the forward kinematics of configurations drawn uniformly inside the joint limits,
so every one of them has a solution. Measured per arm: the share solved (position within
1e-6 m, rotation within 1e-6 rad, joints within the limits), the largest error of a solved
pose, poses per second. Arms: the shipped UR5e (to its TCP, within the scene's narrowed limits;
the closed form exists, the numeric IK is checked on it), and, when ``example-robot-data`` is
installed (or ``EXAMPLE_ROBOT_DATA_SHARE`` names its ``share`` folder), the Franka Panda
(7-DoF, to ``panda_hand_tcp``, within its URDF limits) and the UFactory xArm7. Prints a small
table, then as its last line one JSON object.

    python benchmarks/bench_numeric_ik.py            # 2000 poses per arm
    python benchmarks/bench_numeric_ik.py --quick    # 100 poses per arm, seconds
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

import numpy as np

from sdar_tamp.world._pin import PinRobot, chain_to
from sdar_tamp.world.numeric_ik import chain_fk, numeric_ik, pose_error
from sdar_tamp.world.scene import load_scene
from sdar_tamp.world.urdf import example_robot_data_share


def _arms() -> list[tuple[str, PinRobot, str, np.ndarray | None, np.ndarray | None]]:
    scene = load_scene()
    spec = scene.arms[0]
    ur = PinRobot.load(scene.robot_urdf, scene.package_dirs)
    arms = [("ur5e", ur, "tcp", spec.lower_array, spec.upper_array)]
    share = example_robot_data_share()
    if share is not None:
        robots = share / "example-robot-data" / "robots"
        for name, rel, frame in (
            ("panda", "panda_description/urdf/panda.urdf", "panda_hand_tcp"),
            ("xarm7", "xarm_description/urdf/xarm7.urdf", "link_eef"),
        ):
            arms.append((name, PinRobot.load(robots / rel, (robots, share)), frame, None, None))
    return arms


def bench_arm(
    robot: PinRobot, frame: str, lower: Any, upper: Any, n: int, seed: int
) -> dict[str, Any]:
    chain = chain_to(robot, frame)
    idx = [j.q_index for j in chain.joints]
    lo = np.maximum(robot.model.lowerPositionLimit[idx], -np.pi) if lower is None else lower
    hi = np.minimum(robot.model.upperPositionLimit[idx], np.pi) if upper is None else upper
    rng = np.random.default_rng(seed)
    _, targets = chain_fk(chain, rng.uniform(lo, hi, (n, chain.dof)))
    t0 = time.perf_counter()
    result = numeric_ik(chain, targets, lo, hi, seed=seed)
    seconds = time.perf_counter() - t0
    _, reached = chain_fk(chain, result.q)
    err = np.abs(pose_error(targets, reached)[result.ok])
    within = bool(np.all((result.q >= lo - 1e-12) & (result.q <= hi + 1e-12)))
    return {
        "dof": chain.dof,
        "poses": n,
        "success_rate": result.success_rate,
        "max_error": float(err.max()) if len(err) else None,
        "within_limits": within,
        "poses_per_second": n / seconds,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="100 poses per arm: seconds")
    ap.add_argument("--poses", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    n = 100 if args.quick else args.poses
    out: dict[str, Any] = {"arms": {}}
    print(f"{'arm':8} {'dof':>3} {'poses':>6} {'solved':>8} {'max err':>9} {'poses/s':>8}")
    for name, robot, frame, lo, hi in _arms():
        row = bench_arm(robot, frame, lo, hi, n, args.seed)
        out["arms"][name] = row
        print(
            f"{name:8} {row['dof']:>3} {n:>6} {row['success_rate']:>8.2%} "
            f"{row['max_error'] or 0.0:>9.1e} {row['poses_per_second']:>8.0f}"
        )
    if args.quick:
        out["quick"] = True
    print(json.dumps(out))


if __name__ == "__main__":
    main()
