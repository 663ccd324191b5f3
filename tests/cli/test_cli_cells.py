"""``sdar cells``: the shipped cells listed, a cell file checked."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.cli import main
from sdar_tamp.world.cells import cell_path, describe, shipped_cells
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.scene import default_scene_path, load_scene


def test_the_shipped_cells_are_listed_with_their_first_comment_line() -> None:
    cells = shipped_cells()
    assert "ur5e_facing" in [c.name for c in cells]
    ur5e = next(c for c in cells if c.name == "ur5e_facing")
    assert ur5e.path == default_scene_path() == cell_path("ur5e_facing")
    assert ur5e.description.startswith("Two UR5e arms facing each other")
    for cell in cells:  # every shipped cell loads and says what it is
        assert cell.description and load_scene(cell.path).arm_names
    with pytest.raises(SceneError, match=r"no shipped cell 'ur3'; the shipped cells are: .*ur5e"):
        cell_path("ur3")


def test_describe_takes_the_first_comment_only_before_any_key(tmp_path: Path) -> None:
    path = tmp_path / "c.yaml"
    path.write_text("\n#  A cell.  \n# more\nrobot: r.urdf\n", encoding="utf-8")
    assert describe(path) == "A cell."
    path.write_text("robot: r.urdf  # not a description\n# late\n", encoding="utf-8")
    assert describe(path) == ""
    path.write_text("", encoding="utf-8")
    assert describe(path) == ""


def test_sdar_cells_lists_and_checks(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert main(["cells"]) == 0
    out = capsys.readouterr().out
    assert "ur5e_facing" in out and "Two UR5e arms" in out
    assert main(["cells", str(default_scene_path())]) == 0
    out = capsys.readouterr().out
    assert "a valid cell" in out and "left: ur5e_2f85.urdf, 6 joints base_link -> tool0" in out
    bad = tmp_path / "bad.yaml"
    bad.write_text(default_scene_path().read_text(encoding="utf-8"), encoding="utf-8")
    # its robot, named relative to the cells folder, is missing here
    assert main(["cells", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "bad.yaml:4:" in err and "robot: expected a robot description file" in err


def test_sdar_show_draws_a_cell(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    out = tmp_path / "cell.png"
    assert main(["show", str(default_scene_path()), "-o", str(out)]) == 0
    assert out.stat().st_size > 10_000 and "wrote" in capsys.readouterr().out
    assert main(["show", str(default_scene_path()), "-o", str(tmp_path / "cell.html")]) == 2
    assert "a cell is drawn to one of .png" in capsys.readouterr().err


def test_the_sampled_reach_covers_the_workspace() -> None:
    """Every workspace corner has a sampled TCP of each arm within 10 cm (the shipped cell is
    chosen so that both arms reach all of it)."""
    from sdar_tamp.world.draw_cell import arm_points

    scene = load_scene()
    ws = scene.workspace
    corners = np.array([(x, y) for x in ws.x for y in ws.y])
    for arm in scene.arms:
        chain, near = arm_points(scene, arm, samples=6000)
        assert chain.shape == (arm.dof + 2, 3)
        np.testing.assert_allclose(chain[0, :2], arm.base_xyz[:2], atol=1e-9)
        gaps = np.linalg.norm(near[None, :, :2] - corners[:, None], axis=2).min(axis=1)
        assert gaps.max() < 0.1, (arm.name, gaps)


def _cell_copy(tmp_path: Path, workspace: str) -> Path:
    """The shipped cell with its robot path made absolute and another workspace line."""
    text = default_scene_path().read_text(encoding="utf-8")
    robots = default_scene_path().parent.parent / "robots"
    text = text.replace("../robots/", f"{robots}/")
    lines = [workspace if ln.startswith("workspace:") else ln for ln in text.splitlines()]
    path = tmp_path / "cell.yaml"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_sdar_cells_reach_checks_every_arm(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    assert main(["cells", str(default_scene_path()), "--reach", "0.25"]) == 0
    assert "every arm grasps all 12 workspace points" in capsys.readouterr().out
    far = _cell_copy(tmp_path, "workspace: {x: [-0.25, 0.25], y: [-0.30, 1.20]}")
    line = (
        far.read_text(encoding="utf-8")
        .splitlines()
        .index("workspace: {x: [-0.25, 0.25], y: [-0.30, 1.20]}")
        + 1
    )
    assert main(["cells", str(far), "--reach", "0.25"]) == 2
    err = capsys.readouterr().err
    assert f"cell.yaml:{line}:12: workspace: no arm grasps (" in err
    assert ") m top-down at every yaw within its limits" in err
    assert main(["cells", str(far), "--reach", "0.25", "--every-arm"]) == 2
    err = capsys.readouterr().err
    assert f"cell.yaml:{line}:12: workspace: arm 'left' does not grasp (" in err
    assert main(["cells", str(default_scene_path()), "--reach", "0"]) == 2
    assert "--reach: expected a grid step > 0 [m], got 0.0" in capsys.readouterr().err


def test_unreached_points_per_arm() -> None:
    from sdar_tamp.world.cell_reach import unreached_points
    from sdar_tamp.world.errors import KinematicsError

    missed = unreached_points(load_scene(), 0.25)
    assert set(missed) == {"left", "right"} and all(len(p) == 0 for p in missed.values())
    with pytest.raises(KinematicsError, match="step must be > 0"):
        unreached_points(load_scene(), -1.0)
