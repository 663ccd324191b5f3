"""Every reader of a user file reports unreadable files and bytes that are not UTF-8 with the
project's errors, naming the file, the ``line:column`` and the byte offset."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from sdar_tamp.cli import main
from sdar_tamp.compat.pddlstream import read
from sdar_tamp.errors import SdarError
from sdar_tamp.evaluation.results import read_rows
from sdar_tamp.plan_file import PlanFileError
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.resources import domain_file
from sdar_tamp.textfile import TextFileError, decode_text, read_text
from sdar_tamp.world._pin import PinRobot
from sdar_tamp.world.errors import InstanceError, SceneError
from sdar_tamp.world.instance import load_instance
from sdar_tamp.world.scene import load_scene

# "é" is fine; 0xff on line 2 after "ab\xc3\xa9c" (4 characters, 5 bytes) is not UTF-8.
BAD = b"first line\nab\xc3\xa9c\xffrest\n"
OFFSET = BAD.index(b"\xff")


def test_read_text_locates_the_first_bad_byte(tmp_path: Path) -> None:
    path = tmp_path / "f.txt"
    path.write_bytes(BAD)
    with pytest.raises(TextFileError) as info:
        read_text(path)
    error = info.value
    assert isinstance(error, SdarError)
    assert error.byte_offset == OFFSET == 16
    assert error.file == str(path)
    assert error.location is not None
    assert (error.location.line, error.location.column) == (2, 5)
    assert str(error).startswith(f"{path}:2:5: not UTF-8 text: byte 0xff at byte offset 16")


def test_a_cut_multibyte_sequence_at_the_end() -> None:
    with pytest.raises(TextFileError, match=r"f:1:3: .*byte 0xe2 at byte offset 2"):
        decode_text(b"ab\xe2\x82", "f")


def test_byte_order_mark_is_dropped(tmp_path: Path) -> None:
    path = tmp_path / "bom.pddl"
    path.write_bytes(b"\xef\xbb\xbf(define)\n")
    assert read_text(path) == "(define)\n"
    with pytest.raises(TextFileError, match=r"f:1:2: .*at byte offset 4"):
        decode_text(b"\xef\xbb\xbfa\xff", "f")  # the mark is no column


def test_unreadable_file(tmp_path: Path) -> None:
    with pytest.raises(TextFileError, match=r"^.*none\.pddl: cannot read file: No such file"):
        read_text(tmp_path / "none.pddl")
    with pytest.raises(TextFileError, match="cannot read file"):
        read_text(tmp_path)  # a directory


def _bad_copy(source: Path, target: Path) -> Path:
    """``source`` with a 0xff byte put in front of its second line."""
    lines = source.read_bytes().split(b"\n")
    lines[1] = b"\xff" + lines[1]
    target.write_bytes(b"\n".join(lines))
    return target


def _offset(path: Path) -> int:
    return path.read_bytes().index(b"\xff")


@pytest.mark.parametrize("command", ["check", "plan"])
def test_cli_pddl_inputs(command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    domain = _bad_copy(domain_file("blocksworld"), tmp_path / "domain.pddl")
    problem = domain_file("blocksworld", "problems/sussman.pddl")
    assert (
        main([command, str(domain), str(problem)] if command == "plan" else [command, str(domain)])
        == 2
    )
    err = capsys.readouterr().err
    assert f"{domain}:2:1: not UTF-8 text: byte 0xff at byte offset {_offset(domain)}" in err


def test_cli_problem_and_stream_inputs(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    domain = domain_file("kitchen")
    streams = _bad_copy(domain_file("kitchen", "stream.pddl"), tmp_path / "stream.pddl")
    assert main(["check", str(domain), "--streams", str(streams)]) == 2
    assert f"{streams}:2:1: not UTF-8 text" in capsys.readouterr().err
    problem = _bad_copy(
        domain_file("blocksworld", "problems/sussman.pddl"), tmp_path / "problem.pddl"
    )
    assert main(["plan", str(domain_file("blocksworld")), str(problem)]) == 2
    assert f"{problem}:2:1: not UTF-8 text" in capsys.readouterr().err


def test_compat_read(tmp_path: Path) -> None:
    path = _bad_copy(domain_file("blocksworld"), tmp_path / "domain.pddl")
    with pytest.raises(TextFileError, match=r"domain\.pddl:2:1: not UTF-8"):
        read(path)


def _instance(tmp_path: Path) -> Path:
    source = domain_file("dual_arm_rearrangement", "suites/paper/R4.yaml")
    return _bad_copy(source, tmp_path / "instance.yaml")


READERS: dict[str, tuple[Callable[[Path], Path], Callable[[Path], object], type[SdarError]]] = {
    "instance": (_instance, load_instance, InstanceError),
    "scene": (
        lambda tmp: _bad_copy(
            domain_file("dual_arm_rearrangement", "cells/ur5e_facing.yaml"), tmp / "s.yaml"
        ),
        load_scene,
        SceneError,
    ),
    "robot description": (
        lambda tmp: _bad_copy(
            domain_file("dual_arm_rearrangement", "robots/ur5e_2f85.urdf"), tmp / "robot.urdf"
        ),
        PinRobot.load,
        SceneError,
    ),
    "plan": (
        lambda tmp: _bad_copy_text(tmp / "plan.json", '{"format":\n "sdar-plan"}'),
        load_plan,
        PlanFileError,
    ),
    "results table": (
        lambda tmp: _bad_copy_text(tmp / "results.csv", "a,b\n1,2\n"),
        lambda path: read_rows(path, ["a", "b"]),
        TextFileError,
    ),
}


def _bad_copy_text(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return _bad_copy(path, path)


@pytest.mark.parametrize("name", list(READERS))
def test_world_and_plan_readers(name: str, tmp_path: Path) -> None:
    make, load, error_type = READERS[name]
    path = make(tmp_path)
    with pytest.raises(error_type) as info:
        load(path)
    message = str(info.value)
    assert message.startswith(f"{path}:2:1: not UTF-8 text: byte 0xff")
    assert f"at byte offset {_offset(path)}" in message
