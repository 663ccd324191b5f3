"""YAML reading: control characters, deep nesting and values that do not fit their tag are
located errors of the reader's own type."""

from __future__ import annotations

from pathlib import Path

import pytest

from sdar_tamp.world._yaml import MAX_DEPTH
from sdar_tamp.world.errors import InstanceError, SceneError
from sdar_tamp.world.instance import load_instance, parse_instance
from sdar_tamp.world.scene import load_scene

HEAD = "name: T\nworkspace: {x: [-0.25, 0.25], y: [-0.3, 0.3]}\n"
OBJECT = "  - {name: a, size: [0.08, 0.04, 0.05], start: [0.1, 0.1, 0.0], goal: [0.0, 0.0, 0.0]}\n"
VALID = HEAD + "objects:\n" + OBJECT


def test_the_valid_text_loads() -> None:
    assert parse_instance(VALID, "i.yaml").objects[0].name == "a"


@pytest.mark.parametrize("char", ["\x00", "\x07", "\x1b", "\x7f", "\ufffe"])
def test_control_character(char: str) -> None:
    text = VALID.replace("name: a", f"name: a{char}b")
    with pytest.raises(InstanceError) as info:
        parse_instance(text, "i.yaml")
    message = str(info.value)
    assert message.startswith("i.yaml:4:13: invalid YAML: character #x")
    assert f"#x{ord(char):04x} is not allowed" in message


def test_control_character_after_other_line_breaks() -> None:
    text = "name: T\r\nworkspace: {x: [-0.25, 0.25],\r y: [-0.3, 0.3]}\u2028\x01"
    with pytest.raises(InstanceError, match=r"i\.yaml:4:1: invalid YAML: character #x0001"):
        parse_instance(text, "i.yaml")


def test_control_character_in_a_file(tmp_path: Path) -> None:
    path = tmp_path / "scene.yaml"
    path.write_text("robot: r.urdf\ntable: \t\x08\n", encoding="utf-8")
    with pytest.raises(SceneError, match=r"scene\.yaml:2:9: invalid YAML: character #x0008"):
        load_scene(path)


@pytest.mark.parametrize("depth", [MAX_DEPTH + 1, 500, 100_000])
def test_deep_flow_nesting(depth: int) -> None:
    text = HEAD + "objects: " + "[" * depth + "]" * depth + "\n"
    with pytest.raises(InstanceError) as info:
        parse_instance(text, "i.yaml")
    # the list that is one level too deep opens at column 10 + MAX_DEPTH - 1 of line 3
    assert str(info.value) == (
        f"i.yaml:3:{10 + MAX_DEPTH - 1}: invalid YAML: nesting deeper than {MAX_DEPTH} levels"
    )


def test_deep_block_nesting(tmp_path: Path) -> None:
    path = tmp_path / "i.yaml"
    path.write_text(HEAD + "objects:\n" + "".join(" " * i + "-\n" for i in range(500)))
    with pytest.raises(InstanceError, match=rf"i\.yaml:\d+:\d+: .*deeper than {MAX_DEPTH}"):
        load_instance(path)


def test_nesting_at_the_limit_is_read() -> None:
    # the root mapping is level 1, so MAX_DEPTH - 1 lists fit under 'objects'
    depth = MAX_DEPTH - 1
    text = HEAD + "objects: " + "[" * depth + "]" * depth + "\n"
    with pytest.raises(InstanceError, match=r"objects\[0\]: expected a mapping"):
        parse_instance(text, "i.yaml")


@pytest.mark.parametrize(
    ("value", "detail"),
    [
        ("!!int abc", "cannot read 'abc' as tag:yaml.org,2002:int"),
        ("!!float x1", "cannot read 'x1' as tag:yaml.org,2002:float"),
        ("!!bool maybe", "cannot read 'maybe' as tag:yaml.org,2002:bool"),
        ("2001-13-45", "cannot read '2001-13-45' as tag:yaml.org,2002:timestamp"),
        ("!!timestamp soon", "cannot read 'soon' as tag:yaml.org,2002:timestamp"),
    ],
)
def test_value_that_does_not_fit_its_tag(value: str, detail: str) -> None:
    text = VALID + f"seed: {value}\n"
    with pytest.raises(InstanceError) as info:
        parse_instance(text, "i.yaml")
    assert str(info.value).startswith(f"i.yaml:5:7: invalid YAML: {detail}")


def test_recursive_alias_is_an_error_not_a_hang() -> None:
    text = HEAD + "objects: &a [*a]\n"
    with pytest.raises(InstanceError, match=r"objects\[0\]: expected a mapping"):
        parse_instance(text, "i.yaml")
