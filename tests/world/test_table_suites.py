"""The ``families`` suite kind and its shipped copies on the four cells of the shared table."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.cli import main
from sdar_tamp.world.cells import cell_path
from sdar_tamp.world.errors import SuiteError
from sdar_tamp.world.generators import GeneratorOptions, generate_instance, has_family_structure
from sdar_tamp.world.instance import load_instance
from sdar_tamp.world.scene import load_scene
from sdar_tamp.world.suites import (
    CELL_SUITES,
    FAMILY_SIZES,
    load_suite,
    shipped_suite_dir,
    suite_members,
)
from streams.buffers import reachable_top_down
from streams.context import WorldContext
from streams.feasibility import ProofCheck


def test_the_families_suite_has_four_families_at_four_sizes_twice() -> None:
    members = suite_members("families")
    assert len(members) == 32 and len({m.seed for m in members}) == 32
    assert {m.family for m in members} == set("MRDS")
    assert {m.n_objects for m in members} == set(FAMILY_SIZES) == {12, 16, 20, 24}
    assert [m.name for m in members[:3]] == ["M12-1", "M12-2", "M16-1"]
    assert all(m.gap is None for m in members)  # the generator's (grasp) clearance
    for name in CELL_SUITES:
        assert suite_members(name) == members
    with pytest.raises(SuiteError, match=r"unknown suite 'tables'; expected one of .*table_4arm"):
        suite_members("tables")
    with pytest.raises(SuiteError, match=r"no shipped copy of its own; the shipped ones are \["):
        load_suite("families")


@pytest.mark.parametrize("suite", sorted(CELL_SUITES))
def test_a_shipped_table_suite_names_its_cell_and_keeps_its_promises(suite: str) -> None:
    cell = CELL_SUITES[suite]
    scene = load_scene(cell_path(cell))
    folder = shipped_suite_dir(suite)
    instances = load_suite(suite)  # loading checks sizes, workspace and overlaps
    ctx = WorldContext.load(cell_path(cell))
    for member, inst in zip(suite_members(suite), instances, strict=True):
        assert inst.name == member.name and inst.family == member.family
        assert len(inst.objects) == member.n_objects and inst.seed == member.seed
        assert inst.workspace == scene.workspace
        assert inst.scene_path(folder / f"{inst.name}.yaml").resolve() == cell_path(cell)
        assert has_family_structure(member.family, inst), inst.name
        poses = np.concatenate([inst.start_poses(), inst.goal_poses()])
        size = inst.objects[0].size
        reached = np.zeros(len(poses), dtype=bool)
        for arm in scene.arm_names:  # every start and goal by at least one of the cell's arms
            reached |= reachable_top_down(ctx, arm, poses, size)
        assert reached.all(), (inst.name, poses[~reached])


def test_the_table_suites_hold_the_same_instances() -> None:
    first = load_suite("table_1arm")
    for suite in ("table_2arm", "table_3arm", "table_4arm"):
        for a, b in zip(first, load_suite(suite), strict=True):
            assert a.objects == b.objects and a.name == b.name


def test_a_shipped_table_instance_regenerates() -> None:
    """The command line's generation (the cell's workspace, object and acceptance test)
    gives the shipped file again."""
    cell = cell_path(CELL_SUITES["table_4arm"])
    scene = load_scene(cell)
    member = next(m for m in suite_members("families") if m.name == "D16-1")
    options = GeneratorOptions(
        size=scene.object_size, workspace=scene.workspace, grasp=scene.grasp_limits
    )
    accept = ProofCheck(WorldContext.load(cell))
    again = generate_instance(
        member.family, member.n_objects, member.seed, options, member.name, accept
    )
    shipped = load_instance(shipped_suite_dir("table_4arm") / "D16-1.yaml")
    assert again.objects == shipped.objects and again.seed == shipped.seed


def test_sdar_generate_families_in_a_cell(tmp_path: Path) -> None:
    out = tmp_path / "one.yaml"
    cell = str(cell_path("ur5e_table_3arm"))
    args = ["generate", "--scene", cell, "--family", "S", "--objects", "12", "-o", str(out)]
    assert main(args) == 0
    inst = load_instance(out)
    assert inst.workspace == load_scene(cell_path("ur5e_table_3arm")).workspace
    assert inst.scene is not None and inst.scene.endswith("ur5e_table_3arm.yaml")


def test_sdar_generate_families_needs_a_cell(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["generate", "--suite", "families", "-o", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err
    assert "sdar generate --suite families: expected --scene CELL" in err
    assert not (tmp_path / "s").exists() or not any((tmp_path / "s").iterdir())
