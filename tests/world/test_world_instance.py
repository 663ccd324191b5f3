from __future__ import annotations

from pathlib import Path

import pytest

from sdar_tamp.world.errors import InstanceError
from sdar_tamp.world.instance import (
    Instance,
    ObjectSpec,
    Pose2D,
    dump_instance,
    load_instance,
    parse_instance,
    save_instance,
)
from sdar_tamp.world.scene import Scene, Workspace

HEAD = "name: T\nworkspace: {x: [-0.25, 0.25], y: [-0.3, 0.3]}\nobjects:\n"


def _obj(name: str, start: str, goal: str, size: str = "[0.08, 0.04, 0.05]") -> str:
    return f"  - {{name: {name}, size: {size}, start: {start}, goal: {goal}}}\n"


def test_round_trip(tmp_path: Path) -> None:
    inst = Instance(
        "X3",
        Workspace((-0.25, 0.25), (-0.3, 0.3)),
        (
            ObjectSpec("a", (0.08, 0.04, 0.05), Pose2D(0.1, 0.1 / 3, 0.3), Pose2D(-0.1, 0.0, -1.2)),
            ObjectSpec("b", (0.05, 0.05, 0.05), Pose2D(-0.1, -0.2, 0.0), Pose2D(0.1, 0.2, 1e-17)),
        ),
        scene="scene.yaml",
        family="R",
        seed=3,
    )
    path = save_instance(inst, tmp_path / "sub" / "x3.yaml")
    again = load_instance(path)
    assert again == inst
    assert dump_instance(again) == path.read_text()
    assert again.scene_path(path) == tmp_path / "sub" / "scene.yaml"


def test_valid_text_parses() -> None:
    inst = parse_instance(HEAD + _obj("o0", "[0, 0, 0]", "[0.1, 0.1, 1.5]"))
    assert inst.names == ("o0",) and inst.scene is None
    assert inst.start_poses().shape == (1, 3)


def test_touching_footprints_are_allowed() -> None:
    inst = parse_instance(
        HEAD + _obj("a", "[0, 0, 0]", "[0, 0, 0]") + _obj("b", "[0.08, 0, 0]", "[0, 0.04, 0]")
    )
    assert inst.names == ("a", "b")
    assert inst.objects[1].start == Pose2D(0.08, 0.0, 0.0)
    assert inst.objects[1].goal == Pose2D(0.0, 0.04, 0.0)
    # one millimetre closer, the same two footprints overlap
    with pytest.raises(InstanceError, match="overlaps"):
        parse_instance(
            HEAD + _obj("a", "[0, 0, 0]", "[0, 0, 0]") + _obj("b", "[0.079, 0, 0]", "[0, 0.04, 0]")
        )


def test_overlap_at_start() -> None:
    text = HEAD + _obj("a", "[0, 0, 0]", "[0, 0, 0]") + _obj("b", "[0.05, 0, 0]", "[0, 0.1, 0]")
    with pytest.raises(InstanceError, match=r"object 'a': start footprint overlaps .* of 'b'"):
        parse_instance(text, "inst.yaml")


def test_overlap_at_goal() -> None:
    text = (
        HEAD + _obj("a", "[0, 0, 0]", "[0, 0.1, 0.4]") + _obj("b", "[0, 0.1, 0]", "[0.02, 0.1, 0]")
    )
    with pytest.raises(
        InstanceError, match="'a': goal footprint overlaps the goal footprint of 'b'"
    ):
        parse_instance(text, "inst.yaml")


def test_outside_workspace() -> None:
    text = HEAD + _obj("a", "[0, 0, 0]", "[0.23, 0, 0]")
    with pytest.raises(InstanceError, match=r"inst.yaml:4:5: object 'a': goal footprint leaves"):
        parse_instance(text, "inst.yaml")


def test_ungraspable_size() -> None:
    text = HEAD + _obj("big", "[0, 0, 0]", "[0, 0, 0]", size="[0.1, 0.09, 0.05]")
    with pytest.raises(InstanceError, match=r"object 'big': size .* cannot be grasped"):
        parse_instance(text, "inst.yaml")


