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

``--planner``: instead, the planner's load in the Panda cell (``panda_facing.yaml``): the first
six grasps of the default object at random poses of the workspace, solved pose by pose for
the left arm as the IK stream asks (:func:`~sdar_tamp.world.numeric_ik.numeric_ik_branches`,
four solutions per grasp), with the planner's options
(:data:`~sdar_tamp.world.kinematics.NUMERIC_OPTIONS`) and with the default options (the
null-space pull, 100 iterations, 4 rounds), both descending with numpy, then with the
planner's options and the compiled descent (:mod:`~sdar_tamp.world.ik_kernel`, the planner's
own), one after the other on the same poses: CPU time and descent iterations per pose (numpy
only), grasps solved, solutions found and how far the first one is from the home [rad]. With
``--quick``, 10 poses.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from sdar_tamp.world import numeric_ik as numeric_module
from sdar_tamp.world._pin import PinRobot, chain_to
from sdar_tamp.world.kinematics import NUMERIC_BRANCHES, NUMERIC_OPTIONS, ArmKinematics
from sdar_tamp.world.numeric_ik import (
    NumericIKOptions,
    chain_fk,
    numeric_ik,
    numeric_ik_branches,
    pose_error,
)
from sdar_tamp.world.scene import load_scene
from sdar_tamp.world.transforms import inverse, pose_xyz_yaw
from sdar_tamp.world.urdf import example_robot_data_share
from streams.grasps import sample_grasps


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


PANDA_CELL = (
    Path(__file__).resolve().parents[1] / "domains/dual_arm_rearrangement/cells/panda_facing.yaml"
)


def bench_planner(n: int, seed: int) -> dict[str, Any]:
    """The planner's options against the default ones on grasp poses of the Panda cell."""
    scene = load_scene(PANDA_CELL)
    kin = ArmKinematics.from_scene(scene, scene.arms[0].name)
    grasps = sample_grasps((0.08, 0.04, 0.05), scene.grasp_limits)[:6]
    rng = np.random.default_rng(seed)
    ws = scene.workspace
    T_root = inverse(kin.T_world_base)
    T_tcp_tool0 = inverse(kin.T_tool0_tcp)
    poses = [
        T_root
        @ pose_xyz_yaw(rng.uniform(*ws.x), rng.uniform(*ws.y), 0.025, rng.uniform(-np.pi, np.pi))
        @ np.stack([g.T_object_tcp for g in grasps])
        @ T_tcp_tool0
        for _ in range(n)
    ]
    lo, hi, home = kin.spec.lower_array, kin.spec.upper_array, np.asarray(kin.spec.home)
    out: dict[str, Any] = {}
    fk = numeric_module.chain_fk
    for name, opts in (
        ("planner", replace(NUMERIC_OPTIONS, compiled=False)),
        ("default", NumericIKOptions(rounds=4, iterations=100, compiled=False)),
        ("compiled", NUMERIC_OPTIONS),
    ):
        calls = [0]

        def counting(chain: Any, q: Any, calls: list[int] = calls) -> Any:
            calls[0] += 1
            return fk(chain, q)

        numeric_module.chain_fk = counting  # type: ignore[assignment]
        try:
            t0 = time.process_time()
            solved = [
                numeric_ik_branches(kin.chain, T, lo, hi, home, NUMERIC_BRANCHES, opts)
                for T in poses
            ]
            seconds = time.process_time() - t0
        finally:
            numeric_module.chain_fk = fk  # type: ignore[assignment]
        q = np.concatenate([s[0] for s in solved])
        ok = np.concatenate([s[1] for s in solved])
        first = np.linalg.norm(q[:, 0] - home, axis=1)[ok[:, 0]]
        out[name] = {
            "cpu_ms_per_pose": 1000.0 * seconds / n,
            # the compiled descent does not call chain_fk: its iterations are not counted
            "iterations_per_pose": calls[0] / n if calls[0] else None,
            "grasps_solved": int(ok.any(axis=1).sum()),
            "grasps": len(ok),
            "solutions": int(ok.sum()),
            "first_from_home_mean": float(first.mean()) if len(first) else None,
        }
    return out


def _iterations(row: dict[str, Any]) -> str:
    it = row["iterations_per_pose"]
    return "-" if it is None else f"{it:.1f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="100 poses per arm: seconds")
    ap.add_argument("--poses", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--planner", action="store_true", help="the planner's options (see above)")
    args = ap.parse_args()
    if args.planner:
        n = 10 if args.quick else 40
        result = bench_planner(n, args.seed)
        print(f"{'options':8} {'cpu ms/pose':>11} {'iter/pose':>9} {'grasps':>9} {'sols':>5} "
              f"{'from home':>9}")  # fmt: skip
        for name, row in result.items():
            print(
                f"{name:8} {row['cpu_ms_per_pose']:>11.1f} {_iterations(row):>9} "
                f"{row['grasps_solved']:>4}/{row['grasps']:<4} {row['solutions']:>5} "
                f"{row['first_from_home_mean'] or 0.0:>9.3f}"
            )
        print(json.dumps({"planner": result, "poses": n, "quick": args.quick}))
        return
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
