"""The benchmark runner (CSV, resume, combinations), report and plots, and one real run."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import pytest

from sdar_tamp.cli import main
from sdar_tamp.errors import ParameterError, SdarError
from sdar_tamp.evaluation.report import action_counts, execution_ratios, percentile, write_report
from sdar_tamp.evaluation.results import (
    COLUMNS,
    COMBINATIONS,
    RESULTS,
    STEP_COLUMNS,
    STEPS,
    append_rows,
    instance_sort_key,
    load_results,
    load_steps,
    parse_combos,
)
from sdar_tamp.evaluation.resume import finished_pairs
from sdar_tamp.evaluation.runner import run_bench
from sdar_tamp.evaluation.suite import suite_entries, suite_folder, suite_label

PNG = b"\x89PNG\r\n\x1a\n"


def _row(instance: str, combo: str, ok: bool, **extra: Any) -> dict[str, Any]:
    c = next(c for c in COMBINATIONS if c.id == combo)
    row: dict[str, Any] = dict(
        instance=instance, family=instance[0], objects=int(instance[1:]), combination=combo,
        task_planner=c.task_planner, motion_planner=c.motion_planner, seed=0, time_limit_s=60.0,
        success=ok, status="solved" if ok else "timeout", valid=ok,
        abstract_actions=int(instance[1:]), abstract_buffer_moves=0, abstract_steps=2,
    )  # fmt: skip
    if ok:
        row.update(actions=int(instance[1:]), steps=4, dual_arm_steps=3, buffer_moves=0,
                   execution_time_s=10.0, planning_time_s=1.0)  # fmt: skip
    row.update(extra)
    return row


def _synthetic(folder: Path) -> None:
    rows = []
    for name in ("R4", "S5", "D6"):
        for c in COMBINATIONS:
            ok = not (c.id == "baseline-tp+plain" or (c.id == "sdar-t+plain" and name == "D6"))
            extra: dict[str, Any] = {}
            if ok and c.id != "sdar":
                extra["execution_time_s"] = 20.0 if c.motion_planner == "sequential" else 12.0
            if name == "D6" and c.task_planner == "sdar":  # SDAR-T: one more buffer move
                extra.update(abstract_actions=8, abstract_buffer_moves=2, abstract_steps=4)
                extra.update(actions=9 if ok else None)
            if name == "D6" and c.task_planner == "baseline":
                extra.update(abstract_actions=7, abstract_buffer_moves=1, abstract_steps=6)
                extra.update(actions=7 if ok else None)
            if name == "S5" and c.task_planner == "baseline":
                extra.update(abstract_actions=7, abstract_buffer_moves=2, abstract_steps=5)
            rows.append(_row(name, c.id, ok, **extra))
    append_rows(folder / RESULTS, COLUMNS, rows)
    steps = [
        dict(instance=r["instance"], combination=r["combination"], step=i, selection_s=0.1 * i,
             motion_s=1.0)
        for r in rows if r["success"] for i in range(4)
    ]  # fmt: skip
    append_rows(folder / STEPS, STEP_COLUMNS, steps)


def test_parse_combos() -> None:
    assert parse_combos("all") == COMBINATIONS
    ids = [c.id for c in parse_combos("sdar-t+plain, sdar")]
    assert ids == ["sdar", "sdar-t+plain"]  # canonical order
    assert [c.id for c in parse_combos(["baseline"])] == ["baseline"]
    assert {(c.task_planner, c.motion_planner) for c in COMBINATIONS} == {
        (t, m) for t in ("sdar", "baseline") for m in ("sdar", "sequential", "plain")
    }
    with pytest.raises(ParameterError, match="curobo"):
        parse_combos("sdar,curobo")
    with pytest.raises(ParameterError, match="more than once"):
        parse_combos("sdar,sdar")
    with pytest.raises(ParameterError, match="unknown: ''"):
        parse_combos("sdar,")
    assert main(["bench", "--out", "unused", "--combos", "nope"]) == 2


def test_suite_selection() -> None:
    entries = suite_entries("paper", max_objects=5)
    assert [e.name for e in entries] == ["R4", "S4", "D4", "R5", "S5", "D5"]
    assert [e.name for e in suite_entries("paper", only=["M1", "R4"])] == ["R4", "M1"]
    with pytest.raises(ParameterError, match="R99"):
        suite_entries("paper", only=["R99"])
    with pytest.raises(ParameterError, match="suite must be"):
        suite_entries("no-such-suite")
    assert sorted(["M1", "R10", "S4", "R4"], key=instance_sort_key) == ["R4", "R10", "S4", "M1"]


def test_a_folder_named_like_a_shipped_suite(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A bare name is the shipped suite, even beside a folder of that name without instances
    (an earlier benchmark's output); beside a folder of instances it is ambiguous; written
    as a path, the folder is used."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "paper").mkdir()
    (tmp_path / "paper" / "report.md").write_text("an earlier --out\n")
    shipped = suite_entries("paper", only=["R4"])
    assert shipped[0].path.parent.name == "paper" and shipped[0].path.parent != tmp_path / "paper"
    assert suite_folder("paper")[1] and suite_label("paper") == "paper"
    shutil.copy(shipped[0].path, tmp_path / "paper" / "R4.yaml")
    with pytest.raises(ParameterError, match=r"both a shipped suite and a folder.*\./paper"):
        suite_entries("paper")
    for local in ("./paper", Path("paper")):
        (entry,) = suite_entries(local)
        assert entry.path.resolve() == (tmp_path / "paper" / "R4.yaml").resolve()
        assert suite_label(local) == str((tmp_path / "paper").resolve())
    (tmp_path / "mine").mkdir()
    shutil.copy(shipped[0].path, tmp_path / "mine" / "R4.yaml")
    assert [e.name for e in suite_entries("mine")] == ["R4"]  # not shipped: the folder


def test_resume_skips_finished_and_repairs(tmp_path: Path) -> None:
    finished = [_row("R4", "sdar", True), _row("R4", "baseline", False)]
    append_rows(tmp_path / RESULTS, COLUMNS, finished)
    step = dict(instance="R4", combination="sdar", step=0, selection_s=0.1, motion_s=0.2)
    orphan = dict(step, combination="sdar-t+plain")  # its row was never written
    append_rows(tmp_path / STEPS, STEP_COLUMNS, [step, orphan])
    with (tmp_path / RESULTS).open("a") as fh:  # a row cut short by an interruption
        fh.write("R4,R,4,sdar-t+plain,sdar,pl")
    before = (tmp_path / RESULTS).read_text()
    assert finished_pairs(tmp_path) == {("R4", "sdar"), ("R4", "baseline")}
    assert len(load_results(tmp_path)) == 2 and (tmp_path / RESULTS).read_text() != before
    assert [s["combination"] for s in load_steps(tmp_path)] == ["sdar"]
    # every requested pair is finished: nothing is solved, the files stay as they are
    repaired = (tmp_path / RESULTS).read_text()
    out = run_bench("paper", tmp_path, "sdar,baseline", instances=["R4"], progress=False)
    assert out == tmp_path / RESULTS and out.read_text() == repaired


def test_csv_from_another_version_is_refused(tmp_path: Path) -> None:
    (tmp_path / RESULTS).write_text("instance,combination\nR4,sdar\n")
    with pytest.raises(SdarError, match="unexpected columns"):
        finished_pairs(tmp_path)


def test_report_and_plots_from_synthetic_results(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    from sdar_tamp.evaluation.plots import write_plots

    _synthetic(tmp_path)
    rows = load_results(tmp_path)
    assert [x for _, _, x in execution_ratios(rows, "baseline")] == [2.0, 2.0, 2.0]
    d6 = next(a for a in action_counts(rows) if a.instance == "D6")
    assert d6.ours == (8, 2, 4) and d6.theirs == (7, 1, 6) and d6.ours_real == 9
    assert "buffers 2 object(s), the baseline 1" in d6.explain()
    assert "fell back" in d6.explain()
    text = write_report(tmp_path, "sdar bench --out X").read_text()
    assert "| SDAR | 3 | 3 | 100% | - |" in text
    assert "| Baseline TP + plain TO | 3 | 0 | 0% | timeout 3 |" in text
    assert "| SDAR-T + plain TO | 3 | 2 | 67% | timeout 1 |" in text
    assert "| Baseline | 20.00 | 2.00 | 3 |" in text
    assert "| S5 | 5 | 5 | 7 | 1.40 |" in text
    assert "sdar bench --out X" in text
    assert "| SDAR | 12 | 0.150 | 1.000 | 1.150 | 1.300 |" in text
    paths = write_plots(tmp_path)
    assert len(paths) == 6
    for path in paths:
        assert path.read_bytes()[:8] == PNG, path


def test_report_without_successes(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    from sdar_tamp.evaluation.plots import write_plots

    append_rows(tmp_path / RESULTS, COLUMNS, [_row("R4", "baseline", False)])
    assert "| Baseline | 1 | 0 | 0% | timeout 1 |" in write_report(tmp_path).read_text()
    assert all(p.read_bytes()[:8] == PNG for p in write_plots(tmp_path))


def test_percentile() -> None:
    assert percentile([3.0], 0.9) == 3.0
    assert percentile([0.0, 10.0], 0.9) == pytest.approx(9.0)
    assert percentile(list(map(float, range(11))), 0.5) == 5.0


def test_bench_end_to_end(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``sdar bench`` on R4 with two combinations in one spawned worker, then a rerun."""
    pytest.importorskip("matplotlib")
    args = ["bench", "--out", str(tmp_path), "--only", "R4", "--combos", "sdar,sdar-t+plain",
            "--workers", "1", "--time-limit", "30", "-q"]  # fmt: skip
    assert main(args) == 0
    rows = load_results(tmp_path)
    assert sorted(r["combination"] for r in rows) == ["sdar", "sdar-t+plain"]
    for r in rows:
        assert r["instance"] == "R4" and r["objects"] == "4" and r["family"] == "R"
        assert r["success"] == "1" and r["valid"] == "1" and r["status"] == "solved"
        assert int(r["actions"]) >= 4 and float(r["execution_time_s"]) > 0
        assert r["abstract_actions"] == "4"
        execution, bound = float(r["execution_time_s"]), float(r["bound_s"])
        assert 0.0 < bound < execution  # the same bound for both combinations
        assert float(r["execution_over_bound"]) == pytest.approx(execution / bound, rel=1e-5)
    assert len({r["bound_s"] for r in rows}) == 1
    steps = load_steps(tmp_path)
    assert {s["combination"] for s in steps} == {"sdar", "sdar-t+plain"}
    assert len(steps) == sum(int(r["steps"]) for r in rows)
    for name in ("report.md", "execution_time.png", "success_rate.png"):
        assert (tmp_path / name).is_file()
    assert "sdar bench --suite paper" in (tmp_path / "report.md").read_text()
    before = (tmp_path / RESULTS).read_text()
    assert main(args) == 0  # nothing left to run
    assert (tmp_path / RESULTS).read_text() == before
    assert "| SDAR | 1 | 1 | 100% | - |" in capsys.readouterr().out


