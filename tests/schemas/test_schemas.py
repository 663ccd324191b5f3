"""The shipped JSON Schemas: every shipped instance and scene and a plan file validate, and
invalid documents are rejected by the schema and by the loader alike."""

from __future__ import annotations

import copy
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from sdar_tamp.errors import ParameterError, SdarError
from sdar_tamp.plan_building import GripperEvent, MotionSegment, build_plan_file
from sdar_tamp.plan_reading import plan_from_dict
from sdar_tamp.plan_writing import save_plan
from sdar_tamp.resources import domains_root
from sdar_tamp.schemas import SCHEMAS, schema, schema_path
from sdar_tamp.world.instance import parse_instance
from sdar_tamp.world.scene import default_scene_path, load_scene
from sdar_tamp.world.transforms import pose_xyz_yaw

jsonschema = pytest.importorskip("jsonschema")

INSTANCES = sorted((domains_root()).rglob("suites/**/*.yaml"))
SCENE = default_scene_path()


def _validator(name: str) -> Any:
    return jsonschema.Draft202012Validator(schema(name))


def _errors(name: str, document: Any) -> list[str]:
    return [e.message for e in _validator(name).iter_errors(document)]


@pytest.fixture(scope="module")
def plan_document(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """A plan file as ``sdar solve`` writes it (the same builder and writer)."""
    scene = load_scene()
    home = np.concatenate([np.array(a.home) for a in scene.arms])
    t = np.linspace(0.0, 0.4, 21)
    s = 0.5 - 0.5 * np.cos(np.pi * t / t[-1])
    move = MotionSegment(t, home + s[:, None] * 0.1, "plain", ("o1",), "pick")
    back = MotionSegment(t, move.q[-1] - s[:, None] * 0.1, "plain", ("o1",), "retreat")
    T = pose_xyz_yaw(0.0, 0.0, 0.01, 0.2)
    items = [
        move,
        GripperEvent("left", "grasp", "o1", T),
        back,
        GripperEvent("left", "release", "o1", T),
    ]
    plan = build_plan_file(
        scene, "P1", {"o1": (0.0, 0.1, 0.0)}, {"o1": (0.08, 0.04, 0.05)}, items, {"seed": 0}
    )
    path = save_plan(plan, tmp_path_factory.mktemp("schema") / "P1.plan.json")
    document: dict[str, Any] = json.loads(path.read_text(encoding="utf-8"))
    return document


def test_the_schemas_are_valid_draft_2020_12() -> None:
    for name in SCHEMAS:
        jsonschema.Draft202012Validator.check_schema(schema(name))
        assert schema_path(name).name == f"{name}.schema.json"
    with pytest.raises(ParameterError, match="name must be one of instance, scene, plan"):
        schema_path("solution")


def test_every_shipped_instance_validates() -> None:
    assert len(INSTANCES) >= 40  # the paper and stress suites
    for path in INSTANCES:
        document = yaml.safe_load(path.read_text(encoding="utf-8"))
        assert _errors("instance", document) == [], path


def test_the_shipped_scene_validates(tmp_path: Path) -> None:
    document = yaml.safe_load(SCENE.read_text(encoding="utf-8"))
    assert _errors("scene", document) == []
    # the unmodified document, written as the invalid cases below are, loads
    document["robot"] = str(SCENE.parent / document["robot"])
    (tmp_path / "scene.yaml").write_text(yaml.safe_dump(document), encoding="utf-8")
    assert load_scene(tmp_path / "scene.yaml").arm_names == ("left", "right")


def test_a_plan_file_validates(plan_document: dict[str, Any]) -> None:
    assert _errors("plan", plan_document) == []
    assert plan_from_dict(plan_document).instance == "P1"
    without_steps = {k: v for k, v in plan_document.items() if k != "steps"}
    assert _errors("plan", without_steps) == []


# -- invalid documents: the schema and the loader both refuse them -------------------------------
Edit = Callable[[Any], None]


def _set(keys: list[Any], value: Any) -> Edit:
    def edit(document: Any) -> None:
        for key in keys[:-1]:
            document = document[key]
        document[keys[-1]] = value

    return edit


def _drop(keys: list[Any]) -> Edit:
    def edit(document: Any) -> None:
        for key in keys[:-1]:
            document = document[key]
        del document[keys[-1]]

    return edit


INSTANCE_CASES: dict[str, Edit] = {
    "no objects": _drop(["objects"]),
    "unknown key": _set(["colour"], "red"),
    "size of two": _set(["objects", 0, "size"], [0.08, 0.04]),
    "negative size": _set(["objects", 0, "size"], [0.08, -0.04, 0.05]),
    "pose as text": _set(["objects", 0, "start"], "origin"),
    "object key": _set(["objects", 0, "mass"], 1.0),
    "bad name": _set(["objects", 0, "name"], "o 1"),
    "workspace": _set(["workspace"], {"x": [-0.2, 0.2]}),
}
SCENE_CASES: dict[str, Edit] = {
    "no arms": _set(["arms"], []),
    "no gripper": _drop(["gripper"]),
    "home of words": _set(["arms", 0, "home"], ["up"] * 6),
    "joint limit": _set(["arms", 0, "joint_limits", "wrist_4"], [-1.0]),
    "fingers and box": _set(
        ["gripper", "finger_box"], {"depth": 0.01, "width": 0.01, "length": 0.01, "thickness": 0.01}
    ),
    "zero velocity": _set(["arms", 1, "velocity_limit"], 0.0),
    "table": _set(["table", "size"], [1.4, 0.8]),
    "velocity safety": _set(["velocity_safety"], 1.2),
}
PLAN_CASES: dict[str, Edit] = {
    "format": _set(["format"], "other-plan"),
    "version": _set(["version"], 3),
    "version 1 of three arms": lambda d: (
        d.update(version=1),
        d["arms"].append({**copy.deepcopy(d["arms"][0]), "name": "third"}),
    ),
    "no arms": _set(["arms"], []),
    "units": _set(["units", "length"], "mm"),
    "empty row": _set(["trajectory", "q", 3], []),
    "no joints": _set(["arms", 0, "joints"], []),
    "event type": _set(["events", 0, "type"], "grab"),
    "event key": _set(["events", 0, "force"], 10.0),
    "missing metrics": _drop(["metrics"]),
    "one arm in version 1": lambda d: (d.update(version=1), d["arms"].pop()),
    "transform": _set(["arms", 0, "T_world_base"], [[1, 0, 0, 0]] * 3),
    "metric value": _set(["metrics", "seed"], [0]),
    "step objects": _set(["steps", 0, "objects"], [""]),
}


@pytest.mark.parametrize("case", sorted(INSTANCE_CASES))
def test_invalid_instances(case: str) -> None:
    document = yaml.safe_load(INSTANCES[0].read_text(encoding="utf-8"))
    assert _errors("instance", document) == []
    assert parse_instance(yaml.safe_dump(document), "good.yaml").objects
    INSTANCE_CASES[case](document)
    assert _errors("instance", document), case
    with pytest.raises(SdarError):
        parse_instance(yaml.safe_dump(document), "bad.yaml")


@pytest.mark.parametrize("case", sorted(SCENE_CASES))
def test_invalid_scenes(case: str, tmp_path: Path) -> None:
    document = yaml.safe_load(SCENE.read_text(encoding="utf-8"))
    document["robot"] = str(SCENE.parent / document["robot"])
    SCENE_CASES[case](document)
    assert _errors("scene", document), case
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(document), encoding="utf-8")
    with pytest.raises(SdarError):
        load_scene(path)


@pytest.mark.parametrize("case", sorted(PLAN_CASES))
def test_invalid_plans(case: str, plan_document: dict[str, Any]) -> None:
    document = copy.deepcopy(plan_document)
    PLAN_CASES[case](document)
    assert _errors("plan", document), case
    with pytest.raises(SdarError):
        plan_from_dict(document, "bad.json")
