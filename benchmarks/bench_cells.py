"""Top-down reach of the shipped cells: does every arm reach every point of its cell's
workspace, and how the base poses were chosen.

For each cell file of ``domains/dual_arm_rearrangement/cells/`` that names its robots per arm,
every point of the workspace on a grid (2 cm) is checked with
:func:`sdar_tamp.world.cell_reach.reached`: the TCP pointing down at the default object's
centre height, at the yaws 0, 45, 90 and 135 deg (or those plus 180 deg), the approach 0.08 m
above it too, every joint within the cell's limits, no contact of the arm with itself or the
table. Printed per cell and arm: the share of workspace points reached, the first points
missed; then the share reached by all arms.

``--layout panda|ur``: the computation the cells' layouts were chosen by. For each robot a reach map
in its own base frame (4 cm grid, its URDF limits, home as in the cell); then, for candidate
base layouts on the table (two Pandas side by side on one edge at several spacings and
inward turns, the rectangle in front of the bases, or facing each other at several distances;
a UR5e facing a UR10e at several distances), the largest axis-aligned rectangle every arm
reaches, and its area. ``--limits CELL``: the joint ranges
the cell's workspace needs with the URDF's limits, and the narrowed limits they suggest.

    python benchmarks/bench_cells.py             # the shipped cells' workspaces, 2 cm grid
    python benchmarks/bench_cells.py --layout panda   # the layout search (minutes; or ur)
    python benchmarks/bench_cells.py --limits panda_facing   # joint ranges used
    python benchmarks/bench_cells.py --quick     # 10 cm grid, two yaws: seconds
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from sdar_tamp.world._pin import PinRobot, chain_to
from sdar_tamp.world.cell_reach import (
    DEFAULT_YAWS,
    ReachArm,
    grid,
    largest_rectangle,
    reached,
    solve_top_down,
)
from sdar_tamp.world.scene import domain_path
from sdar_tamp.world.transforms import inverse, pose_xyz_yaw

CELLS = ("panda_facing", "panda_side_by_side", "mixed_ur5e_ur10e")


def cell_arms(path: Path) -> tuple[dict[str, Any], list[tuple[str, ReachArm]]]:
    """The cell file (read as plain YAML) and its arms, for the reach check."""
    cell = yaml.safe_load(path.read_text(encoding="utf-8"))
    arms = []
    for spec in cell["arms"]:
        robot = PinRobot.load(path.parent / spec.get("robot", cell.get("robot")))
        tool = spec.get("tool_frame", "tool0")
        chain = chain_to(robot, tool)
        names = [j.name for j in chain.joints]
        if spec.get("joints", names) != names:
            raise SystemExit(f"{path.name}: {spec['name']}: joints {spec['joints']} != {names}")
        idx = [j.q_index for j in chain.joints]
        lo = robot.model.lowerPositionLimit[idx].copy()
        hi = robot.model.upperPositionLimit[idx].copy()
        for name, (a, b) in spec.get("joint_limits", {}).items():
            i = names.index(name if name in names else f"{name}_joint")
            lo[i], hi[i] = a, b
        gripper = spec.get("gripper", cell.get("gripper"))
        (x, y, z), yaw = spec["base"]["xyz"], spec["base"]["yaw"]
        T = pose_xyz_yaw(x, y, z, yaw)
        home = np.array(spec["home"], dtype=float)
        arms.append((spec["name"], ReachArm(robot, T, tool, gripper["tcp_offset"], lo, hi, home)))
    return cell, arms


def check_cell(path: Path, step: float, yaws: tuple[float, ...]) -> dict[str, Any]:
    cell, arms = cell_arms(path)
    ws = cell["workspace"]
    points = grid(tuple(ws["x"]), tuple(ws["y"]), step)
    z = cell["object_size"][2] / 2.0
    every = np.ones(len(points), dtype=bool)
    out: dict[str, Any] = {"points": len(points), "arms": {}}
    for name, arm in arms:
        ok = reached(arm, points, z, yaws)
        every &= ok
        missed = [[round(float(v), 3) for v in p] for p in points[~ok][:5]]
        out["arms"][name] = {"reached": float(ok.mean()), "missed": missed}
    out["reached_by_all"] = float(every.mean())
    return out


# --- the layout search -------------------------------------------------------------------

PANDA_READY = (0.0, -np.pi / 4, 0.0, -3 * np.pi / 4, 0.0, np.pi / 2, np.pi / 4)
UR_HOME = (0.0, -2.2, 1.9, -1.383, -1.57, 0.0)
UR_LOWER = (-1.57, -np.pi, 0.0, -np.pi, -np.pi, -np.pi)
UR_UPPER = (1.57, np.pi, np.pi, 0.0, np.pi, np.pi)


def _reach_map(urdf: str, tcp: float, limits: Any, home: Any, radius: float) -> Any:
    """Points ``(n, 2)`` of the robot's base frame within ``radius`` [m] and which it
    reaches (4 cm grid, the default object height)."""
    robot = PinRobot.load(domain_path(urdf))
    if limits is None:
        limits = (robot.model.lowerPositionLimit.copy(), robot.model.upperPositionLimit.copy())
    arm = ReachArm(robot, np.eye(4), "tool0", tcp, np.array(limits[0]), np.array(limits[1]),
                   np.array(home))  # fmt: skip
    pts = grid((-0.2, radius), (-radius, radius), 0.04)
    pts = pts[np.hypot(pts[:, 0], pts[:, 1]) <= radius]
    return pts, reached(arm, pts, 0.025)


def _lookup(reach: Any, T_world_base: Any, world: Any) -> Any:
    """Whether the map's nearest grid point to each world point ``(m, 2)`` is reached."""
    pts, ok = reach
    local = (inverse(T_world_base) @ np.c_[world, np.zeros(len(world)), np.ones(len(world))].T).T
    d = np.linalg.norm(local[:, None, :2] - pts[None], axis=2)
    near = d.argmin(axis=1)
    return ok[near] & (d[np.arange(len(world)), near] <= 0.03)


