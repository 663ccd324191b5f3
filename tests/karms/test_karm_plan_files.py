"""Plan files of one, three and four arms (version 2): round trip, schema, validation, the
counts; version-1 files (two arms) still read; every error of a bad k-arm file located."""

from __future__ import annotations

import copy
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from karm_cells import build

from sdar_tamp.plan_file import READ_VERSIONS, VERSION, PlanFile, PlanFileError
from sdar_tamp.plan_reading import load_plan, locate_key, plan_from_dict
from sdar_tamp.plan_rules import check_scene
from sdar_tamp.plan_writing import plan_to_dict, save_plan
from sdar_tamp.replay import validate_plan
from sdar_tamp.schemas import schema
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.layout import ArmLayout
from sdar_tamp.world.scene import Scene, load_scene

SOLVED = Path(__file__).resolve().parents[1] / "plan" / "solved"
K = (1, 3, 4)


@pytest.mark.parametrize("k", K)
def test_k_arm_plans_round_trip_and_validate(
    k: int,
    cells: dict[int, Scene],
    instances: dict[int, Instance],
    plans: dict[int, PlanFile],
    tmp_path: Path,
) -> None:
    plan, scene = plans[k], cells[k]
    path = save_plan(plan, tmp_path / f"K{k}.plan.json")
    data = json.loads(path.read_text(encoding="utf-8"))
    assert VERSION == 2 and data["version"] == 2
    assert [a["name"] for a in data["arms"]] == list(scene.arm_names)
    assert all(len(a["joints"]) == 6 and len(a["home"]) == 6 for a in data["arms"])
    assert {len(row) for row in data["trajectory"]["q"]} == {6 * k}
    loaded = load_plan(path, scene.layout)
    assert plan_to_dict(loaded) == plan_to_dict(plan)
    np.testing.assert_array_equal(loaded.q, plan.q)
    assert loaded.layout == scene.layout
    report = validate_plan(instances[k], loaded, scene)
    assert report.ok, report.violation
    # every arm's objects placed; the grasps (then the releases) of all arms at one instant
    assert loaded.metrics.actions == k
    grasps = {e.t for e in loaded.events if e.type == "grasp"}
    assert len(grasps) == 1 and len([e for e in loaded.events if e.type == "grasp"]) == k


@pytest.mark.parametrize("k", K)
def test_k_arm_plan_documents_follow_the_schema(
    k: int, plans: dict[int, PlanFile], tmp_path: Path
) -> None:
    jsonschema = pytest.importorskip("jsonschema")
    document = json.loads(save_plan(plans[k], tmp_path / "p.json").read_text(encoding="utf-8"))
    validator = jsonschema.Draft202012Validator(schema("plan"))
    assert list(validator.iter_errors(document)) == []
    document["version"] = 1  # version 1 holds exactly two arms
    assert list(validator.iter_errors(document))


def test_motions_with_two_arms_or_more_are_counted(
    cells: dict[int, Scene], instances: dict[int, Instance]
) -> None:
    """``dual_arm_steps``: motions in which two arms or more move at once (one arm alone does
    not count; two and three do)."""
    scene = cells[3]
    home = scene.home
    q = {a: np.array(scene.arm(a).home) + 0.1 for a in scene.arm_names}
    phases = [
        {"south": q["south"]},
        {"south": home[:6], "north": q["north"]},
        {"south": q["south"], "north": home[6:12], "west": q["west"]},
        {"south": home[:6], "west": home[12:]},
        {"north": home[6:12]},
    ]
    plan = build(scene, instances[3], phases, name="K3")
    assert plan.metrics.steps == 5
    assert plan.metrics.dual_arm_steps == 3
    one = build(scene, instances[3], [phases[0], {"south": home[:6]}], name="K3")
    assert one.metrics.dual_arm_steps == 0


# -- version 1 ----------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["D5", "M2", "R5"])
def test_version_1_files_read_as_their_version_2_copies(name: str, tmp_path: Path) -> None:
    source = SOLVED / f"{name}.plan.json"
    assert json.loads(source.read_text(encoding="utf-8"))["version"] == 1
    assert READ_VERSIONS[1] == (2, 2)
    plan = load_plan(source, load_scene().layout)
    assert plan.arm_names == ("left", "right")
    copy_path = save_plan(plan, tmp_path / "v2.json")
    assert json.loads(copy_path.read_text(encoding="utf-8"))["version"] == 2
    again = load_plan(copy_path)
    assert plan_to_dict(again) == plan_to_dict(plan)


