"""Instances carried as text: packed on one machine, unpacked on another with the same layout."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from sdar_tamp.evaluation.payload import InstanceFiles, PayloadError, pack, unpack
from sdar_tamp.evaluation.suite import suite_entries
from sdar_tamp.resources import domain_file
from sdar_tamp.world.instance import load_instance
from sdar_tamp.world.scene import load_scene


def test_a_shipped_instance_travels_alone(tmp_path: Path) -> None:
    source = suite_entries("paper", only=["R4"])[0].path
    files = pack(source)
    assert files.instance == "R4.yaml" and [n for n, _ in files.files] == ["R4.yaml"]
    path = unpack(files, tmp_path)
    assert path.read_text() == source.read_text()
    assert load_instance(path) == load_instance(source)
    assert unpack(files, tmp_path) == path  # same files, same place: the world is reused


def _custom_suite(tmp_path: Path) -> Path:
    """An instance in suite/ whose scene (and robot) sit in scenes/."""
    scenes = tmp_path / "scenes"
    scenes.mkdir(parents=True)
    shipped = domain_file("dual_arm_rearrangement", "cells/ur5e_facing.yaml")
    text = shipped.read_text(encoding="utf-8")
    (scenes / "wide.yaml").write_text(text.replace("../robots/", ""), encoding="utf-8")
    shutil.copy(load_scene(shipped).robot_urdf, scenes / load_scene(shipped).robot_urdf.name)
    suite = tmp_path / "suite"
    suite.mkdir()
    text = suite_entries("paper", only=["R4"])[0].path.read_text()
    scene = "family: R\nscene: ../scenes/wide.yaml\n"
    (suite / "R4.yaml").write_text(text.replace("family: R\n", scene))
    return suite / "R4.yaml"


def test_an_instance_with_its_own_scene_takes_it_along(tmp_path: Path) -> None:
    files = pack(_custom_suite(tmp_path / "here"))
    assert sorted(n for n, _ in files.files) == [
        "scenes/ur5e_2f85.urdf", "scenes/wide.yaml", "suite/R4.yaml",
    ]  # fmt: skip
    path = unpack(files, tmp_path / "there")
    assert path.relative_to(tmp_path / "there").parts[1:] == ("suite", "R4.yaml")
    scene = load_instance(path).scene_path(path)
    assert scene is not None and scene.resolve().is_relative_to(tmp_path / "there")
    assert load_scene(scene).robot_urdf.is_file()


def test_what_cannot_travel(tmp_path: Path) -> None:
    instance = _custom_suite(tmp_path)
    text = instance.read_text().replace("../scenes/wide.yaml", str(tmp_path / "scenes/wide.yaml"))
    instance.write_text(text)
    with pytest.raises(PayloadError, match="absolute path; to carry the instance"):
        pack(instance)
    for name in ("../evil.yaml", "/etc/evil.yaml"):
        with pytest.raises(PayloadError, match="expected a relative path"):
            unpack(InstanceFiles(name, ((name, "x"),)), tmp_path / "out")
    assert not (tmp_path / "evil.yaml").exists()
