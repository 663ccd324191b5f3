"""Resuming ``sdar bench``: rows are reused only under the settings that made them."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest

from sdar_tamp import __version__
from sdar_tamp.cli import main
from sdar_tamp.errors import SdarError
from sdar_tamp.evaluation import settings
from sdar_tamp.evaluation.results import COLUMNS, COMBINATIONS, RESULTS, append_rows, load_results
from sdar_tamp.evaluation.runner import run_bench
from sdar_tamp.evaluation.settings import SETTINGS, plan_extras
from sdar_tamp.evaluation.suite import suite_entries


def _row(instance: str, combo: str, seed: int = 0, time_limit: float = 60.0) -> dict[str, Any]:
    c = next(c for c in COMBINATIONS if c.id == combo)
    return dict(
        instance=instance, family=instance[0], objects=int(instance[1:]), combination=combo,
        task_planner=c.task_planner, motion_planner=c.motion_planner, seed=seed,
        time_limit_s=time_limit, success=True, status="solved", valid=True, actions=4, steps=3,
        dual_arm_steps=1, execution_time_s=10.0, planning_time_s=1.0, abstract_actions=4,
        abstract_buffer_moves=0, abstract_steps=2,
    )  # fmt: skip


def _bench(out: Path, *extra: str) -> list[str]:
    return ["bench", "--out", str(out), "--only", "R4", "--combos", "sdar", "-q", *extra]


def test_other_seed_or_time_limit_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    append_rows(tmp_path / RESULTS, COLUMNS, [_row("R4", "sdar", seed=0, time_limit=60.0)])
    before = (tmp_path / RESULTS).read_text()
    assert main(_bench(tmp_path, "--seed", "1", "--time-limit", "5")) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("sdar: error: ")
    assert "seed 1 (the rows: 0)" in err and "time limit 5 s (the rows: 60 s)" in err
    assert "--restart" in err
    assert (tmp_path / RESULTS).read_text() == before  # nothing run, nothing rewritten
    assert not (tmp_path / SETTINGS).exists()


def test_settings_record_is_written_then_enforced(tmp_path: Path) -> None:
    append_rows(tmp_path / RESULTS, COLUMNS, [_row("R4", "sdar")])
    run_bench("paper", tmp_path, "sdar", instances=["R4"], progress=False)  # nothing to run
    record = json.loads((tmp_path / SETTINGS).read_text())
    assert record["seed"] == 0 and record["time_limit_s"] == 60.0 and record["workers"] == 1
    assert record["suite"] == "paper" and record["version"] == __version__
    assert set(record["instances"]) == {"R4"} and len(record["instances"]["R4"]) == 64
    with pytest.raises(SdarError, match=r"workers 2 \(the rows: 1\)"):
        run_bench("paper", tmp_path, "sdar", instances=["R4"], workers=2, progress=False)
    with pytest.raises(SdarError, match=r"suite stress \(the rows: paper\)"):
        run_bench("stress", tmp_path, "sdar", instances=["R16"], progress=False)
    (tmp_path / SETTINGS).write_text(json.dumps(dict(record, version="0.0.1")))
    with pytest.raises(SdarError, match=rf"version {__version__} \(the rows: 0.0.1\)"):
        run_bench("paper", tmp_path, "sdar", instances=["R4"], progress=False)
    (tmp_path / SETTINGS).write_text("{not json")
    with pytest.raises(SdarError, match=f"{SETTINGS}: not a settings record"):
        run_bench("paper", tmp_path, "sdar", instances=["R4"], progress=False)


def test_changed_instance_file_is_refused(tmp_path: Path) -> None:
    suite = tmp_path / "suite"
    suite.mkdir()
    shutil.copy(suite_entries("paper", only=["R4"])[0].path, suite / "R4.yaml")
    out = tmp_path / "out"
    out.mkdir()
    append_rows(out / RESULTS, COLUMNS, [_row("R4", "sdar")])
    run_bench(suite, out, "sdar", progress=False)
    assert json.loads((out / SETTINGS).read_text())["suite"] == str(suite.resolve())
    with (suite / "R4.yaml").open("a") as fh:
        fh.write("# edited\n")
    with pytest.raises(SdarError, match=r"instance R4 \(file changed"):
        run_bench(suite, out, "sdar", progress=False)


def test_mixed_rows_without_record_are_refused(tmp_path: Path) -> None:
    append_rows(tmp_path / RESULTS, COLUMNS, [_row("R4", "sdar"), _row("S4", "sdar", seed=3)])
    with pytest.raises(SdarError, match=r"seed 0 \(the rows: 0, 3\)"):
        run_bench("paper", tmp_path, "sdar", instances=["R4", "S4"], progress=False)


def test_report_prints_the_commands_that_made_the_rows(tmp_path: Path) -> None:
    """The rows, not the last command line, decide the report's commands."""
    rows = [_row("R4", "sdar"), _row("R4", "baseline"), _row("S4", "sdar")]
    append_rows(tmp_path / RESULTS, COLUMNS, rows)
    assert main(_bench(tmp_path)) == 0  # R4 with sdar is finished: nothing to run
    text = (tmp_path / "report.md").read_text()
    head = f"sdar bench --suite paper --out {tmp_path}"
    tail = "--workers 1 --time-limit 60 --seed 0"
    assert f"{head} --combos sdar,baseline {tail} --only R4" in text
    assert f"{head} --combos sdar {tail} --only S4" in text
    assert f"sdar-tamp {__version__}" in text


