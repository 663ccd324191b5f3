"""``sdar export``: each format through the command line, default outputs next to the plan,
refusals (exit status 2, one line on stderr, nothing written)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from sdar_tamp.cli import main
from sdar_tamp.errors import ParameterError
from sdar_tamp.export import default_output, export_plan, export_plan_file
from sdar_tamp.plan_file import PlanFile, PlanFileError
from tests.cli.conftest import refused


@pytest.fixture
def copy(plan_path: Path, tmp_path: Path) -> Path:
    """The plan in a fresh folder (default outputs go next to it)."""
    return Path(shutil.copy(plan_path, tmp_path / "run.json"))


@pytest.mark.parametrize(
    ("fmt", "names"),
    [
        ("joint-trajectory", ["run.trajectory.json"]),
        ("csv", ["run.csv"]),
        ("urscript", ["run.urscript/left.script", "run.urscript/right.script"]),
    ],
)
def test_each_format_by_default_next_to_the_plan(
    copy: Path, fmt: str, names: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["export", str(copy), "--format", fmt]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out == [f"wrote {copy.parent / n}" for n in names]
    assert all((copy.parent / n).stat().st_size > 1000 for n in names)
    assert default_output(copy, fmt) == copy.parent / names[0].split("/")[0]


def test_output_option_and_force(
    copy: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / "deep" / "er" / "plan.json"
    assert main(["export", str(copy), "--format", "joint-trajectory", "-o", str(target)]) == 0
    assert json.loads(target.read_text(encoding="utf-8"))["format"] == "sdar-joint-trajectory"
    capsys.readouterr()
    err = refused(["export", str(copy), "--format", "joint-trajectory", "-o", str(target)], capsys)
    assert "exists; pass --force to replace it" in err
    target.write_text("old", encoding="utf-8")
    argv = ["export", str(copy), "--format", "joint-trajectory", "-o", str(target), "--force"]
    assert main(argv) == 0
    assert target.read_text(encoding="utf-8") != "old"


def test_urscript_folder_refuses_existing_scripts(
    copy: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "ur"
    folder.mkdir()
    (folder / "notes.txt").write_text("kept", encoding="utf-8")  # other files are fine
    argv = ["export", str(copy), "--format", "urscript", "-o", str(folder), "--period", "0.002"]
    assert main(argv) == 0
    assert "servo_t = 0.002" in (folder / "left.script").read_text(encoding="utf-8")
    capsys.readouterr()
    err = refused(argv, capsys)
    assert "left.script' exists; pass --force" in err
    assert main([*argv, "--force"]) == 0
    assert (folder / "notes.txt").read_text(encoding="utf-8") == "kept"


def test_unknown_format(copy: Path, plan: PlanFile, capsys: pytest.CaptureFixture[str]) -> None:
    err = refused(["export", str(copy), "--format", "rosbag"], capsys)
    assert "argument --format: invalid choice: 'rosbag'" in err
    with pytest.raises(ParameterError, match="format must be one of joint-trajectory, csv"):
        export_plan(plan, "rosbag", copy.parent / "x")
    with pytest.raises(ParameterError, match="format must be one of"):
        export_plan_file(copy, "mcap")
    assert sorted(p.name for p in copy.parent.iterdir()) == ["run.json"]


def test_missing_and_broken_plans(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    missing = tmp_path / "none.json"
    err = refused(["export", str(missing), "--format", "csv"], capsys)
    assert str(missing) in err and "sdar: error:" in err
    broken = tmp_path / "broken.json"
    broken.write_text('{"format": "sdar-plan"', encoding="utf-8")
    err = refused(["export", str(broken), "--format", "csv"], capsys)
    assert f"{broken}:1:" in err and "invalid JSON" in err
    with pytest.raises(PlanFileError):
        export_plan_file(missing, "csv")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["broken.json"]


@pytest.mark.parametrize(
    ("fmt", "output", "message"),
    [
        ("csv", "table.txt", "expected a file ending in .csv"),
        ("joint-trajectory", "out.csv", "expected a file ending in .json"),
        ("csv", "FOLDER.csv", "is a folder"),
        ("urscript", "FILE", "expected a folder"),
        ("csv", "FILE/sub/x.csv", "is a file, not a folder"),
    ],
)
def test_bad_output_paths(
    copy: Path, fmt: str, output: str, message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    (copy.parent / "FOLDER.csv").mkdir()
    (copy.parent / "FILE").write_text("x", encoding="utf-8")
    before = sorted(p.name for p in copy.parent.iterdir())
    err = refused(["export", str(copy), "--format", fmt, "-o", str(copy.parent / output)], capsys)
    assert message in err
    assert sorted(p.name for p in copy.parent.iterdir()) == before
    assert not any((copy.parent / "FOLDER.csv").iterdir())


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--format", "csv", "--gain", "500"], "--gain applies to --format urscript only"),
        (["--format", "urscript", "--rate", "10"], "--rate applies to --format csv only"),
        (["--format", "urscript", "--gain", "50"], "gain must be a number in [100, 2000]"),
        (["--format", "urscript", "--lookahead", "1"], "lookahead must be a number in [0.03"),
        (["--format", "urscript", "--period", "0"], "argument --period: expected a finite"),
        (["--format", "csv", "--rate", "nan"], "argument --rate: expected a finite number > 0"),
    ],
)
def test_options_are_checked(
    copy: Path, argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    err = refused(["export", str(copy), *argv], capsys)
    assert message in err
    assert sorted(p.name for p in copy.parent.iterdir()) == ["run.json"]


def test_csv_rate_option(copy: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["export", str(copy), "--format", "csv", "--rate", "25"]) == 0
    rows = (copy.parent / "run.csv").read_text(encoding="utf-8").splitlines()
    assert rows[1].startswith("0.000000,") and rows[2].startswith("0.040000,")
