"""The skip lines of the benchmarks that need what the repository does not hold: in
``--quick``, without it, the last line is ``{"skipped": "<why>", ...}`` and the run ends
normally; a full run without it is refused instead where it cannot do anything useful."""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import pytest

Loader = Callable[[str], ModuleType]


def _last_line(capsys: pytest.CaptureFixture[str]) -> dict[str, object]:
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert isinstance(out, dict)
    return out


def test_pddlstream_examples_without_a_checkout(
    benchmark_script: Loader,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    tmp_path: Path,
) -> None:
    bench = benchmark_script("bench_pddlstream_compat")
    monkeypatch.delenv("PDDLSTREAM_PATH", raising=False)
    for argv, quick in (([], False), (["--quick"], True), ([str(tmp_path), "--quick"], True)):
        assert bench.main(argv) == 0
        out = _last_line(capsys)
        assert out["quick"] is quick
        assert isinstance(out["skipped"], str) and "no PDDLStream checkout" in out["skipped"]


def test_pddlstream_robot_example_without_its_simulator(
    benchmark_script: Loader, tmp_path: Path
) -> None:
    bench = benchmark_script("bench_pddlstream_compat")
    example = bench.Example("kuka", "examples.pybullet.kuka.run", needs="no_such_module_xyz")
    row = bench.run_example(tmp_path, example, 1.0)
    assert row["skipped"] is True and row["passed"] is False and row["seconds"] == 0.0
    assert "needs 'no_such_module_xyz'" in str(row["result"])
    assert {e.name for e in bench.EXAMPLES if e.needs == "pybullet"} == {
        "kuka",
        "pr2",
        "namo",
        "pr2_rovers",
        "pr2_belief",
        "tamp",
        "turtlebot_rovers",
        "turtlebots",
    }


def test_classical_without_its_problem_folder(
    benchmark_script: Loader, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    bench = benchmark_script("bench_classical")
    missing = tmp_path / "ipc"
    summary = bench.main(["--quick", "--suite", str(missing)])
    assert _last_line(capsys) == summary
    assert summary["quick"] is True and str(missing) in summary["skipped"]
    with pytest.raises(SystemExit) as info:  # a full run is refused
        bench.main(["--suite", str(missing)])
    assert info.value.code == 2
    assert f"--suite: {missing} is not a folder" in capsys.readouterr().err


def test_hard_motion_set_without_ompl(
    benchmark_script: Loader, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    bench = benchmark_script("bench_motion")
    monkeypatch.setitem(sys.modules, "ompl", None)  # importlib finds no such module
    bench.main(["--quick", "--hard", "1"])
    out = _last_line(capsys)
    assert out["quick"] is True and "OMPL is not installed" in str(out["skipped"])
