"""benchmarks/bench_solve.py: its arguments are checked, a failing solve stops it, and the
medians it prints come from the runs."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import pytest


@pytest.fixture(scope="module")
def bench(benchmark_script: Callable[[str], ModuleType]) -> ModuleType:
    return benchmark_script("bench_solve")


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--runs", "0"], "--runs: expected a number of runs >= 1, got 0"),
        (["--against", "/nonexistent/place"], "is not a checkout of sdar-tamp"),
    ],
)
def test_bad_arguments_are_refused(
    bench: ModuleType,
    argv: list[str],
    message: str,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setattr(sys, "argv", ["bench_solve.py", *argv])
    with pytest.raises(SystemExit) as exit_info:
        bench.main()
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err


def test_a_failing_solve_stops_the_benchmark(bench: ModuleType, tmp_path: Path) -> None:
    missing = tmp_path / "nothing.yaml"
    with pytest.raises(SystemExit, match=r"sdar solve failed \(\d+\): .*nothing.yaml"):
        bench.solve_once(missing, None, tmp_path / "plan.json")


def test_medians_and_ranges_of_the_runs(bench: ModuleType) -> None:
    runs = [
        dict(wall_s=w, cpu_s=w + 0.5, planning_s=1.0, schedule_s=0.5, execution_s=30.38,
             valid=True)
        for w in (6.0, 9.0, 5.0)
    ]  # fmt: skip
    m = bench.medians(runs)
    assert m["wall_s"] == 6.0 and m["cpu_s"] == 6.5 and m["wall_range_s"] == [5.0, 9.0]
    assert m["execution_s"] == [30.38] and m["all_valid"] is True