def test_a_version_1_file_of_three_arms_is_refused_at_its_arms(
    plans: dict[int, PlanFile], tmp_path: Path
) -> None:
    data = plan_to_dict(plans[3])
    data["version"] = 1
    path = tmp_path / "v1.json"
    path.write_text(json.dumps(data, indent=1), encoding="utf-8")
    with pytest.raises(PlanFileError) as info:
        load_plan(path)
    line, column = locate_key(path.read_text(encoding="utf-8"), "arms") or (0, 0)
    assert str(info.value) == (
        f"{path}:{line}:{column}: arms: expected 2 arms (a version-1 file), got 3"
    )


# -- bad version-2 files: every error located ----------------------------------------------------
Edit = Callable[[dict[str, Any]], object]


def _set(keys: list[Any], value: Any) -> Edit:
    def edit(data: dict[str, Any]) -> None:
        node = data
        for key in keys[:-1]:
            node = node[key]
        node[keys[-1]] = value

    return edit


def _drop_arm(data: dict[str, Any]) -> None:
    data["arms"].pop(1)  # the rows still hold three arms' joints


BAD: dict[str, tuple[Edit, str, str]] = {
    "no arms": (_set(["arms"], []), "arms", "expected at least 1 arm (a version-2 file), got 0"),
    "arms an object": (_set(["arms"], {"south": 1}), "arms", "expected a list of arms, got"),
    "arm not an object": (_set(["arms", 2], "west"), "arms[2]", "expected an object with keys"),
    "arm key missing": (
        lambda d: d["arms"][2].pop("T_tool0_tcp"),
        "arms[2]",
        "missing key 'T_tool0_tcp'",
    ),
    "repeated name": (
        _set(["arms", 2, "name"], "south"),
        "arms[2].name",
        "expected a name different from 'south'",
    ),
    "third arm without joints": (
        _set(["arms", 2, "joints"], []),
        "arms[2].joints",
        "expected the arm's joint names, got an empty list",
    ),
    "third arm's home": (
        _set(["arms", 2, "home"], [0.0] * 5),
        "arms[2].home",
        "expected 6 numbers, got 5",
    ),
    "third arm's base": (
        _set(["arms", 2, "T_world_base", 3], [0, 0, 1, 1]),
        "arms[2].T_world_base",
        "expected a rigid transform",
    ),
    "rows of three arms, two named": (_drop_arm, "trajectory.q[0]", "expected 12 numbers, got 18"),
    "short row": (
        lambda d: d["trajectory"]["q"][7].pop(),
        "trajectory.q[7]",
        "expected 18 numbers, got 17",
    ),
    "event of no arm": (
        _set(["events", 2, "arm"], "east"),
        "events[2].arm",
        "expected one of ['south', 'north', 'west'], got \"east\"",
    ),
    "version": (_set(["version"], 3), "version", "expected one of [1, 2] (this reader), got 3"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_each_error_of_a_three_arm_file_is_located(
    case: str, plans: dict[int, PlanFile], tmp_path: Path
) -> None:
    edit, key, detail = BAD[case]
    data = copy.deepcopy(plan_to_dict(plans[3]))
    edit(data)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data, indent=1), encoding="utf-8")
    with pytest.raises(PlanFileError) as info:
        load_plan(path)
    err = info.value
    assert err.key == key
    spot = locate_key(path.read_text(encoding="utf-8"), key)
    assert spot is not None
    assert str(err).startswith(f"{path}:{spot[0]}:{spot[1]}: {key}: {detail}"), str(err)


def test_plans_and_cells_of_different_arms_are_located_errors(
    plans: dict[int, PlanFile], cells: dict[int, Scene], tmp_path: Path
) -> None:
    path = save_plan(plans[3], tmp_path / "K3.json")
    text = path.read_text(encoding="utf-8")
    with pytest.raises(PlanFileError) as info:
        load_plan(path, cells[4].layout)
    line, column = locate_key(text, "arms") or (0, 0)
    assert str(info.value) == f"{path}:{line}:{column}: arms: the cell has 4 arms, the plan 3"
    seven = ArmLayout(("south", "north", "west"), (6, 6, 7))
    with pytest.raises(PlanFileError) as info:
        load_plan(path, seven)
    line, column = locate_key(text, "arms[2].joints") or (0, 0)
    assert str(info.value).startswith(
        f"{path}:{line}:{column}: arms[2].joints: the cell's arm 'west' has 7 joints, "
        "the plan's arm 'west' 6"
    )
    # read without the cell, the validator's scene rule names the difference
    v = check_scene(load_plan(path), cells[4])
    assert v is not None and v.kind == "scene"
    assert "arms ['south', 'north', 'west'] differ from the scene's" in v.message


def test_a_plan_in_memory_with_no_arms_is_a_format_violation(plans: dict[int, PlanFile]) -> None:
    data = plan_to_dict(plans[1])
    assert plan_from_dict(data).arm_names == ("south",)
    data["arms"] = []
    with pytest.raises(PlanFileError, match=r"^<plan>: arms: expected at least 1 arm"):
        plan_from_dict(data)