def _best(maps: list[Any], bases: list[Any], y_min: float = -1.0) -> tuple[float, Any]:
    """The largest rectangle (4 cm grid, ``y >= y_min`` [m]) every arm reaches: area [m^2]
    and ``[[x0, x1], [y0, y1]]``."""
    xs, ys = np.arange(-1.0, 1.0001, 0.04), np.arange(y_min, 1.0001, 0.04)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    world = np.stack([X.ravel(), Y.ravel()], axis=1)
    ok = np.ones(len(world), dtype=bool)
    for reach, T in zip(maps, bases, strict=True):
        ok &= _lookup(reach, T, world)
    rect = largest_rectangle(ok.reshape(len(xs), len(ys)), xs, ys)
    if rect is None:
        return 0.0, None
    (x0, x1), (y0, y1) = rect
    area = round((x1 - x0) * (y1 - y0), 3)
    return area, [[round(x0, 2), round(x1, 2)], [round(y0, 2), round(y1, 2)]]


def layout_search(robots: str) -> dict[str, Any]:
    """Candidate layouts of two Pandas (``robots == "panda"``) or of a UR5e and a UR10e
    (``"ur"``) and the largest rectangle each gives."""
    rows: list[dict[str, Any]] = []
    if robots == "panda":
        panda = _reach_map("robots/panda_hand.urdf", 0.1034, None, PANDA_READY, 0.9)
        # side by side on the edge y = -0.4, facing +y, turned by `toe` [rad] toward the
        # other arm; the rectangle in front of the bases (y >= -0.3)
        for toe in (0.0, 0.25, 0.5):
            for spacing in (0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0):
                bases = [pose_xyz_yaw(s * spacing / 2, -0.4, 0.0, np.pi / 2 + s * toe)
                         for s in (-1, 1)]  # fmt: skip
                area, rect = _best([panda, panda], bases, y_min=-0.3)
                rows.append({"cell": "panda side by side", "spacing": spacing, "toe": toe,
                             "area": area, "rect": rect})  # fmt: skip
        for distance in (0.8, 0.9, 1.0, 1.1, 1.2):  # facing each other across the table
            bases = [pose_xyz_yaw(s * distance / 2, 0.0, 0.0, np.pi * (s > 0)) for s in (-1, 1)]
            area, rect = _best([panda, panda], bases)
            rows.append({"cell": "panda facing", "distance": distance, "area": area, "rect": rect})
    else:
        ur5e = _reach_map("robots/ur5e_2f85.urdf", 0.178, (UR_LOWER, UR_UPPER), UR_HOME, 1.0)
        ur10e = _reach_map("robots/ur10e_2f85.urdf", 0.178, (UR_LOWER, UR_UPPER), UR_HOME, 1.4)
        for x10 in (0.55, 0.65, 0.75, 0.85, 0.95):  # UR5e at x = -0.55 facing a UR10e at x10
            bases = [pose_xyz_yaw(-0.55, 0.0, 0.0, 0.0), pose_xyz_yaw(x10, 0.0, 0.0, np.pi)]
            area, rect = _best([ur5e, ur10e], bases)
            rows.append({"cell": "ur5e-ur10e facing", "ur10e_x": x10, "area": area, "rect": rect})
    return {"layouts": rows}


