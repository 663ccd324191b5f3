"""Independent, domain-specific plan checkers for the teaching domains (plain Python geometry,
no solver code), and the list of domains and algorithms the tests run."""

from __future__ import annotations

import math
from typing import Any

import pytest

from domains.dual_arm_swap import samplers as swap
from domains.kitchen import samplers as kitchen
from domains.pick_place_2d import samplers as pp
from solvers.solution import Solution

ALGORITHMS = ("incremental", "focused", "binding", "adaptive")


def check_pick_place_2d(solution: Solution) -> None:
    """Re-run the plan on the geometry: kinematics, sweeps, overlaps, and the goal."""
    assert solution.plan is not None
    blocks, regions = pp.DEFAULT_BLOCKS, pp.DEFAULT_REGIONS
    poses: dict[str, float] = {"A": -3.0, "B": 2.7}
    conf: tuple[float, float] = (0.0, 3.0)
    held: tuple[str, Any] | None = None

    def ik(b: str, p: float, g: pp.Grasp) -> tuple[float, float]:
        return (round(p + g.dx, 3), round(blocks[b].height + pp.GRIPPER_H / 2, 3))

    for action in solution.plan:
        name, args = action.name, action.args
        if name in ("move-free", "move-holding"):
            q1, traj, q2 = args[:3]
            assert q1 == conf and traj.path[0] == q1 and traj.path[-1] == q2
            if name == "move-free":
                assert held is None and traj.shapes == (pp.gripper_shape(),)
            else:
                assert held == (args[3], args[4])
                assert pp.held_shape(blocks[args[3]], args[4]) in traj.shapes
            for other, x in poses.items():
                assert not pp.trajectory_collides(traj, blocks[other], x), (action, other)
            conf = q2
        elif name == "pick":
            b, p, g, q = args
            assert held is None and poses[b] == p and q == conf == ik(b, p, g)
            del poses[b]
            held = (b, g)
        elif name == "place":
            b, p, g, q = args
            assert held is not None and held[0] == b and q == conf == ik(b, p, g)
            for other, x in poses.items():
                gap = (blocks[b].width + blocks[other].width) / 2
                assert abs(p - x) >= gap - 1e-9, (action, other)
            poses[b] = p
            held = None
        else:
            raise AssertionError(f"unknown action {action}")
    lo, hi = regions["goal"]
    half = blocks["A"].width / 2
    assert "A" in poses and lo <= poses["A"] - half and poses["A"] + half <= hi


def check_kitchen(solution: Solution, items: tuple[str, ...] = ("cabbage", "turnip")) -> None:
    """Re-run the plan: reach, the cleaning/cooking order, the goal, and the reported cost."""
    assert solution.plan is not None
    on = dict.fromkeys(items, "shelf")
    cleaned: set[str] = set()
    cooked: set[str] = set()
    served: set[str] = set()
    conf: tuple[float, float] = (0.0, 0.0)
    holding: str | None = None
    cost = 0.0

    def reaches(q: tuple[float, float], station: str) -> bool:
        return abs(math.dist(q, kitchen.STATIONS[station]) - kitchen.REACH) < 1e-2

    for action in solution.plan:
        name, args = action.name, action.args
        if name == "move":
            assert args[0] == conf and args[0] != args[1]
            cost += round(math.dist(args[0], args[1]), 3)
            conf = args[1]
            continue
        item, station, q = args
        assert q == conf and reaches(q, station), action
        cost += 1
        if name == "pick":
            assert holding is None and on[item] == station
            on[item], holding = "", item
        elif name == "place":
            assert holding == item
            on[item], holding = station, None
        else:
            assert on[item] == station
            if name == "clean":
                assert station in ("basin", "tub")
                cleaned.add(item)
            elif name == "cook":
                assert station == "stove" and item in cleaned
                cooked.add(item)
            else:
                assert name == "serve" and station == "table" and item in cooked
                served.add(item)
    assert served == set(items)
    assert solution.cost == pytest.approx(cost, abs=1e-6)


def check_dual_arm_swap(solution: Solution) -> None:
    """Re-run the plan: reach of each arm, hand-overs, overlaps, and the swapped goal."""
    assert solution.plan is not None
    poses: dict[str, float] = {"X": -0.6, "Y": 0.6}
    holding: dict[str, str | None] = {"left": None, "right": None}
    for action in solution.plan:
        name, args = action.name, action.args
        if name == "pick":
            arm, o, p = args
            assert holding[arm] is None and poses.get(o) == p and swap.Swap.reach(arm, p)
            del poses[o]
            holding[arm] = o
        elif name == "place":
            arm, o, p = args
            assert holding[arm] == o and swap.Swap.reach(arm, p)
            assert all(abs(p - x) >= swap.WIDTH - 1e-9 for x in poses.values()), action
            poses[o] = p
            holding[arm] = None
        elif name == "handover":
            source, target, o = args
            assert source != target and holding[source] == o and holding[target] is None
            holding[source], holding[target] = None, o
        else:
            raise AssertionError(f"unknown action {action}")
    assert poses == {"X": 0.6, "Y": -0.6}


CHECKS = {
    "pick_place_2d": check_pick_place_2d,
    "kitchen": check_kitchen,
    "dual_arm_swap": check_dual_arm_swap,
}
