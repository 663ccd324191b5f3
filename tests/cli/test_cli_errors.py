"""Refusals of the ``sdar`` command line: one line on stderr, exit status 2, nothing written."""

from __future__ import annotations

from pathlib import Path

import pytest

from sdar_tamp.cli import main
from sdar_tamp.resources import domain_file
from sdar_tamp.world.instance import load_instance
from tests.cli.conftest import refused

S4 = str(domain_file("dual_arm_rearrangement", "suites/paper/S4.yaml"))


@pytest.mark.parametrize("value", ["nan", "inf", "-inf", "0", "-1", "soon"])
@pytest.mark.parametrize(
    "command",
    [
        ["solve", S4],
        ["bench", "--out", "OUT"],
        ["demo"],
        ["plan", "domain.pddl", "problem.pddl"],
    ],
)
def test_time_limits_must_be_finite_and_positive(
    command: list[str], value: str, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    argv = [str(tmp_path / "out") if a == "OUT" else a for a in command]
    err = refused([*argv, f"--time-limit={value}"], capsys)
    assert f"argument --time-limit: expected a finite number > 0 [s], got '{value}'" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("option", "value", "expected"),
    [
        ("--workers", "0", "an integer >= 1"),
        ("--workers", "1.5", "an integer >= 1"),
        ("--seed", "-1", "an integer >= 0"),
        ("--max-objects", "0", "an integer >= 1"),
    ],
)
def test_bench_numbers_are_checked(
    option: str, value: str, expected: str, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    err = refused(["bench", "--out", str(tmp_path / "b"), option, value], capsys)
    assert f"argument {option}: expected {expected}, got '{value}'" in err
    assert not (tmp_path / "b").exists()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--seed", "-5"], "argument --seed: expected an integer >= 0, got '-5'"),
        (["--objects", "0"], "argument --objects: expected an integer >= 1, got '0'"),
        (["--objects", "200"], "objects: at most 47 objects"),
        (["--objects", "48"], "got 48"),
    ],
)
def test_generate_numbers_are_checked_at_once(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    out = tmp_path / "x.yaml"
    err = refused(["generate", "--family", "R", "--objects", "4", *argv, "-o", str(out)], capsys)
    assert message in err
    assert not out.exists()


def test_solve_seed_and_show_fps_are_checked(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    assert "argument --seed: expected an integer >= 0" in refused(
        ["solve", S4, "--seed", "-3"], capsys
    )
    for fps in ("0", "nan", "inf", "-4"):
        err = refused(["show", S4, "-o", str(tmp_path / "x.png"), "--fps", fps], capsys)
        assert f"argument --fps: expected a finite number > 0 [1/s], got '{fps}'" in err
    assert not (tmp_path / "x.png").exists()


def test_generate_does_not_overwrite_without_force(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    out = tmp_path / "mine.yaml"
    out.write_text("precious")
    err = refused(["generate", "--family", "S", "--objects", "4", "-o", str(out)], capsys)
    assert f"--output: '{out}' exists; pass --force to replace it" in err
    assert out.read_text() == "precious"
    assert main(["generate", "--family", "S", "--objects", "4", "-o", str(out), "--force"]) == 0
    assert len(load_instance(out).objects) == 4


def test_generate_output_must_be_yaml_and_writable(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    args = ["generate", "--family", "S", "--objects", "4", "-o"]
    err = refused([*args, str(tmp_path / "x.txt")], capsys)
    assert "--output: expected a file ending in .yaml, .yml" in err
    blocker = tmp_path / "file"
    blocker.write_text("")
    err = refused([*args, str(blocker / "x.yaml")], capsys)
    assert f"'{blocker}' is a file, not a folder" in err
    err = refused([*args, str(tmp_path)], capsys)
    assert "expected a file ending in .yaml" in err


def test_generate_suite_needs_a_folder_and_force_to_replace(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import sdar_tamp.world.instance_files as commands
    import sdar_tamp.world.suites as suites

    few = suites.suite_members("paper")[:2]
    monkeypatch.setattr(suites, "suite_members", lambda name: few)
    monkeypatch.setattr(commands, "suite_members", lambda name: few)
    afile = tmp_path / "suite.yaml"
    afile.write_text("")
    err = refused(["generate", "--suite", "paper", "-o", str(afile)], capsys)
    assert f"--output: expected a folder, '{afile}' is a file" in err
    folder = tmp_path / "paper"
    folder.mkdir()
    (folder / "R5.yaml").write_text("precious")
    err = refused(["generate", "--suite", "paper", "-o", str(folder)], capsys)
    assert "1 instance file(s) of suite 'paper' exist" in err and "R5.yaml" in err
    assert (folder / "R5.yaml").read_text() == "precious"
    assert main(["generate", "--suite", "paper", "-o", str(folder), "--force"]) == 0
    assert sorted(p.name for p in folder.iterdir()) == ["R4.yaml", "R5.yaml"]
    assert (folder / "R5.yaml").read_text() != "precious"
    capsys.readouterr()
    err = refused(["generate", "--suite", "paper", "--objects", "4", "-o", str(folder)], capsys)
    assert "--suite cannot be combined with --family/--objects" in err


def test_show_names_the_supported_suffixes(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    err = refused(["show", S4, "-o", str(tmp_path / "x.weird")], capsys)
    assert "output must end in one of .html, .png, .pdf, .svg, .jpg, .jpeg" in err
    assert "x.weird" in err
    err = refused(["show", S4, "plan.json", "-o", str(tmp_path / "x.svg")], capsys)
    assert "output must end in one of .html, .png, .gif when a plan is given" in err
    err = refused(["show", S4, "-o", str(tmp_path / "x.gif")], capsys)
    assert "a .gif animation needs a plan" in err


def test_show_does_not_overwrite_without_force(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    picture = tmp_path / "sub" / "S4.svg"
    assert main(["show", S4, "-o", str(picture)]) == 0  # missing folders are created
    first = picture.read_bytes()
    capsys.readouterr()
    assert "exists; pass --force" in refused(["show", S4, "-o", str(picture)], capsys)
    assert picture.read_bytes() == first
    assert main(["show", S4, "-o", str(picture), "--force"]) == 0


def test_solve_checks_its_output_before_planning(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import sdar_tamp.app.pipeline as command

    def no_planning(*args: object, **kwargs: object) -> None:
        raise AssertionError("the output must be checked before planning")

    monkeypatch.setattr(command, "solve_instance", no_planning)
    existing = tmp_path / "plan.json"
    existing.write_text("{}")
    assert "exists; pass --force" in refused(["solve", S4, "-q", "-o", str(existing)], capsys)
    err = refused(["solve", S4, "-q", "-o", str(tmp_path / "plan.yaml")], capsys)
    assert "--output: expected a file ending in .json" in err


def test_demo_output_folder_is_checked(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    afile = tmp_path / "f"
    afile.write_text("")
    assert "--output: expected a folder" in refused(["demo", "--out", str(afile)], capsys)
    assert "--output: expected a folder" in refused(["demo", "-o", str(afile)], capsys)


def test_a_failed_write_is_one_line(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import sdar_tamp.viewer.pictures as commands

    def denied(*args: object) -> Path:
        raise PermissionError(13, "Permission denied", str(tmp_path / "x.png"))

    monkeypatch.setattr(commands, "show", denied)
    err = refused(["show", S4, "-o", str(tmp_path / "x.png")], capsys)
    assert err == f"sdar: error: {tmp_path / 'x.png'}: Permission denied"
