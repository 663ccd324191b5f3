"""``sdar bench --merge``: the shards of a sweep joined into one folder that resumes."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import pytest

from sdar_tamp.cli import main
from sdar_tamp.errors import ParameterError, SdarError
from sdar_tamp.evaluation.merge import merge_folders
from sdar_tamp.evaluation.results import (
    RESULTS,
    load_results,
    load_steps,
    plan_path,
)
from sdar_tamp.evaluation.runner import run_bench
from sdar_tamp.evaluation.settings import SETTINGS, SettingsMismatch, read_settings
from sdar_tamp.evaluation.shards import Shard

FinishedFolder = Callable[..., Path]
NAMES = ["R4", "S4"]
COMBOS = "sdar,baseline,sdar-t+plain"


def _shards(tmp_path: Path, finished_folder: FinishedFolder, count: int = 2) -> list[Path]:
    """``count`` finished shard folders of R4, S4 with three combinations, a plan per row."""
    folders = []
    for i in range(1, count + 1):
        shard = Shard(i, count)
        pairs = [(n, c) for n in NAMES for c in COMBOS.split(",") if shard.takes(n, c)]
        folder = finished_folder(tmp_path / f"shard{i}", pairs)
        for n, c in pairs:
            plan = plan_path(folder, n, c)
            plan.parent.mkdir(exist_ok=True)
            plan.write_text(json.dumps({"instance": n, "combination": c}))
        run_bench("paper", folder, COMBOS, instances=NAMES, shard=str(shard), progress=False)
        folders.append(folder)
    return folders


def test_merged_shards_hold_every_run_and_resume(
    tmp_path: Path, finished_folder: FinishedFolder
) -> None:
    a, b = _shards(tmp_path, finished_folder)
    assert len(load_results(a)) + len(load_results(b)) == 6 and load_results(a)
    merged = tmp_path / "merged"
    assert merge_folders([a, b], merged) == merged / RESULTS
    rows = load_results(merged)
    assert sorted((r["instance"], r["combination"]) for r in rows) == sorted(
        (n, c) for n in NAMES for c in COMBOS.split(",")
    )
    assert len(load_steps(merged)) == 2 * 6
    for r in rows:
        plan = json.loads(plan_path(merged, r["instance"], r["combination"]).read_text())
        assert plan == {"instance": r["instance"], "combination": r["combination"]}
    settings = read_settings(merged)
    assert settings is not None and settings.shard == "" and set(settings.instances) == {"R4", "S4"}
    before = (merged / RESULTS).read_text()
    run_bench("paper", merged, COMBOS, instances=NAMES, progress=False)  # the unsharded command
    assert (merged / RESULTS).read_text() == before  # everything is finished: nothing ran


def test_merge_on_the_command_line(
    tmp_path: Path, finished_folder: FinishedFolder, capsys: pytest.CaptureFixture[str]
) -> None:
    a, b = _shards(tmp_path, finished_folder)
    merged = tmp_path / "merged"
    assert main(["bench", "--merge", str(a), str(b), "--out", str(merged), "-q"]) == 0
    out = capsys.readouterr().out
    assert f"results: {merged / RESULTS}" in out and "| SDAR | 2 | 2 | 100% | - |" in out
    report = (merged / "report.md").read_text()
    assert f"--out {merged} --combos sdar,baseline,sdar-t+plain --workers 1" in report
    assert "--shard" not in report


def test_merge_refuses_what_does_not_fit(tmp_path: Path, finished_folder: FinishedFolder) -> None:
    a, b = _shards(tmp_path, finished_folder)
    with pytest.raises(ParameterError, match="is one of the folders to merge"):
        merge_folders([a, b], a)
    merged = merge_folders([a, b], tmp_path / "merged").parent
    with pytest.raises(ParameterError, match="already holds results"):
        merge_folders([a, b], merged)
    with pytest.raises(SdarError, match=r"R4 with .* is in both .*shard1 and .*merged"):
        merge_folders([a, merged], tmp_path / "again")
    with pytest.raises(SdarError, match=f"holds no {SETTINGS}"):
        merge_folders([a, finished_folder(tmp_path / "bare", [("D4", "sdar")])], tmp_path / "x")
    with pytest.raises(ParameterError, match="is not a folder"):
        merge_folders([a, tmp_path / "missing"], tmp_path / "y")
    with pytest.raises(ParameterError, match="one or more folders"):
        merge_folders([], tmp_path / "z")
    record = json.loads((b / SETTINGS).read_text())
    (b / SETTINGS).write_text(json.dumps(dict(record, seed=7)))
    other = r"other settings than .*shard1: seed 7 \(the rows: 0\)"
    with pytest.raises(SettingsMismatch, match=other):
        merge_folders([a, b], tmp_path / "w")
    assert not (tmp_path / "w").exists()  # refused before anything is written