def test_restart_discards_the_old_rows(tmp_path: Path) -> None:
    """One real run (R4, SDAR-T + plain TO) under a new seed after ``--restart``."""
    append_rows(tmp_path / RESULTS, COLUMNS, [_row("R4", "sdar"), _row("S4", "sdar")])
    args = ["bench", "--out", str(tmp_path), "--only", "R4", "--combos", "sdar-t+plain", "-q"]
    assert main([*args, "--seed", "2", "--time-limit", "30"]) == 2
    assert main([*args, "--seed", "2", "--time-limit", "30", "--restart"]) == 0
    rows = load_results(tmp_path)
    assert [(r["instance"], r["combination"], r["seed"]) for r in rows] == [
        ("R4", "sdar-t+plain", "2")
    ]
    assert json.loads((tmp_path / SETTINGS).read_text())["seed"] == 2
    text = (tmp_path / "report.md").read_text()
    assert "--combos sdar-t+plain --workers 1 --time-limit 30 --seed 2 --only R4" in text


@pytest.mark.parametrize(
    ("option", "value"),
    [("time_limit", float("nan")), ("time_limit", -1.0), ("workers", 0), ("seed", -5)],
)
def test_run_bench_refuses_bad_numbers_before_writing(
    tmp_path: Path, option: str, value: float
) -> None:
    from sdar_tamp.errors import ParameterError
    from sdar_tamp.evaluation.runner import run_bench

    out = tmp_path / "out"
    with pytest.raises(ParameterError, match=option):
        run_bench("paper", out, "sdar", progress=False, **{option: value})
    assert not out.exists()


def test_the_optional_packages_that_change_plans_are_recorded_and_enforced(
    tmp_path: Path,
) -> None:
    """A table made with OMPL installed is not extended on a machine without it (the motion
    ladder differs), nor the other way round; a record from before ``extras`` is not
    compared on them."""
    append_rows(tmp_path / RESULTS, COLUMNS, [_row("R4", "sdar")])
    run_bench("paper", tmp_path, "sdar", instances=["R4"], progress=False)
    record = json.loads((tmp_path / SETTINGS).read_text())
    assert record["extras"] == plan_extras() and set(record["extras"]) == {"ompl"}
    other = "none" if record["extras"]["ompl"] != "none" else "2.0.1"
    (tmp_path / SETTINGS).write_text(json.dumps(dict(record, extras={"ompl": other})))
    with pytest.raises(SdarError, match=rf"ompl {record['extras']['ompl']} \(the rows: {other}\)"):
        run_bench("paper", tmp_path, "sdar", instances=["R4"], progress=False)
    older = {k: v for k, v in record.items() if k != "extras"}
    (tmp_path / SETTINGS).write_text(json.dumps(older))
    run_bench("paper", tmp_path, "sdar", instances=["R4"], progress=False)  # not compared
    assert json.loads((tmp_path / SETTINGS).read_text())["extras"] == plan_extras()


def test_plan_extras_name_a_missing_package_none(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(settings, "PLAN_EXTRAS", (("ompl", "no_such_module_here"),))
    assert settings.plan_extras() == {"ompl": "none"}
