"""The four cells of the shared 1.2 m x 1.0 m table: one to four UR5e arms, one workspace."""

from __future__ import annotations

import numpy as np
import pytest

from sdar_tamp.cli import main
from sdar_tamp.world.cell_reach import uncovered_points, unreached_points
from sdar_tamp.world.cells import cell_path
from sdar_tamp.world.scene import load_scene

TABLE_CELLS = {k: f"ur5e_table_{k}arm" for k in (1, 2, 3, 4)}


def test_the_table_cells_share_the_table_workspace_and_first_arms() -> None:
    scenes = {k: load_scene(cell_path(name)) for k, name in TABLE_CELLS.items()}
    for k, scene in scenes.items():
        assert len(scene.arms) == k
        assert scene.table.size[:2] == (1.20, 1.00)
        assert scene.workspace == scenes[1].workspace
        assert scene.arm_names == ("south", "north", "west", "east")[:k]
        for arm in scene.arms:  # every base off the table, beside it
            x, y = arm.base_xyz[:2]
            assert abs(x) > 0.6 or abs(y) > 0.5, arm.name


def test_the_one_arm_reaches_the_whole_workspace() -> None:
    scene = load_scene(cell_path(TABLE_CELLS[1]))
    missed = unreached_points(scene, 0.05)
    assert list(missed) == ["south"] and len(missed["south"]) == 0


@pytest.mark.parametrize("k", [2, 3, 4])
def test_every_point_is_reached_by_some_arm(k: int) -> None:
    scene = load_scene(cell_path(TABLE_CELLS[k]))
    missed = unreached_points(scene, 0.1)
    assert len(uncovered_points(missed)) == 0
    if k >= 3:  # the side arms keep to their own side of the table
        west = missed["west"]
        assert len(west) and np.all(west[:, 0] > 0.0)
    if k == 4:
        assert np.all(missed["east"][:, 0] < 0.0)


def test_uncovered_points_are_those_no_arm_reaches() -> None:
    a = np.array([[0.0, 0.0], [0.1, 0.0]])
    b = np.array([[0.1, 0.0], [0.2, 0.0]])
    np.testing.assert_array_equal(uncovered_points({"a": a, "b": b}), [[0.1, 0.0]])
    assert uncovered_points({"a": a, "b": np.zeros((0, 2))}).shape == (0, 2)
    assert uncovered_points({}).shape == (0, 2)


def test_sdar_cells_reach_by_at_least_one_arm(capsys: pytest.CaptureFixture[str]) -> None:
    path = cell_path(TABLE_CELLS[3])
    assert main(["cells", str(path), "--reach", "0.1"]) == 0
    out = capsys.readouterr().out
    assert "is grasped top-down by at least one arm" in out and "west " in out
    assert main(["cells", str(path), "--reach", "0.1", "--every-arm"]) == 2
    assert "workspace: arm 'west' does not grasp (" in capsys.readouterr().err
