"""The shipped cells written in the per-arm form (scene v2): two Franka Pandas facing each
other, two side by side, and a UR5e with a UR10e.

Their workspaces are checked reachable top-down by every arm within the cell's limits (a
coarse grid here; ``benchmarks/bench_cells.py`` checks the 2 cm grid). Loading them with
:func:`sdar_tamp.world.scene.load_scene` needs the per-arm keys; until the scene reader takes
them, that test skips and says so.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from sdar_tamp.world._pin import PinRobot, chain_to
from sdar_tamp.world.cell_reach import grid, reached
from sdar_tamp.world.finger_geometry import finger_geometry
from sdar_tamp.world.graspability import grasp_problem
from sdar_tamp.world.scene import domain_path, load_scene

CELLS = domain_path("cells")
NAMES = ("panda_facing", "panda_side_by_side", "mixed_ur5e_ur10e")


def _bench() -> object:
    import importlib.util

    path = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_cells.py"
    spec = importlib.util.spec_from_file_location("bench_cells", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("name", NAMES)
def test_cell_arms_match_their_robots(name: str) -> None:
    """Joints named in order of the chain, limits within the URDF's, home within the limits,
    the TCP offset equal to the URDF's ``tcp`` frame, the fingers' opening the gripper's."""
    path = CELLS / f"{name}.yaml"
    cell = yaml.safe_load(path.read_text(encoding="utf-8"))
    assert len(cell["arms"]) == 2
    for arm in cell["arms"]:
        robot = PinRobot.load(path.parent / arm["robot"])
        chain = chain_to(robot, arm["tool_frame"])
        assert arm["joints"] == [j.name for j in chain.joints]
        for joint, (lo, hi) in arm["joint_limits"].items():
            i = arm["joints"].index(joint)
            assert robot.model.lowerPositionLimit[chain.joints[i].q_index] <= lo < hi
            assert hi <= robot.model.upperPositionLimit[chain.joints[i].q_index]
        bounds = {j: arm["joint_limits"].get(j) for j in arm["joints"]}
        for joint, value in zip(arm["joints"], arm["home"], strict=True):
            if bounds[joint] is not None:
                assert bounds[joint][0] <= value <= bounds[joint][1], (name, joint)
        gripper = arm.get("gripper", cell.get("gripper"))
        T_tool_tcp = np.linalg.inv(
            robot.frame_pose(np.zeros(robot.nq), robot.frame_id(arm["tool_frame"]))
        ) @ robot.frame_pose(np.zeros(robot.nq), robot.frame_id("tcp"))
        expected = np.eye(4)
        expected[2, 3] = gripper["tcp_offset"]
        np.testing.assert_allclose(T_tool_tcp, expected, atol=1e-12)
        fingers = finger_geometry(robot, gripper["fingers"])
        assert fingers.opening == gripper["max_opening"] <= gripper["stroke"]
    scene = load_scene(path)
    assert grasp_problem(tuple(cell["object_size"]), scene.grasp_limits) is None


@pytest.mark.parametrize("name", NAMES)
def test_cell_workspace_is_reached_by_every_arm(name: str) -> None:
    path = CELLS / f"{name}.yaml"
    bench = _bench()
    cell, arms = bench.cell_arms(path)  # type: ignore[attr-defined]
    ws = cell["workspace"]
    points = grid(tuple(ws["x"]), tuple(ws["y"]), 0.1)
    for arm_name, arm in arms:
        ok = reached(arm, points, cell["object_size"][2] / 2, (0.0, np.pi / 2))
        assert ok.all(), (name, arm_name, points[~ok].tolist())


@pytest.mark.parametrize("name", NAMES)
def test_cell_loads_as_a_scene(name: str) -> None:
    scene = load_scene(CELLS / f"{name}.yaml")
    assert len(scene.arms) == 2
