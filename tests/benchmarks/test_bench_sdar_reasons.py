"""``bench_sdar.py`` says why an instance failed: the solver's status and diagnosis when it
returned no plan, the replay's violation when its plan is invalid."""

from __future__ import annotations

import json
from collections.abc import Callable
from types import ModuleType, SimpleNamespace

import pytest

Loader = Callable[[str], ModuleType]


def test_a_failure_without_a_plan_gives_the_solvers_diagnosis(benchmark_script: Loader) -> None:
    bench = benchmark_script("bench_sdar")
    timeout = SimpleNamespace(
        plan=None,
        status="timeout",
        violation="no plan",
        diagnosis=("max_time reached with 3 object(s) left",),
    )
    assert bench.failure_reason(timeout) == "timeout: max_time reached with 3 object(s) left"
    silent = SimpleNamespace(plan=None, status="error", violation="no plan", diagnosis=())
    assert bench.failure_reason(silent) == "error: no plan"


def test_an_invalid_plan_gives_the_replays_violation(benchmark_script: Loader) -> None:
    bench = benchmark_script("bench_sdar")
    invalid = SimpleNamespace(
        plan=object(), status="solved", violation="t=1.000 s: contact: arms touch", diagnosis=()
    )
    assert bench.failure_reason(invalid) == "invalid: t=1.000 s: contact: arms touch"


def test_a_run_out_of_time_prints_the_objects_left(
    benchmark_script: Loader, capsys: pytest.CaptureFixture[str]
) -> None:
    bench = benchmark_script("bench_sdar")
    bench.main(["--only", "R4", "--time-limit", "0.001"])
    lines = capsys.readouterr().out.strip().splitlines()
    row = next(line for line in lines if line.split()[:1] == ["R4"])
    assert row.endswith("timeout: max_time reached with 4 object(s) left")
    summary = json.loads(lines[-1])
    assert summary["success"] == 0 and summary["failures"] == ["R4"]
    assert summary["failure_reasons"] == {"R4": "timeout: max_time reached with 4 object(s) left"}