def test_sweep_plots_stay_small(tmp_path: Path) -> None:
    """Past 60 instances the execution times are boxes per family, not a bar per instance."""
    pytest.importorskip("matplotlib")
    from sdar_tamp.evaluation.plots import MAX_BARS, plot_execution_times

    rows = [
        _row(f"{'RSDM'[k % 4]}{k + 5}", c, True) for k in range(MAX_BARS + 1)
        for c in ("sdar", "baseline")
    ]  # fmt: skip
    append_rows(tmp_path / RESULTS, COLUMNS, rows)
    path = plot_execution_times(load_results(tmp_path), tmp_path / "times.png")
    head = path.read_bytes()
    assert head[:8] == PNG
    width = int.from_bytes(head[16:20], "big")  # the PNG header's image width [px]
    assert width < 2000  # 61 instances as bars: 0.7 in each, over 5000 px


def test_the_asynchronous_combination_reaches_the_solver(monkeypatch: pytest.MonkeyPatch) -> None:
    """``sdar-async`` is SDAR with ``execution="async"``; the paper's six stay synchronous."""
    import sdar_tamp.app.pipeline as command
    from sdar_tamp.evaluation.bench_task import BenchTask, run_task
    from sdar_tamp.evaluation.results import COMBINATIONS, parse_combos

    assert [c.id for c in parse_combos("sdar-async")] == ["sdar-async"]
    assert [c.execution for c in COMBINATIONS].count("async") == 1
    seen: list[Any] = []

    def capture(path: Path, **kwargs: Any) -> Any:
        seen.append(kwargs["execution"])
        raise RuntimeError("stop")

    monkeypatch.setattr(command, "solve_instance", capture)
    (entry,) = suite_entries("paper", only=["R4"])
    for combo in parse_combos("sdar,sdar-async"):
        row = run_task(BenchTask(entry, combo, 60.0, 0)).row
        assert row.status == "error" and row.combination == combo.id
    assert seen == ["sync", "async"]


def test_a_bench_row_has_one_field_per_column_in_order() -> None:
    """The CSV columns come from the row record at the writing boundary, in COLUMNS order."""
    import dataclasses

    from sdar_tamp.evaluation.records import BenchRow

    assert tuple(f.name for f in dataclasses.fields(BenchRow)) == COLUMNS
    row = BenchRow("R4", "R", 4, "sdar", "sdar", "sdar", 0, 60.0, False, "error", False)
    assert list(row.cells()) == list(COLUMNS) and row.cells()["actions"] is None
