"""``--scene`` on generate, solve, validate and bench: a cell file replaces the instance's."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import yaml

from sdar_tamp.cli import main
from sdar_tamp.errors import ParameterError
from sdar_tamp.evaluation.runner import run_bench
from sdar_tamp.evaluation.settings import SettingsMismatch, read_settings
from sdar_tamp.world.instance import load_instance
from sdar_tamp.world.scene import default_scene_path, domain_path, load_scene


def _cell(folder: Path, name: str, **changes: Any) -> Path:
    """The shipped cell with its workspace narrowed (and ``changes`` to the left arm)."""
    data: dict[str, Any] = yaml.safe_load(default_scene_path().read_text(encoding="utf-8"))
    data["robot"] = str(domain_path("robots/ur5e_2f85.urdf"))
    data["workspace"] = {"x": [-0.15, 0.15], "y": [0.0, 0.25]}
    data["arms"][0].update(changes)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def solved(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    """A 2-object instance generated in a narrowed cell, solved: (cell, instance, plan)."""
    root = tmp_path_factory.mktemp("cell")
    cell = _cell(root / "cells", "narrow.yaml")
    instance = root / "suite" / "R2.yaml"
    instance.parent.mkdir()
    argv = ["generate", "--family", "R", "--objects", "2", "--seed", "1", "-o", str(instance)]
    assert main([*argv, "--scene", str(cell)]) == 0
    plan = root / "plan.json"
    assert main(["solve", str(instance), "-o", str(plan), "-q"]) == 0
    return cell, instance, plan


def test_generate_inside_the_cell_names_it(solved: tuple[Path, Path, Path]) -> None:
    cell, path, _ = solved
    instance = load_instance(path)
    assert instance.scene == "../cells/narrow.yaml"
    assert instance.scene_path(path) is not None
    assert instance.scene_path(path).resolve() == cell.resolve()  # type: ignore[union-attr]
    ws = load_scene(cell).workspace
    assert (instance.workspace.x, instance.workspace.y) == (ws.x, ws.y)
    for o in instance.objects:
        for pose in (o.start, o.goal):
            assert ws.x[0] < pose.x < ws.x[1] and ws.y[0] < pose.y < ws.y[1]


def test_validate_replays_in_the_scene_it_is_given(
    solved: tuple[Path, Path, Path], capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    cell, instance, plan = solved
    assert main(["validate", str(instance), str(plan), "--scene", str(cell)]) == 0
    assert "valid:" in capsys.readouterr().out
    moved = _cell(tmp_path, "moved.yaml", base={"xyz": [-0.50, 0.0, 0.0], "yaw": 0.0})
    assert main(["validate", str(instance), str(plan), "--scene", str(moved)]) == 1
    assert "invalid at" in capsys.readouterr().out


def test_solve_with_a_scene_that_does_not_load(
    solved: tuple[Path, Path, Path], capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    _, instance, _ = solved
    assert main(["solve", str(instance), "-q", "--scene", str(tmp_path / "none.yaml")]) == 2
    assert "none.yaml:1:1: cannot read file" in capsys.readouterr().err
    small = _cell(tmp_path, "small.yaml")
    text = small.read_text(encoding="utf-8").replace("max_opening: 0.06", "max_opening: 0.03")
    small.write_text(text, encoding="utf-8")
    assert main(["solve", str(instance), "-q", "--scene", str(small)]) == 2
    assert "small.yaml:" in capsys.readouterr().err


def test_solve_with_another_scene(solved: tuple[Path, Path, Path], tmp_path: Path) -> None:
    """The left arm 5 cm closer: the plan is made (and validated) in that cell."""
    _, instance, _ = solved
    moved = _cell(tmp_path, "moved.yaml", base={"xyz": [-0.50, 0.0, 0.0], "yaw": 0.0})
    plan = tmp_path / "plan.json"
    assert main(["solve", str(instance), "-q", "-o", str(plan), "--scene", str(moved)]) == 0
    arms = json.loads(plan.read_text(encoding="utf-8"))["arms"]
    assert arms[0]["T_world_base"][0][3] == pytest.approx(-0.50)
    assert main(["validate", str(instance), str(plan), "--scene", str(moved)]) == 0


def test_bench_records_the_scene(solved: tuple[Path, Path, Path], tmp_path: Path) -> None:
    cell, instance, _ = solved
    out = tmp_path / "bench"
    run_bench(instance.parent, out, "sdar", progress=False, scene=cell)
    record = read_settings(out)
    assert record is not None and record.scene.startswith(f"{cell.resolve()} sha256:")
    assert "R2,R,2,sdar," in (out / "results.csv").read_text(encoding="utf-8")
    with pytest.raises(SettingsMismatch, match="scene the instances' own"):
        run_bench(instance.parent, out, "sdar", progress=False)
    with pytest.raises(ParameterError, match="process backend only"):
        run_bench(instance.parent, tmp_path / "ray", "sdar", scene=cell, backend="ray")


def test_sdar_bench_takes_the_scene_option(
    solved: tuple[Path, Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cell, instance, _ = solved
    out = tmp_path / "bench"
    argv = ["bench", "--suite", str(instance.parent), "-o", str(out), "--combos", "sdar", "-q"]
    assert main([*argv, "--scene", str(cell)]) == 0
    record = read_settings(out)
    assert record is not None and str(cell.resolve()) in record.scene


def test_generate_checks_objects_against_the_cells_gripper(tmp_path: Path) -> None:
    """A cell with a wider gripper and object: instances the shipped gripper could not hold
    are generated for it, and load against its grippers only."""
    from sdar_tamp.world.errors import InstanceError
    from sdar_tamp.world.instance_files import generate

    cell = _cell(tmp_path, "wide.yaml")
    data = yaml.safe_load(cell.read_text(encoding="utf-8"))
    data["gripper"].update(max_opening=0.09, stroke=0.09)
    data["object_size"] = [0.08, 0.07, 0.05]
    cell.write_text(yaml.safe_dump(data), encoding="utf-8")
    path = generate("R", 2, 0, tmp_path / "R2.yaml", scene=cell)
    with pytest.raises(InstanceError, match="cannot be grasped"):
        load_instance(path)
    instance = load_instance(path, load_scene(cell).grasp_limits)
    assert {o.size for o in instance.objects} == {(0.08, 0.07, 0.05)}
