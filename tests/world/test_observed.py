"""Observed-state files: their reader's located errors, the arrangement an observation gives
and every impossible observed state refused at its entry; object names YAML reads as
booleans, in observed states and instances."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.world.errors import InstanceError, ObservedStateError
from sdar_tamp.world.footprint import corners
from sdar_tamp.world.instance import (
    Instance,
    ObjectSpec,
    Pose2D,
    dump_instance,
    parse_instance,
)
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.observed import (
    AddedObject,
    ObservedState,
    Resting,
    check_clear_of_arms,
    load_observed,
    observed_arrangement,
    overlap_depth,
    parse_observed,
)
from sdar_tamp.world.scene import Scene, Workspace

WS = Workspace((-0.3, 0.3), (-0.3, 0.3))
SIZE = (0.08, 0.04, 0.05)
RESTING = {
    "o1": Resting(SIZE, Pose2D(0.0, 0.0, 0.0)),
    "o2": Resting(SIZE, Pose2D(0.2, 0.0, 0.0)),
}
KNOWN = ("o1", "o2", "o3")  # o3: held by the left arm


def _arrange(text: str) -> dict[str, Resting]:
    return observed_arrangement(
        parse_observed(text, "obs.yaml"), RESTING, {"o3": "left"}, KNOWN, WS
    )


def test_a_file_is_read_with_every_entry_located(tmp_path: Path) -> None:
    path = tmp_path / "obs.yaml"
    path.write_text(
        "poses:\n  - {name: o1, pose: [0.01, 0.02, 0.3]}\nremoved: [o2]\n"
        "added:\n  - {name: b1, size: [0.05, 0.05, 0.05], pose: [0.1, 0.1, 0]}\n",
        encoding="utf-8",
    )
    observed = load_observed(path)
    assert observed.poses == {"o1": Pose2D(0.01, 0.02, 0.3)}
    assert observed.removed == ("o2",)
    assert observed.added == (AddedObject("b1", (0.05, 0.05, 0.05), Pose2D(0.1, 0.1, 0.0)),)
    assert (observed.where("o1").line, observed.where("o2").line, observed.where("b1").line) == (
        2, 3, 5,
    )  # fmt: skip
    assert parse_observed("") == ObservedState(source="<observed>")


@pytest.mark.parametrize(
    ("text", "where", "message"),
    [
        ("removed: [on]", "obs.yaml:1:11", "YAML reads as the boolean True; quote it ('on')"),
        ("removed: [off]", "obs.yaml:1:11", "the boolean False; quote it ('off')"),
        ("poses: [{name: yes, pose: [0, 0, 0]}]", "obs.yaml:1:16", "boolean True"),
        ("added: [{name: no, size: [1, 1, 1], pose: [0, 0, 0]}]", "obs.yaml:1:16", "boolean"),
        ("poses: [{name: o1, pose: [1, 2]}]", "obs.yaml:1:26", "expected [x, y, yaw]"),
        ("poses: [{name: o1, pose: [1, 2, .nan]}]", "obs.yaml:1:33", "a finite number"),
        ("removed: [o1, o1]", "obs.yaml:1:15", "'o1' is already named at line 1"),
        ("added: [{name: x, size: [1, 1], pose: [0, 0, 0]}]", "obs.yaml:1:25", "[lx, ly, lz]"),
        ("added: [{name: x, size: [1, -1, 1], pose: [0, 0, 0]}]", "obs.yaml:1:29", "> 0"),
        ("added: [{name: x}]", "obs.yaml:1:9", "key 'size'"),
        ("moved: []", "obs.yaml:1:8", "unknown key 'moved'"),
        ("removed: o1", "obs.yaml:1:10", "expected a list"),
        ("removed: ['a b']", "obs.yaml:1:11", "a name of letters"),
        ("[1, 2]", "obs.yaml:1:1", "a mapping"),
        ("poses: [", "obs.yaml:1:9", "invalid YAML"),
    ],
)
def test_a_bad_file_is_refused_at_its_place(text: str, where: str, message: str) -> None:
    with pytest.raises(ObservedStateError) as err:
        parse_observed(text, "obs.yaml")
    assert str(err.value).startswith(where + ":"), str(err.value)
    assert message in str(err.value)


def test_a_quoted_boolean_word_is_a_name() -> None:
    observed = parse_observed("removed: ['on', 7]")
    assert observed.removed == ("on", "7")


def test_a_missing_file_is_a_located_error(tmp_path: Path) -> None:
    with pytest.raises(ObservedStateError, match=r"obs\.yaml"):
        load_observed(tmp_path / "obs.yaml")


def test_the_observation_replaces_the_arrangement() -> None:
    out = _arrange(
        "poses: [{name: o1, pose: [0.0, 0.1, 0.2]}]\nremoved: [o2]\n"
        "added: [{name: b1, size: [0.05, 0.05, 0.05], pose: [-0.2, 0.0, 0]}]"
    )
    assert out == {
        "o1": Resting(SIZE, Pose2D(0.0, 0.1, 0.2)),
        "b1": Resting((0.05, 0.05, 0.05), Pose2D(-0.2, 0.0, 0.0)),
    }


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [
        ("removed: [o9]", 1, "unknown object 'o9': the instance has ['o1', 'o2', 'o3']"),
        ("poses: [{name: o3, pose: [0, 0.2, 0]}]", 1, "'o3' is held by arm 'left'"),
        ("removed: [o3]", 1, "'o3' is held by arm 'left'"),
        ("added: [{name: o2, size: [0.05, 0.05, 0.05], pose: [0, 0.2, 0]}]", 1,
         "added object 'o2': the name is the instance's"),
        ("poses: [{name: o2, pose: [0.05, 0.0, 0.0]}]", 1,
         "objects 'o1' and 'o2' overlap by 30.0 mm"),
        ("removed: [o2]\nadded: [{name: b1, size: [0.05, 0.05, 0.05], pose: [0.02, 0.0, 0]}]",
         2, "objects 'b1' and 'o1' overlap by 40.0 mm"),
        ("poses: [{name: o2, pose: [0.29, 0.0, 0.0]}]", 1,
         "object 'o2' at (0.290, 0.000) m: its footprint leaves the workspace"),
        ("added: [{name: b1, size: [0.05, 0.05, 0.05], pose: [0, 0.9, 0]}]", 1,
         "(off the table or out of reach)"),
    ],
)  # fmt: skip
def test_an_impossible_arrangement_is_refused_at_its_entry(
    text: str, line: int, message: str
) -> None:
    with pytest.raises(ObservedStateError) as err:
        _arrange(text)
    assert err.value.location is not None and err.value.location.line == line
    assert str(err.value).startswith(f"obs.yaml:{line}:")
    assert message in str(err.value), str(err.value)


def test_a_removed_object_named_again_is_unknown() -> None:
    resting = {"o1": RESTING["o1"]}
    with pytest.raises(ObservedStateError, match="unknown object 'o2': it was removed before"):
        observed_arrangement(parse_observed("removed: [o2]"), resting, {}, KNOWN, WS)


def test_overlap_depth() -> None:
    a, b = corners(np.array([[0.0, 0.0, 0.0], [0.05, 0.0, 0.0]]), np.array([SIZE[:2]] * 2))
    assert overlap_depth(a, b) == pytest.approx(0.03)
    far = corners(np.array([[0.5, 0.0, 0.0]]), np.array([SIZE[:2]]))[0]
    assert overlap_depth(a, far) < 0.0


def test_an_object_inside_an_arm_is_refused_with_the_configuration(scene: Scene) -> None:
    q = scene.home
    kin = ArmKinematics.from_scene(scene, "left")
    tcp = kin.fk_tcp(scene.layout.part(q, "left"))
    x, y = float(tcp[0, 3]), float(tcp[1, 3])
    observed = parse_observed(
        f"added: [{{name: b1, size: [0.04, 0.04, {tcp[2, 3] + 0.05:.3f}], pose: [{x}, {y}, 0]}}]",
        "obs.yaml",
    )
    arrangement = {"b1": Resting(observed.added[0].size, observed.added[0].pose)}
    with pytest.raises(ObservedStateError) as err:
        check_clear_of_arms(arrangement, scene, q, 2.5, observed)
    text = str(err.value)
    assert text.startswith("obs.yaml:1:") and "object 'b1' is inside arm 'left'" in text
    assert "at t = 2.500 s, the arm at [" in text
    check_clear_of_arms({"b1": Resting((0.04, 0.04, 0.04), Pose2D(0.0, 0.0, 0.0))}, scene, q,
                        0.0, observed)  # fmt: skip


def test_instance_names_yaml_reads_as_booleans() -> None:
    text = (
        "name: N\nworkspace: {x: [-0.3, 0.3], y: [-0.3, 0.3]}\nobjects:\n"
        "  - {name: on, size: [0.08, 0.04, 0.05], start: [0, 0, 0], goal: [0.1, 0.1, 0]}\n"
    )
    with pytest.raises(InstanceError, match=r"objects\[0\]\.name: expected a name, got 'on'"):
        parse_instance(text, "i.yaml")
    for name in ("on", "no", "1", "null", "1e3", "o_1"):
        o = ObjectSpec(name, (0.08, 0.04, 0.05), Pose2D(0, 0, 0), Pose2D(0.1, 0.1, 0))
        instance = Instance("N", WS, (o,))
        assert parse_instance(dump_instance(instance)).objects[0].name == name