def test_an_object_too_short_to_hold_is_refused_with_its_place_and_reason() -> None:
    text = (
        HEAD
        + _obj("ok", "[0, 0.2, 0]", "[0, 0.2, 0]")
        + _obj("flat", "[0, 0, 0]", "[0, 0, 0]", size="[0.08, 0.04, 0.008]")
    )
    with pytest.raises(
        InstanceError,
        match=r"inst.yaml:5:\d+: object 'flat': size .* cannot be grasped: height 0.008 m is too "
        r"short: .* expected a height >= 0.013 m",
    ):
        parse_instance(text, "inst.yaml")


def test_a_cube_as_wide_as_the_gripper_allows_and_a_short_bar_load(scene: Scene) -> None:
    """The loader and the grasp sampler share one width tolerance: the scene's graspable
    width (0.06 - 0.01, a hair under 0.05 m) accepts a 0.05 m cube."""
    text = HEAD + _obj("cube", "[0, 0, 0]", "[0, 0.2, 0]", size="[0.05, 0.05, 0.05]")
    text += _obj("bar", "[0.15, 0, 0]", "[0.15, 0.2, 0]", size="[0.08, 0.04, 0.03]")
    assert parse_instance(text, "inst.yaml", grasp=scene.grasp_limits).names == ("cube", "bar")


def test_duplicate_names() -> None:
    text = HEAD + _obj("a", "[0, 0, 0]", "[0, 0, 0]") + _obj("a", "[0, 0.2, 0]", "[0, 0.2, 0]")
    with pytest.raises(InstanceError, match="object 'a': duplicate name"):
        parse_instance(text, "inst.yaml")


def test_bad_shape_names_file_and_key() -> None:
    text = HEAD + "  - {name: a, size: [0.08, 0.04, 0.05], start: [0, 0], goal: [0, 0, 0]}\n"
    with pytest.raises(
        InstanceError, match=r"inst.yaml:4:\d+: objects\[0\]\.start: expected \[x, y, yaw\]"
    ):
        parse_instance(text, "inst.yaml")


def test_missing_and_unknown_keys() -> None:
    with pytest.raises(InstanceError, match="expected key 'objects'"):
        parse_instance("name: T\nworkspace: {x: [0, 1], y: [0, 1]}\n", "inst.yaml")
    with pytest.raises(InstanceError, match=r"objects\[0\]\.colour: unknown key"):
        parse_instance(HEAD + "  - {name: a, colour: red}\n", "inst.yaml")


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(InstanceError, match="cannot read file"):
        load_instance(tmp_path / "none.yaml")


def test_bad_object_name() -> None:
    text = HEAD + _obj("'a b'", "[0, 0, 0]", "[0, 0, 0]")
    with pytest.raises(InstanceError, match="object 'a b': expected a name of letters"):
        parse_instance(text, "inst.yaml")


def test_a_relative_scene_resolves_against_the_file_read_whatever_the_working_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An instance read from a file finds its cell next to that file, also where a caller
    does not pass the file again (the validator's default scene)."""
    import os

    from sdar_tamp.plan_reading import load_plan
    from sdar_tamp.replay import validate_plan

    root = Path(__file__).parents[2]
    cell = root / "domains" / "dual_arm_rearrangement" / "cells" / "ur5e_facing.yaml"
    folder = tmp_path / "made" / "here"
    folder.mkdir(parents=True)
    text = (
        root / "domains" / "dual_arm_rearrangement" / "suites" / "paper" / "D5.yaml"
    ).read_text()
    key = os.path.relpath(cell, folder)
    (folder / "D5.yaml").write_text(f"scene: {key}\n{text}")
    elsewhere = tmp_path / "a" / "b" / "c" / "d"
    elsewhere.mkdir(parents=True)
    monkeypatch.chdir(elsewhere)  # the key read from the working folder names no file
    instance = load_instance(folder / "D5.yaml")
    assert instance.scene == key and instance.source == folder / "D5.yaml"
    assert instance.scene_path() == folder / key and instance.scene_path().is_file()
    assert not Path(key).is_file()
    plan = load_plan(root / "tests" / "plan" / "solved" / "D5.plan.json")
    assert validate_plan(instance, plan).ok
    assert instance == load_instance(folder / "D5.yaml")  # the source is not part of the value