#: Margin [rad] kept around the joint ranges the workspace uses when limits are narrowed.
LIMIT_MARGIN = 0.35


def joint_ranges(path: Path, step: float) -> dict[str, Any]:
    """Per arm of the cell, with the URDF's limits: the joint ranges [rad] the top-down grasps
    of the workspace (grid ``step`` [m], every yaw of the check, approach included) use, and
    the narrowed limits they suggest (the range widened by :data:`LIMIT_MARGIN`, within the
    URDF's)."""
    cell, arms = cell_arms(path)
    ws = cell["workspace"]
    points = grid(tuple(ws["x"]), tuple(ws["y"]), step)
    z = cell["object_size"][2] / 2.0
    out: dict[str, Any] = {}
    for name, arm in arms:
        chain = chain_to(arm.robot, arm.tool_frame)
        idx = [j.q_index for j in chain.joints]
        lo, hi = arm.robot.model.lowerPositionLimit[idx], arm.robot.model.upperPositionLimit[idx]
        wide = ReachArm(arm.robot, arm.T_world_base, arm.tool_frame, arm.tcp_offset, lo, hi,
                        arm.home)  # fmt: skip
        used = []
        for yaw in DEFAULT_YAWS:
            for lift in (0.0, 0.08):
                sol = solve_top_down(wide, points, z + lift, yaw)
                used.append(sol.q[sol.ok])
        q = np.concatenate(used)
        low = np.maximum(q.min(axis=0) - LIMIT_MARGIN, lo)
        high = np.minimum(q.max(axis=0) + LIMIT_MARGIN, hi)
        pairs = zip(q.min(axis=0), q.max(axis=0), strict=True)
        out[name] = {
            "used": [[round(float(a), 3), round(float(b), 3)] for a, b in pairs],
            "suggested": [
                [round(float(a), 2), round(float(b), 2)] for a, b in zip(low, high, strict=True)
            ],
        }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="10 cm grid, two yaws: seconds")
    ap.add_argument("--layout", choices=("panda", "ur"), help="the layout search (minutes)")
    ap.add_argument("--limits", metavar="CELL", help="joint ranges the cell's workspace uses")
    args = ap.parse_args()
    t0 = time.perf_counter()
    out: dict[str, Any]
    if args.limits:
        out = joint_ranges(domain_path("cells") / f"{args.limits}.yaml", 0.04)
        for arm, row in out.items():
            print(arm, json.dumps(row))
    elif args.layout:
        out = layout_search(args.layout)
        for row in out["layouts"]:
            print(json.dumps(row))
    else:
        step, yaws = (0.1, (0.0, np.pi / 2)) if args.quick else (0.02, DEFAULT_YAWS)
        out = {"step": step, "cells": {}}
        for name in CELLS:
            res = check_cell(domain_path("cells") / f"{name}.yaml", step, yaws)
            out["cells"][name] = res
            rows = [(arm, row["reached"]) for arm, row in res["arms"].items()]
            for arm, share in [*rows, ("all", res["reached_by_all"])]:
                print(f"{name:20} {arm:6} {res['points']:>5} points  reached {share:.1%}")
    out["seconds"] = round(time.perf_counter() - t0, 1)
    if args.quick:
        out["quick"] = True
    print(json.dumps(out))


if __name__ == "__main__":
    main()
